"""Compiled covariance algebra of the error-state EKF in 3 x 3 blocks: transition, propagation, Joseph update.

Error state (closed loop, reset to zero after every correction), in this order:
``dp`` (0:3, m, world), ``dv`` (3:6, m/s, world), ``dtheta`` (6:9, rad, world-frame small rotation with
``C_true = (I + [dtheta x]) C_est``), ``db_a`` (9:12, m/s^2), ``db_g`` (12:15, rad/s), ``dG`` (15:24,
rad/s per m/s^2, row-major gyro g-sensitivity matrix). Each ``d*`` is true minus estimated. The sensor model
behind it: ``f_meas = f_true + b_a`` and ``w_meas = w_true + b_g + G f_true``.

The transition over h seconds, ``Phi = I + F h`` with ``a = C f`` the world specific force, is the identity but
for three block rows::

    p:      + h dv
    v:      - h a x dtheta  - h C db_a
    theta:  - h C (db_g + dG f)

so applying it to a vector or to the columns of P costs a few dozen flops per column (:func:`transition_rows`),
not a dense product. Phi is unit block-triangular, so ``Phi^-1`` is the same three rows with the sign flipped,
applied in the reverse order (each row then uses the already solved blocks below it).

Storage. P (n x n) is held flat, row by row, each row padded to :func:`row_stride` entries (16 for up to 16 states,
else 24): element (i, j) is ``P[i * W + j]`` and the padding columns stay zero. With the stride a compile-time
constant and every row's loop over W columns, LLVM sees the distance between rows and vectorises the loops over
columns (the transition of all columns at once, the update's rows); a 2-D array's row length is a runtime value,
and loops of 9 or 15 iterations are below its minimum. Every entry is computed by the same operations in the same
order as on a dense n x n array; the padding only adds columns of zeros.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .linalg import spd_inverse3


@njit(cache=True, inline="always")
def row_stride(n):
    """Row length W of the flat covariance of n states (see the module docstring): 16 up to 16 states, else 24."""
    return 16 if n <= 16 else 24


@njit(cache=True)
def covariance_zeros(n):
    """A flat n x n covariance of zeros, rows padded to :func:`row_stride` (n)."""
    return np.zeros(n * row_stride(n))


def flat_covariances(P: np.ndarray) -> np.ndarray:
    """The flat storage of the dense covariances P (..., n, n): shape (..., n * row_stride(n)), padding zero."""
    n = P.shape[-1]
    rows = np.zeros(P.shape[:-1] + (row_stride(n),))
    rows[..., :n] = P
    return rows.reshape(P.shape[:-2] + (-1,))


def dense_covariances(X: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Views of the flat covariances X (..., n * row_stride(n)) of n states: (the (..., n, n) matrices, their
    (..., n, row_stride(n) - n) padding)."""
    rows = X.reshape(X.shape[:-1] + (n, row_stride(n)))
    return rows[..., :n], rows[..., n:]


@njit(cache=True, inline="always")
def _transition_column(X, W, j, n, h, a, C, f, inverse, first_row):
    """Column j of X <- Phi X[:, j] (or Phi^-1 X[:, j]), X flat with rows of W entries; only its rows first_row:9
    change and are computed (``first_row`` 0, 3 or 6; the rows above it are left as they are: callers that need
    the lower triangle)."""
    p0, p1, p2 = X[j], X[W + j], X[2 * W + j]
    v0, v1, v2 = X[3 * W + j], X[4 * W + j], X[5 * W + j]
    t0, t1, t2 = X[6 * W + j], X[7 * W + j], X[8 * W + j]
    s = -h if inverse else h
    ca0 = ca1 = ca2 = 0.0  # C db_a
    cg0 = cg1 = cg2 = 0.0  # C (db_g + dG f)
    if n >= 15:
        b0, b1, b2 = X[9 * W + j], X[10 * W + j], X[11 * W + j]
        g0, g1, g2 = X[12 * W + j], X[13 * W + j], X[14 * W + j]
        if n == 24:
            g0 += f[0] * X[15 * W + j] + f[1] * X[16 * W + j] + f[2] * X[17 * W + j]
            g1 += f[0] * X[18 * W + j] + f[1] * X[19 * W + j] + f[2] * X[20 * W + j]
            g2 += f[0] * X[21 * W + j] + f[1] * X[22 * W + j] + f[2] * X[23 * W + j]
        if first_row < 6:
            ca0 = C[0, 0] * b0 + C[0, 1] * b1 + C[0, 2] * b2
            ca1 = C[1, 0] * b0 + C[1, 1] * b1 + C[1, 2] * b2
            ca2 = C[2, 0] * b0 + C[2, 1] * b1 + C[2, 2] * b2
        cg0 = C[0, 0] * g0 + C[0, 1] * g1 + C[0, 2] * g2
        cg1 = C[1, 0] * g0 + C[1, 1] * g1 + C[1, 2] * g2
        cg2 = C[2, 0] * g0 + C[2, 1] * g1 + C[2, 2] * g2
    if inverse:  # solve by back substitution: attitude, then velocity with it, then position with that
        t0, t1, t2 = t0 - s * cg0, t1 - s * cg1, t2 - s * cg2
    if first_row < 6:
        n0 = v0 - s * ((a[1] * t2 - a[2] * t1) + ca0)
        n1 = v1 - s * ((a[2] * t0 - a[0] * t2) + ca1)
        n2 = v2 - s * ((a[0] * t1 - a[1] * t0) + ca2)
        if first_row == 0:
            if inverse:
                X[j], X[W + j], X[2 * W + j] = p0 + s * n0, p1 + s * n1, p2 + s * n2
            else:
                X[j], X[W + j], X[2 * W + j] = p0 + s * v0, p1 + s * v1, p2 + s * v2
        X[3 * W + j], X[4 * W + j], X[5 * W + j] = n0, n1, n2
    if not inverse:
        t0, t1, t2 = t0 - s * cg0, t1 - s * cg1, t2 - s * cg2
    X[6 * W + j], X[7 * W + j], X[8 * W + j] = t0, t1, t2


@njit(cache=True, inline="always")
def transition_rows(X, W, n, h, a, C, f, inverse):
    """X <- Phi X (or Phi^-1 X when ``inverse``) for every column of X: n rows held flat, W entries each (a
    vector is W = 1).

    ``h`` s, ``a = C f`` (3,) world specific force, ``C`` (3, 3) body->world, ``f`` (3,) corrected specific force
    in the body frame, all at the start of the interval.
    """
    for j in range(W):
        _transition_column(X, W, j, n, h, a, C, f, inverse, 0)


@njit(cache=True)
def transition_transposed(lam, n, h, a, C, f):
    """lam <- Phi^T lam (n,), in place (the adjoint of :func:`transition_rows`)."""
    v0, v1, v2 = lam[3], lam[4], lam[5]
    t0, t1, t2 = lam[6], lam[7], lam[8]
    lam[3] += h * lam[0]
    lam[4] += h * lam[1]
    lam[5] += h * lam[2]
    # (-h [a x])^T = h [a x]
    lam[6] += h * (a[1] * v2 - a[2] * v1)
    lam[7] += h * (a[2] * v0 - a[0] * v2)
    lam[8] += h * (a[0] * v1 - a[1] * v0)
    if n >= 15:
        for c in range(3):
            lam[9 + c] -= h * (C[0, c] * v0 + C[1, c] * v1 + C[2, c] * v2)
            ct = h * (C[0, c] * t0 + C[1, c] * t1 + C[2, c] * t2)  # h (C^T lam_theta)_c
            lam[12 + c] -= ct
            if n == 24:
                for e in range(3):
                    lam[15 + 3 * c + e] -= ct * f[e]


@njit(cache=True, inline="always")
def propagate(P, n, h, a, C, f, noise_power):
    """P <- Phi P Phi^T + Q in place over one interval of h seconds; Q = diag(noise_power) h; P flat
    (:func:`covariance_zeros`).

    Phi acts on the columns of P (block rows 0:9 change), all of them at once; then on the rows of the result:
    by symmetry only the lower triangle of the 9 x 9 block of position, velocity and attitude needs it (mirrored
    after), and the block rows 9:n of the result are the transpose of the block columns already computed.
    """
    W = row_stride(n)
    transition_rows(P, W, n, h, a, C, f, False)  # P <- Phi P: rows 0:9 change
    for i in range(9):  # (Phi P)^T into the first 9 columns (rows 9: of Phi P are P's, unchanged)
        for j in range(i + 1, 9):
            P[i * W + j], P[j * W + i] = P[j * W + i], P[i * W + j]
        for j in range(9, n):
            P[j * W + i] = P[i * W + j]
    # columns 0:9 <- Phi (Phi P)^T = (Phi P Phi^T)[:, 0:9], their lower triangle (block rows from the column's)
    for j in range(3):
        _transition_column(P, W, j, n, h, a, C, f, False, 0)
    for j in range(3, 6):
        _transition_column(P, W, j, n, h, a, C, f, False, 3)
    for j in range(6, 9):
        _transition_column(P, W, j, n, h, a, C, f, False, 6)
    for i in range(9):
        for j in range(i + 1, 9):
            P[i * W + j] = P[j * W + i]
    for i in range(n):
        P[i * W + i] += noise_power[i] * h


_U, _V, _W, _KT = 0, 1, 2, 3  # the n x 3 factors of the Joseph update in its work buffer, each held transposed


@njit(cache=True)
def update_buffers(n):
    """Work buffer of :func:`joseph_update`: U, V, W and K, each transposed (3 rows of :func:`row_stride` (n)
    entries), flat."""
    return np.empty(4 * 3 * row_stride(n))


@njit(cache=True, inline="always")
def _hu(w, W, h_col, h_val, h_cnt, m, r, q):
    """(H U)[r, q]: row r of the sparse H times column q of U (held as row q of U in ``w``); 0 for r >= m."""
    acc = 0.0
    if r < m:
        for e in range(h_cnt[r]):
            acc += h_val[r, e] * w[(3 * _U + q) * W + h_col[r, e]]
    return acc


@njit(cache=True)
def joseph_update(P, n, h_col, h_val, h_cnt, m, z, r_var, dx, K, s, w):
    """Kalman update of P (n x n, flat: :func:`covariance_zeros`) in place with z = H dx + noise (variances r_var,
    m <= 3 values), Joseph form.

    H is sparse: row r has ``h_cnt[r]`` non-zeros ``h_val[r, :]`` in columns ``h_col[r, :]``. With
    ``U = P H^T``, ``S = H U + R``, ``K = U S^-1``, ``V = U - K H U`` and ``W = U - K R`` the Joseph form
    ``(I - K H) P (I - K H)^T + K R K^T`` is ``P - K W^T - V K^T``; its upper triangle is kept and mirrored (each
    row is computed whole, which vectorises, and its part left of the diagonal overwritten). The n x 3 factors are
    held transposed in one work array ``w`` (:func:`update_buffers`; one array, not a tuple of them, costs no
    reference counting per call); their rows m..2 are zero, and S is padded with the identity there
    (:func:`spd_inverse3`, on scalars), so every sum has a fixed length of 3. P is symmetric: column c of P is
    read as its row c.
    Writes the correction ``K z`` into ``dx``, the gain into ``K`` (n, 3) and ``S^-1 z`` into ``s`` (3,).
    Returns False (P untouched) if S is not positive definite.
    """
    W = row_stride(n)
    u_, v_, w_, kt = 3 * _U * W, 3 * _V * W, 3 * _W * W, 3 * _KT * W  # where each factor's rows start in w
    for i in range(3 * W):
        w[u_ + i] = 0.0
    for r in range(m):
        for e in range(h_cnt[r]):
            c, value = h_col[r, e], h_val[r, e]
            for i in range(W):
                w[u_ + r * W + i] += P[c * W + i] * value
    hu00, hu11, hu22 = _hu(w, W, h_col, h_val, h_cnt, m, 0, 0), _hu(w, W, h_col, h_val, h_cnt, m, 1, 1), \
        _hu(w, W, h_col, h_val, h_cnt, m, 2, 2)
    hu10, hu20, hu21 = _hu(w, W, h_col, h_val, h_cnt, m, 1, 0), _hu(w, W, h_col, h_val, h_cnt, m, 2, 0), \
        _hu(w, W, h_col, h_val, h_cnt, m, 2, 1)
    hu01, hu02, hu12 = _hu(w, W, h_col, h_val, h_cnt, m, 0, 1), _hu(w, W, h_col, h_val, h_cnt, m, 0, 2), \
        _hu(w, W, h_col, h_val, h_cnt, m, 1, 2)
    r0, r1, r2 = (r_var[0] if m > 0 else 0.0), (r_var[1] if m > 1 else 0.0), (r_var[2] if m > 2 else 0.0)
    # S = H U + R, its diagonal padded with ones beyond m
    ok, i00, i01, i02, i11, i12, i22 = spd_inverse3(hu00 + (r0 if m > 0 else 1.0), hu10, hu11 + (r1 if m > 1 else 1.0),
                                                    hu20, hu21, hu22 + (r2 if m > 2 else 1.0))
    if not ok:
        return False
    # the padding's inverse is the identity: zero it
    i01, i02, i11, i12, i22 = (i01 if m > 1 else 0.0), (i02 if m > 2 else 0.0), (i11 if m > 1 else 0.0), \
        (i12 if m > 2 else 0.0), (i22 if m > 2 else 0.0)
    z0, z1, z2 = (z[0] if m > 0 else 0.0), (z[1] if m > 1 else 0.0), (z[2] if m > 2 else 0.0)
    s[0] = i00 * z0 + i01 * z1 + i02 * z2
    s[1] = i01 * z0 + i11 * z1 + i12 * z2
    s[2] = i02 * z0 + i12 * z1 + i22 * z2
    for i in range(W):  # U's padding (i >= n) is zero, so is theirs
        u0, u1, u2 = w[u_ + i], w[u_ + W + i], w[u_ + 2 * W + i]
        k0 = u0 * i00 + u1 * i01 + u2 * i02
        k1 = u0 * i01 + u1 * i11 + u2 * i12
        k2 = u0 * i02 + u1 * i12 + u2 * i22
        w[kt + i], w[kt + W + i], w[kt + 2 * W + i] = k0, k1, k2
        w[v_ + i] = u0 - (k0 * hu00 + k1 * hu10 + k2 * hu20)
        w[v_ + W + i] = u1 - (k0 * hu01 + k1 * hu11 + k2 * hu21)
        w[v_ + 2 * W + i] = u2 - (k0 * hu02 + k1 * hu12 + k2 * hu22)
        w[w_ + i] = u0 - k0 * r0
        w[w_ + W + i] = u1 - k1 * r1
        w[w_ + 2 * W + i] = u2 - k2 * r2
    for i in range(n):
        k0, k1, k2 = w[kt + i], w[kt + W + i], w[kt + 2 * W + i]
        K[i, 0], K[i, 1], K[i, 2] = k0, k1, k2
        dx[i] = k0 * z0 + k1 * z1 + k2 * z2
    for i in range(n):
        k0, k1, k2 = w[kt + i], w[kt + W + i], w[kt + 2 * W + i]
        e0, e1, e2 = w[v_ + i], w[v_ + W + i], w[v_ + 2 * W + i]
        row = i * W
        for j in range(W):
            P[row + j] = P[row + j] - (k0 * w[w_ + j] + e0 * w[kt + j] + k1 * w[w_ + W + j] + e1 * w[kt + W + j]
                                       + k2 * w[w_ + 2 * W + j] + e2 * w[kt + 2 * W + j])
    for i in range(n):
        for j in range(i):
            P[i * W + j] = P[j * W + i]
    return True
