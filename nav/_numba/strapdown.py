"""Compiled strapdown: body-frame increments over one sample interval and the nominal-state update."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .quat import qexp, qmul, qnormalised, qrot

MODE_POINT_SAMPLES = 0  # acc/gyr are point samples; RK4 with interpolated mid-samples
MODE_INCREMENTS = 1  # acc/gyr hold exact increments dv (m/s, body at t_k) and dtheta (rad) over [t_k, t_k+1]


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
    k2r = qmul(r[0], r[1], r[2], r[3], 0.0, 0.5 * wm[0], 0.5 * wm[1], 0.5 * wm[2])
    k2u = qrot(r[0], r[1], r[2], r[3], fm[0], fm[1], fm[2])
    # stage 3 (tau = h/2)
    r = (1.0 + hh * k2r[0], hh * k2r[1], hh * k2r[2], hh * k2r[3])
    u3 = (hh * k2u[0], hh * k2u[1], hh * k2u[2])
    k3r = qmul(r[0], r[1], r[2], r[3], 0.0, 0.5 * wm[0], 0.5 * wm[1], 0.5 * wm[2])
    k3u = qrot(r[0], r[1], r[2], r[3], fm[0], fm[1], fm[2])
    # stage 4 (tau = h)
    r = (1.0 + h * k3r[0], h * k3r[1], h * k3r[2], h * k3r[3])
    u4 = (h * k3u[0], h * k3u[1], h * k3u[2])
    k4r = qmul(r[0], r[1], r[2], r[3], 0.0, 0.5 * w1[0], 0.5 * w1[1], 0.5 * w1[2])
    k4u = qrot(r[0], r[1], r[2], r[3], f1[0], f1[1], f1[2])
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


@njit(cache=True, inline="always")
def apply_increment(q, v, p, dq, du, ds, h, gravity):
    """Advance the nominal state (q, v, p) in place by body increments over an interval of h seconds.

    ``v += C du + g h``, ``p += v h + C ds + g h^2 / 2`` (with the old v), ``q = q ⊗ dq``; g = (0, 0, -gravity).
    """
    a0, a1, a2 = qrot(q[0], q[1], q[2], q[3], du[0], du[1], du[2])
    b0, b1, b2 = qrot(q[0], q[1], q[2], q[3], ds[0], ds[1], ds[2])
    p[0] += v[0] * h + b0
    p[1] += v[1] * h + b1
    p[2] += v[2] * h + b2 - 0.5 * gravity * h * h
    v[0] += a0
    v[1] += a1
    v[2] += a2 - gravity * h
    n0, n1, n2, n3 = qmul(q[0], q[1], q[2], q[3], dq[0], dq[1], dq[2], dq[3])
    q[0], q[1], q[2], q[3] = qnormalised(n0, n1, n2, n3)


@njit(cache=True)
def mid_sample_weights(t, k, weights):
    """Cubic Lagrange weights (4,) of the value at the middle of [t_k, t_k+1]; returns the first sample index.

    The stencil is samples k-1..k+2, shifted inward at both ends of the recording (a quadratic or linear
    stencil, padded with zero weights, when it has fewer than 4 samples): nav.strapdown.mid_samples, whose
    weights are computed in the same order.
    """
    n = t.shape[0]
    order = min(4, n)
    first = min(max(k - 1 if order == 4 else k, 0), n - order)
    tm = 0.5 * (t[k] + t[k + 1])
    for j in range(4):
        weights[j] = 0.0
    for j in range(order):
        w = 1.0
        for m in range(order):
            if m != j:
                w *= (tm - t[first + m]) / (t[first + j] - t[first + m])
        weights[j] = w
    return first


@njit(cache=True)
def _mid_sample(weights, x, j0, j1, j2, j3):
    """The weighted sum of rows j0..j3 of x (N, 3) with the (4,) weights of :func:`mid_sample_weights`, a 3-tuple."""
    return ((weights[0] * x[j0, 0] + weights[1] * x[j1, 0] + weights[2] * x[j2, 0] + weights[3] * x[j3, 0]),
            (weights[0] * x[j0, 1] + weights[1] * x[j1, 1] + weights[2] * x[j2, 1] + weights[3] * x[j3, 1]),
            (weights[0] * x[j0, 2] + weights[1] * x[j1, 2] + weights[2] * x[j2, 2] + weights[3] * x[j3, 2]))


@njit(cache=True)
def _less_bias(f, ba):
    """Specific force sample f (3,) less the accelerometer bias ba (3,), m/s^2, as a 3-tuple."""
    return f[0] - ba[0], f[1] - ba[1], f[2] - ba[2]


@njit(cache=True)
def _corrected_rate(w, bg, G, f):
    """Rate sample w (3,) less the gyro bias bg (3,) and the g-sensitivity G (9,) times the corrected specific force
    f (3-tuple), rad/s, as a 3-tuple."""
    return (w[0] - bg[0] - (G[0] * f[0] + G[1] * f[1] + G[2] * f[2]),
            w[1] - bg[1] - (G[3] * f[0] + G[4] * f[1] + G[5] * f[2]),
            w[2] - bg[2] - (G[6] * f[0] + G[7] * f[1] + G[8] * f[2]))


@njit(cache=True, inline="always")
def interval_increments(mode, k, t, u_acc, u_gyr, ba, bg, G, dq, du, ds, fhat, weights):
    """Bias-corrected body increments over [t_k, t_k+1]; returns h = t_k+1 - t_k (s).

    ``u_acc``, ``u_gyr`` are the samples (or increments); the mid-interval samples are interpolated here
    (:func:`mid_sample_weights`). ``ba``, ``bg``, ``G`` are the bias and g-sensitivity estimates. Writes
    ``dq``, ``du``, ``ds`` and the corrected specific force at t_k into ``fhat``; ``weights`` is a (4,) work
    buffer. The samples of the interval are held in scalars (tuples), not buffers, so that they stay in registers.
    """
    h = t[k + 1] - t[k]
    if mode == MODE_INCREMENTS:
        for i in range(3):
            du[i] = u_acc[k, i] - ba[i] * h
            fhat[i] = du[i] / h
        for i in range(3):
            dth = u_gyr[k, i] - bg[i] * h - (G[3 * i] * du[0] + G[3 * i + 1] * du[1] + G[3 * i + 2] * du[2])
            ds[i] = dth  # temporary store of the corrected rotation vector
        e0, e1, e2, e3 = qexp(ds[0], ds[1], ds[2])
        dq[0], dq[1], dq[2], dq[3] = e0, e1, e2, e3
        for i in range(3):
            ds[i] = 0.5 * h * du[i]  # trapezoid position increment
    else:
        first = mid_sample_weights(t, k, weights)
        n = t.shape[0]
        j1, j2, j3 = min(first + 1, n - 1), min(first + 2, n - 1), min(first + 3, n - 1)
        f0 = _less_bias(u_acc[k], ba)
        fm = _less_bias(_mid_sample(weights, u_acc, first, j1, j2, j3), ba)
        f1 = _less_bias(u_acc[k + 1], ba)
        w0 = _corrected_rate(u_gyr[k], bg, G, f0)
        wm = _corrected_rate(_mid_sample(weights, u_gyr, first, j1, j2, j3), bg, G, fm)
        w1 = _corrected_rate(u_gyr[k + 1], bg, G, f1)
        fhat[0], fhat[1], fhat[2] = f0
        rk4_increment(h, w0, wm, w1, f0, fm, f1, dq, du, ds)
    return h


@njit(cache=True)
def increment_buffers():
    """Work buffers of :func:`interval_increments`: dq (4), du (3), ds (3), fhat (3), weights (4)."""
    return np.empty(4), np.empty(3), np.empty(3), np.empty(3), np.empty(4)


@njit(cache=True)
def strapdown_run(mode, t, u_acc, u_gyr, i0, q0, v0, p0, gravity, quat, vel, pos):
    """Unaided mechanisation from sample i0; fills quat (N,4), vel (N,3), pos (N,3) from i0 on."""
    n_samples = t.shape[0]
    q = q0.copy()
    v = v0.copy()
    p = p0.copy()
    zero3 = np.zeros(3)
    zero9 = np.zeros(9)
    dq, du, ds, fhat, weights = increment_buffers()
    for k in range(i0, n_samples):
        quat[k] = q
        vel[k] = v
        pos[k] = p
        if k == n_samples - 1:
            break
        h = interval_increments(mode, k, t, u_acc, u_gyr, zero3, zero3, zero9, dq, du, ds, fhat, weights)
        apply_increment(q, v, p, dq, du, ds, h, gravity)
