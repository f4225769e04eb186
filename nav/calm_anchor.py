"""The anchored SHOE: a fixed-threshold zero-velocity test that also takes each stride's calmest stretch.

Rule. The fixed test of :mod:`nav.detectors` marks window k stationary when its statistic T(k) < gamma_0. The
anchor adds, where that test finds nothing for a while, the stride's calmest stretch. With Tc(k) the statistic
averaged over ``calm_s`` (centred) and h = ``half_span_s`` in windows,

    m(k) = min { Tc(j) : |j - k| <= h }
    window k is anchored when  T(j) >= gamma_0 for every |j - k| <= h  (the fixed test finds nothing near),
                               Tc(k) < widen * m(k),  m(k) < cap * gamma_0,
                               and k lies in one unbroken run of such windows that holds a valley (Tc(v) = m(v)),

so the decision is ``T(k) < gamma_0 or anchored(k)``. A valley is the calmest window within +-h; its run is the
stretch around it where the averaged statistic stays within ``widen`` times the valley's value.

Why. The fixed test (OpenShoe's) assumes the foot comes to rest in every stance. In running it does not: the
shoe rolls and pronates through the whole ground contact, and on tracked real runs the shared filter with a fixed
SHOE threshold missed stances and ended metres off (issue 17's measurement). Every stride still has a stance, and
the stance is the stride's calmest part: the stride-segmentation event of Rampp et al. (IEEE TBME 62(4):1089-1097,
2015; gaitmap's ``min_vel``) is exactly the minimum of the gyro energy inside the stance, and stride-level
trajectory methods for running integrate from it as a zero-velocity instant (Zrenner et al., Sensors 18(12):4194,
2018). The anchor applies that fact only where the fixed threshold fails:

- the anchor acts only where no window within +-h passed the fixed test, so wherever the fixed test finds the stance
  (every stride of the shared walking recordings and of the simulated walks) the decisions are the fixed test's,
  bit for bit;
- a valley must be the calmest window within +-h. From any instant of a walk a stance lies within h (h above
  half the slowest walking swing: 0.35 s at 60 steps/min), so a swing instant is never a valley while a stance
  is in reach; and the next stride's stance lies beyond h (h below the shortest running stride: 0.67 s at
  180 steps/min), so one stride's calmer stance (or a fixed-test pass there) does not hide the next one's.
  h = 0.5 s lies between the two;
- ``cap`` bounds how hard a valley may be and still count as a stance: pyshoe's motion-classified detector
  (Wagstaff, Peretroukhin & Kelly, IPIN 2017; the thresholds of utiasSTARS/pyshoe's code) uses for running a SHOE
  threshold 35x its walking threshold (a window-mean rate of ~94 against ~16 deg/s with its sigmas), the
  widest gate a published fixed setting gives running. Beyond it a valley is motion (a leg swung while sitting,
  a foot kept moving), not a stance;
- ``widen`` sets how much of the stance around the calmest instant is taken: the windows whose statistic is within
  that factor of the valley's, for a gyro-dominated statistic a rate within sqrt(widen) of the calmest rate.

The span is centred (non-causal): the detector looks h ahead, as an offline (smoothing) pipeline may.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import minimum_filter1d, uniform_filter1d

from .constants import DEFAULT_GRAVITY, DEFAULT_SIGMA_A, DEFAULT_SIGMA_G, DEFAULT_THRESHOLD, DEFAULT_WINDOW
from .detectors import SLIDING, DetectorResult, detect, spread_marks

ANCHOR_SEMANTICS = ("plus, where no window within +-h passes, the run of windows within widen x the calmest one's "
                    "statistic around it (per-stride calm anchor)")


@dataclass(frozen=True)
class CalmAnchor:
    """How the anchored SHOE takes each stride's calmest stretch (module docstring).

    Attributes
    ----------
    half_span_s : s, h: a valley is the calmest window within +-h. Default 0.5.
    widen : dimensionless, the anchored stretch is where T < widen x the valley's T. Default 4 (a gyro rate
        within 2x the calmest).
    cap : dimensionless, valleys with T >= cap x gamma_0 are motion, not stance. Default 35 (pyshoe's running
        threshold over its walking one).
    calm_s : s, the anchor compares the statistic averaged over this centred duration, so that a valley is a calm
        stretch, not an instant where the rate vector passes through zero (a few ms in a swing or at a forefoot
        landing). Default 0.02.
    """

    half_span_s: float = 0.5
    widen: float = 4.0
    cap: float = 35.0
    calm_s: float = 0.02

    def __post_init__(self):
        for name in ("half_span_s", "widen", "cap", "calm_s"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"CalmAnchor.{name} = {value!r}; must be a finite number > 0")
        if self.widen < 1 or self.cap < 1:
            raise ValueError(f"CalmAnchor: widen = {self.widen} and cap = {self.cap} must be >= 1")


def anchored_windows(stat: np.ndarray, threshold: float, fs: float, anchor: CalmAnchor) -> tuple[np.ndarray,
                                                                                                 np.ndarray]:
    """Windows the anchor adds to the fixed test, and the threshold each window was compared with.

    Parameters
    ----------
    stat : (..., M) the detector statistic T(k) of every window (dimensionless; leading axes: runs).
    threshold : gamma_0, the fixed threshold (dimensionless).
    fs : Hz, sample rate (one window per sample).
    anchor : CalmAnchor.

    Returns
    -------
    anchored : (..., M) bool, windows marked by the anchor (never one with T < gamma_0).
    gamma : (..., M) the effective threshold: gamma_0, or widen x m(k) inside an anchored run.
    """
    stat = np.asarray(stat, float)
    half = max(1, int(round(anchor.half_span_s * fs)))
    found_near = minimum_filter1d(stat, size=2 * half + 1, axis=-1, mode="nearest") < threshold
    calm = uniform_filter1d(stat, size=max(1, int(round(anchor.calm_s * fs))), axis=-1, mode="nearest")
    calmest = minimum_filter1d(calm, size=2 * half + 1, axis=-1, mode="nearest")
    candidate = (calm < anchor.widen * calmest) & ~found_near & (calmest < anchor.cap * threshold)
    valley = candidate & (calm == calmest)
    anchored = np.zeros_like(candidate)
    for row in np.ndindex(stat.shape[:-1]):
        run_id = np.cumsum(np.diff(candidate[row], prepend=False) & candidate[row]) * candidate[row]
        anchored[row] = np.isin(run_id, run_id[valley[row]]) & candidate[row]
    gamma = np.where(anchored, anchor.widen * calmest, threshold)
    return anchored, gamma


def detect_anchored(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, threshold: float = DEFAULT_THRESHOLD,
                    sigma_a: float = DEFAULT_SIGMA_A, sigma_g: float = DEFAULT_SIGMA_G, window: int = DEFAULT_WINDOW,
                    anchor: CalmAnchor = CalmAnchor(), gravity: float = DEFAULT_GRAVITY) -> DetectorResult:
    """Run the anchored SHOE (module docstring): OpenShoe's sliding-window SHOE plus each stride's calmest stretch.

    Parameters
    ----------
    t : (N,) s; acc : (..., N, 3) m/s^2; gyr : (..., N, 3) rad/s.
    threshold : gamma_0 (dimensionless); sigma_a : m/s^2; sigma_g : rad/s; window : W, samples; gravity : m/s^2.
    anchor : CalmAnchor.

    Returns
    -------
    DetectorResult; ``threshold`` holds the threshold every window was compared with.
    """
    fixed = detect("shoe", t, acc, gyr, threshold, sigma_a, sigma_g, window, gravity)
    anchored, gamma = anchored_windows(fixed.statistic, fixed.params.threshold, fixed.params.fs, anchor)
    params = dataclasses.replace(fixed.params, name="anchored", semantics=SLIDING + "; " + ANCHOR_SEMANTICS,
                                 adaptation=dataclasses.asdict(anchor))
    return DetectorResult(fixed.stationary | spread_marks(anchored, fixed.params.window), fixed.statistic, params,
                          gamma)
