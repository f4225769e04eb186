"""Bad-input checks on recordings: each problem is an error or a warning with counts, never silently fixed.

One entry point, :func:`check_recording`, runs on any recording (simulated or measured, navigated or looped).

Errors (raise :class:`nav.recording.RecordingError`): mismatched shapes, fewer than 2 samples, NaN or infinite
samples, repeated or decreasing timestamps, and -- unless the caller allows them by name (``allow``, see
:data:`ALLOWABLE`; ``gaitsim nav --allow NAME``) -- a sample rate outside 20 Hz..5 kHz (time in ms or us:
read the recording with ``time_unit``, ``gaitsim nav --time-unit ms``), an accelerometer that reads ~1 at rest
(units of g), a gyro whose rates exceed any walking range on more than a handful of samples (units of deg/s),
and strides over which the gyro's attitude disagrees with the accelerometer's where another gyro scale, or the
gyro's sign, closes them at least :data:`CLOSURE_SCALE_GAIN` times better (a wrong gyro scale or unit, a mirrored
frame; strides holding clipped samples are not judged, since saturation alone spoils them). No stance found by
the detector is an error too.
Warnings (returned in :class:`CheckReport` with counts and issued with ``warnings.warn``): irregular sample
intervals, gaps longer than :data:`GAP_PERIODS` sample periods, no rest at the start, static specific force far
from gravity or not along +z, a static gyro offset too large for rad/s, a handful of gyro samples above any
walking rate (glitches), flat tops at a column's extreme (clipping, at any range; with the strides the closure
check left out for it), strides that end fast whatever the gyro's scale (a foot not still at its rests, as in
running, or an accelerometer error).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from .closure import stride_closure
from .constants import DEFAULT_GRAVITY
from .recording import IMU_COLUMNS, Recording, RecordingError, require_finite

STATIC_WINDOW_S = 0.5  # s, length of the quietest window used for the unit checks
RATE_RANGE_HZ = (20.0, 5000.0)  # sample rates of foot IMUs (60 Hz trackers to 1-4 kHz lab sensors)
MAX_WALKING_RATE = 35.0  # rad/s (2000 deg/s, the top of common gyro ranges; walking peaks at 10-31 rad/s)
MAX_GLITCH_SHARE = 0.001  # share of samples above MAX_WALKING_RATE still read as glitches, not as deg/s
MAX_STATIC_RATE = 0.1  # rad/s (5.7 deg/s): a rad/s gyro at rest reads bias + noise, far below this
ACC_IN_G_BAND = (0.8, 1.25)  # |f| at rest, if it lies here the accelerometer reports g
GRAVITY_TOLERANCE = 0.1  # relative deviation of the static |f| from gravity that triggers a warning
JITTER_TOLERANCE = 0.2  # relative deviation of an interval from the median interval counted as irregular
GAP_PERIODS = 5.0  # an interval longer than this many median intervals is a gap (lost samples)
CLIP_MIN_RUN = 3  # consecutive samples sitting exactly at a column's extreme that count as a flat top
CLIP_MIN_SPREAD = 20.0  # a flat top lies this many column standard deviations at rest away from the rest level
REST_RATE = 0.6  # rad/s, |w| below which a sample may be at rest (the foot's stance roll-over stays below)
REST_FORCE = 1.0  # m/s^2, ||f| - g| below which a sample may be at rest
START_REST_S = 0.6  # s of rest expected at the start (the filter aligns on it; a walking stance is shorter)
STRIDE_RANGE_S = (0.2, 3.0)  # s between two rests that count as one stride for the closure check
MAX_CLOSURE_SPEED = 1.0  # m/s, median speed a stride ends with (gyro-carried attitude) that refuses gyro against
# acc: clean recordings end at 0.1-0.46 m/s (simulated, gaitmap, UCR, x-io), a gyro scaled x2 at 1.5-7 m/s
MIN_CLOSURE_STRIDES = 3  # strides needed before the closure check judges
# gyro scales tried on strides that end fast: refused only when one of these closes the strides CLOSURE_SCALE_GAIN
# times better than the recording's own gyro (a foot that is not still at its rests, e.g. a running foot, or an
# accelerometer error ends strides fast at every scale, its own closing best). -1: a mirrored frame (one axis
# flipped, or two swapped, on both sensors) turns the gyro's rotations the other way against the accelerometer
GYRO_SCALES_TRIED = (-1.0, 1 / 4, 1 / 3, 1 / 2, 2 / 3, 3 / 2, 2.0, 3.0, 4.0)
CLOSURE_SCALE_GAIN = 2.0
ALLOWABLE = ("rate", "units", "closure")  # refusals a caller may turn into warnings by name


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

    def refuse(self, allowed: bool, message: str, **counts) -> None:
        """Raise ``message`` as a RecordingError, or, when the caller allowed the check, warn with it."""
        if not allowed:
            raise RecordingError(message)
        self.warn(message + " (allowed by the caller)", **counts)


def check_timestamps(t: np.ndarray, name: str = "imu.csv") -> dict:
    """Raise on repeated or decreasing timestamps; return counts of irregular intervals and gaps (s)."""
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
    gaps = dt > GAP_PERIODS * median
    return {"median_interval_s": median, "irregular_intervals": irregular, "gaps": int(gaps.sum()),
            "longest_gap_s": float(dt.max()), "first_gap_row": int(np.argmax(gaps)) + 1 if gaps.any() else 0}


def _time_unit_hint(rate: float) -> str:
    """What a sample rate outside RATE_RANGE_HZ says about the unit of the time column."""
    for unit, factor in (("ms", 1e3), ("us", 1e6), ("ns", 1e9)):
        if RATE_RANGE_HZ[0] <= rate * factor <= RATE_RANGE_HZ[1]:
            return (f"the time column looks like it is in {unit} ({rate * factor:.4g} Hz if it were): read it with "
                    f"time_unit='{unit}' (gaitsim nav --time-unit {unit})")
    return "if the rate is real, pass allow=('rate',) (gaitsim nav --allow rate)"


def quietest_window(acc: np.ndarray, length: int) -> tuple[int, int]:
    """(start, end) of the window of ``length`` samples with the smallest specific-force variance."""
    n = len(acc)
    length = max(2, min(length, n))
    centred = acc - acc.mean(axis=0)
    c = np.cumsum(np.concatenate([np.zeros((1, 3)), centred]), axis=0)
    c2 = np.cumsum(np.concatenate([[0.0], np.sum(centred ** 2, axis=1)]))
    s1 = c[length:] - c[:-length]
    s2 = c2[length:] - c2[:-length]
    var = s2 - np.sum(s1**2, axis=1) / length
    start = int(np.argmin(var))
    return start, start + length


def rest_runs(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, gravity: float,
              min_duration: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
    """(starts, ends) sample indices (end exclusive) of runs of at least ``min_duration`` s in which every sample
    has ``|w| < REST_RATE`` and ``||f| - gravity| < REST_FORCE``: candidate stances and pauses."""
    rest = (np.linalg.norm(gyr, axis=1) < REST_RATE) & (np.abs(np.linalg.norm(acc, axis=1) - gravity) < REST_FORCE)
    edges = np.diff(np.concatenate([[0], rest.astype(np.int8), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    long_enough = t[ends - 1] - t[starts] >= min_duration
    return starts[long_enough], ends[long_enough]


def stride_spans(t: np.ndarray, rests: tuple[np.ndarray, np.ndarray], spoiled: np.ndarray | None = None) -> np.ndarray:
    """(rests - 1,) bool: which gaps between consecutive rests (:func:`rest_runs`) are strides the closure check
    judges: ``STRIDE_RANGE_S`` long and, with ``spoiled`` ((N,) bool), holding none of those samples."""
    starts, ends = rests
    first, last = ends[:-1] - 1, starts[1:]
    stride = (STRIDE_RANGE_S[0] <= t[last] - t[first]) & (t[last] - t[first] <= STRIDE_RANGE_S[1])
    if spoiled is not None:
        count = np.concatenate([[0], np.cumsum(spoiled)])
        stride &= count[last + 1] == count[first]
    return stride


def closure_between_rests(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, gravity: float,
                          rests: tuple[np.ndarray, np.ndarray] | None = None,
                          spoiled: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Speed (m/s) and tilt (rad) each stride ends with when the gyro carries the accelerometer's attitude.

    For each pair of rests (:func:`rest_runs`) ``STRIDE_RANGE_S`` apart, the attitude levelled on the first
    rest's mean specific force is carried by the raw gyro (no bias removed) from the last sample of that rest to
    the first sample of the next (:func:`nav.closure.stride_closure`). There the foot is still again: the speed
    the strapdown ends with and the angle between the gravity direction it carried and the next rest's mean
    specific force stay small (cm/s, degrees) for a consistent sensor, and grow to m/s and tens of degrees for a
    gyro scaled wrong (or in deg/s) against the accelerometer: gravity is projected with the wrong attitude
    through the swing. (Flipping every accelerometer sign mirrors the walk and closes; that one shows at rest as
    gravity along -z.) ``rests``: ``rest_runs(t, acc, gyr, gravity)`` when the caller has them already.
    ``spoiled``: (N,) bool, samples that make a stride unfit to judge (clipped readings: a saturated sensor
    misses rate or force the stride had, whatever its scale); strides holding one are left out.

    Returns
    -------
    speed : (strides,) m/s, |v| at the first sample of the next rest.
    tilt : (strides,) rad, angle between the carried and the read gravity direction there.
    """
    starts, ends = rest_runs(t, acc, gyr, gravity) if rests is None else rests
    first, last = ends[:-1] - 1, starts[1:]
    stride = stride_spans(t, (starts, ends), spoiled)
    rests = np.column_stack([starts, ends])
    found = stride_closure(t, acc, gyr, rests[:-1][stride], first[stride],
                           np.column_stack([last, last + 1])[stride], rests[1:][stride], gravity)
    return np.linalg.norm(found.velocity, axis=1), found.angle


def flat_tops(x: np.ndarray, rest_level: np.ndarray, rest_sd: np.ndarray) -> np.ndarray:
    """(N, 6) bool: samples in runs of >= CLIP_MIN_RUN consecutive samples sitting exactly at a column's maximum
    or minimum, where that extreme lies more than CLIP_MIN_SPREAD rest standard deviations from the rest level
    (so that a quantised still signal is not read as clipping); columns acc_x, acc_y, acc_z, gyr_x, gyr_y,
    gyr_z."""
    found = np.zeros(x.shape, bool)
    for c in range(x.shape[1]):
        column = x[:, c]
        spread = max(rest_sd[c], 1e-12)
        for extreme in (column.max(), column.min()):
            if abs(extreme - rest_level[c]) <= CLIP_MIN_SPREAD * spread:
                continue
            edges = np.diff(np.concatenate([[0], (column == extreme).astype(np.int8), [0]]))
            for start, end in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)):
                if end - start >= CLIP_MIN_RUN:
                    found[start:end, c] = True
    return found


def check_recording(rec: Recording, gravity: float = DEFAULT_GRAVITY, name: str = "imu.csv",
                    allow: tuple[str, ...] = ()) -> CheckReport:
    """Check a recording before navigation (see the module docstring for what is refused and what is flagged).

    Parameters
    ----------
    rec : Recording (t in s, acc in m/s^2, gyr in rad/s).
    gravity : m/s^2, expected static specific-force magnitude.
    name : how to call the source in messages (e.g. the file path).
    allow : names of :data:`ALLOWABLE` refusals to report as warnings instead ("rate": a sample rate outside
        RATE_RANGE_HZ; "units": an accelerometer reading g or a gyro above any walking rate; "closure": strides
        whose gyro attitude disagrees with the accelerometer).

    Returns
    -------
    CheckReport with the warnings and counts (the reader's flags, ``rec.flags``, included); raises
    RecordingError on fatal problems.
    """
    unknown = sorted(set(allow) - set(ALLOWABLE))
    if unknown:
        raise ValueError(f"allow = {unknown}: unknown check names; allowed: {', '.join(ALLOWABLE)}")
    t = np.asarray(rec.t, float)
    acc = np.asarray(rec.acc, float)
    gyr = np.asarray(rec.gyr, float)
    n = len(t)
    if t.ndim != 1 or acc.shape != (n, 3) or gyr.shape != (n, 3):
        raise RecordingError(f"{name}: shapes t {t.shape}, acc {acc.shape}, gyr {gyr.shape}; "
                             "expected (N,), (N,3), (N,3)")
    if n < 2:
        raise RecordingError(f"{name}: {n} samples; at least 2 are needed (and enough rest to align)")
    require_finite(np.column_stack([t, acc, gyr]), IMU_COLUMNS, name)
    report = CheckReport()
    report.counts.update(getattr(rec, "flags", {}))
    timing = check_timestamps(t, name)
    report.counts.update(timing)
    fs = 1.0 / timing["median_interval_s"]
    report.counts["rate_hz"] = fs
    if not RATE_RANGE_HZ[0] <= fs <= RATE_RANGE_HZ[1]:
        report.refuse("rate" in allow, f"{name}: column t: the median sample interval gives {fs:.4g} Hz, outside "
                      f"{RATE_RANGE_HZ[0]:g} Hz..{RATE_RANGE_HZ[1]:g} kHz; {_time_unit_hint(fs)}".replace(
                          f"{RATE_RANGE_HZ[1]:g} kHz", f"{RATE_RANGE_HZ[1] / 1e3:g} kHz"))
    if timing["irregular_intervals"]:
        report.warn(f"{name}: {timing['irregular_intervals']} of {n - 1} sample intervals deviate more than "
                    f"{JITTER_TOLERANCE:.0%} from the median {timing['median_interval_s']:.6g} s; the timestamps are "
                    "used as they are", irregular_intervals=timing["irregular_intervals"])
    if timing["gaps"]:
        report.warn(f"{name}: {timing['gaps']} gaps longer than {GAP_PERIODS:g} sample periods (longest "
                    f"{timing['longest_gap_s']:.4g} s, first after row {timing['first_gap_row']}): lost samples; the "
                    "filter integrates across them as they are")

    start, end = quietest_window(acc, int(round(STATIC_WINDOW_S * fs)))
    report.static_window = (start, end)
    static_acc = acc[start:end].mean(axis=0)
    static_f = float(np.linalg.norm(static_acc))
    static_w = float(np.linalg.norm(gyr[start:end].mean(axis=0)))
    report.counts.update(static_specific_force=static_f, static_rate=static_w)
    if ACC_IN_G_BAND[0] <= static_f <= ACC_IN_G_BAND[1]:
        report.refuse("units" in allow, f"{name}: columns acc_*: specific force at rest (samples {start}..{end - 1}) "
                      f"is {static_f:.4g}: the accelerometer looks like it reports g; expected ~{gravity} m/s^2")
    if abs(static_f - gravity) > GRAVITY_TOLERANCE * gravity:
        report.warn(f"{name}: specific force in the quietest window (samples {start}..{end - 1}) is {static_f:.4g} "
                    f"m/s^2, not ~{gravity}: wrong units or no rest in the recording")
    if static_acc[2] < 0:
        report.warn(f"{name}: columns acc_*: specific force at rest (samples {start}..{end - 1}) is "
                    f"{np.round(static_acc, 3).tolist()} m/s^2, pointing along -z: the sensor is upside down or the "
                    "accelerometer's signs are flipped (z must point up when the foot is flat)")
    rate_norm = np.linalg.norm(gyr, axis=1)
    peak_rate = float(rate_norm.max())
    # per axis: a gyro's range is per axis, and one saturated at +-2000 deg/s (34.9 rad/s) in a run is not deg/s
    fast = int(np.sum(np.abs(gyr).max(axis=1) > MAX_WALKING_RATE))
    report.counts.update(peak_rate=peak_rate, samples_above_walking_rate=fast)
    if fast > max(1, MAX_GLITCH_SHARE * n):
        report.refuse("units" in allow, f"{name}: columns gyr_*: {fast} of {n} samples exceed {MAX_WALKING_RATE} rad/s "
                      f"({math.degrees(MAX_WALKING_RATE):.0f} deg/s; peak {peak_rate:.4g}): the gyro looks like it "
                      "reports deg/s; expected rad/s")
    elif fast:
        report.warn(f"{name}: columns gyr_*: {fast} of {n} samples exceed {MAX_WALKING_RATE} rad/s (peak "
                    f"{peak_rate:.4g} rad/s): isolated glitches, not a unit problem; left as they are")
    if static_w > MAX_STATIC_RATE:
        report.warn(f"{name}: mean rate in the quietest window is {static_w:.4g} rad/s "
                    f"({math.degrees(static_w):.3g} deg/s) at rest: gyro in deg/s or a large uncompensated bias")
    rests = rest_runs(t, acc, gyr, gravity)  # the long ones among them are those rest_runs keeps at START_REST_S
    starts = rests[0][t[rests[1] - 1] - t[rests[0]] >= START_REST_S]
    first_rest = float(t[starts[0]] - t[0]) if len(starts) else math.inf
    report.counts["first_rest_s"] = first_rest
    if first_rest > 0:
        where = f"begins {first_rest:.4g} s in" if len(starts) else "is nowhere"
        report.warn(f"{name}: the recording does not start at rest: the first {START_REST_S:g} s of rest {where}; the "
                    "filter aligns on the first stationary window")
    both = np.column_stack([acc, gyr])
    window = both[start:end]
    tops = flat_tops(both, window.mean(axis=0), window.std(axis=0))
    clipped = {column: int(count) for column, count in zip(IMU_COLUMNS[1:], tops.sum(axis=0)) if count}
    if clipped:
        report.warn(f"{name}: flat tops at a column's extreme value (possible clipping), samples per column: "
                    f"{clipped}", clipped_samples=clipped)
    speed, tilt = closure_between_rests(t, acc, gyr, gravity, rests, spoiled=tops.any(axis=1))
    report.counts["closure_strides"] = len(speed)
    if clipped:
        every = int(stride_spans(t, rests).sum())
        report.counts["closure_strides_clipped"] = every - len(speed)
        if len(speed) < MIN_CLOSURE_STRIDES <= every:
            report.warn(f"{name}: gyro against accelerometer not judged: {every - len(speed)} of {every} strides "
                        f"hold clipped samples (a saturated sensor misses rate or force the stride had), "
                        f"{len(speed)} left, {MIN_CLOSURE_STRIDES} needed")
    if len(speed) >= MIN_CLOSURE_STRIDES:
        median = float(np.median(speed))
        off = int(np.sum(speed > MAX_CLOSURE_SPEED))
        report.counts.update(closure_speed_median_mps=median, closure_tilt_median_deg=math.degrees(np.median(tilt)),
                             closure_strides_off=off)
        if median > MAX_CLOSURE_SPEED:
            scale, scaled = best_gyro_scale(t, acc, gyr, gravity, rests, tops.any(axis=1), median)
            report.counts.update(closure_best_gyro_scale=scale, closure_speed_median_at_best_scale_mps=scaled)
            fast = (f"{name}: gyro against accelerometer: carried by the gyro from one rest to the next, {off} of "
                    f"{len(speed)} strides end faster than {MAX_CLOSURE_SPEED:g} m/s (median {median:.3g} m/s, tilt "
                    f"off by {math.degrees(np.median(tilt)):.1f} deg) where the foot should be still")
            cause = ("a mirrored sensor frame (an axis flipped or two swapped)" if scale < 0
                     else "a wrong gyro scale or unit against the accelerometer")
            if scale != 1.0 and scaled * CLOSURE_SCALE_GAIN <= median:
                report.refuse("closure" in allow, f"{fast}; the gyro times {scale:.3g} closes them at a median "
                              f"{scaled:.3g} m/s: {cause}; pass allow=('closure',) (gaitsim nav --allow closure) "
                              "to navigate anyway")
            else:
                report.warn(f"{fast}; no gyro scale of {', '.join(f'{x:.3g}' for x in GYRO_SCALES_TRIED)} closes "
                            f"them {CLOSURE_SCALE_GAIN:g} times better (best: x{scale:.3g}, {scaled:.3g} m/s), so "
                            "it is not the gyro's scale or frame: a foot that is not still at its rests (running) "
                            "or an accelerometer error")
    return report


def best_gyro_scale(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, gravity: float,
                    rests: tuple[np.ndarray, np.ndarray], spoiled: np.ndarray,
                    own_median: float) -> tuple[float, float]:
    """The gyro scale, 1 or one of :data:`GYRO_SCALES_TRIED`, whose median stride-closure speed (m/s,
    :func:`closure_between_rests` over the same ``rests``, leaving out strides with ``spoiled`` samples) is least,
    and that median; ``own_median`` is the gyro's own (scale 1), already measured."""
    scales = (1.0, *GYRO_SCALES_TRIED)
    medians = [own_median] + [float(np.median(closure_between_rests(t, acc, gyr * scale, gravity, rests, spoiled)[0]))
                              for scale in GYRO_SCALES_TRIED]
    best = int(np.argmin(medians))
    return scales[best], medians[best]


def check_stance_found(stationary: np.ndarray, detector_description: str, min_statistic: float = math.nan) -> None:
    """Raise if a detector marked no sample as stationary."""
    if not np.any(stationary):
        raise RecordingError(f"no stance found by the detector ({detector_description}); smallest statistic "
                             f"{min_statistic:.4g}: raise the threshold or check the noise parameters and units")
