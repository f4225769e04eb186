"""Bad-input checks on recordings: each problem is an error or a warning with counts, never silently fixed.

Errors (raise :class:`nav.recording.RecordingError`): mismatched shapes, fewer than 2 samples, NaN or infinite
samples, repeated or decreasing timestamps, an accelerometer that reads ~1 at rest (units of g), a gyro whose
rates exceed any walking range (units of deg/s), no stance found by the detector.
Warnings (returned in :class:`CheckReport` and issued with ``warnings.warn``): irregular sample intervals,
static specific force far from gravity, a static gyro offset too large for rad/s, samples stuck at a column's
extreme (possible clipping).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from .constants import DEFAULT_GRAVITY
from .recording import Recording, RecordingError

STATIC_WINDOW_S = 0.5  # s, length of the quietest window used for the unit checks
MAX_WALKING_RATE = 35.0  # rad/s (2000 deg/s, the top of common gyro ranges; walking peaks at 10-31 rad/s)
MAX_STATIC_RATE = 0.1  # rad/s (5.7 deg/s): a rad/s gyro at rest reads bias + noise, far below this
ACC_IN_G_BAND = (0.8, 1.25)  # |f| at rest, if it lies here the accelerometer reports g
GRAVITY_TOLERANCE = 0.1  # relative deviation of the static |f| from gravity that triggers a warning
JITTER_TOLERANCE = 0.2  # relative deviation of an interval from the median interval counted as irregular
CLIP_MIN_COUNT = 3  # samples at a column's extreme value that count as possible clipping
CLIP_MIN_LEVEL = {"acc": 2 * DEFAULT_GRAVITY, "gyr": 5.0}  # m/s^2, rad/s: extremes below these are not a sensor range


@dataclass
class CheckReport:
    """Non-fatal findings of :func:`check_recording`.

    Attributes
    ----------
    warnings : human-readable messages (with counts).
    counts : dict of the numbers behind them (e.g. ``irregular_intervals``).
    static_window : (start, end) sample indices of the quietest window used for the unit checks.
    """

    warnings: list[str] = field(default_factory=list)
    counts: dict = field(default_factory=dict)
    static_window: tuple[int, int] = (0, 0)

    def warn(self, message: str, **counts) -> None:
        self.warnings.append(message)
        self.counts.update(counts)
        warnings.warn(message, stacklevel=3)


def _finite_check(name: str, columns: tuple[str, ...], values: np.ndarray) -> None:
    bad = ~np.isfinite(values)
    if bad.any():
        per_col = {c: int(n) for c, n in zip(columns, bad.reshape(len(values), -1).sum(axis=0)) if n}
        first = int(np.flatnonzero(bad.reshape(len(values), -1).any(axis=1))[0])
        raise RecordingError(f"{name}: {int(bad.sum())} NaN/inf values (per column {per_col}; first at row {first}); "
                             "all samples must be finite")


def check_timestamps(t: np.ndarray, name: str = "imu.csv") -> dict:
    """Raise on repeated or decreasing timestamps; return counts of irregular intervals (s)."""
    dt = np.diff(t)
    repeated = int(np.sum(dt == 0))
    backwards = int(np.sum(dt < 0))
    if repeated or backwards:
        first = int(np.flatnonzero(dt <= 0)[0]) + 1
        raise RecordingError(
            f"{name}: column t is not strictly increasing: {repeated} repeated and {backwards} decreasing timestamps "
            f"(first at row {first}, t = {t[first]!r} after {t[first - 1]!r}); drop or fix those rows first"
        )
    median = float(np.median(dt))
    irregular = int(np.sum(np.abs(dt - median) > JITTER_TOLERANCE * median))
    return {"median_interval_s": median, "irregular_intervals": irregular}


def quietest_window(acc: np.ndarray, length: int) -> tuple[int, int]:
    """(start, end) of the window of ``length`` samples with the smallest specific-force variance."""
    n = len(acc)
    length = max(2, min(length, n))
    c = np.cumsum(np.concatenate([np.zeros((1, 3)), acc - acc.mean(axis=0)]), axis=0)
    c2 = np.cumsum(np.concatenate([[0.0], np.sum((acc - acc.mean(axis=0)) ** 2, axis=1)]))
    s1 = c[length:] - c[:-length]
    s2 = c2[length:] - c2[:-length]
    var = s2 - np.sum(s1**2, axis=1) / length
    start = int(np.argmin(var))
    return start, start + length


def check_recording(rec: Recording, gravity: float = DEFAULT_GRAVITY, name: str = "imu.csv") -> CheckReport:
    """Check a recording before navigation.

    Parameters
    ----------
    rec : Recording (t in s, acc in m/s^2, gyr in rad/s).
    gravity : m/s^2, expected static specific-force magnitude.
    name : how to call the source in messages (e.g. the file path).

    Returns
    -------
    CheckReport with the warnings; raises RecordingError on fatal problems.
    """
    t = np.asarray(rec.t, float)
    acc = np.asarray(rec.acc, float)
    gyr = np.asarray(rec.gyr, float)
    n = len(t)
    if t.ndim != 1 or acc.shape != (n, 3) or gyr.shape != (n, 3):
        raise RecordingError(f"{name}: shapes t {t.shape}, acc {acc.shape}, gyr {gyr.shape}; "
                             "expected (N,), (N,3), (N,3)")
    if n < 2:
        raise RecordingError(f"{name}: {n} samples; at least 2 are needed (and enough rest to align)")
    _finite_check(name, ("t",), t[:, None])
    _finite_check(name, ("acc_x", "acc_y", "acc_z"), acc)
    _finite_check(name, ("gyr_x", "gyr_y", "gyr_z"), gyr)
    report = CheckReport()
    timing = check_timestamps(t, name)
    report.counts.update(timing)
    if timing["irregular_intervals"]:
        report.warn(f"{name}: {timing['irregular_intervals']} of {n - 1} sample intervals deviate more than "
                    f"{JITTER_TOLERANCE:.0%} from the median {timing['median_interval_s']:.6g} s; the timestamps are "
                    "used as they are", irregular_intervals=timing["irregular_intervals"])

    fs = 1.0 / timing["median_interval_s"]
    start, end = quietest_window(acc, int(round(STATIC_WINDOW_S * fs)))
    report.static_window = (start, end)
    static_f = float(np.linalg.norm(acc[start:end].mean(axis=0)))
    static_w = float(np.linalg.norm(gyr[start:end].mean(axis=0)))
    report.counts.update(static_specific_force=static_f, static_rate=static_w)
    if ACC_IN_G_BAND[0] <= static_f <= ACC_IN_G_BAND[1]:
        raise RecordingError(f"{name}: columns acc_*: specific force at rest (samples {start}..{end - 1}) is "
                             f"{static_f:.4g}: the accelerometer looks like it reports g; expected ~{gravity} m/s^2")
    if abs(static_f - gravity) > GRAVITY_TOLERANCE * gravity:
        report.warn(f"{name}: specific force in the quietest window (samples {start}..{end - 1}) is {static_f:.4g} "
                    f"m/s^2, not ~{gravity}: wrong units or no rest in the recording")
    peak_rate = float(np.max(np.linalg.norm(gyr, axis=1)))
    report.counts["peak_rate"] = peak_rate
    if peak_rate > MAX_WALKING_RATE:
        raise RecordingError(f"{name}: columns gyr_*: peak rate {peak_rate:.4g} exceeds {MAX_WALKING_RATE} rad/s "
                             f"({math.degrees(MAX_WALKING_RATE):.0f} deg/s): the gyro looks like it reports deg/s; "
                             "expected rad/s")
    if static_w > MAX_STATIC_RATE:
        report.warn(f"{name}: mean rate in the quietest window is {static_w:.4g} rad/s "
                    f"({math.degrees(static_w):.3g} deg/s) at rest: gyro in deg/s or a large uncompensated bias")
    clipped = {}
    for label, x in (("acc", acc), ("gyr", gyr)):
        for i, axis in enumerate("xyz"):
            extreme = np.max(np.abs(x[:, i]))
            count = int(np.sum(np.abs(x[:, i]) == extreme))
            if extreme > CLIP_MIN_LEVEL[label] and count >= CLIP_MIN_COUNT:
                clipped[f"{label}_{axis}"] = count
    if clipped:
        report.warn(f"{name}: samples sitting exactly at a column's extreme value (possible clipping): {clipped}",
                    clipped_samples=clipped)
    return report


def check_stance_found(stationary: np.ndarray, detector_description: str, min_statistic: float = math.nan) -> None:
    """Raise if a detector marked no sample as stationary."""
    if not np.any(stationary):
        raise RecordingError(f"no stance found by the detector ({detector_description}); smallest statistic "
                             f"{min_statistic:.4g}: raise the threshold or check the noise parameters and units")
