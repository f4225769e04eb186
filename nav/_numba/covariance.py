"""Compiled covariance algebra of the error-state EKF: transition, propagation and the Joseph-form update.

Error state (closed loop, reset to zero after every correction), in this order:
``dp`` (0:3, m, world), ``dv`` (3:6, m/s, world), ``dtheta`` (6:9, rad, world-frame small rotation with
``C_true = (I + [dtheta x]) C_est``), ``db_a`` (9:12, m/s^2), ``db_g`` (12:15, rad/s), ``dG`` (15:24,
rad/s per m/s^2, row-major gyro g-sensitivity matrix). Each ``d*`` is true minus estimated. The sensor model
behind it: ``f_meas = f_true + b_a`` and ``w_meas = w_true + b_g + G f_true``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .linalg import cholesky_factor, cholesky_solve
from .quat import qmatrix


@njit(cache=True)
def _build_transition(E, n, C, fhat, h):
    """Non-identity part E (9 x n) of the transition Phi = I + F h of the error state (first order)."""
    E[:, :] = 0.0
    a0 = C[0, 0] * fhat[0] + C[0, 1] * fhat[1] + C[0, 2] * fhat[2]
    a1 = C[1, 0] * fhat[0] + C[1, 1] * fhat[1] + C[1, 2] * fhat[2]
    a2 = C[2, 0] * fhat[0] + C[2, 1] * fhat[1] + C[2, 2] * fhat[2]
    for i in range(3):
        E[i, 3 + i] = h
    # dv' = -[a x] dtheta - C db_a
    E[3, 7] = h * a2
    E[3, 8] = -h * a1
    E[4, 6] = -h * a2
    E[4, 8] = h * a0
    E[5, 6] = h * a1
    E[5, 7] = -h * a0
    if n >= 15:
        for i in range(3):
            for j in range(3):
                E[3 + i, 9 + j] = -h * C[i, j]  # velocity <- accelerometer bias
                E[6 + i, 12 + j] = -h * C[i, j]  # attitude <- gyro bias
    if n == 24:
        for i in range(3):
            for r in range(3):
                for c in range(3):
                    E[6 + i, 15 + 3 * r + c] = -h * C[i, r] * fhat[c]  # attitude <- g-sensitivity


@njit(cache=True)
def _block_range(block, n):
    """Column range [lo, hi) of the non-zero part of E's row block (0: position, 1: velocity, 2: attitude)."""
    if block == 0:
        return 3, 6
    if block == 1:
        return 6, (12 if n >= 15 else 9)
    return (12, n) if n >= 15 else (12, 12)


@njit(cache=True)
def _propagate_with(P, n, E, B, qdiag):
    """P <- (I + E) P (I + E)^T + diag(qdiag), exploiting that only E's first 9 rows are non-zero."""
    for i in range(9):
        lo, hi = _block_range(i // 3, n)
        for j in range(n):
            s = 0.0
            for m in range(lo, hi):
                s += E[i, m] * P[m, j]
            B[i, j] = s  # B = E P
    # E P E^T (9 x 9) before P changes
    for i in range(9):
        lo, hi = _block_range(i // 3, n)
        for j in range(i, 9):
            s = 0.0
            for m in range(lo, hi):
                s += E[i, m] * B[j, m]
            P[i, j] += s
            if j != i:
                P[j, i] = P[i, j]
    for i in range(n):
        for j in range(i, n):
            add = 0.0
            if i < 9:
                add += B[i, j]
            if j < 9:
                add += B[j, i]
            if i == j:
                add += qdiag[i]
            val = P[i, j] + add
            P[i, j] = val
            P[j, i] = val


@njit(cache=True)
def propagation_buffers(n):
    """Work buffers of :func:`propagate`: C (3, 3), E (9, n), B (9, n), qdiag (n,)."""
    return np.empty((3, 3)), np.zeros((9, n)), np.empty((9, n)), np.empty(n)


@njit(cache=True)
def propagate(P, n, q, fhat, h, rw, buffers):
    """Propagate the covariance P (n x n) in place over one interval of h seconds.

    ``q`` (4,) is the nominal attitude and ``fhat`` (3,) the corrected specific force (m/s^2) at the start of the
    interval; ``rw`` (n,) the continuous driving-noise power per state. Leaves the transition's non-identity
    part E (9 x n) in ``buffers[1]`` (from :func:`propagation_buffers`).
    """
    C, E, B, qdiag = buffers
    qmatrix(q, C)
    _build_transition(E, n, C, fhat, h)
    for i in range(n):
        qdiag[i] = rw[i] * h
    _propagate_with(P, n, E, B, qdiag)


@njit(cache=True)
def _sparse_product(h_col, h_val, h_cnt, m, X, n, out):
    """out (m x n) = H X for the sparse m-row H of :func:`joseph_update` and X with n columns."""
    for r in range(m):
        for j in range(n):
            s = 0.0
            for e in range(h_cnt[r]):
                s += h_val[r, e] * X[h_col[r, e], j]
            out[r, j] = s


@njit(cache=True)
def update_buffers(n, m):
    """Work buffers of :func:`joseph_update` for up to m measurements."""
    return (np.empty((m, n)), np.empty((m, m)), np.empty((m, m)), np.empty((n, m)), np.empty((n, n)),
            np.empty((m, n)), np.empty(m), np.empty(m))


@njit(cache=True)
def joseph_update(P, n, h_col, h_val, h_cnt, m, z, r_var, dx, w):
    """Kalman update of P (n x n) with measurement z = H dx + noise (variance r_var, m values), Joseph form.

    H is given sparsely: row r has ``h_cnt[r]`` non-zeros ``h_val[r, :]`` in columns ``h_col[r, :]``. Adds the
    state correction to ``dx``; ``w`` holds the work buffers of :func:`update_buffers`. Returns False if S is not
    positive definite.
    """
    HP, S, L, K, A, HAt, col, sol = w
    _sparse_product(h_col, h_val, h_cnt, m, P, n, HP)
    for r in range(m):
        for q in range(m):
            s = 0.0
            for e in range(h_cnt[q]):
                s += HP[r, h_col[q, e]] * h_val[q, e]
            S[r, q] = s + (r_var[r] if r == q else 0.0)
    if not cholesky_factor(S, m, L):
        return False
    # K = P H^T S^-1, one row at a time: K[j, :] = S^-1 HP[:, j]
    for j in range(n):
        for r in range(m):
            col[r] = HP[r, j]
        cholesky_solve(L, m, col, sol)
        for r in range(m):
            K[j, r] = sol[r]
    for j in range(n):
        s = 0.0
        for r in range(m):
            s += K[j, r] * z[r]
        dx[j] += s
    # A = (I - K H) P
    for i in range(n):
        for j in range(n):
            s = P[i, j]
            for r in range(m):
                s -= K[i, r] * HP[r, j]
            A[i, j] = s
    _sparse_product(h_col, h_val, h_cnt, m, A.T, n, HAt)  # (A H^T)^T
    # P = A (I - K H)^T + K R K^T: symmetric in exact arithmetic; the upper triangle is computed and mirrored
    for i in range(n):
        for j in range(i, n):
            s = A[i, j]
            for r in range(m):
                s += K[i, r] * r_var[r] * K[j, r] - HAt[r, i] * K[j, r]
            P[i, j] = s
            P[j, i] = s
    return True
