"""Compiled Cholesky factor, solve and inverse for the small symmetric positive definite matrices of the filter."""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def cholesky_factor(A, m, L):
    """Lower Cholesky factor L of the symmetric m x m matrix A; returns False if A is not positive definite."""
    for i in range(m):
        for j in range(i + 1):
            s = A[i, j]
            for k in range(j):
                s -= L[i, k] * L[j, k]
            if i == j:
                if s <= 0.0:
                    return False
                L[i, i] = math.sqrt(s)
            else:
                L[i, j] = s / L[j, j]
    return True


@njit(cache=True)
def cholesky_solve(L, m, b, out):
    """Solve L L^T x = b into out, given the factor L from :func:`cholesky_factor`."""
    for i in range(m):
        s = b[i]
        for k in range(i):
            s -= L[i, k] * out[k]
        out[i] = s / L[i, i]
    for i in range(m - 1, -1, -1):
        s = out[i]
        for k in range(i + 1, m):
            s -= L[k, i] * out[k]
        out[i] = s / L[i, i]


@njit(cache=True)
def spd_inverse(A, diag, m, out):
    """out (3, 3) = (A + diag(diag))^-1 for the leading m x m block (m <= 3), zero elsewhere, from its Cholesky
    factor; returns False if that block is not positive definite."""
    S = np.empty((3, 3))
    L = np.zeros((3, 3))
    for i in range(m):
        for j in range(m):
            S[i, j] = A[i, j] + (diag[i] if i == j else 0.0)
    if not cholesky_factor(S, m, L):
        return False
    e = np.empty(3)
    col = np.empty(3)
    out[:, :] = 0.0
    for c in range(m):
        for i in range(m):
            e[i] = 1.0 if i == c else 0.0
        cholesky_solve(L, m, e, col)
        for i in range(m):
            out[i, c] = col[i]
    for i in range(m):  # exactly symmetric
        for j in range(i + 1, m):
            value = 0.5 * (out[i, j] + out[j, i])
            out[i, j] = value
            out[j, i] = value
    return True
