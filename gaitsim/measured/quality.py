"""Data-quality checks shared by every measured-data loader.

The loaders never repair a trap silently: they count it with the functions here, store the counts in
``meta["data_quality"]`` and emit a :class:`DataQualityWarning` naming the file and the count. The frame checks at
the end verify, on the data, the axis mapping a loader applied (gravity on +z at rest, pitch about y, x forward).
"""

from __future__ import annotations

import warnings

import numpy as np

from nav.constants import DEFAULT_GRAVITY


class DataQualityWarning(UserWarning):
    """A measured file carries a documented trap (repeated rows, NaNs, saturation, jitter, unit doubt)."""


def warn_quality(source: str, message: str) -> None:
    """Emit one :class:`DataQualityWarning` for ``source`` (a file name or dataset/recording label)."""
    warnings.warn(f"{source}: {message}", DataQualityWarning, stacklevel=3)


def non_increasing_time_mask(t: np.ndarray) -> np.ndarray:
    """Rows whose time stamp does not increase past every earlier row.

    Parameters
    ----------
    t : (N,) s, time stamps as stored in the file.

    Returns
    -------
    (N,) bool, True for a row with ``t[i] <= max(t[:i])`` (a repeated packet or a step back in time).
    """
    t = np.asarray(t, dtype=float)
    running_max = np.maximum.accumulate(t)
    mask = np.zeros(len(t), dtype=bool)
    mask[1:] = t[1:] <= running_max[:-1]
    return mask


def timestamp_report(t: np.ndarray) -> dict:
    """Counts of timestamp traps: rows that repeat the previous time and rows that go back in time.

    Parameters
    ----------
    t : (N,) s, time stamps as stored in the file.

    Returns
    -------
    dict with ``rows`` (N), ``repeated_time_rows`` (``t[i] == t[i-1]``), ``backward_time_rows`` (``t[i] < t[i-1]``)
    and ``non_increasing_rows`` (what :func:`non_increasing_time_mask` marks).
    """
    t = np.asarray(t, dtype=float)
    step = np.diff(t)
    return {
        "rows": int(len(t)),
        "repeated_time_rows": int(np.count_nonzero(step == 0)),
        "backward_time_rows": int(np.count_nonzero(step < 0)),
        "non_increasing_rows": int(np.count_nonzero(non_increasing_time_mask(t))),
    }


def jitter_stats(t: np.ndarray) -> dict:
    """Sample-interval statistics of strictly increasing time stamps.

    Parameters
    ----------
    t : (N,) s, strictly increasing.

    Returns
    -------
    dict, intervals in s: ``dt_mean``, ``dt_median``, ``dt_std``, ``dt_min``, ``dt_max``; ``rate_hz`` (1/median),
    ``jitter_rel`` (std/median, dimensionless) and ``gaps`` (intervals longer than 1.5 medians, i.e. lost samples).
    """
    dt = np.diff(np.asarray(t, dtype=float))
    median = float(np.median(dt))
    return {
        "dt_mean": float(dt.mean()),
        "dt_median": median,
        "dt_std": float(dt.std()),
        "dt_min": float(dt.min()),
        "dt_max": float(dt.max()),
        "rate_hz": 1.0 / median,
        "jitter_rel": float(dt.std() / median),
        "gaps": int(np.count_nonzero(dt > 1.5 * median)),
    }


def nan_counts(columns: dict[str, np.ndarray]) -> dict[str, int]:
    """Number of NaN samples per named column (any component NaN counts the sample once)."""
    counts = {}
    for name, values in columns.items():
        values = np.asarray(values, dtype=float)
        bad = np.isnan(values) if values.ndim == 1 else np.isnan(values).any(axis=1)
        counts[name] = int(np.count_nonzero(bad))
    return counts


def saturation_counts(values: np.ndarray, full_scale: float, fraction: float = 0.99) -> dict:
    """Samples at the range limit of a sensor.

    A sample counts as saturated when ``|value| >= fraction * full_scale`` on any axis: calibration (offset and
    scale per axis) moves the clipped raw reading off the nominal full scale by up to ~1 %.

    Parameters
    ----------
    values : (N, 3) readings in the unit of ``full_scale``.
    full_scale : the sensor's range limit (same unit, e.g. m/s^2 for 16 g).
    fraction : share of full scale from which a sample counts as saturated (dimensionless).

    Returns
    -------
    dict with ``threshold`` (unit of ``values``), ``per_axis`` (three counts) and ``samples`` (rows with any axis
    at the limit).
    """
    at_limit = np.abs(np.asarray(values, dtype=float)) >= fraction * full_scale
    return {
        "threshold": float(fraction * full_scale),
        "per_axis": [int(c) for c in np.count_nonzero(at_limit, axis=0)],
        "samples": int(np.count_nonzero(at_limit.any(axis=1))),
    }


def still_mask(t: np.ndarray, gyr: np.ndarray, rate_threshold: float = 0.6, min_duration: float = 0.1) -> np.ndarray:
    """Samples inside still (stance) windows found from the angular-rate norm.

    Parameters
    ----------
    t : (N,) s.
    gyr : (N, 3) rad/s.
    rate_threshold : rad/s, a sample is still when ``|gyr| < rate_threshold``.
    min_duration : s, shorter still runs are discarded.

    Returns
    -------
    (N,) bool.
    """
    still = np.linalg.norm(gyr, axis=1) < rate_threshold
    edges = np.diff(np.concatenate([[0], still.astype(np.int8), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    mask = np.zeros(len(t), dtype=bool)
    for start, end in zip(starts, ends):
        if t[end - 1] - t[start] >= min_duration:
            mask[start:end] = True
    return mask


def frame_checks(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray) -> dict:
    """Verify on the data that a recording is in the project's body frame (x toes, y left, z up).

    Three signatures of a foot-mounted IMU in that frame:

    - at rest the specific force points along +z (``still_acc_mean`` ~ (0, 0, +9.81) m/s^2 up to mount tilt);
    - during walking the dominant angular-rate axis is the pitch axis y (``dominant_gyro_axis`` == 1);
    - from the end of one stance to the next the foot pitches toes-down (heel rise, positive rotation about y when
      x points forward) by far more than it pitches toes-up before heel strike, so the median signed largest pitch
      excursion per swing (``pitch_excursion_deg``) is positive when x points forward and negative when it points
      backward.

    Parameters
    ----------
    t : (N,) s, increasing.
    acc : (N, 3) m/s^2 specific force.
    gyr : (N, 3) rad/s.

    Returns
    -------
    dict with ``still_acc_mean`` (m/s^2), ``still_acc_norm`` (m/s^2, median), ``dominant_gyro_axis`` (0, 1, 2),
    ``gyro_rms`` (rad/s per axis), ``pitch_excursion_deg`` (deg, median over swings), ``swings`` (count) and
    ``forward_is_plus_x`` (bool).
    """
    still = still_mask(t, gyr)
    edges = np.diff(np.concatenate([[0], still.astype(np.int8), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    excursions = []
    for swing_start, swing_end in zip(ends[:-1], starts[1:]):
        if t[swing_end] - t[swing_start - 1] > 2.0:  # a pause or turn on the spot, not one swing
            continue
        window = slice(swing_start - 1, swing_end + 1)
        pitch = np.concatenate([[0.0], np.cumsum(gyr[window, 1][:-1] * np.diff(t[window]))])
        excursions.append(pitch[np.argmax(np.abs(pitch))])
    gyro_rms = np.sqrt(np.mean(gyr**2, axis=0))
    excursion = float(np.rad2deg(np.median(excursions))) if excursions else float("nan")
    return {
        "still_acc_mean": acc[still].mean(axis=0).tolist() if still.any() else [float("nan")] * 3,
        "still_acc_norm": float(np.median(np.linalg.norm(acc[still], axis=1))) if still.any() else float("nan"),
        "dominant_gyro_axis": int(np.argmax(gyro_rms)),
        "gyro_rms": gyro_rms.tolist(),
        "pitch_excursion_deg": excursion,
        "swings": len(excursions),
        "forward_is_plus_x": bool(excursion > 0),
    }


def frame_problems(checks: dict, tolerance: float = 0.05, gravity: float = DEFAULT_GRAVITY) -> list[str]:
    """Every frame check of :func:`frame_checks` that fails, as a message; the walking checks (pitch axis, toes
    forward) only when the recording has swings.

    Parameters
    ----------
    checks : output of :func:`frame_checks`.
    tolerance : allowed relative deviation of the still |specific force| from ``gravity`` (a unit error is >> 5 %).
    gravity : m/s^2.
    """
    problems = []
    norm = checks["still_acc_norm"]
    if not abs(norm - gravity) <= tolerance * gravity:
        problems.append(f"still |specific force| is {norm:.3f} m/s^2, expected {gravity} within {tolerance:.0%} "
                        "(units?)")
    if not checks["still_acc_mean"][2] > 0.7 * gravity:
        problems.append(f"gravity is not on +z at rest: mean still specific force {checks['still_acc_mean']} m/s^2")
    if checks["swings"] == 0:
        return problems
    if checks["dominant_gyro_axis"] != 1:
        problems.append(f"dominant angular-rate axis is {'xyz'[checks['dominant_gyro_axis']]}, expected y (pitch)")
    if not checks["forward_is_plus_x"]:
        problems.append(f"median swing pitch excursion {checks['pitch_excursion_deg']:.1f} deg is not positive: "
                        "x does not point toward the toes")
    return problems


def warn_frame_problems(source: str, checks: dict, tolerance: float = 0.05) -> list[str]:
    """Warn about every frame check of :func:`frame_checks` that fails (:func:`frame_problems`); return the
    messages.

    Parameters
    ----------
    source : label used in the warning.
    checks : output of :func:`frame_checks`.
    tolerance : allowed relative deviation of the still |specific force| from 9.81 m/s^2 (a unit error is >> 5 %).
    """
    problems = frame_problems(checks, tolerance)
    for message in problems:
        warn_quality(source, message)
    return problems
