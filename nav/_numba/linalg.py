"""Compiled inverse of the filter's small (at most 3 x 3) symmetric positive definite matrices, on scalars."""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True, inline="always")
def _solve_unit(c, l00, l10, l11, l20, l21, l22):
    """Column c of (L L^T)^-1, as a 3-tuple, for the lower triangular L: L y = e_c forward, then L^T x = y."""
    y0 = (1.0 if c == 0 else 0.0) / l00
    y1 = ((1.0 if c == 1 else 0.0) - l10 * y0) / l11
    y2 = ((1.0 if c == 2 else 0.0) - l20 * y0 - l21 * y1) / l22
    x2 = y2 / l22
    x1 = (y1 - l21 * x2) / l11
    x0 = (y0 - l10 * x1 - l20 * x2) / l00
    return x0, x1, x2


@njit(cache=True, inline="always")
def spd_inverse3(s00, s10, s11, s20, s21, s22):
    """Inverse of the symmetric 3 x 3 matrix S (its lower triangle given) from its Cholesky factor.

    Returns (ok, i00, i01, i02, i11, i12, i22): ``ok`` False (and zeros) if S is not positive definite, else the
    upper triangle of S^-1, each off-diagonal value the mean of the two the solve gives (so that it is exactly
    symmetric). A smaller m x m matrix is inverted exactly so when padded with the identity (rows and columns m..2):
    every operation on the padding adds or subtracts a zero.
    """
    if s00 <= 0.0:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    l00 = math.sqrt(s00)
    l10 = s10 / l00
    d11 = s11 - l10 * l10
    if d11 <= 0.0:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    l11 = math.sqrt(d11)
    l20 = s20 / l00
    l21 = (s21 - l20 * l10) / l11
    d22 = s22 - l20 * l20 - l21 * l21
    if d22 <= 0.0:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    l22 = math.sqrt(d22)
    a0, a1, a2 = _solve_unit(0, l00, l10, l11, l20, l21, l22)
    b0, b1, b2 = _solve_unit(1, l00, l10, l11, l20, l21, l22)
    c0, c1, c2 = _solve_unit(2, l00, l10, l11, l20, l21, l22)
    return True, a0, 0.5 * (b0 + a1), 0.5 * (c0 + a2), b1, 0.5 * (c1 + b2), c2
