"""numba inner loops of the strapdown and the error-state EKF (private; use nav.strapdown and nav.ekf).

Everything here works on plain float64 arrays, allocates its work buffers once per run and is compiled with
``cache=True`` so a new process does not recompile. Frames and units are those of the package: world ENU (m,
m/s), body frame of the sensor, quaternions (w, x, y, z) body->world, specific force in m/s^2, rates in rad/s.

Error state (closed loop, reset to zero after every correction), in this order:
``dp`` (0:3, m, world), ``dv`` (3:6, m/s, world), ``dtheta`` (6:9, rad, world-frame small rotation with
``C_true = (I + [dtheta x]) C_est``), ``db_a`` (9:12, m/s^2), ``db_g`` (12:15, rad/s), ``dG`` (15:24,
rad/s per m/s^2, row-major gyro g-sensitivity matrix). Each ``d*`` is true minus estimated. The sensor model
behind it: ``f_meas = f_true + b_a`` and ``w_meas = w_true + b_g + G f_true``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

MODE_POINT_SAMPLES = 0  # acc/gyr are point samples; RK4 with interpolated mid-samples
MODE_INCREMENTS = 1  # acc/gyr hold exact increments dv (m/s, body at t_k) and dtheta (rad) over [t_k, t_k+1]

# indices into the float64 configuration vector built by nav.ekf.FilterConfig.as_array()
CFG_GRAVITY = 0
CFG_ACC_NOISE = 1
CFG_GYR_NOISE = 2
CFG_ACC_BIAS_RW = 3
CFG_GYR_BIAS_RW = 4
CFG_GSENS_RW = 5
CFG_ZUPT_SIGMA = 6
CFG_ZARU_SIGMA = 7
CFG_LEVEL_SIGMA = 8
CFG_P0_POS = 9
CFG_P0_VEL = 10
CFG_P0_TILT = 11
CFG_P0_YAW = 12
CFG_P0_ACC_BIAS = 13
CFG_P0_GYR_BIAS = 14
CFG_P0_GSENS = 15
CFG_SIZE = 16


# ----------------------------------------------------------------------------------------------- quaternions
@njit(cache=True, inline="always")
def _qmul(a0, a1, a2, a3, b0, b1, b2, b3):
    return (
        a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
        a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
        a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
        a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0,
    )


@njit(cache=True, inline="always")
def _qrot(q0, q1, q2, q3, v0, v1, v2):
    """Rotate v by the rotation of q; q need not be unit (divides by |q|^2)."""
    nn = q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3
    t0 = 2.0 * (q2 * v2 - q3 * v1)
    t1 = 2.0 * (q3 * v0 - q1 * v2)
    t2 = 2.0 * (q1 * v1 - q2 * v0)
    r0 = v0 * nn + q0 * t0 + (q2 * t2 - q3 * t1)
    r1 = v1 * nn + q0 * t1 + (q3 * t0 - q1 * t2)
    r2 = v2 * nn + q0 * t2 + (q1 * t1 - q2 * t0)
    return r0 / nn, r1 / nn, r2 / nn


@njit(cache=True, inline="always")
def _qexp(p0, p1, p2):
    """Unit quaternion of the rotation vector p (rad)."""
    a = math.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
    if a < 1e-6:
        k = 0.5 - a * a / 48.0
    else:
        k = math.sin(0.5 * a) / a
    return math.cos(0.5 * a), k * p0, k * p1, k * p2


@njit(cache=True)
def _qmatrix(q, C):
    """Body->world rotation matrix of unit quaternion q into C (3x3)."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    C[0, 0] = 1 - 2 * (y * y + z * z)
    C[0, 1] = 2 * (x * y - w * z)
    C[0, 2] = 2 * (x * z + w * y)
    C[1, 0] = 2 * (x * y + w * z)
    C[1, 1] = 1 - 2 * (x * x + z * z)
    C[1, 2] = 2 * (y * z - w * x)
    C[2, 0] = 2 * (x * z - w * y)
    C[2, 1] = 2 * (y * z + w * x)
    C[2, 2] = 1 - 2 * (x * x + y * y)


# ----------------------------------------------------------------------------------------------- mechanisation
@njit(cache=True)
def rk4_increment(h, w0, wm, w1, f0, fm, f1, dq, du, ds):
    """Body-frame increments over one interval by RK4 on the relative motion from t_k.

    Integrates ``r' = r ⊗ (0, w)/2``, ``u' = R(r) f``, ``s' = u`` from ``r = 1, u = s = 0`` with the rates
    ``w0, wm, w1`` (rad/s) and specific forces ``f0, fm, f1`` (m/s^2) at the start, middle and end of the
    interval of length ``h`` (s). Writes the unit attitude increment ``dq`` (4), the velocity increment ``du``
    (m/s) and the position increment ``ds`` (m), both in the body frame at t_k.
    """
    hh = 0.5 * h
    # stage 1 (tau = 0, r = 1, u = 0)
    k1r = (0.0, 0.5 * w0[0], 0.5 * w0[1], 0.5 * w0[2])
    k1u = (f0[0], f0[1], f0[2])
    # stage 2 (tau = h/2)
    r = (1.0, hh * k1r[1], hh * k1r[2], hh * k1r[3])
    u2 = (hh * k1u[0], hh * k1u[1], hh * k1u[2])
    k2r = _qmul(r[0], r[1], r[2], r[3], 0.0, 0.5 * wm[0], 0.5 * wm[1], 0.5 * wm[2])
    k2u = _qrot(r[0], r[1], r[2], r[3], fm[0], fm[1], fm[2])
    # stage 3 (tau = h/2)
    r = (1.0 + hh * k2r[0], hh * k2r[1], hh * k2r[2], hh * k2r[3])
    u3 = (hh * k2u[0], hh * k2u[1], hh * k2u[2])
    k3r = _qmul(r[0], r[1], r[2], r[3], 0.0, 0.5 * wm[0], 0.5 * wm[1], 0.5 * wm[2])
    k3u = _qrot(r[0], r[1], r[2], r[3], fm[0], fm[1], fm[2])
    # stage 4 (tau = h)
    r = (1.0 + h * k3r[0], h * k3r[1], h * k3r[2], h * k3r[3])
    u4 = (h * k3u[0], h * k3u[1], h * k3u[2])
    k4r = _qmul(r[0], r[1], r[2], r[3], 0.0, 0.5 * w1[0], 0.5 * w1[1], 0.5 * w1[2])
    k4u = _qrot(r[0], r[1], r[2], r[3], f1[0], f1[1], f1[2])
    h6 = h / 6.0
    dq[0] = 1.0 + h6 * (k1r[0] + 2.0 * k2r[0] + 2.0 * k3r[0] + k4r[0])
    for i in range(3):
        dq[i + 1] = h6 * (k1r[i + 1] + 2.0 * k2r[i + 1] + 2.0 * k3r[i + 1] + k4r[i + 1])
    norm = math.sqrt(dq[0] * dq[0] + dq[1] * dq[1] + dq[2] * dq[2] + dq[3] * dq[3])
    for i in range(4):
        dq[i] /= norm
    du[0] = h6 * (k1u[0] + 2.0 * k2u[0] + 2.0 * k3u[0] + k4u[0])
    du[1] = h6 * (k1u[1] + 2.0 * k2u[1] + 2.0 * k3u[1] + k4u[1])
    du[2] = h6 * (k1u[2] + 2.0 * k2u[2] + 2.0 * k3u[2] + k4u[2])
    ds[0] = h6 * (2.0 * u2[0] + 2.0 * u3[0] + u4[0])
    ds[1] = h6 * (2.0 * u2[1] + 2.0 * u3[1] + u4[1])
    ds[2] = h6 * (2.0 * u2[2] + 2.0 * u3[2] + u4[2])


@njit(cache=True)
def apply_increment(q, v, p, dq, du, ds, h, gravity):
    """Advance the nominal state (q, v, p) in place by body increments over an interval of h seconds.

    ``v += C du + g h``, ``p += v h + C ds + g h^2 / 2`` (with the old v), ``q = q ⊗ dq``; g = (0, 0, -gravity).
    """
    a0, a1, a2 = _qrot(q[0], q[1], q[2], q[3], du[0], du[1], du[2])
    b0, b1, b2 = _qrot(q[0], q[1], q[2], q[3], ds[0], ds[1], ds[2])
    p[0] += v[0] * h + b0
    p[1] += v[1] * h + b1
    p[2] += v[2] * h + b2 - 0.5 * gravity * h * h
    v[0] += a0
    v[1] += a1
    v[2] += a2 - gravity * h
    n0, n1, n2, n3 = _qmul(q[0], q[1], q[2], q[3], dq[0], dq[1], dq[2], dq[3])
    norm = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2 + n3 * n3)
    q[0], q[1], q[2], q[3] = n0 / norm, n1 / norm, n2 / norm, n3 / norm


@njit(cache=True)
def _interval_increments(mode, k, t, u_acc, u_gyr, m_acc, m_gyr, ba, bg, G, dq, du, ds, fhat, wk):
    """Bias-corrected body increments over [t_k, t_k+1]; fhat gets the corrected specific force at t_k.

    ``wk`` is a (6, 3) work buffer.
    """
    h = t[k + 1] - t[k]
    if mode == MODE_INCREMENTS:
        for i in range(3):
            du[i] = u_acc[k, i] - ba[i] * h
            fhat[i] = du[i] / h
        for i in range(3):
            dth = u_gyr[k, i] - bg[i] * h - (G[3 * i] * du[0] + G[3 * i + 1] * du[1] + G[3 * i + 2] * du[2])
            ds[i] = dth  # temporary store of the corrected rotation vector
        e0, e1, e2, e3 = _qexp(ds[0], ds[1], ds[2])
        dq[0], dq[1], dq[2], dq[3] = e0, e1, e2, e3
        for i in range(3):
            ds[i] = 0.5 * h * du[i]  # trapezoid position increment
    else:
        f0, fm, f1, w0, wm, w1 = wk[0], wk[1], wk[2], wk[3], wk[4], wk[5]
        for i in range(3):
            f0[i] = u_acc[k, i] - ba[i]
            fm[i] = m_acc[k, i] - ba[i]
            f1[i] = u_acc[k + 1, i] - ba[i]
        for i in range(3):
            w0[i] = u_gyr[k, i] - bg[i] - (G[3 * i] * f0[0] + G[3 * i + 1] * f0[1] + G[3 * i + 2] * f0[2])
            wm[i] = m_gyr[k, i] - bg[i] - (G[3 * i] * fm[0] + G[3 * i + 1] * fm[1] + G[3 * i + 2] * fm[2])
            w1[i] = u_gyr[k + 1, i] - bg[i] - (G[3 * i] * f1[0] + G[3 * i + 1] * f1[1] + G[3 * i + 2] * f1[2])
            fhat[i] = f0[i]
        rk4_increment(h, w0, wm, w1, f0, fm, f1, dq, du, ds)
    return h


@njit(cache=True)
def strapdown_run(mode, t, u_acc, u_gyr, m_acc, m_gyr, i0, q0, v0, p0, gravity, quat, vel, pos):
    """Unaided mechanisation from sample i0; fills quat (N,4), vel (N,3), pos (N,3) from i0 on."""
    n_samples = t.shape[0]
    q = q0.copy()
    v = v0.copy()
    p = p0.copy()
    zero3 = np.zeros(3)
    zero9 = np.zeros(9)
    dq = np.empty(4)
    du = np.empty(3)
    ds = np.empty(3)
    fhat = np.empty(3)
    wk = np.empty((6, 3))
    for k in range(i0, n_samples):
        quat[k] = q
        vel[k] = v
        pos[k] = p
        if k == n_samples - 1:
            break
        h = _interval_increments(mode, k, t, u_acc, u_gyr, m_acc, m_gyr, zero3, zero3, zero9, dq, du, ds, fhat, wk)
        apply_increment(q, v, p, dq, du, ds, h, gravity)


# ----------------------------------------------------------------------------------------------- covariance
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
def _propagate_cov(P, n, E, B, qdiag):
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
def _cholesky_factor(A, m, L):
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
def _cholesky_apply(L, m, b, out):
    """Solve L L^T x = b into out, given the factor L from _cholesky_factor."""
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
def _joseph_update(P, n, h_col, h_val, h_cnt, m, z, r_var, dx, w):
    """Kalman update of P (n x n) with measurement z = H dx + noise (variance r_var, m values), Joseph form.

    H is given sparsely: row r has ``h_cnt[r]`` non-zeros ``h_val[r, :]`` in columns ``h_col[r, :]``. Adds the
    state correction to ``dx``; ``w`` is a tuple of work buffers. Returns False if S is not positive definite.
    """
    HP, S, L, K, A, AHt, col, sol = w
    for r in range(m):
        for j in range(n):
            s = 0.0
            for e in range(h_cnt[r]):
                s += h_val[r, e] * P[h_col[r, e], j]
            HP[r, j] = s
    for r in range(m):
        for q in range(m):
            s = 0.0
            for e in range(h_cnt[q]):
                s += HP[r, h_col[q, e]] * h_val[q, e]
            S[r, q] = s + (r_var[r] if r == q else 0.0)
    if not _cholesky_factor(S, m, L):
        return False
    # K = P H^T S^-1, one row at a time: K[j, :] = S^-1 HP[:, j]
    for j in range(n):
        for r in range(m):
            col[r] = HP[r, j]
        _cholesky_apply(L, m, col, sol)
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
    for i in range(n):
        for r in range(m):
            s = 0.0
            for e in range(h_cnt[r]):
                s += A[i, h_col[r, e]] * h_val[r, e]
            AHt[i, r] = s
    # P = A (I - K H)^T + K R K^T: symmetric in exact arithmetic; the upper triangle is computed and mirrored
    for i in range(n):
        for j in range(i, n):
            s = A[i, j]
            for r in range(m):
                s += K[i, r] * r_var[r] * K[j, r] - AHt[i, r] * K[j, r]
            P[i, j] = s
            P[j, i] = s
    return True


@njit(cache=True)
def _inject(dx, n, q, v, p, ba, bg, G):
    """Closed loop: add the error-state estimate dx to the nominal state and leave dx at zero."""
    for i in range(3):
        p[i] += dx[i]
        v[i] += dx[3 + i]
    e0, e1, e2, e3 = _qexp(dx[6], dx[7], dx[8])
    n0, n1, n2, n3 = _qmul(e0, e1, e2, e3, q[0], q[1], q[2], q[3])
    norm = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2 + n3 * n3)
    q[0], q[1], q[2], q[3] = n0 / norm, n1 / norm, n2 / norm, n3 / norm
    if n >= 15:
        for i in range(3):
            ba[i] += dx[9 + i]
            bg[i] += dx[12 + i]
    if n == 24:
        for i in range(9):
            G[i] += dx[15 + i]
    dx[:] = 0.0


@njit(cache=True)
def _update_and_inject(P, n, h_col, h_val, h_cnt, m, z, r_var, dx, work, corr, q, v, p, ba, bg, G):
    """One Joseph-form update, its correction added to ``corr`` and injected; returns 1 if it was skipped."""
    if not _joseph_update(P, n, h_col, h_val, h_cnt, m, z, r_var, dx, work):
        dx[:] = 0.0
        return 1
    for i in range(n):
        corr[i] += dx[i]
    _inject(dx, n, q, v, p, ba, bg, G)
    return 0


# ----------------------------------------------------------------------------------------------- the filter
@njit(cache=True)
def filter_run(mode, t, u_acc, u_gyr, m_acc, m_gyr, zupt, zaru, v_heading, i0, q0, v0, p0, n, cfg, rts,
               quat, vel, pos, bias_acc, bias_gyr, gsens, p_diag):
    """Error-state EKF over one recording from sample i0; see nav.ekf.run_filter for the meaning of the inputs.

    Outputs (filled from i0 on, in place): quat (N,4), vel (N,3), pos (N,3), bias_acc (N,3), bias_gyr (N,3),
    gsens (N,9), p_diag (N,n) -- a posteriori at each sample, or smoothed when ``rts``. Returns the number of
    measurement updates skipped because the innovation covariance was not positive definite.
    """
    n_samples = t.shape[0]
    gravity = cfg[CFG_GRAVITY]
    q = q0.copy()
    v = v0.copy()
    p = p0.copy()
    ba = np.zeros(3)
    bg = np.zeros(3)
    G = np.zeros(9)
    P = np.zeros((n, n))
    p0_std = (cfg[CFG_P0_POS], cfg[CFG_P0_VEL], cfg[CFG_P0_TILT], cfg[CFG_P0_TILT], cfg[CFG_P0_YAW])
    for i in range(3):
        P[i, i] = p0_std[0] ** 2
        P[3 + i, 3 + i] = p0_std[1] ** 2
    P[6, 6] = p0_std[2] ** 2
    P[7, 7] = p0_std[3] ** 2
    P[8, 8] = p0_std[4] ** 2
    rw = np.zeros(n)  # continuous driving noise power per state, (unit/s)^2 * s
    for i in range(3):
        rw[3 + i] = cfg[CFG_ACC_NOISE] ** 2
        rw[6 + i] = cfg[CFG_GYR_NOISE] ** 2
    if n >= 15:
        for i in range(3):
            P[9 + i, 9 + i] = cfg[CFG_P0_ACC_BIAS] ** 2
            P[12 + i, 12 + i] = cfg[CFG_P0_GYR_BIAS] ** 2
            rw[9 + i] = cfg[CFG_ACC_BIAS_RW] ** 2
            rw[12 + i] = cfg[CFG_GYR_BIAS_RW] ** 2
    if n == 24:
        for i in range(9):
            P[15 + i, 15 + i] = cfg[CFG_P0_GSENS] ** 2
            rw[15 + i] = cfg[CFG_GSENS_RW] ** 2
    level_on = cfg[CFG_LEVEL_SIGMA] > 0.0
    z_level = p0[2]

    C = np.empty((3, 3))
    E = np.zeros((9, n))
    B = np.empty((9, n))
    qdiag = np.empty(n)
    dq = np.empty(4)
    du = np.empty(3)
    ds = np.empty(3)
    fhat = np.empty(3)
    wk = np.empty((6, 3))
    dx = np.zeros(n)
    h_col = np.zeros((3, 4), np.int64)  # sparse measurement matrix: columns, values, count per row
    h_val = np.zeros((3, 4))
    h_cnt = np.zeros(3, np.int64)
    z = np.empty(3)
    r_var = np.empty(3)
    work = (np.empty((3, n)), np.empty((3, 3)), np.empty((3, 3)), np.empty((n, 3)), np.empty((n, n)),
            np.empty((n, 3)), np.empty(3), np.empty(3))
    corr_sink = np.zeros(n)  # receives the corrections when they are not stored for the smoother
    n_store = n_samples - i0 if rts else 0
    P_store = np.empty((n_store, n, n))
    f_store = np.empty((n_store, 3))
    corr_store = np.zeros((n_store, n))
    skipped = 0

    for k in range(i0, n_samples):
        # ---- measurement updates at t_k; each correction is injected before the next update
        corr = corr_store[k - i0] if rts else corr_sink
        if zupt[k]:
            _qmatrix(q, C)
            yaw = math.atan2(C[1, 0], C[0, 0])
            cy, sy = math.cos(yaw), math.sin(yaw)
            vh = v_heading[k]
            z[0] = cy * vh[0] - sy * vh[1] - v[0]
            z[1] = sy * vh[0] + cy * vh[1] - v[1]
            z[2] = vh[2] - v[2]
            for i in range(3):
                h_cnt[i] = 1
                h_col[i, 0] = 3 + i
                h_val[i, 0] = 1.0
                r_var[i] = cfg[CFG_ZUPT_SIGMA] ** 2
            skipped += _update_and_inject(P, n, h_col, h_val, h_cnt, 3, z, r_var, dx, work, corr, q, v, p, ba, bg, G)
            if level_on:
                h_cnt[0] = 1
                h_col[0, 0] = 2
                h_val[0, 0] = 1.0
                z[0] = z_level - p[2]
                r_var[0] = cfg[CFG_LEVEL_SIGMA] ** 2
                skipped += _update_and_inject(P, n, h_col, h_val, h_cnt, 1, z, r_var, dx, work, corr, q, v, p, ba, bg,
                                              G)
        if zaru[k] and n >= 15 and k < n_samples - 1:
            # pseudo-measurement "the true rate is zero": residual -(corrected rate) = H dx
            h = t[k + 1] - t[k]
            for i in range(3):
                fhat[i] = (u_acc[k, i] / h if mode == MODE_INCREMENTS else u_acc[k, i]) - ba[i]
            for i in range(3):
                w_i = u_gyr[k, i] / h if mode == MODE_INCREMENTS else u_gyr[k, i]
                w_i -= bg[i] + G[3 * i] * fhat[0] + G[3 * i + 1] * fhat[1] + G[3 * i + 2] * fhat[2]
                z[i] = -w_i
                h_cnt[i] = 1
                h_col[i, 0] = 12 + i
                h_val[i, 0] = -1.0
                if n == 24:
                    h_cnt[i] = 4
                    for c in range(3):
                        h_col[i, 1 + c] = 15 + 3 * i + c
                        h_val[i, 1 + c] = -fhat[c]
                r_var[i] = cfg[CFG_ZARU_SIGMA] ** 2
            skipped += _update_and_inject(P, n, h_col, h_val, h_cnt, 3, z, r_var, dx, work, corr, q, v, p, ba, bg, G)

        quat[k] = q
        vel[k] = v
        pos[k] = p
        bias_acc[k] = ba
        bias_gyr[k] = bg
        gsens[k] = G
        for i in range(n):
            p_diag[k, i] = P[i, i]
        if rts:
            P_store[k - i0] = P
        if k == n_samples - 1:
            break

        # ---- propagate to t_k+1
        h = _interval_increments(mode, k, t, u_acc, u_gyr, m_acc, m_gyr, ba, bg, G, dq, du, ds, fhat, wk)
        _qmatrix(q, C)
        _build_transition(E, n, C, fhat, h)
        for i in range(n):
            qdiag[i] = rw[i] * h
        _propagate_cov(P, n, E, B, qdiag)
        if rts:
            f_store[k - i0] = fhat
        apply_increment(q, v, p, dq, du, ds, h, gravity)

    if rts:
        skipped += _rts_backward(t, i0, n, rw, P_store, f_store, corr_store, quat, vel, pos, bias_acc, bias_gyr,
                                 gsens, p_diag)
    return skipped


@njit(cache=True)
def _rts_backward(t, i0, n, rw, P_store, f_store, corr_store, quat, vel, pos, bias_acc, bias_gyr, gsens,
                  p_diag):
    """Rauch-Tung-Striebel pass for the closed-loop error state; smooths the nominal outputs in place.

    The smoothed error of the filtered nominal at k is ``P_k Phi_k^T P_{k+1|k}^-1 (ds_{k+1} + c_{k+1})``,
    where ``c_{k+1}`` is the correction the filter applied at k+1 (the error relative to the predicted nominal
    is the smoothed error plus that correction). Only the state is smoothed: ``p_diag`` keeps the filtered
    variances.
    """
    n_samples = t.shape[0]
    C = np.empty((3, 3))
    E = np.zeros((9, n))
    B = np.empty((9, n))
    qdiag = np.empty(n)
    P_pred = np.empty((n, n))
    L = np.empty((n, n))
    y = np.empty(n)
    x = np.empty(n)
    phit_x = np.empty(n)
    ds = np.zeros(n)
    dx = np.zeros(n)
    q = np.empty(4)
    v = np.empty(3)
    p = np.empty(3)
    ba = np.empty(3)
    bg = np.empty(3)
    G = np.empty(9)
    failed = 0
    for k in range(n_samples - 2, i0 - 1, -1):
        j = k - i0
        h = t[k + 1] - t[k]
        for i in range(n):
            y[i] = ds[i] + corr_store[j + 1, i]
        q[:] = quat[k]
        _qmatrix(q, C)
        _build_transition(E, n, C, f_store[j], h)
        for i in range(n):
            qdiag[i] = rw[i] * h
        P_pred[:, :] = P_store[j]
        _propagate_cov(P_pred, n, E, B, qdiag)
        if not _cholesky_factor(P_pred, n, L):
            failed += 1
            ds[:] = 0.0
            continue
        _cholesky_apply(L, n, y, x)
        # Phi^T x = x + E^T x
        for c in range(n):
            s = x[c]
            for r in range(9):
                s += E[r, c] * x[r]
            phit_x[c] = s
        for r in range(n):
            s = 0.0
            for c in range(n):
                s += P_store[j, r, c] * phit_x[c]
            ds[r] = s
        dx[:] = ds
        v[:] = vel[k]
        p[:] = pos[k]
        ba[:] = bias_acc[k]
        bg[:] = bias_gyr[k]
        G[:] = gsens[k]
        _inject(dx, n, q, v, p, ba, bg, G)
        quat[k] = q
        vel[k] = v
        pos[k] = p
        bias_acc[k] = ba
        bias_gyr[k] = bg
        gsens[k] = G
    return failed


@njit(cache=True, parallel=True)
def filter_batch(mode, t, u_acc, u_gyr, m_acc, m_gyr, zupt, zaru, v_heading, i0, q0, v0, p0, n, cfg, rts,
                 quat, vel, pos, bias_acc, bias_gyr, gsens, p_diag, skipped):
    """filter_run for R recordings at once: every array gains a leading run axis; runs spread over cores."""
    for r in prange(t.shape[0]):
        skipped[r] = filter_run(mode, t[r], u_acc[r], u_gyr[r], m_acc[r], m_gyr[r], zupt[r], zaru[r],
                                v_heading[r], i0[r], q0[r], v0[r], p0[r], n, cfg[r], rts, quat[r], vel[r], pos[r],
                                bias_acc[r], bias_gyr[r], gsens[r], p_diag[r])
