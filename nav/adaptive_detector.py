"""Adaptive-threshold SHOE: a zero-velocity test whose threshold follows the gait's own motion intensity.

Statistic. The SHOE/GLRT statistic of :mod:`nav.detectors` (Skog et al., IEEE TBME 2010), over a window of fixed
*duration* ``window_s`` (W = round(window_s * fs) samples, at least 2), normalised by sigma_a (m/s^2) and sigma_g
(rad/s) as there:

    T(k) = (1/W) sum_l [ |y_a,l - g ybar_a/|ybar_a| |^2 / sigma_a^2 + |y_w,l|^2 / sigma_g^2 ],  l = k .. k+W-1

Gait intensity. The gyro part of the same statistic, R(k) = (1/W) sum_l |y_w,l|^2 / sigma_g^2 (the ARE statistic),
and its largest value over a span of ``span_s`` seconds centred on window k:

    M(k) = max { R(j) : |j - k| <= span/2 }

Over a span longer than the gait cycle, M(k) is the square of the stride's peak swing rate in units of sigma_g:
(omega_peak / sigma_g)^2.

Decision rule. Window k is stationary when

    T(k) < gamma(k) = max(gamma_0, ratio * M(k)),

and, as in OpenShoe, all W samples of a stationary window are marked. gamma_0 is the fixed SHOE threshold (the
floor, used on standing and whenever the gait is gentle); ``ratio`` (dimensionless) says how far below the
stride's peak swing energy the foot must come to count as still: for the gyro alone the test reads
|omega| < max(sigma_g sqrt(gamma_0), sqrt(ratio) omega_peak), a gate proportional to the stride's peak rate. A
faster gait (running: peak rates 2-3x walking's, a stance that never comes fully to rest) therefore gets a
proportionally wider gate, while standing and slow walking keep the fixed floor.

Why these two choices (see the module's tests for the laws):

- The window is a duration, not a sample count, because the quantity that separates a stance (>= ~0.1 s of
  near-rest, even in running) from the brief instant in mid- or late swing where the rate vector passes through
  zero while |specific force| passes through g (a few ms) is time. A fixed sample count means 3.75 ms at 800 Hz
  and 50 ms at 60 Hz; at 800 Hz such swing instants pass a 3-sample test, and each false update there drags the
  position back by about foot speed x time since the last stance.
- The threshold scales with the gait's peak rate after the adaptive schemes that scale with gait speed or
  motion type: Wang and Shkel (IEEE Sensors Letters 3(11), 2019, doi:10.1109/LSENS.2019.2946129: 80 to 160
  steps/min without retuning), Wagstaff, Peretroukhin and Kelly (IPIN 2017, pyshoe: a per-motion-class threshold,
  running's 35x walking's) and Tian et al. (Sensors 16(10):1578, 2016: threshold as a function of gait
  frequency). The peak rate is measured from the signal itself, so there is no classifier and no fitted
  threshold-versus-frequency curve; with ``ratio = 0`` the detector is the fixed SHOE with a W-sample window.

The span is centred (non-causal): the detector sees up to span/2 ahead, as an offline (smoothing) pipeline may.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from scipy.ndimage import maximum_filter1d

from .detectors import SLIDING, DetectorParams, DetectorResult, sample_rate, spread_marks, statistic, window_sum


@dataclass(frozen=True)
class AdaptiveThreshold:
    """How the adaptive SHOE sets its threshold (the floor gamma_0 is ``NavOptions.threshold``).

    Attributes
    ----------
    ratio : dimensionless, gamma(k) = max(gamma_0, ratio * M(k)) with M(k) the span's peak gyro energy in units of
        sigma_g^2. 0 turns the adaptation off (fixed SHOE). Default 1e-3: a gyro gate of 3.2 % of the stride's
        peak rate.
    span_s : s, width of the centred span the peak is taken over; longer than the slowest gait cycle expected
        (60 steps/min: 2 s). Default 2.5.
    window_s : s, duration of the GLRT window. Default 0.05.
    """

    ratio: float = 1e-3
    span_s: float = 2.5
    window_s: float = 0.05

    def __post_init__(self):
        for name in ("ratio", "span_s", "window_s"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"AdaptiveThreshold.{name} = {value!r}; must be a finite number >= 0")
        if self.window_s <= 0 or self.span_s <= 0:
            raise ValueError(f"AdaptiveThreshold: window_s = {self.window_s} s and span_s = {self.span_s} s must be "
                             "> 0")

    def window_samples(self, fs: float) -> int:
        """W (samples) of a ``window_s`` window at ``fs`` Hz, at least 2 (one sample has no spread)."""
        return max(2, int(round(self.window_s * fs)))


def gait_intensity(gyr: np.ndarray, sigma_g: float, window: int, span: int) -> np.ndarray:
    """M(k): largest gyro energy R(j) (units of sigma_g^2) over the ``span`` windows centred on window k.

    Parameters
    ----------
    gyr : (..., N, 3) rad/s; sigma_g : rad/s; window : W, samples; span : windows (>= 1).

    Returns
    -------
    (..., N - W + 1) dimensionless.
    """
    energy = window_sum(np.einsum("...i,...i->...", gyr, gyr), window) / (sigma_g**2 * window)
    return maximum_filter1d(energy, size=max(1, int(span)), axis=-1, mode="nearest")


def detect_adaptive(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, threshold: float, sigma_a: float,
                    sigma_g: float, adaptive: AdaptiveThreshold = AdaptiveThreshold(),
                    gravity: float = 9.81) -> DetectorResult:
    """Run the adaptive-threshold SHOE (module docstring).

    Parameters
    ----------
    t : (N,) s; acc : (..., N, 3) m/s^2; gyr : (..., N, 3) rad/s.
    threshold : gamma_0, the floor (dimensionless); sigma_a : m/s^2; sigma_g : rad/s; gravity : m/s^2.
    adaptive : ratio, span and window.

    Returns
    -------
    DetectorResult; ``threshold`` holds gamma(k) of every window.
    """
    if not (sigma_a > 0 and sigma_g > 0 and threshold > 0):
        raise ValueError(f"detector sigmas and threshold must be positive: sigma_a={sigma_a} m/s^2, "
                         f"sigma_g={sigma_g} rad/s, threshold={threshold}")
    fs = sample_rate(t)
    window = adaptive.window_samples(fs)
    stat = statistic("shoe", acc, gyr, sigma_a, sigma_g, window, gravity)
    span = max(1, int(round(adaptive.span_s * fs)))
    gamma = np.maximum(threshold, adaptive.ratio * gait_intensity(np.asarray(gyr, float), sigma_g, window, span))
    params = DetectorParams("adaptive", float(threshold), float(sigma_a), float(sigma_g), window, fs, float(gravity),
                            SLIDING + "; threshold max(gamma_0, ratio x peak gyro energy over a centred span)",
                            adaptation=asdict(adaptive))
    return DetectorResult(spread_marks(stat < gamma, window), stat, params, gamma)
