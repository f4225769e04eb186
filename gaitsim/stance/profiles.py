"""Foot-flat profiles of a foot IMU and its site track: how the angular rate, the sagittal rate, the SHOE
statistic and the site's velocity run from forefoot contact to heel off, stride by stride.

Each stride's foot flat (forefoot contact FF to heel off HO, :func:`gaitsim.stance.events.gait_events` at the
largest threshold of the sweep) is mapped onto the phase ``u`` in [0, 1]; the grid reaches ``MARGIN`` beyond
both ends into the slap and the push-off. The site velocity is the track's central difference over
+-``VELOCITY_HALF_SPAN_S`` (its mean velocity over that span: no filter ringing from the fast phases into
the quiet ones); forward is the stride direction (previous to next stance middle), up is z.
A profile is the per-phase median over strides and the median absolute deviation / sqrt(strides) as its
spread: the same recipe for a measured recording and for its twin.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nav import detectors
from nav.recording import Recording
from nav.series import resample

from .events import DetectedStances, GaitEvents, gait_events, group_stances
from .sweep import SIGMA_A, SIGMA_G, THRESHOLDS, WINDOW

POINTS = 29
MARGIN = 0.2
VELOCITY_HALF_SPAN_S = 0.025  # s
CHANNELS = {"rate_dps": "deg/s", "sagittal_rate_dps": "deg/s", "log10_shoe": "log10",
            "forward_velocity_mps": "m/s", "vertical_velocity_mps": "m/s"}


def site_velocity(t: np.ndarray, pos: np.ndarray) -> np.ndarray:
    """(N, 3) m/s: mean velocity of a site track (t (N,) s, pos (N, 3) m; NaN rows bridged linearly) over
    [t - h, t + h], h = ``VELOCITY_HALF_SPAN_S`` (one-sided at the ends)."""
    ok = np.all(np.isfinite(pos), axis=1)
    ahead = np.minimum(t + VELOCITY_HALF_SPAN_S, t[-1])
    behind = np.maximum(t - VELOCITY_HALF_SPAN_S, t[0])
    return np.stack([(np.interp(ahead, t[ok], pos[ok, i]) - np.interp(behind, t[ok], pos[ok, i])) / (ahead - behind)
                     for i in range(3)], -1)


@dataclass
class Profiles:
    """Foot-flat profiles (module docstring).

    Attributes
    ----------
    phase : (P,) foot-flat phase u (0 = forefoot contact, 1 = heel off).
    median, spread : {channel: (P,)} in the units of :data:`CHANNELS`.
    strides : number of strides.
    foot_flat_s : s, median FF-to-HO time.
    """

    phase: np.ndarray
    median: dict
    spread: dict
    strides: int
    foot_flat_s: float

    def as_dict(self) -> dict:
        return {"phase": self.phase.tolist(), "strides": self.strides, "foot_flat_s": self.foot_flat_s,
                "units": CHANNELS, "median": {k: v.tolist() for k, v in self.median.items()},
                "spread": {k: v.tolist() for k, v in self.spread.items()}}


def detected_gait(rec: Recording) -> tuple[detectors.DetectorResult, DetectedStances, GaitEvents]:
    """SHOE at the sweep's largest threshold on ``rec``, its stances and their gait events: what the foot-flat
    profiles and the twin's timing (:mod:`gaitsim.stance.twin`) both read the gait from."""
    t = np.asarray(rec.t, float)
    result = detectors.detect("shoe", t, rec.acc, rec.gyr, max(THRESHOLDS), SIGMA_A, SIGMA_G, WINDOW)
    stances = group_stances(t, result.stationary)
    return result, stances, gait_events(rec.gyr, stances)


def foot_flat_profiles(rec: Recording, track_t: np.ndarray, track_pos: np.ndarray) -> Profiles:
    """Foot-flat profiles of ``rec`` with its site track (t (M,) s, pos (M, 3) m)."""
    t = np.asarray(rec.t, float)
    result, stances, events = detected_gait(rec)
    middles = stances.middles()
    velocity = site_velocity(track_t, track_pos)
    centres = resample(t[middles], track_t, track_pos[:, :2])
    shoe = np.full(len(t), np.nan)
    shoe[:len(result.statistic)] = np.log10(np.maximum(result.statistic, 1e-12))
    channels = {"rate_dps": np.degrees(np.linalg.norm(rec.gyr, axis=1)), "sagittal_rate_dps": np.degrees(rec.gyr[:, 1]),
                "log10_shoe": shoe}
    phase = np.linspace(-MARGIN, 1.0 + MARGIN, POINTS)
    rows = {name: [] for name in CHANNELS}
    durations = []
    for k in np.flatnonzero(events.complete()):
        if k == 0 or k == len(middles) - 1:
            continue
        forward = centres[k + 1] - centres[k - 1]
        forward = forward / np.linalg.norm(forward)
        t_ff, t_ho = t[events.ff[k]], t[events.ho[k]]
        at = t_ff + phase * (t_ho - t_ff)
        durations.append(t_ho - t_ff)
        for name, values in channels.items():
            rows[name].append(np.interp(at, t, values))
        v = resample(at, track_t, velocity)
        rows["forward_velocity_mps"].append(v[:, :2] @ forward)
        rows["vertical_velocity_mps"].append(v[:, 2])
    median, spread = {}, {}
    for name, values in rows.items():
        values = np.array(values)
        median[name] = np.nanmedian(values, axis=0)
        spread[name] = np.nanmedian(np.abs(values - median[name]), axis=0) / math.sqrt(max(len(values), 1))
    return Profiles(phase, median, spread, len(durations), float(np.median(durations)))
