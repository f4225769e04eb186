"""Gait-cycle averages (the paper's Fig. 2-4) and the analytic length-loss prediction of Fig. 5.

Cycles run from one initial contact to the next, resampled on a common phase grid and averaged; times are
phase x mean cycle duration. Foot velocity comes from the simulated 60 Hz tracker (what the paper measured),
expressed in the walking frame (forward, left, up).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nav import detectors
from nav.recording import Recording
from nav.series import resample
from nav.zupt_velocity import to_heading_frame

from .tracker import TrackerSpec, track

PHASES = 400


@dataclass
class CycleAverages:
    """Averages over ``cycles`` gait cycles on ``phase`` (0..1); ``time`` = phase x mean cycle (s)."""

    phase: np.ndarray
    time: np.ndarray
    velocity: np.ndarray  # (cycles, P, 3) m/s tracked, walking frame
    true_velocity: np.ndarray  # (cycles, P, 3) m/s exact
    statistic: np.ndarray  # (cycles, P) SHOE statistic
    detected: dict  # threshold -> (cycles, P) bool
    cycle_s: float


def cycle_averages(rec: Recording, cycles: int, sigma_a: float, sigma_g: float, window: int, thresholds,
                   tracker: TrackerSpec, rng: np.random.Generator) -> CycleAverages:
    """Resample tracked velocity, true velocity, the SHOE statistic and detections onto the gait cycle."""
    ev, tr = rec.events, rec.truth
    ic = ev.t_ic[1:]  # stance 0 is the initial standing
    ic = ic[: cycles + 1]
    phase = (np.arange(PHASES) + 0.5) / PHASES
    tracked = track(tr, tracker, rng)
    yaw_q = tr.quat  # the walking frame follows the foot's heading
    v_true = to_heading_frame(tr.vel, yaw_q)
    v_tracked = to_heading_frame(
        resample(rec.t, tracked.t, tracked.vel), yaw_q)
    stat = detectors.statistic("shoe", rec.acc, rec.gyr, sigma_a, sigma_g, window)
    stat = np.concatenate([stat, np.full(len(rec.t) - len(stat), stat[-1])])
    detected = {thr: detectors.detect("shoe", rec.t, rec.acc, rec.gyr, thr, sigma_a, sigma_g, window).stationary
                for thr in thresholds}
    n = len(ic) - 1
    times = ic[:-1, None] + phase[None, :] * np.diff(ic)[:, None]
    on = lambda x: np.interp(times.ravel(), rec.t, x).reshape(n, PHASES)  # noqa: E731
    vel = np.stack([on(v_tracked[:, i]) for i in range(3)], -1)
    true = np.stack([on(v_true[:, i]) for i in range(3)], -1)
    det = {thr: on(d.astype(float)) > 0.5 for thr, d in detected.items()}
    cycle_s = float(np.mean(np.diff(ic)))
    return CycleAverages(phase, phase * cycle_s, vel, true, on(stat), det, cycle_s)


def detected_stance_s(avg: CycleAverages) -> dict:
    """Mean detected stance per cycle (s) and its mean start / end within the cycle (s), per threshold."""
    out = {}
    for thr, det in avg.detected.items():
        first = np.array([avg.time[np.argmax(d)] if d.any() else np.nan for d in det])
        last = np.array([avg.time[len(d) - 1 - np.argmax(d[::-1])] if d.any() else np.nan for d in det])
        out[thr] = {"duration_s": float(det.mean(axis=1).mean() * avg.cycle_s),
                    "start_s": float(np.nanmean(first)), "end_s": float(np.nanmean(last))}
    return out


def predicted_length_loss(avg: CycleAverages, detected: dict, strides: int) -> dict:
    """Fig. 5's analysis: strides x cycle time x integral over phase of the mean tracked forward velocity times
    the probability that the detector marks that phase stationary (m over the walk), per threshold."""
    v_forward = avg.velocity[:, :, 0].mean(axis=0)
    return {thr: float(strides * avg.cycle_s * np.mean(v_forward * det.mean(axis=0)))
            for thr, det in detected.items()}
