"""Compiled SHOE statistic: :func:`nav.detectors.statistic` ("shoe") in one pass over the samples.

numpy evaluates the statistic in about a dozen whole-array passes (the window sums, the spread about the window
mean, the norms), 140-220 ns per sample on this project's machines, a sixth of the forward filter it feeds. This
kernel performs the floating-point operations of :func:`nav.detectors.numpy_statistic` in the same order per
window, so the two statistics agree bit for bit (``tests/test_nav_detectors.py``).
"""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True, inline="always")
def _square_norm(x, y, z):
    """(x^2 + y^2) + z^2: :func:`nav.detectors.square_norm` on scalars."""
    return (x * x + y * y) + z * z


@njit(cache=True)
def shoe_statistic(acc, gyr, window, var_a, var_g, gravity, out):
    """SHOE statistic of every window start of every run, written into ``out``.

    Parameters
    ----------
    acc, gyr : (R, N, 3) C-contiguous float64, m/s^2 and rad/s (R runs of N samples).
    window : W, samples (1 <= W <= N).
    var_a, var_g : sigma_a^2 (m/s^2)^2 and sigma_g^2 (rad/s)^2.
    gravity : m/s^2.
    out : (R, N - W + 1) float64, dimensionless.

    Per window (in the order of :func:`nav.detectors.numpy_statistic`): the mean ybar of the specific force; its spread
    sum_l |y_l - y_k|^2 - W |ybar - y_k|^2 about the window's first sample y_k (floored at zero, NaN kept); then
    (spread + W (|ybar| - g)^2) / sigma_a^2 + sum_l |w_l|^2 / sigma_g^2, divided by W.
    """
    w = float(window)
    for r in range(acc.shape[0]):
        a, g = acc[r], gyr[r]
        for k in range(out.shape[1]):
            s0, s1, s2 = a[k, 0], a[k, 1], a[k, 2]
            rate = _square_norm(g[k, 0], g[k, 1], g[k, 2])
            for j in range(1, window):
                s0 += a[k + j, 0]
                s1 += a[k + j, 1]
                s2 += a[k + j, 2]
                rate += _square_norm(g[k + j, 0], g[k + j, 1], g[k + j, 2])
            m0, m1, m2 = s0 / w, s1 / w, s2 / w
            spread = 0.0
            for j in range(window):
                spread += _square_norm(a[k + j, 0] - a[k, 0], a[k + j, 1] - a[k, 1], a[k + j, 2] - a[k, 2])
            spread -= w * _square_norm(m0 - a[k, 0], m1 - a[k, 1], m2 - a[k, 2])
            if spread < 0.0:
                spread = 0.0
            excess = math.sqrt(_square_norm(m0, m1, m2)) - gravity
            out[r, k] = ((spread + w * (excess * excess)) / var_a + rate / var_g) / w
