"""The seed paper's Fig. 5 on any recording with a position track of its IMU site: per zero-velocity threshold,
the detected windows, the mean velocity of the IMU site inside them and the stance-to-stance length
underestimate of the shared filter, with bootstrap uncertainties over strides.

Definitions (the same for a measured recording and its simulated twin):

- The filter runs with :func:`nav_options` (SHOE, sigma_a 0.01 m/s^2, sigma_g 0.07 deg/s, window 3 samples,
  9 states: the settings the issue measured real feet with) and the pipeline's mechanisation (default
  automatic: RK4 on point samples, the exact increments of a simulated ideal sensor; the stance study runs
  its twins through both, :mod:`gaitsim.stance.command`).
- Detected stances: :func:`gaitsim.stance.events.group_stances` of the filter's zero-velocity flags, from the
  filter's start on. *Walking stances* exclude the first and the last (the rests at the ends) and any longer
  than ``MAX_STANCE_S``.
- Length underestimate (%): ``100 (1 - sum |e_{s+1} - e_s| / sum |r_{s+1} - r_s|)`` over consecutive detected
  stances, with e the solution's and r the track's horizontal position at each stance's middle sample:
  independent of rotation, reflection and start alignment.
- Window length (s): detected samples of a walking stance over the sample rate; reported as the mean over
  walking stances.
- In-window velocity (m/s): the track's forward displacement summed over the detected runs of the walking
  stances over their summed durations, forward being the horizontal direction from the previous to the next
  stance's middle.
- Stance-velocity share of the underestimate: the filter is run a second time with the track's own velocity
  as the stance pseudo-measurement (:func:`track_pseudo_velocity`: in each zero-velocity run, the track's
  mean velocity over that run, in the walking frame, forward along the stride; the filter applies it along
  its own heading, so a toe-out of a few degrees turns a few percent of it sideways). What that removes is the share the foot's motion inside
  the windows causes; what remains comes from elsewhere (sensor errors, integration, the swing).
- Level: the mean of a curve over the thresholds, with its bootstrap spread from the same draws (the loop's
  Fig. 5 residuals, :mod:`gaitsim.loop.fig5`).
- Uncertainty: bootstrap over strides, in blocks of ``BLOCK_STRIDES`` consecutive strides: an error in the
  solution's position at one stance middle lengthens one step and shortens the next, so neighbouring steps
  are anticorrelated and only whole runs of strides resample the sum's spread. The walk is cut into blocks at
  every ``BLOCK_STRIDES``-th middle of the stances detected at the largest threshold; each step and window
  belongs to the block holding its start, each stance to the block holding its middle; ``BOOTSTRAP`` resamples of blocks (the same for every
  threshold, seeded) give each curve's standard deviation, and the slope's (largest minus smallest
  threshold) from the same draws.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nav import pipeline
from nav.ekf import FilterConfig
from nav.recording import Recording
from nav.zupt_velocity import rotate_to_heading
from nav.series import resample

from .events import DetectedStances, group_stances

THRESHOLDS = (1.0e4, 2.0e4, 3.0e4, 4.0e4, 5.0e4)
SIGMA_A = 0.01  # m/s^2
SIGMA_G = math.radians(0.07)  # rad/s
WINDOW = 3  # samples
STATES = 9
MAX_STANCE_S = 2.0  # s, longer detected stances are rests, not steps
BOOTSTRAP = 1000
BOOTSTRAP_SEED = 11
BLOCK_STRIDES = 4


def nav_options(threshold: float, stance_velocity: np.ndarray | None = None, method: str = "auto") -> pipeline.NavOptions:
    """The issue's filter settings at zero-velocity threshold ``threshold`` (dimensionless SHOE gamma), with an
    optional per-sample stance pseudo-velocity (N, 3) m/s in the heading frame (default zero) and the
    mechanisation ``method`` (:class:`nav.pipeline.NavOptions`: "auto", "rk4" or "increments")."""
    return pipeline.NavOptions(detector="shoe", threshold=threshold, sigma_a=SIGMA_A, sigma_g=SIGMA_G,
                               window=WINDOW, filter=FilterConfig(states=STATES), stance_velocity=stance_velocity,
                               method=method)


def _at(t_query: np.ndarray, t: np.ndarray, pos: np.ndarray) -> np.ndarray:
    """(M, 3) positions of the finite rows of a track (t (N,) s, pos (N, 3) m) interpolated at ``t_query``."""
    ok = np.all(np.isfinite(pos), axis=1)
    return np.stack([np.interp(t_query, t[ok], pos[ok, i], left=np.nan, right=np.nan) for i in range(3)], -1)


@dataclass
class ThresholdResult:
    """Everything one threshold gives on one recording (SI units).

    Attributes
    ----------
    threshold : SHOE gamma.
    step_start : (S-1,) s, time of the first stance middle of each step.
    step_estimate, step_track : (S-1,) m, horizontal distance between consecutive stance middles in the
        solution and in the track (NaN where the track has none).
    walking : (S,) bool, walking stances (module docstring).
    stance_time : (S,) s, middle of each stance.
    window : (S,) s, detected samples of each stance over the sample rate.
    window_displacement : (S,) m, forward displacement of the track summed over the stance's detected runs.
    window_duration : (S,) s, summed durations of those runs (first to last sample of each).
    step_estimate_track_pseudo : (S-1,) m, as ``step_estimate`` with the track's velocity as the stance
        pseudo-measurement.
    """

    threshold: float
    step_start: np.ndarray
    step_estimate: np.ndarray
    step_track: np.ndarray
    step_estimate_track_pseudo: np.ndarray
    walking: np.ndarray
    stance_time: np.ndarray
    window: np.ndarray
    window_displacement: np.ndarray
    window_duration: np.ndarray

    def underestimate_pct(self, steps: np.ndarray | None = None, track_pseudo: bool = False) -> float:
        """Length underestimate (%) over the given steps (index array; default all with a track), of the
        solution with zero or (``track_pseudo``) the track's velocity as stance pseudo-measurement."""
        ok = np.isfinite(self.step_track)
        idx = np.flatnonzero(ok) if steps is None else steps[ok[steps]]
        estimate = self.step_estimate_track_pseudo if track_pseudo else self.step_estimate
        return 100.0 * (1.0 - estimate[idx].sum() / self.step_track[idx].sum())

    def in_window_velocity(self, stances: np.ndarray | None = None) -> float:
        """m/s, duration-weighted mean forward velocity of the track in the walking stances' windows."""
        ok = self.walking & np.isfinite(self.window_displacement)
        idx = np.flatnonzero(ok) if stances is None else stances[ok[stances]]
        return float(self.window_displacement[idx].sum() / self.window_duration[idx].sum())

    def window_mean(self, stances: np.ndarray | None = None) -> float:
        """s, mean detected window of the walking stances."""
        idx = np.flatnonzero(self.walking) if stances is None else stances[self.walking[stances]]
        return float(self.window[idx].mean())


def _forward(middle_pos: np.ndarray) -> np.ndarray:
    """(S, 2) horizontal unit vectors from each stance's previous to its next stance (one-sided at the ends)."""
    xy = middle_pos[:, :2]
    ahead = np.vstack([xy[1:], xy[-1:]])
    behind = np.vstack([xy[:1], xy[:-1]])
    d = ahead - behind
    return d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-12)


@dataclass
class Windows:
    """The detected stances of a recording and what its site track does inside them (SI units).

    Attributes
    ----------
    stances : the detected stances (from the given start on).
    stance_time : (S,) s, middle of each stance.   middle_pos : (S, 3) m, the track there.
    walking : (S,) bool, walking stances (module docstring).
    window : (S,) s, detected samples of each stance over the sample rate.
    displacement : (S,) m, forward displacement of the track summed over the stance's detected runs.
    duration : (S,) s, summed durations of those runs (first to last sample of each).
    """

    stances: DetectedStances
    stance_time: np.ndarray
    middle_pos: np.ndarray
    walking: np.ndarray
    window: np.ndarray
    displacement: np.ndarray
    duration: np.ndarray


def _runs(stances: DetectedStances) -> tuple[np.ndarray, np.ndarray]:
    """The zero-velocity runs (R, 2) [start, end) of all stances in order, and the stance each belongs to (R,)."""
    runs = np.concatenate(stances.runs) if len(stances) else np.empty((0, 2), int)
    return runs, np.repeat(np.arange(len(stances)), [len(r) for r in stances.runs])


def windows(t: np.ndarray, stationary: np.ndarray, track_t: np.ndarray, track_pos: np.ndarray) -> Windows:
    """Detected stances of zero-velocity flags ``stationary`` (N,) on the clock ``t`` (N,) s and the site
    track (t (M,) s, pos (M, 3) m) inside them."""
    stances = group_stances(t, stationary)
    middles = t[stances.middles()]
    ref = _at(middles, track_t, track_pos)
    window = stances.detected_samples() / (1.0 / np.median(np.diff(t)))
    walking = np.zeros(len(stances), bool)
    walking[1:-1] = window[1:-1] <= MAX_STANCE_S
    forward = _forward(ref) if len(stances) > 1 else np.zeros((len(stances), 2))
    runs, owner = _runs(stances)
    first, last = t[runs[:, 0]], t[runs[:, 1] - 1]
    moved = _at(last, track_t, track_pos)[:, :2] - _at(first, track_t, track_pos)[:, :2]
    displacement = np.bincount(owner, np.einsum("ij,ij->i", moved, forward[owner]), minlength=len(stances))
    duration = np.bincount(owner, last - first, minlength=len(stances))
    return Windows(stances, middles, ref, walking, window, displacement, duration)


def track_pseudo_velocity(t: np.ndarray, track_t: np.ndarray, track_pos: np.ndarray, w: Windows) -> np.ndarray:
    """(N, 3) m/s on the clock ``t``: in every zero-velocity run of the detected stances, the track's mean
    velocity over that run (end minus start position over its duration) in the stance's walking frame
    (forward along its stride, left, up); zero elsewhere."""
    out = np.zeros((len(t), 3))
    runs, owner = _runs(w.stances)
    first, last = t[runs[:, 0]], t[runs[:, 1] - 1]
    forward = _forward(w.middle_pos)[owner]
    velocity = rotate_to_heading((_at(last, track_t, track_pos) - _at(first, track_t, track_pos))
                                 / (last - first)[:, None], forward[:, 0], forward[:, 1])
    for (a, b), v in zip(runs, velocity):
        if np.all(np.isfinite(v)):
            out[a:b] = v
    return out


def _steps(sol, w: Windows) -> np.ndarray:
    est = resample(w.stance_time, sol.t, sol.pos[:, :2])
    return np.linalg.norm(np.diff(est, axis=0), axis=1)


def run_thresholds(rec: Recording, track_t: np.ndarray, track_pos: np.ndarray, thresholds, method: str = "auto",
                   track_pseudo: bool = True) -> list[ThresholdResult]:
    """Navigate ``rec`` at each of the ``thresholds`` (mechanisation ``method``; the recording's input checks run
    once for all, :func:`nav.pipeline.navigate_variants`) and measure each against the site track (t (N,) s,
    pos (N, 3) m); without ``track_pseudo`` the second navigation (the track's velocity as the stance
    pseudo-measurement) is skipped and ``step_estimate_track_pseudo`` is NaN."""
    t = np.asarray(rec.t, float)
    solutions = pipeline.navigate_variants(rec, [nav_options(th, method=method) for th in thresholds])
    found = []
    for sol in solutions:
        stationary = np.asarray(sol.stationary, bool).copy()
        stationary[:sol.start] = False
        found.append(windows(t, stationary, track_t, track_pos))
    steps = [_steps(sol, w) for sol, w in zip(solutions, found)]
    if track_pseudo:
        options = [nav_options(th, track_pseudo_velocity(t, track_t, track_pos, w), method)
                   for th, w in zip(thresholds, found)]
        pseudo = pipeline.navigate_variants(rec, options)
        steps_pseudo = [_steps(sol, w) for sol, w in zip(pseudo, found)]
    else:
        steps_pseudo = [np.full_like(s, np.nan) for s in steps]
    return [ThresholdResult(
        threshold=float(th), step_start=w.stance_time[:-1], step_estimate=s,
        step_track=np.linalg.norm(np.diff(w.middle_pos[:, :2], axis=0), axis=1),
        step_estimate_track_pseudo=s_pseudo,
        walking=w.walking, stance_time=w.stance_time, window=w.window, window_displacement=w.displacement,
        window_duration=w.duration) for th, w, s, s_pseudo in zip(thresholds, found, steps, steps_pseudo)]


@dataclass
class Curve:
    """One quantity against the threshold with its bootstrap standard deviation.

    Attributes
    ----------
    value : (T,) the quantity at each threshold.
    sd : (T,) bootstrap standard deviation.
    slope : value at the largest minus at the smallest threshold.
    slope_sd : its bootstrap standard deviation.
    level : mean of ``value`` over the thresholds.
    level_sd : its bootstrap standard deviation.
    """

    value: np.ndarray
    sd: np.ndarray
    slope: float
    slope_sd: float
    level: float
    level_sd: float

    def as_dict(self) -> dict:
        return {"value": self.value.tolist(), "sd": self.sd.tolist(), "slope": self.slope, "slope_sd": self.slope_sd,
                "level": self.level, "level_sd": self.level_sd}


QUANTITIES = {
    "underestimate_pct": lambda r, steps, stances: r.underestimate_pct(steps),
    "underestimate_track_pseudo_pct": lambda r, steps, stances: r.underestimate_pct(steps, track_pseudo=True),
    "stance_velocity_share_pct": lambda r, steps, stances: (r.underestimate_pct(steps)
                                                            - r.underestimate_pct(steps, track_pseudo=True)),
    "in_window_velocity_mps": lambda r, steps, stances: r.in_window_velocity(stances),
    "window_s": lambda r, steps, stances: r.window_mean(stances),
}
TRACK_PSEUDO_QUANTITIES = ("underestimate_track_pseudo_pct", "stance_velocity_share_pct")  # need 2nd navigation


@dataclass
class Sweep:
    """A recording's threshold sweep: the curves of :data:`QUANTITIES` over the thresholds."""

    thresholds: np.ndarray
    curves: dict
    strides: int

    def as_dict(self) -> dict:
        return {"thresholds": self.thresholds.tolist(), "strides": self.strides,
                **{name: curve.as_dict() for name, curve in self.curves.items()}}


def _curve(values: np.ndarray, draws: np.ndarray) -> Curve:
    return Curve(values, np.nanstd(draws, axis=0, ddof=1), float(values[-1] - values[0]),
                 float(np.nanstd(draws[:, -1] - draws[:, 0], ddof=1)), float(np.mean(values)),
                 float(np.nanstd(np.mean(draws, axis=1), ddof=1)))


def sweep(rec: Recording, track_t: np.ndarray, track_pos: np.ndarray, thresholds=THRESHOLDS,
          bootstrap: int = BOOTSTRAP, seed: int = BOOTSTRAP_SEED, method: str = "auto",
          quantities=tuple(QUANTITIES)) -> Sweep:
    """Threshold sweep of ``rec`` against its site track with bootstrap curves (module docstring) of the named
    ``quantities`` (keys of :data:`QUANTITIES`), navigated with the mechanisation ``method``; the track's
    pseudo-measurement run only when a quantity needs it (:data:`TRACK_PSEUDO_QUANTITIES`)."""
    unknown = sorted(set(quantities) - set(QUANTITIES))
    if unknown:
        raise ValueError(f"sweep: quantities {unknown} unknown; allowed: {', '.join(QUANTITIES)}")
    thresholds = np.asarray(sorted(thresholds), float)
    pseudo = any(name in TRACK_PSEUDO_QUANTITIES for name in quantities)
    results = run_thresholds(rec, track_t, track_pos, thresholds, method, pseudo)
    edges = results[-1].stance_time[BLOCK_STRIDES::BLOCK_STRIDES]
    blocks = len(edges) + 1

    def members(times: np.ndarray) -> list[np.ndarray]:
        block = np.searchsorted(edges, times, side="right")
        return [np.flatnonzero(block == b) for b in range(blocks)]

    step_members = [members(r.step_start) for r in results]
    stance_members = [members(r.stance_time) for r in results]
    rng = np.random.default_rng(seed)
    picks = rng.integers(0, blocks, size=(bootstrap, blocks))
    # the steps and stances of every resample at every threshold, drawn once for all quantities
    resamples = [[(np.concatenate([step_members[j][p] for p in pick]),
                   np.concatenate([stance_members[j][p] for p in pick])) for j in range(len(results))]
                 for pick in picks]
    curves = {}
    for name in quantities:
        quantity = QUANTITIES[name]
        values = np.array([quantity(r, None, None) for r in results])
        draws = np.full((bootstrap, len(results)), np.nan)
        for b, drawn in enumerate(resamples):
            for j, (r, (steps, stances)) in enumerate(zip(results, drawn)):
                if len(steps) and np.any(r.walking[stances]):
                    draws[b, j] = quantity(r, steps, stances)
        curves[name] = _curve(values, draws)
    return Sweep(thresholds, curves, strides=int(np.sum(results[-1].walking)))
