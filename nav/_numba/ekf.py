"""Compiled error-state EKF: the forward filter, the RTS pass and the batch over runs.

The filter settings arrive as ``cfg``, the named tuple :meth:`nav.ekf.FilterConfig.for_kernel` builds from
FilterConfig's own fields (read here by field name, so there is no second list of them). The error state and
its covariance algebra are described in :mod:`.covariance`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .covariance import joseph_update, propagate, propagation_buffers, update_buffers
from .linalg import cholesky_factor, cholesky_solve
from .quat import qexp, qmatrix, qmul, qnormalised
from .strapdown import MODE_INCREMENTS, apply_increment, increment_buffers, interval_increments


@njit(cache=True)
def initial_covariance_and_noise(n, cfg):
    """Initial covariance P (n x n) and continuous driving-noise power rw (n,), (unit/s)^2 * s, from cfg."""
    P = np.zeros((n, n))
    p0_std = (cfg.p0_pos, cfg.p0_vel, cfg.p0_tilt, cfg.p0_tilt, cfg.p0_yaw)
    for i in range(3):
        P[i, i] = p0_std[0] ** 2
        P[3 + i, 3 + i] = p0_std[1] ** 2
    P[6, 6] = p0_std[2] ** 2
    P[7, 7] = p0_std[3] ** 2
    P[8, 8] = p0_std[4] ** 2
    rw = np.zeros(n)
    for i in range(3):
        rw[3 + i] = cfg.acc_noise_density ** 2
        rw[6 + i] = cfg.gyr_noise_density ** 2
    if n >= 15:
        for i in range(3):
            P[9 + i, 9 + i] = cfg.p0_acc_bias ** 2
            P[12 + i, 12 + i] = cfg.p0_gyr_bias ** 2
            rw[9 + i] = cfg.acc_bias_random_walk ** 2
            rw[12 + i] = cfg.gyr_bias_random_walk ** 2
    if n == 24:
        for i in range(9):
            P[15 + i, 15 + i] = cfg.p0_gsens ** 2
            rw[15 + i] = cfg.gsens_random_walk ** 2
    return P, rw


@njit(cache=True)
def _store(k, q, v, p, ba, bg, G, quat, vel, pos, bias_acc, bias_gyr, gsens):
    """Write the nominal state into row k of the outputs."""
    quat[k] = q
    vel[k] = v
    pos[k] = p
    bias_acc[k] = ba
    bias_gyr[k] = bg
    gsens[k] = G


@njit(cache=True)
def _inject(dx, n, q, v, p, ba, bg, G):
    """Closed loop: add the error-state estimate dx to the nominal state and leave dx at zero."""
    for i in range(3):
        p[i] += dx[i]
        v[i] += dx[3 + i]
    e0, e1, e2, e3 = qexp(dx[6], dx[7], dx[8])
    n0, n1, n2, n3 = qmul(e0, e1, e2, e3, q[0], q[1], q[2], q[3])
    q[0], q[1], q[2], q[3] = qnormalised(n0, n1, n2, n3)
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
    if not joseph_update(P, n, h_col, h_val, h_cnt, m, z, r_var, dx, work):
        dx[:] = 0.0
        return 1
    for i in range(n):
        corr[i] += dx[i]
    _inject(dx, n, q, v, p, ba, bg, G)
    return 0


@njit(cache=True)
def filter_run(mode, t, u_acc, u_gyr, m_acc, m_gyr, zupt, zaru, stance_velocity, i0, q0, v0, p0, cfg, rts,
               quat, vel, pos, bias_acc, bias_gyr, gsens, p_diag):
    """Error-state EKF over one recording from sample i0; see nav.ekf.run_filter for the meaning of the inputs.

    Outputs (filled from i0 on, in place): quat (N,4), vel (N,3), pos (N,3), bias_acc (N,3), bias_gyr (N,3),
    gsens (N,9), p_diag (N,n) -- a posteriori at each sample, or smoothed when ``rts``. Returns the number of
    measurement updates skipped because the innovation covariance was not positive definite.
    """
    n_samples = t.shape[0]
    n = cfg.states
    q = q0.copy()
    v = v0.copy()
    p = p0.copy()
    ba = np.zeros(3)
    bg = np.zeros(3)
    G = np.zeros(9)
    P, rw = initial_covariance_and_noise(n, cfg)
    level_on = cfg.level_sigma > 0.0
    z_level = p0[2]

    C = np.empty((3, 3))
    prop = propagation_buffers(n)
    dq, du, ds, fhat, wk = increment_buffers()
    dx = np.zeros(n)
    h_col = np.zeros((3, 4), np.int64)  # sparse measurement matrix: columns, values, count per row
    h_val = np.zeros((3, 4))
    h_cnt = np.zeros(3, np.int64)
    z = np.empty(3)
    r_var = np.empty(3)
    work = update_buffers(n, 3)
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
            qmatrix(q, C)
            yaw = math.atan2(C[1, 0], C[0, 0])
            cy, sy = math.cos(yaw), math.sin(yaw)
            v_stance = stance_velocity[k]
            z[0] = cy * v_stance[0] - sy * v_stance[1] - v[0]
            z[1] = sy * v_stance[0] + cy * v_stance[1] - v[1]
            z[2] = v_stance[2] - v[2]
            for i in range(3):
                h_cnt[i] = 1
                h_col[i, 0] = 3 + i
                h_val[i, 0] = 1.0
                r_var[i] = cfg.zupt_sigma ** 2
            skipped += _update_and_inject(P, n, h_col, h_val, h_cnt, 3, z, r_var, dx, work, corr, q, v, p, ba, bg, G)
            if level_on:
                h_cnt[0] = 1
                h_col[0, 0] = 2
                h_val[0, 0] = 1.0
                z[0] = z_level - p[2]
                r_var[0] = cfg.level_sigma ** 2
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
                r_var[i] = cfg.zaru_sigma ** 2
            skipped += _update_and_inject(P, n, h_col, h_val, h_cnt, 3, z, r_var, dx, work, corr, q, v, p, ba, bg, G)

        _store(k, q, v, p, ba, bg, G, quat, vel, pos, bias_acc, bias_gyr, gsens)
        for i in range(n):
            p_diag[k, i] = P[i, i]
        if rts:
            P_store[k - i0] = P
        if k == n_samples - 1:
            break

        # ---- propagate to t_k+1
        h = interval_increments(mode, k, t, u_acc, u_gyr, m_acc, m_gyr, ba, bg, G, dq, du, ds, fhat, wk)
        propagate(P, n, q, fhat, h, rw, prop)
        if rts:
            f_store[k - i0] = fhat
        apply_increment(q, v, p, dq, du, ds, h, cfg.gravity)

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
    prop = propagation_buffers(n)
    E = prop[1]
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
        P_pred[:, :] = P_store[j]
        propagate(P_pred, n, q, f_store[j], h, rw, prop)
        if not cholesky_factor(P_pred, n, L):
            failed += 1
            ds[:] = 0.0
            continue
        cholesky_solve(L, n, y, x)
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
        _store(k, q, v, p, ba, bg, G, quat, vel, pos, bias_acc, bias_gyr, gsens)
    return failed


@njit(cache=True, parallel=True)
def filter_batch(mode, t, u_acc, u_gyr, m_acc, m_gyr, zupt, zaru, stance_velocity, i0, q0, v0, p0, cfg, rts,
                 quat, vel, pos, bias_acc, bias_gyr, gsens, p_diag, skipped):
    """:func:`filter_run` for R recordings with one ``cfg``: every array gains a leading run axis; runs spread
    over cores."""
    for r in prange(t.shape[0]):
        skipped[r] = filter_run(mode, t[r], u_acc[r], u_gyr[r], m_acc[r], m_gyr[r], zupt[r], zaru[r],
                                stance_velocity[r], i0[r], q0[r], v0[r], p0[r], cfg, rts, quat[r], vel[r], pos[r],
                                bias_acc[r], bias_gyr[r], gsens[r], p_diag[r])
