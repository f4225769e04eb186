"""Compiled Cholesky factor and solve for the small symmetric positive definite matrices of the filter."""

from __future__ import annotations

import math

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
