"""The lag between a recording's gyro and accelerometer samples, read from the foot's push-off.

From heel off to toe off the shoe turns about its toe contact, which does not move. For a rigid body turning about a
still point the specific force at the sensor follows from the angular rate alone (body frame):

    f(t) = (S(dw/dt) + S(w)^2) r + u(t) + b,

with S(.) the cross-product matrix, r the lever from the contact to the sensor (m, unknown, constant), u(t) the
reaction to gravity (m/s^2: the specific force at rest at the end of the stance, carried forward by the rate) and b
a constant offset (m/s^2: the accelerometer's bias and what the rigid model leaves, e.g. a contact that rolls a
little). When the gyro's samples come tau later than the accelerometer's, the relation holds for the rate read tau
later, w(t) = w_measured(t + tau). The lag is the tau whose least-squares fit of (r, b) leaves the least residual
over the first ``settings.PUSH_OFF_S`` after every detected stance: searched on a grid of ``settings.LAG_STEP_MS``
over +-``settings.LAG_RANGE_MS`` and refined by the parabola through the best grid point and its neighbours. Its
standard error is the jackknife over the stances.

The reading needs no template and no model of the gait: a twin whose swing is off reads the same lag as the
recording when both have their sensors in step. A simulated foot reads a small lag with its sensors in step
(about +0.3 ms on a consumer sensor and +1 ms on the paper's VN-200 in its 200 Hz blind walks: the rolling sole's
contact is not quite still, and the window reaches past toe off); the loop compares a recording with its twin, so
that part cancels. A shift of the gyro by tau moves the reading by tau (tests/test_loop_lag.py).
"""

from __future__ import annotations

import math

import numpy as np

from nav.quaternion import skew

from . import settings

QUIET_S = 0.02  # s, the end of the stance averaged for the gravity reaction u at its end


def _gravity_reaction(acc: np.ndarray, gyr: np.ndarray, ends: np.ndarray, first: int, count: int,
                      rate_hz: float) -> np.ndarray:
    """u (m/s^2) at samples ends + first .. ends + first + count - 1 of every stance: the mean specific force over
    the last ``QUIET_S`` before sample ``ends + first`` (the foot still), turned with the body by the measured rate
    (a vector fixed in the world seen from the body: du/dt = -w x u), (m, count, 3)."""
    quiet = max(1, int(round(QUIET_S * rate_hz)))
    start = ends + first
    u = np.stack([acc[s - quiet:s].mean(0) for s in start])
    out = np.empty((len(ends), count, 3))
    for k in range(count):
        out[:, k] = u
        angle = gyr[start + k] / rate_hz  # rad, rotation of the body over one sample
        size = np.linalg.norm(angle, axis=1, keepdims=True)
        axis = np.divide(angle, size, out=np.zeros_like(angle), where=size > 0)
        c, s = np.cos(size), np.sin(size)  # turn u by -angle about axis (Rodrigues)
        u = u * c - np.cross(axis, u) * s + axis * np.sum(axis * u, axis=1, keepdims=True) * (1.0 - c)
    return out


def _parabola_minimum(x: np.ndarray, cost: np.ndarray) -> float:
    """The minimum of the parabola through the grid's best point and its neighbours (the best point on an edge)."""
    i = int(np.argmin(cost))
    if i == 0 or i == len(cost) - 1:
        return float(x[i])
    c0, c1, c2 = cost[i - 1:i + 2]
    curvature = c0 - 2.0 * c1 + c2
    step = x[1] - x[0]
    return float(x[i] + (0.5 * (c0 - c2) / curvature * step if curvature > 0 else 0.0))


def push_off_lag(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, stances: np.ndarray) -> tuple[float, float]:
    """The gyro's lag behind the accelerometer (ms, > 0: the gyro's samples come later) and its jackknife standard
    error (module docstring); NaN for fewer than three stances with a full push-off window.

    Parameters
    ----------
    t : (N,) s; acc : (N, 3) m/s^2 specific force; gyr : (N, 3) rad/s.
    stances : (m, 2) sample indices [start, end) of the detected stances of regular strides.
    """
    rate = 1.0 / float(np.median(np.diff(t)))  # the samples read are taken as evenly spaced at the median rate
    n = max(3, int(round(settings.PUSH_OFF_S * rate)))
    margin = int(math.ceil(settings.LAG_RANGE_MS / 1000.0 * rate)) + 2
    quiet = max(1, int(round(QUIET_S * rate)))
    ends = stances[:, 1]
    ends = ends[(ends - margin - quiet >= stances[:, 0]) & (ends + n + margin < len(t))]
    if len(ends) < 3:
        return math.nan, math.nan
    taus = np.arange(-settings.LAG_RANGE_MS, settings.LAG_RANGE_MS + settings.LAG_STEP_MS / 2, settings.LAG_STEP_MS)
    span = ends[:, None] + np.arange(-margin, n + margin)  # (m, L) the samples any shifted read may reach
    on_span = np.concatenate([gyr[span], (np.gradient(gyr, axis=0) * rate)[span],
                              _gravity_reaction(acc, gyr, ends, -margin, n + 2 * margin, rate)], axis=-1)
    f = acc[ends[:, None] + np.arange(n)]  # (m, n, 3) the samples fitted
    normal, moment, energy = [], [], []  # per tau and stance: D^T D (6, 6), D^T y (6,), y^T y
    for tau in taus:
        # rate, its derivative and u read tau later, by linear interpolation between samples
        read = margin + np.arange(n) + tau / 1000.0 * rate
        i = np.floor(read).astype(int)
        share = (read - i)[None, :, None]
        w, w_dot, u = np.split(on_span[:, i] * (1.0 - share) + on_span[:, i + 1] * share, 3, axis=-1)
        sw = skew(w)
        design = np.concatenate([skew(w_dot) + sw @ sw, np.broadcast_to(np.eye(3), sw.shape)], axis=-1)
        y = f - u
        normal.append(np.einsum("mnij,mnik->mjk", design, design))
        moment.append(np.einsum("mnij,mni->mj", design, y))
        energy.append(np.einsum("mni,mni->m", y, y))
    normal, moment, energy = np.array(normal), np.array(moment), np.array(energy)  # (taus, m, ...)

    def lag(keep: np.ndarray) -> float:
        a, b, e = normal[:, keep].sum(1), moment[:, keep].sum(1), energy[:, keep].sum(1)
        solution = (np.linalg.pinv(a, rcond=1e-10) @ b[..., None])[..., 0]  # a lever axis the turns leave unseen
        # (a turn about one axis cannot show the lever along it) takes no part
        return _parabola_minimum(taus, e - np.einsum("ti,ti->t", b, solution))

    m = len(ends)
    value = lag(np.ones(m, bool))
    left_out = np.array([lag(np.arange(m) != j) for j in range(m)])
    se = math.sqrt((m - 1) / m * float(np.sum((left_out - left_out.mean()) ** 2)))
    return value, se
