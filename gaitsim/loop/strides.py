"""Strides of a foot-IMU recording from its IMU alone, and signals resampled on their gait phase.

Stance is detected as nav detects it by default, with the anchored SHOE (:mod:`nav.calm_anchor`: OpenShoe's
fixed-threshold SHOE, plus each stride's calmest stretch where that finds nothing, as in running); runs of stance
closer than ``settings.MERGE_GAP_S`` are merged, and runs of the fixed test shorter than ``settings.MIN_STANCE_S``
are dropped (a swing crossing the threshold for a few samples). Where the anchor acted (a recording whose feet
are not still in stance: a run), a run it marked is a stride's stance whatever its length (a running foot's calm
stretch lasts 50-70 ms), and so is a short run of the fixed test with no other stance within the anchor's span (the
fixed test passed that stance for a few samples, which held the anchor off). A stride runs from one stance onset
to the next, the onset being where |w| last rose above ``settings.QUIET_RATE_DPS`` before the stance centre (a
gyro-only event, so accelerometer-side effects that move the SHOE onset do not shift the phase grid); strides whose
period is not within ``settings.STRIDE_PERIOD_BAND`` times the median (rest at the ends, missed stances) are
dropped.
"""

from __future__ import annotations

import numpy as np

from nav.alignment import merged_runs
from nav.calm_anchor import CalmAnchor, detect_anchored
from nav.detectors import DetectorResult, spread_marks
from nav.series import resample

from . import settings


def detect_stances(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, gravity: float) -> tuple[DetectorResult,
                                                                                             np.ndarray]:
    """nav's default zero-velocity detection of a recording (t (N,) s, acc (N, 3) m/s^2, gyr (N, 3) rad/s, gravity
    m/s^2; the anchored SHOE at nav's settings) and its stances (:func:`stance_intervals`)."""
    anchor = CalmAnchor()
    result = detect_anchored(t, acc, gyr, gravity=gravity, anchor=anchor)
    anchored = spread_marks(result.threshold > result.params.threshold, result.params.window)
    return result, stance_intervals(t, result.stationary, anchored, anchor.half_span_s)


def stance_intervals(t: np.ndarray, stationary: np.ndarray, anchored: np.ndarray | None = None,
                     span_s: float = 0.0) -> np.ndarray:
    """(m, 2) sample indices [start, end) of detected stances after merging gaps < ``settings.MERGE_GAP_S`` and
    dropping runs shorter than ``settings.MIN_STANCE_S``; ``t`` in s. Where ``anchored`` (N,) bool, the anchored
    SHOE's own marks, holds any sample, a short run is kept when it holds one of them or when no kept run lies
    within ``span_s`` (s, the anchor's half span) of it (module docstring)."""
    out = merged_runs(t, stationary, settings.MERGE_GAP_S)[0]
    start, end = t[out[:, 0]], t[out[:, 1] - 1]
    keep = end - start >= settings.MIN_STANCE_S
    if anchored is not None and anchored.any():
        keep |= np.array([anchored[a:b].any() for a, b in out], bool)
        gaps = np.maximum(start[:, None] - end[keep][None, :], start[keep][None, :] - end[:, None])  # (m, kept)
        keep |= ~np.any(gaps <= span_s, axis=1)
    return out[keep]


def gyro_onsets(gyr: np.ndarray, stances: np.ndarray) -> np.ndarray:
    """Sample index where |w| last rose above ``settings.QUIET_RATE_DPS`` before each stance's centre, plus one."""
    loud = np.degrees(np.linalg.norm(gyr, axis=1)) >= settings.QUIET_RATE_DPS
    loud_index = np.flatnonzero(loud)
    centres = (stances[:, 0] + stances[:, 1]) // 2
    before = np.searchsorted(loud_index, centres) - 1
    return np.where(before >= 0, loud_index[np.maximum(before, 0)] + 1, stances[:, 0])


def regular_strides(t: np.ndarray, gyr: np.ndarray, stances: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Stride [start, end) sample indices (gyro onset to next onset) and their stances, regular ones only."""
    if len(stances) < 2:
        return np.empty((0, 2), int), np.empty((0, 2), int)
    onsets = gyro_onsets(gyr, stances)
    periods = t[onsets[1:]] - t[onsets[:-1]]
    usable = periods < settings.MAX_STRIDE_S
    if not usable.any():
        return np.empty((0, 2), int), np.empty((0, 2), int)
    median = np.median(periods[usable])
    low, high = settings.STRIDE_PERIOD_BAND
    keep = usable & (periods > low * median) & (periods < high * median)
    # a stance that lasts longer than the stride's own period is rest, not gait
    keep &= (t[stances[:-1, 1] - 1] - t[onsets[:-1]]) < settings.REST_STANCE_SHARE * periods
    strides = np.column_stack([onsets[:-1], onsets[1:]])[keep]
    return strides, stances[:-1][keep]


def phase_resample(t: np.ndarray, x: np.ndarray, strides: np.ndarray, points: int = settings.PHASE_POINTS) -> np.ndarray:
    """(S, P, ...) the signal ``x`` (N, ...) resampled linearly on ``points`` equal phases of each stride
    [s0, s1] (sample indices; phase 0 at s0, the last phase one step before s1)."""
    phase = np.linspace(0.0, 1.0, points, endpoint=False)
    x = np.asarray(x, float)
    flat = x.reshape(len(x), -1)
    out = []
    for s0, s1 in strides:
        grid = t[s0] + phase * (t[s1] - t[s0])
        out.append(resample(grid, t[s0:s1 + 1], flat[s0:s1 + 1]))
    return np.array(out).reshape((len(strides), points) + x.shape[1:])


def dominant_axis(gyr: np.ndarray) -> np.ndarray:
    """Unit principal axis of the angular rate (N, 3) over a stride, signed so that its y component is >= 0."""
    _, vectors = np.linalg.eigh(gyr.T @ gyr)
    return vectors[:, -1] * (1.0 if vectors[1, -1] >= 0 else -1.0)
