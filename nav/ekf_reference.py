"""The error-state EKF of :mod:`nav.ekf` written plainly: dense matrices, numpy, one Python loop over samples.

It holds the filter's mathematics in a few lines each (the transition ``Phi = I + F h``, the Joseph-form
update, the closed-loop injection, the textbook Rauch-Tung-Striebel pass) so that they can be read and checked,
and the compiled filter (:mod:`nav._numba`), which computes the same quantities in 3 x 3 blocks and smooths
with an equivalent adjoint recursion, is tested against it to round-off. It is slow (tens of microseconds per
sample): use it on short recordings. States, units and settings are those of :mod:`nav.ekf`.
"""

from __future__ import annotations

import numpy as np

from . import quaternion as quat
from .ekf import FilterConfig, FilterOutput, check_filter_inputs, empty_outputs, per_sample_stance_velocity
from .strapdown import mid_samples

I3 = np.eye(3)


def initial_state(config: FilterConfig) -> tuple[np.ndarray, np.ndarray]:
    """Initial covariance P0 (n, n) and continuous driving-noise power (n,) ((unit/s)^2 s) of ``config``."""
    c = config
    std = [c.p0_pos] * 3 + [c.p0_vel] * 3 + [c.p0_tilt, c.p0_tilt, c.p0_yaw]
    power = [0.0] * 3 + [c.acc_noise_density ** 2] * 3 + [c.gyr_noise_density ** 2] * 3
    if c.states >= 15:
        std += [c.p0_acc_bias] * 3 + [c.p0_gyr_bias] * 3
        power += [c.acc_bias_random_walk ** 2] * 3 + [c.gyr_bias_random_walk ** 2] * 3
    if c.states == 24:
        std += [c.p0_gsens] * 9
        power += [c.gsens_random_walk ** 2] * 9
    return np.diag(np.square(std)), np.array(power)


def transition(C: np.ndarray, f: np.ndarray, h: float, n: int) -> np.ndarray:
    """Phi = I + F h of the error state over h seconds, attitude C (3, 3) and corrected specific force f (3,)."""
    F = np.zeros((n, n))
    F[0:3, 3:6] = I3  # dp' = dv
    F[3:6, 6:9] = -quat.skew(C @ f)  # dv' = -[a x] dtheta - C db_a
    if n >= 15:
        F[3:6, 9:12] = -C
        F[6:9, 12:15] = -C  # dtheta' = -C db_g - C dG f
    if n == 24:
        F[6:9, 15:24] = -C @ np.kron(I3, f[None, :])  # (dG f)_r = sum_c f_c dG_rc, dG row-major
    return np.eye(n) + F * h


def rk4_increment(h, w0, wm, w1, f0, fm, f1):
    """Body increments (dq, du, ds) over one interval by RK4 on r' = r (0, w)/2, u' = R(r) f, s' = u."""

    def rates(r, w, f):
        return 0.5 * quat.multiply(r, np.concatenate([[0.0], w])), quat.rotate(r / np.linalg.norm(r), f)

    one = np.array([1.0, 0.0, 0.0, 0.0])
    k1r, k1u = rates(one, w0, f0)
    k2r, k2u = rates(one + 0.5 * h * k1r, wm, fm)
    k3r, k3u = rates(one + 0.5 * h * k2r, wm, fm)
    k4r, k4u = rates(one + h * k3r, w1, f1)
    dq = one + h / 6 * (k1r + 2 * k2r + 2 * k3r + k4r)
    du = h / 6 * (k1u + 2 * k2u + 2 * k3u + k4u)
    ds = h / 6 * (2 * (0.5 * h * k1u) + 2 * (0.5 * h * k2u) + h * k3u)  # s' = u at the four stages
    return dq / np.linalg.norm(dq), du, ds


class _State:
    """Nominal state: attitude q (4,), velocity v, position p, biases ba, bg (3,), g-sensitivity G (3, 3)."""

    def __init__(self, q, v, p):
        self.q, self.v, self.p = np.array(q, float), np.array(v, float), np.array(p, float)
        self.ba, self.bg, self.G = np.zeros(3), np.zeros(3), np.zeros((3, 3))

    def inject(self, dx: np.ndarray) -> None:
        """Closed loop: add an error-state estimate (true minus estimated) to the nominal state."""
        self.p = self.p + dx[0:3]
        self.v = self.v + dx[3:6]
        q = quat.multiply(quat.from_rotvec(dx[6:9]), self.q)
        self.q = q / np.linalg.norm(q)
        if len(dx) >= 15:
            self.ba = self.ba + dx[9:12]
            self.bg = self.bg + dx[12:15]
        if len(dx) == 24:
            self.G = self.G + dx[15:24].reshape(3, 3)

    def copy(self) -> "_State":
        out = _State(self.q, self.v, self.p)
        out.ba, out.bg, out.G = self.ba.copy(), self.bg.copy(), self.G.copy()
        return out


def joseph_update(P, H, z, R):
    """(correction dx, updated P) of the measurement z = H dx + noise(R), or (None, P) if S is not positive
    definite."""
    S = H @ P @ H.T + R
    if np.any(np.linalg.eigvalsh(S) <= 0):
        return None, P
    K = np.linalg.solve(S, H @ P).T  # P H^T S^-1 (S and P symmetric)
    A = np.eye(len(P)) - K @ H
    P = A @ P @ A.T + K @ R @ K.T
    return K @ z, 0.5 * (P + P.T)


def run_reference_filter(t, acc, gyr, stationary, quat0, vel0=(0.0, 0.0, 0.0), pos0=(0.0, 0.0, 0.0), start=0,
                         config: FilterConfig = FilterConfig(), method="rk4", stance_velocity=None,
                         rts=False) -> FilterOutput:
    """The filter of :func:`nav.ekf.run_filter` (same parameters and output), written densely in numpy."""
    t, acc, gyr, stationary = check_filter_inputs(t, acc, gyr, stationary, start)
    n_samples, n = len(t), config.states
    increments = method == "increments"
    acc_mid = None if increments else mid_samples(t, acc)
    gyr_mid = None if increments else mid_samples(t, gyr)
    v_stance = per_sample_stance_velocity(stance_velocity, (n_samples,))
    out = empty_outputs((n_samples,), n)
    for name in ("quat", "vel", "pos", "bias_acc", "bias_gyr", "gsens", "p_diag"):
        getattr(out, name)[:start] = np.nan
    P, power = initial_state(config)
    x = _State(np.asarray(quat0, float) / np.linalg.norm(quat0), vel0, pos0)
    z_level = x.p[2]
    filtered, transitions, corrections = [], [], []
    skipped = 0

    def update(H, z, sigma):
        nonlocal P, skipped
        dx, P = joseph_update(P, H, z, sigma ** 2 * np.eye(len(z)))
        if dx is None:
            skipped += 1
            return np.zeros(n)
        x.inject(dx)
        return dx

    for k in range(start, n_samples):
        correction = np.zeros(n)
        h = t[k + 1] - t[k] if k < n_samples - 1 else np.nan
        if stationary[k]:
            C = quat.to_matrix(x.q)
            yaw = np.arctan2(C[1, 0], C[0, 0])
            heading = np.array([[np.cos(yaw), -np.sin(yaw), 0.0], [np.sin(yaw), np.cos(yaw), 0.0], [0, 0, 1]])
            correction += update(np.eye(3, n, 3), heading @ v_stance[k] - x.v, config.zupt_sigma)
            if config.level_sigma > 0:
                correction += update(np.eye(1, n, 2), np.array([z_level - x.p[2]]), config.level_sigma)
        if config.zaru and stationary[k] and k < n_samples - 1:
            f = (acc[k] / h if increments else acc[k]) - x.ba
            w = (gyr[k] / h if increments else gyr[k]) - x.bg - x.G @ f
            H = -np.eye(3, n, 12)
            if n == 24:
                H[:, 15:24] = -np.kron(I3, f[None, :])
            correction += update(H, -w, config.zaru_sigma)
        out.quat[k], out.vel[k], out.pos[k] = x.q, x.v, x.p
        out.bias_acc[k], out.bias_gyr[k], out.gsens[k] = x.ba, x.bg, x.G.ravel()
        out.p_diag[k] = np.diag(P)
        filtered.append((x.copy(), P))
        corrections.append(correction)
        if k == n_samples - 1:
            break
        if increments:
            du = acc[k] - x.ba * h
            dq = quat.from_rotvec(gyr[k] - x.bg * h - x.G @ du)
            ds = 0.5 * h * du
            f = du / h
        else:
            f0, fm, f1 = acc[k] - x.ba, acc_mid[k] - x.ba, acc[k + 1] - x.ba
            w0, wm, w1 = (gyr[k] - x.bg - x.G @ f0, gyr_mid[k] - x.bg - x.G @ fm, gyr[k + 1] - x.bg - x.G @ f1)
            dq, du, ds = rk4_increment(h, w0, wm, w1, f0, fm, f1)
            f = f0
        Phi = transition(quat.to_matrix(x.q), f, h, n)
        transitions.append(Phi)
        P = Phi @ P @ Phi.T + np.diag(power * h)
        g = np.array([0.0, 0.0, -config.gravity])
        x.p = x.p + x.v * h + quat.rotate(x.q, ds) + 0.5 * g * h * h
        x.v = x.v + quat.rotate(x.q, du) + g * h
        q = quat.multiply(x.q, dq)
        x.q = q / np.linalg.norm(q)

    if rts:  # smoothed error of the filtered state at k: P_k Phi_k^T P_k+1|k^-1 (smoothed error at k+1 + c_k+1)
        smoothed_error = np.zeros(n)
        for j in range(len(transitions) - 1, -1, -1):
            state, P_k = filtered[j]
            Phi = transitions[j]
            h = t[start + j + 1] - t[start + j]
            predicted = Phi @ P_k @ Phi.T + np.diag(power * h)
            smoothed_error = P_k @ Phi.T @ np.linalg.solve(predicted, smoothed_error + corrections[j + 1])
            state = state.copy()
            state.inject(smoothed_error)
            k = start + j
            out.quat[k], out.vel[k], out.pos[k] = state.q, state.v, state.p
            out.bias_acc[k], out.bias_gyr[k], out.gsens[k] = state.ba, state.bg, state.G.ravel()
    out.skipped_updates = skipped
    return out
