"""Detected stances and gait events of a foot IMU, with one recipe for measured and simulated recordings.

- A *detected stance* is a group of zero-velocity runs (the samples a detector marks) whose gaps are shorter
  than ``MERGE_GAP_S``: a foot that stops and starts within one stance (a run broken where the angular rate
  touches the gate) is one stance, never two, because no swing is that short.
- *Gait events* come from the sagittal angular rate (body y, positive toes down, the project's body frame):
  the swing is the most negative rate between two stances; initial contact (IC) is the first upward zero
  crossing after it, toe off (TO) the last downward zero crossing before it (the convention of gaitmap's
  published events, whose ic and tc sit at these crossings). Forefoot contact (FF) is where the rate, after
  the slap's peak following IC, first falls below ``RATE_EVENT``; heel off (HO) where it last rises above
  ``RATE_EVENT`` before the push-off's peak preceding TO. The level is far above the zero-velocity gates
  (7..16 deg/s at the thresholds studied), so these events time the fast phases of the stance without
  presupposing how slowly the foot moves between them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nav.alignment import merged_runs

MERGE_GAP_S = 0.15  # s, shorter gaps between zero-velocity runs lie inside one stance (a swing lasts > 0.25 s)
MIN_SWING_RATE = np.deg2rad(50.0)  # rad/s, a swing's sagittal rate reaches below minus this
RATE_EVENT = np.deg2rad(50.0)  # rad/s, sagittal rate that ends the forefoot slap and starts the push-off


@dataclass
class DetectedStances:
    """Groups of zero-velocity runs, one per stance.

    Attributes
    ----------
    bounds : (S, 2) int, first sample and one past the last sample of each group.
    runs : list of (R_s, 2) int arrays, the runs (start, end) inside each group.
    """

    bounds: np.ndarray
    runs: list

    def __len__(self) -> int:
        return len(self.bounds)

    def middles(self) -> np.ndarray:
        """(S,) int, the middle sample of each group (between its first and last detected sample)."""
        return (self.bounds[:, 0] + self.bounds[:, 1] - 1) // 2

    def detected_samples(self) -> np.ndarray:
        """(S,) int, how many samples of each group the detector marked."""
        return np.array([int(np.sum(r[:, 1] - r[:, 0])) for r in self.runs], int)


def group_stances(t: np.ndarray, stationary: np.ndarray, merge_gap_s: float = MERGE_GAP_S) -> DetectedStances:
    """Group the zero-velocity runs of ``stationary`` (N,) bool on the clock ``t`` (N,) s into stances."""
    bounds, runs, group = merged_runs(t, stationary, merge_gap_s)
    return DetectedStances(bounds, [runs[group == g] for g in range(len(bounds))])


@dataclass
class GaitEvents:
    """Initial contact, forefoot contact, heel off and toe off around each detected stance (sample indices; -1
    where not found).

    Attributes
    ----------
    ic : (S,) int, initial contact before stance s.
    ff : (S,) int, forefoot contact (end of the slap).
    ho : (S,) int, heel off (start of the push-off).
    to : (S,) int, toe off after stance s.
    """

    ic: np.ndarray
    ff: np.ndarray
    ho: np.ndarray
    to: np.ndarray

    def complete(self) -> np.ndarray:
        """(S,) bool, stances with all four events in order."""
        return (self.ic >= 0) & (self.ff > self.ic) & (self.ho > self.ff) & (self.to > self.ho)


def _crossing(rate: np.ndarray, lo: int, hi: int, upward: bool) -> int:
    """First upward (last downward) zero crossing of ``rate`` in [lo, hi): the index of the first sample at or
    above zero after a negative one (the last sample at or above zero before a negative one); -1 if none."""
    seg = rate[lo:hi]
    if upward:
        hits = np.flatnonzero((seg[:-1] < 0) & (seg[1:] >= 0))
        return lo + int(hits[0]) + 1 if len(hits) else -1
    hits = np.flatnonzero((seg[:-1] >= 0) & (seg[1:] < 0))
    return lo + int(hits[-1]) if len(hits) else -1


def gait_events(gyr: np.ndarray, stances: DetectedStances) -> GaitEvents:
    """IC, FF, HO and TO of every detected stance from the sagittal rate ``gyr[:, 1]`` (rad/s); see the module docstring.

    The first stance has no IC unless a swing precedes it, the last no TO unless one follows it."""
    rate = np.asarray(gyr, float)[:, 1]
    middles = stances.middles()
    n = len(middles)
    ic, ff, ho, to = (np.full(n, -1) for _ in range(4))
    for k in range(n - 1):
        lo, hi = middles[k], middles[k + 1]
        swing = lo + int(np.argmin(rate[lo:hi]))
        if rate[swing] > -MIN_SWING_RATE:
            continue
        to[k] = _crossing(rate, lo, swing + 1, upward=False)
        ic[k + 1] = _crossing(rate, swing, hi + 1, upward=True)
    for k in range(n):
        if ic[k] >= 0:
            peak = ic[k] + int(np.argmax(rate[ic[k]:middles[k] + 1]))
            below = np.flatnonzero(rate[peak:middles[k] + 1] < RATE_EVENT)
            ff[k] = peak + int(below[0]) if rate[peak] >= RATE_EVENT and len(below) else -1
        if to[k] >= 0:
            peak = middles[k] + int(np.argmax(rate[middles[k]:to[k] + 1]))
            below = np.flatnonzero(rate[middles[k]:peak + 1] < RATE_EVENT)
            ho[k] = middles[k] + int(below[-1]) + 1 if rate[peak] >= RATE_EVENT and len(below) else -1
    return GaitEvents(ic, ff, ho, to)
