"""Overlapping Allan deviation and the read-outs of the usual noise terms (IEEE Std 952 conventions).

Read-outs (anchors §5): white noise N is sigma(tau) sqrt(tau) on the -1/2 slope (sigma(1 s) = N); rate random
walk K is sigma(tau) sqrt(3/tau) on the +1/2 slope; bias instability B is the flat part of the curve divided
by 0.664 (here: the peak of a first-order Gauss-Markov process's curve, see :mod:`gaitsim.imu.model`).
"""

from __future__ import annotations

import numpy as np

BIAS_INSTABILITY_FLOOR = 0.664  # sigma_floor / B for 1/f (flicker) bias noise
# (tau_peak / tau_c, sigma_peak / sigma) of a first-order Gauss-Markov process's Allan deviation: what
# gauss_markov_peak() finds (tests/test_imu_allan.py recomputes it), kept as numbers so that simulating a sensor
# does not import scipy.optimize (~0.35 s of every process)
GAUSS_MARKOV_PEAK = (1.8926178613844984, 0.6173642831444415)


def log_spaced_clusters(n_samples: int, n_points: int = 40, max_fraction: float = 0.1) -> np.ndarray:
    """Distinct cluster sizes m (samples), log-spaced from 1 to ``max_fraction * n_samples``."""
    top = max(1, int(max_fraction * n_samples))
    return np.unique(np.round(np.logspace(0, np.log10(top), n_points)).astype(int))


def allan_deviation(x: np.ndarray, rate_hz: float, clusters: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Overlapping Allan deviation of rate-type data.

    Parameters
    ----------
    x : (N,) or (N, k) samples of a rate quantity (e.g. rad/s or m/s^2), uniformly sampled.
    rate_hz : sample rate, Hz.
    clusters : cluster sizes m in samples (tau = m / rate_hz); default :func:`log_spaced_clusters`.

    Returns
    -------
    taus : (n_tau,) averaging times, s.
    adev : (n_tau,) or (n_tau, k) Allan deviation, in the unit of ``x``.
    """
    x = np.asarray(x, float)
    n = x.shape[0]
    m_values = log_spaced_clusters(n) if clusters is None else np.asarray(clusters, int)
    if np.any(m_values < 1) or np.any(2 * m_values >= n):
        raise ValueError(f"cluster sizes must lie in [1, {(n - 1) // 2}] for {n} samples, got {m_values.tolist()}")
    dt = 1.0 / rate_hz
    theta = np.concatenate([np.zeros((1,) + x.shape[1:]), np.cumsum(x, axis=0) * dt])  # integrated signal
    adev = []
    for m in m_values:
        tau = m * dt
        second_difference = theta[2 * m:] - 2.0 * theta[m:-m] + theta[:-2 * m]
        adev.append(np.sqrt(np.mean(second_difference**2, axis=0) / (2.0 * tau**2)))
    return m_values * dt, np.array(adev)


def _log_mean_scaled(taus, adev, tau_range, scale):
    """Geometric mean over taus in ``tau_range`` of ``adev * scale`` (scale per tau), per column."""
    pick = (taus >= tau_range[0]) & (taus <= tau_range[1])
    if not np.any(pick):
        raise ValueError(f"no tau in {tau_range} s among {taus.min():.3g}..{taus.max():.3g} s")
    scaled = adev[pick] * scale[pick].reshape(-1, *([1] * (adev.ndim - 1)))
    return np.exp(np.mean(np.log(scaled), axis=0))


def white_noise_density(taus: np.ndarray, adev: np.ndarray, tau_range: tuple[float, float]) -> np.ndarray:
    """Noise density N = sigma(tau) sqrt(tau), averaged in the log over taus within ``tau_range`` (s).

    Returns N in (unit of the data)/sqrt(Hz), per column of ``adev``.
    """
    return _log_mean_scaled(taus, adev, tau_range, np.sqrt(taus))


def rate_random_walk(taus: np.ndarray, adev: np.ndarray, tau_range: tuple[float, float]) -> np.ndarray:
    """Rate random walk K = sigma(tau) sqrt(3 / tau), averaged in the log over taus within ``tau_range`` (s).

    Returns K in (unit of the data)/sqrt(s), per column of ``adev``.
    """
    return _log_mean_scaled(taus, adev, tau_range, np.sqrt(3.0 / taus))


def bias_instability(adev: np.ndarray) -> np.ndarray:
    """Bias instability B = max over tau of sigma(tau) / 0.664, for data whose curve has one hump or plateau
    (a Gauss-Markov bias alone). Returns B in the unit of the data, per column."""
    return np.max(adev, axis=0) / BIAS_INSTABILITY_FLOOR


def gauss_markov_allan_deviation(taus: np.ndarray, sigma: float, tau_c: float) -> np.ndarray:
    """Closed-form Allan deviation of a stationary first-order Gauss-Markov process.

    Parameters
    ----------
    taus : averaging times, s.
    sigma : stationary standard deviation of the process (unit of the data).
    tau_c : correlation time, s.
    """
    x = np.asarray(taus, float) / tau_c
    avar = sigma**2 * (2.0 / x) * (1.0 - (3.0 - 4.0 * np.exp(-x) + np.exp(-2.0 * x)) / (2.0 * x))
    return np.sqrt(avar)


def gauss_markov_peak() -> tuple[float, float]:
    """(tau_peak / tau_c, sigma_peak / sigma) of a first-order Gauss-Markov process's Allan deviation
    (about 1.893 and 0.6174), by maximising :func:`gauss_markov_allan_deviation`; the simulator uses the result,
    :data:`GAUSS_MARKOV_PEAK`."""
    from scipy.optimize import minimize_scalar

    result = minimize_scalar(lambda x: -gauss_markov_allan_deviation(x, 1.0, 1.0), bounds=(0.1, 20.0),
                             method="bounded", options={"xatol": 1e-10})
    return float(result.x), float(-result.fun)
