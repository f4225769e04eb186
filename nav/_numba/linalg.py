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
def cholesky_solve(L, m, B, X):
    """Solve L L^T X = B for the m columns of B (m x m) into X, given the factor L from :func:`cholesky_factor`.

    The columns are solved side by side, so that their divisions overlap; each column sees the operations of a
    solve on its own, in the same order.
    """
    for i in range(m):
        for c in range(m):
            s = B[i, c]
            for k in range(i):
                s -= L[i, k] * X[k, c]
            X[i, c] = s / L[i, i]
    for i in range(m - 1, -1, -1):
        for c in range(m):
            s = X[i, c]
            for k in range(i + 1, m):
                s -= L[k, i] * X[k, c]
            X[i, c] = s / L[i, i]


@njit(cache=True)
def inverse_buffers():
    """Work buffers of :func:`spd_inverse` (allocated once per run, not per update): S, L and the identity (3, 3)."""
    return np.empty((3, 3)), np.empty((3, 3)), np.eye(3)


@njit(cache=True)
def spd_inverse(A, diag, m, out, work):
    """out (3, 3) = (A + diag(diag))^-1 for the leading m x m block (m <= 3), zero elsewhere, from its Cholesky
    factor; returns False if that block is not positive definite. ``work`` holds :func:`inverse_buffers`."""
    S, L, identity = work
    L[:, :] = 0.0
    for i in range(m):
        for j in range(m):
            S[i, j] = A[i, j] + (diag[i] if i == j else 0.0)
    if not cholesky_factor(S, m, L):
        return False
    out[:, :] = 0.0
    cholesky_solve(L, m, identity, out)
    for i in range(m):  # exactly symmetric
        for j in range(i + 1, m):
            value = 0.5 * (out[i, j] + out[j, i])
            out[i, j] = value
            out[j, i] = value
    return True
