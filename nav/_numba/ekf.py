"""Compiled error-state EKF: the forward filter, the smoother's backward pass and the batch over runs.

The filter settings arrive as ``cfg``, the named tuple :meth:`nav.ekf.FilterConfig.for_kernel` builds from
FilterConfig's own fields (read here by field name, so there is no second list of them). The error state and
its covariance algebra are described in :mod:`.covariance`; :mod:`nav.ekf_reference` is the same filter
written densely in numpy.

Smoother. The Rauch-Tung-Striebel estimate ``x_k|N = P_k Phi_k^T P_k+1|k^-1 x_k+1|N`` needs every P_k and an
inverse per sample. The same estimate follows from the adjoint (Bryson-Frazier) recursion, which needs only
what the filter's updates and transitions were:

- adjoint after the updates at k: ``lam_k = Phi_k^T lam~_k+1``; before them, one step per update u (in
  reverse order): ``lam~ = lam - H_u^T (K_u^T lam + S_u^-1 z_u)``, from ``lam_N-1 = 0``;
- smoothed error of the predicted nominal at k+1: ``w_k+1 = d_k+1 + c_k+1`` (``c`` the corrections the filter
  injected there) equals ``-P_k+1|k lam~_k+1``; with ``P_k Phi_k^T = Phi_k^-1 (P_k+1|k - Q_k)`` the smoothed
  error of the filtered nominal at k is ``d_k = -P_k lam_k = Phi_k^-1 (w_k+1 + Q_k lam~_k+1)``.

So the forward pass stores per update the gain K (n x m), the sparse H, z and ``S^-1 z`` (stance samples
only), and per sample the corrected specific force (the attitude is the filter's output); the backward pass
costs two structured transitions per sample and no factorisation.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from .covariance import (covariance_zeros, joseph_update, propagate, row_stride, transition_rows,
                         transition_transposed, update_buffers)
from .quat import qexp, qmatrix, qmul, qnormalised
from .strapdown import MODE_INCREMENTS, apply_increment, increment_buffers, interval_increments


@njit(cache=True)
def initial_covariance_and_noise(n, cfg):
    """Initial covariance P (n x n, flat: :func:`.covariance.covariance_zeros`) and continuous driving-noise power
    (n,), (unit/s)^2 * s, from cfg."""
    P = covariance_zeros(n)
    d = row_stride(n) + 1  # from one diagonal element to the next
    for i in range(3):
        P[i * d] = cfg.p0_pos ** 2
        P[(3 + i) * d] = cfg.p0_vel ** 2
    P[6 * d] = cfg.p0_tilt ** 2
    P[7 * d] = cfg.p0_tilt ** 2
    P[8 * d] = cfg.p0_yaw ** 2
    power = np.zeros(n)
    for i in range(3):
        power[3 + i] = cfg.acc_noise_density ** 2
        power[6 + i] = cfg.gyr_noise_density ** 2
    if n >= 15:
        for i in range(3):
            P[(9 + i) * d] = cfg.p0_acc_bias ** 2
            P[(12 + i) * d] = cfg.p0_gyr_bias ** 2
            power[9 + i] = cfg.acc_bias_random_walk ** 2
            power[12 + i] = cfg.gyr_bias_random_walk ** 2
    if n == 24:
        for i in range(9):
            P[(15 + i) * d] = cfg.p0_gsens ** 2
            power[15 + i] = cfg.gsens_random_walk ** 2
    return P, power


@njit(cache=True, inline="always")
def _store(k, q, v, p, ba, bg, G, quat, vel, pos, bias_acc, bias_gyr, gsens):
    """Write the nominal state into row k of the outputs (the estimates into their only row when they keep the
    final sample's alone: see :func:`filter_run`)."""
    e = min(k, bias_acc.shape[0] - 1)
    for i in range(4):
        quat[k, i] = q[i]
    for i in range(3):
        vel[k, i] = v[i]
        pos[k, i] = p[i]
        bias_acc[e, i] = ba[i]
        bias_gyr[e, i] = bg[i]
    for i in range(9):
        gsens[e, i] = G[i]


@njit(cache=True, inline="always")
def _inject(dx, n, q, v, p, ba, bg, G):
    """Closed loop: add the error-state estimate dx to the nominal state."""
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


@njit(cache=True)
def smoother_buffers(records, n, steps):
    """What the backward pass needs: per update its sample, H (columns, values, counts), K (n, 3), z and
    S^-1 z (3); per interval the corrected specific force (3)."""
    return (np.empty(records, np.int64), np.empty((records, 3, 4), np.int64), np.empty((records, 3, 4)),
            np.zeros((records, 3), np.int64), np.empty((records, n, 3)), np.zeros((records, 3)),
            np.zeros((records, 3)), np.empty((steps, 3)))


@njit(cache=True, inline="always")
def _update(k, P, n, h_col, h_val, h_cnt, m, z, r_var, dx, K, s, work, q, v, p, ba, bg, G, rts, records, count):
    """One Joseph-form update injected into the nominal state, recorded for the smoother when ``rts``.

    Returns (records used, 1 if the update was skipped because S was not positive definite else 0).
    """
    if rts:
        K, s = records[4][count], records[6][count]
    if not joseph_update(P, n, h_col, h_val, h_cnt, m, z, r_var, dx, K, s, work):
        return count, 1
    _inject(dx, n, q, v, p, ba, bg, G)
    if not rts:
        return count, 0
    sample, cols, vals, cnts, _, zs, _, _ = records
    sample[count] = k
    for r in range(m):
        zs[count, r] = z[r]
        cnts[count, r] = h_cnt[r]
        for e in range(h_cnt[r]):
            cols[count, r, e] = h_col[r, e]
            vals[count, r, e] = h_val[r, e]
    return count + 1, 0


@njit(cache=True)
def filter_run(mode, t, u_acc, u_gyr, stationary, stance_velocity, i0, q0, v0, p0, cfg, rts,
               quat, vel, pos, bias_acc, bias_gyr, gsens, p_diag):
    """Error-state EKF over one recording from sample i0; see nav.ekf.run_filter for the meaning of the inputs.

    Outputs (filled in place; rows before i0 NaN): quat (N,4), vel (N,3), pos (N,3), bias_acc (N,3),
    bias_gyr (N,3), gsens (N,9), p_diag (N,n) -- a posteriori at each sample, or smoothed when ``rts`` (state
    only; p_diag stays filtered). The estimates bias_acc, bias_gyr, gsens and p_diag may instead have one row:
    it receives every sample in turn and holds the last one's (not with ``rts``, which reads them back). Returns
    the number of measurement updates skipped because the innovation covariance was not positive definite.

    The state count is a constant in each branch: the compiler unrolls the block loops for it, and the covariance's
    row stride is a constant with it, so that the loops over its columns vectorise (:mod:`.covariance`).
    """
    if cfg.states == 9:
        return _filter(9, mode, t, u_acc, u_gyr, stationary, stance_velocity, i0, q0, v0, p0, cfg, rts, quat, vel,
                       pos, bias_acc, bias_gyr, gsens, p_diag)
    if cfg.states == 15:
        return _filter(15, mode, t, u_acc, u_gyr, stationary, stance_velocity, i0, q0, v0, p0, cfg, rts, quat, vel,
                       pos, bias_acc, bias_gyr, gsens, p_diag)
    return _filter(24, mode, t, u_acc, u_gyr, stationary, stance_velocity, i0, q0, v0, p0, cfg, rts, quat, vel,
                   pos, bias_acc, bias_gyr, gsens, p_diag)


@njit(cache=True)
def _filter(n, mode, t, u_acc, u_gyr, stationary, stance_velocity, i0, q0, v0, p0, cfg, rts,
            quat, vel, pos, bias_acc, bias_gyr, gsens, p_diag):
    """:func:`filter_run` for n states."""
    n_samples = t.shape[0]
    for k in range(i0):
        quat[k] = np.nan
        vel[k] = np.nan
        pos[k] = np.nan
        if p_diag.shape[0] == n_samples:
            bias_acc[k] = np.nan
            bias_gyr[k] = np.nan
            gsens[k] = np.nan
            p_diag[k] = np.nan
    q = q0.copy()
    v = v0.copy()
    p = p0.copy()
    ba = np.zeros(3)
    bg = np.zeros(3)
    G = np.zeros(9)
    P, power = initial_covariance_and_noise(n, cfg)
    level_on = cfg.level_sigma > 0.0
    zaru_on = cfg.zaru and n >= 15
    z_level = p0[2]

    C = np.empty((3, 3))
    a = np.empty(3)
    dq, du, ds, fhat, weights = increment_buffers()
    dx = np.zeros(n)
    h_col = np.zeros((3, 4), np.int64)  # sparse measurement matrix: columns, values, count per row
    h_val = np.zeros((3, 4))
    h_cnt = np.zeros(3, np.int64)
    z = np.empty(3)
    r_var = np.empty(3)
    K = np.empty((n, 3))
    s = np.empty(3)
    work = update_buffers(n)
    n_records = 0
    if rts:
        for k in range(i0, n_samples):
            n_records += stationary[k] * (1 + level_on + (zaru_on and k < n_samples - 1))
    records = smoother_buffers(n_records, n, max(n_samples - 1 - i0, 0) if rts else 0)
    f_store = records[7]
    count = 0
    skipped = 0

    for k in range(i0, n_samples):
        # ---- measurement updates at t_k; each correction is injected before the next update
        if stationary[k]:
            qmatrix(q, C)
            # the stance velocity is given in the heading frame: rotate it by the current yaw
            norm = np.hypot(C[0, 0], C[1, 0])
            cy, sy = (C[0, 0] / norm, C[1, 0] / norm) if norm > 0.0 else (1.0, 0.0)
            v_stance = stance_velocity[k]
            z[0] = cy * v_stance[0] - sy * v_stance[1] - v[0]
            z[1] = sy * v_stance[0] + cy * v_stance[1] - v[1]
            z[2] = v_stance[2] - v[2]
            for i in range(3):
                h_cnt[i] = 1
                h_col[i, 0] = 3 + i
                h_val[i, 0] = 1.0
                r_var[i] = cfg.zupt_sigma ** 2
            count, miss = _update(k, P, n, h_col, h_val, h_cnt, 3, z, r_var, dx, K, s, work, q, v, p, ba, bg, G,
                                  rts, records, count)
            skipped += miss
            if level_on:
                h_cnt[0] = 1
                h_col[0, 0] = 2
                h_val[0, 0] = 1.0
                z[0] = z_level - p[2]
                r_var[0] = cfg.level_sigma ** 2
                count, miss = _update(k, P, n, h_col, h_val, h_cnt, 1, z, r_var, dx, K, s, work, q, v, p, ba, bg,
                                      G, rts, records, count)
                skipped += miss
        if zaru_on and stationary[k] and k < n_samples - 1:
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
            count, miss = _update(k, P, n, h_col, h_val, h_cnt, 3, z, r_var, dx, K, s, work, q, v, p, ba, bg, G,
                                  rts, records, count)
            skipped += miss

        _store(k, q, v, p, ba, bg, G, quat, vel, pos, bias_acc, bias_gyr, gsens)
        for i in range(n):
            p_diag[min(k, p_diag.shape[0] - 1), i] = P[i * (row_stride(n) + 1)]
        if k == n_samples - 1:
            break

        # ---- propagate to t_k+1
        h = interval_increments(mode, k, t, u_acc, u_gyr, ba, bg, G, dq, du, ds, fhat, weights)
        qmatrix(q, C)
        for i in range(3):
            a[i] = C[i, 0] * fhat[0] + C[i, 1] * fhat[1] + C[i, 2] * fhat[2]
        propagate(P, n, h, a, C, fhat, power)
        if rts:
            f_store[k - i0] = fhat[:3]
        apply_increment(q, v, p, dq, du, ds, h, cfg.gravity)

    if rts:
        _smooth(t, i0, n, power, records, count, quat, vel, pos, bias_acc, bias_gyr, gsens)
    return skipped


@njit(cache=True)
def _adjoint_updates(k, count, records, n, lam, w, g):
    """Undo the updates at sample k in the adjoint ``lam`` (last first) and add their corrections to ``w``;
    ``g`` is a (3,) work buffer. Returns the number of records left."""
    sample, cols, vals, cnts, gains, zs, sz, _ = records
    while count > 0 and sample[count - 1] == k:
        count -= 1
        K = gains[count]
        for r in range(3):  # g = K^T lam + S^-1 z (rows beyond the update's m have no entries)
            acc = sz[count, r]
            if cnts[count, r] > 0:
                for i in range(n):
                    acc += K[i, r] * lam[i]
                    w[i] += K[i, r] * zs[count, r]
            g[r] = acc
        for r in range(3):  # lam -= H^T g
            for e in range(cnts[count, r]):
                lam[cols[count, r, e]] -= vals[count, r, e] * g[r]
    return count


@njit(cache=True)
def _smooth(t, i0, n, power, records, count, quat, vel, pos, bias_acc, bias_gyr, gsens):
    """Backward pass (see the module docstring): smooths the nominal outputs from the last sample to i0."""
    n_samples = t.shape[0]
    f_store = records[7]
    lam = np.zeros(n)
    w = np.zeros(n)
    d = np.empty(n)
    dx = np.empty(n)
    C = np.empty((3, 3))
    a = np.empty(3)
    q = np.empty(4)
    v = np.empty(3)
    p = np.empty(3)
    ba = np.empty(3)
    bg = np.empty(3)
    G = np.empty(9)
    g = np.empty(3)
    count = _adjoint_updates(n_samples - 1, count, records, n, lam, w, g)
    for k in range(n_samples - 2, i0 - 1, -1):
        h = t[k + 1] - t[k]
        f = f_store[k - i0]
        q[:] = quat[k]
        qmatrix(q, C)
        for i in range(3):
            a[i] = C[i, 0] * f[0] + C[i, 1] * f[1] + C[i, 2] * f[2]
        for i in range(n):
            d[i] = w[i] + power[i] * h * lam[i]
        transition_rows(d, 1, n, h, a, C, f, True)
        transition_transposed(lam, n, h, a, C, f)
        for i in range(n):
            dx[i] = d[i]
            w[i] = d[i]
        v[:] = vel[k]
        p[:] = pos[k]
        ba[:] = bias_acc[k]
        bg[:] = bias_gyr[k]
        G[:] = gsens[k]
        _inject(dx, n, q, v, p, ba, bg, G)
        _store(k, q, v, p, ba, bg, G, quat, vel, pos, bias_acc, bias_gyr, gsens)
        count = _adjoint_updates(k, count, records, n, lam, w, g)


@njit(cache=True, parallel=True)
def filter_batch(mode, t, u_acc, u_gyr, stationary, stance_velocity, i0, q0, v0, p0, cfg, rts,
                 quat, vel, pos, bias_acc, bias_gyr, gsens, p_diag, skipped):
    """:func:`filter_run` for R recordings with one ``cfg``: every array gains a leading run axis; runs spread
    over cores."""
    for r in prange(t.shape[0]):
        skipped[r] = filter_run(mode, t[r], u_acc[r], u_gyr[r], stationary[r], stance_velocity[r], i0[r],
                                q0[r], v0[r], p0[r], cfg, rts, quat[r], vel[r], pos[r], bias_acc[r], bias_gyr[r],
                                gsens[r], p_diag[r])
