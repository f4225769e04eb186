"""An analytic straight walk with exact truth, for the nav tests (no simulator needed)."""

from __future__ import annotations

import numpy as np

from nav import quaternion as Q
from nav.recording import Recording, Truth

G = 9.81


def synthetic_walk(strides=10, fs=800.0, creep=0.02, stride_length=1.4, period=1.4, stance_frac=0.4,
                   stand=1.0, yaw=np.pi / 2) -> Recording:
    """Analytic straight walk along heading ``yaw`` (rad from east) with exact truth and an ideal IMU.

    Rest (``stand`` s), then ``strides`` strides of ``period`` s: a stance of ``stance_frac * period`` in which
    the foot creeps forward with v = creep sin^2(pi tau) (m/s; zero at the stance edges, displacement
    creep * T_stance / 2 per stance; none in the first stance, which joins the initial rest), and a swing
    that advances ``stride_length`` m by a smooth step while the foot lifts 8 cm and pitches up to 0.3 rad;
    rest again. ``truth.stance`` labels the stances.
    """
    t_st, t_sw = stance_frac * period, (1 - stance_frac) * period
    n = int(round((stand + strides * period + stand) * fs)) + 1
    t = np.arange(n) / fs
    x = np.zeros(n); vx = np.zeros(n); ax = np.zeros(n)
    z = np.zeros(n); vz = np.zeros(n); az = np.zeros(n)
    th = np.zeros(n); thd = np.zeros(n)
    stance = np.ones(n, bool)
    disp = creep * t_st / 2  # creep displacement per stance
    for s in range(strides):
        t0 = stand + s * period
        base = s * (stride_length + disp) - disp if s else 0.0
        c_s = creep if s else 0.0  # the first stance joins the initial rest: no creep there
        # stance [t0, t0 + t_st): v = c_s sin^2(pi tau)
        m = (t >= t0) & (t < t0 + t_st)
        tau = (t[m] - t0) / t_st
        x[m] = base + c_s * t_st * (tau / 2 - np.sin(2 * np.pi * tau) / (4 * np.pi))
        vx[m] = c_s * np.sin(np.pi * tau) ** 2
        ax[m] = c_s * np.pi / t_st * np.sin(2 * np.pi * tau)
        # swing [t0 + t_st, t0 + period): smooth step of stride_length
        m = (t >= t0 + t_st) & (t < t0 + period)
        tau = (t[m] - t0 - t_st) / t_sw
        w = 2 * np.pi
        x[m] = base + (disp if s else 0.0) + stride_length * (tau - np.sin(w * tau) / w)
        vx[m] = stride_length / t_sw * (1 - np.cos(w * tau))
        ax[m] = stride_length / t_sw**2 * w * np.sin(w * tau)
        z[m] = 0.04 * (1 - np.cos(w * tau))
        vz[m] = 0.04 * w / t_sw * np.sin(w * tau)
        az[m] = 0.04 * w**2 / t_sw**2 * np.cos(w * tau)
        th[m] = 0.3 * (1 - np.cos(w * tau)) / 2
        thd[m] = 0.3 * w / (2 * t_sw) * np.sin(w * tau)
        stance[m] = False
    end = t >= stand + strides * period
    x[end] = strides * stride_length + (strides - 1) * disp
    c, s_ = np.cos(yaw), np.sin(yaw)
    pos = np.stack([c * x, s_ * x, z], -1)
    vel = np.stack([c * vx, s_ * vx, vz], -1)
    acc_w = np.stack([c * ax, s_ * ax, az], -1)
    q = Q.from_euler_zyx(np.full(n, yaw), th, np.zeros(n))
    gyr = np.stack([np.zeros(n), thd, np.zeros(n)], -1)  # pitch about body y, yaw fixed
    f = Q.rotate(Q.conjugate(q), acc_w - [0.0, 0.0, -G])
    dt = np.diff(t)[:, None]
    dv = np.zeros_like(vel); dth = np.zeros_like(vel)
    dv[:-1] = Q.rotate(Q.conjugate(q[:-1]), vel[1:] - vel[:-1] - np.array([0, 0, -G]) * dt)
    dth[:-1] = Q.to_rotvec(Q.multiply(Q.conjugate(q[:-1]), q[1:]))
    truth = Truth(t=t, pos=pos, vel=vel, quat=q, gyr=gyr, acc=f, dv=dv, dth=dth, stance=stance)
    return Recording(t=t, acc=f.copy(), gyr=gyr.copy(), meta={}, truth=truth)
