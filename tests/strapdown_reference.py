"""A strapdown written for the tests only, independent of nav/: vectorised over independent windows."""

import numpy as np

from nav import quaternion as Q


def integrate_increments(q0, v0, p0, dv, dth, dt, gravity=9.81):
    """Propagate with exact increments (dv in the body frame at t_k, dth a rotation vector); trapezoid position."""
    g = np.array([0.0, 0.0, -gravity])
    q, v, p = q0.copy(), v0.copy(), p0.copy()
    for k in range(len(dv)):
        v_next = v + Q.rotate(q, dv[k]) + g * dt
        p = p + 0.5 * (v + v_next) * dt
        q = Q.multiply(q, Q.from_rotvec(dth[k]))
        v = v_next
    return q, v, p


def rk4_windows(q0, v0, p0, gyr, acc, dt, gravity=9.81):
    """RK4 over windows in parallel: q0/v0/p0 (W, 4/3/3), gyr/acc (W, M, 3) point samples at t_k.

    Mid-samples come from 4-point cubic interpolation of the neighbouring samples, so each window needs one sample
    before its start and two after its end: the returned state is at sample index M - 3 of the window (after
    M - 4 steps from index 1).
    """
    g = np.array([0.0, 0.0, -gravity])
    mid_w = (9 * (gyr[:, 1:-2] + gyr[:, 2:-1]) - (gyr[:, :-3] + gyr[:, 3:])) / 16
    mid_a = (9 * (acc[:, 1:-2] + acc[:, 2:-1]) - (acc[:, :-3] + acc[:, 3:])) / 16

    def deriv(q, v, w, a):
        dq = 0.5 * Q.multiply(q, np.concatenate([np.zeros(w.shape[:-1] + (1,)), w], axis=-1))
        return dq, Q.rotate(q, a) + g

    q, v, p = q0.copy(), v0.copy(), p0.copy()
    for k in range(1, gyr.shape[1] - 3):
        w0, w1, wm = gyr[:, k], gyr[:, k + 1], mid_w[:, k - 1]
        a0, a1, am = acc[:, k], acc[:, k + 1], mid_a[:, k - 1]
        k1q, k1v = deriv(q, v, w0, a0)
        k2q, k2v = deriv(q + 0.5 * dt * k1q, v + 0.5 * dt * k1v, wm, am)
        k3q, k3v = deriv(q + 0.5 * dt * k2q, v + 0.5 * dt * k2v, wm, am)
        k4q, k4v = deriv(q + dt * k3q, v + dt * k3v, w1, a1)
        p = p + dt / 6 * (6 * v + dt * (k1v + k2v + k3v))
        v = v + dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        q = q + dt / 6 * (k1q + 2 * k2q + 2 * k3q + k4q)
        q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return q, v, p
