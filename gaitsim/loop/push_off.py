"""The foot's push-off, a turn about the still toe contact: the gyro's lag behind the accelerometer, and the
sensor's height above the contact.

From heel off to toe off the shoe turns about its toe contact, which does not move. For a rigid body turning about a
still point the specific force at the sensor follows from the angular rate alone (body frame):

    f(t) = (S(dw/dt) + S(w)^2) r + u(t) + b,

with S(.) the cross-product matrix, r the lever from the contact to the sensor (m, unknown, constant), u(t) the
reaction to gravity (m/s^2: the specific force at rest at the end of the stance, carried forward by the rate) and b
a constant offset (m/s^2: the accelerometer's bias and what the rigid model leaves, e.g. a contact that rolls a
little). The turn must stay rigid over the window: the walking kind's toe release (the toe contact sliding forward
over the push-off's last 40 ms, :class:`gaitsim.world.gait.GaitParams` ``toe_release_accel_mps2``) stays beyond it
up to 115 steps/min; faster it enters it and the lag is wrong (+0.45 / -3.9 ms at 120 / 125 steps/min against
+0.8 on a fixed toe, the search's -15 ms edge at 130). The least-squares fit of (r, b) over the first
``settings.PUSH_OFF_S`` after every detected stance gives two readings:

- **The lag** (:func:`push_off_lag`). When the gyro's samples come tau later than the accelerometer's, the relation
  holds for the rate read tau later, w(t) = w_measured(t + tau). The lag is the tau whose fit leaves the least
  residual: searched on a grid of ``settings.LAG_STEP_MS`` over +-``settings.LAG_RANGE_MS`` and refined by the
  parabola through the best grid point and its neighbours. A simulated foot reads a small lag with its sensors in
  step (about +0.3 ms on a consumer sensor and +1 ms on the paper's VN-200 in its 200 Hz blind walks: the rolling
  sole's contact is not quite still, and the window reaches past toe off); the loop compares a recording with its
  twin, so that part cancels. A shift of the gyro by tau moves the reading by tau.
- **The height** (:func:`push_off_height`): r read at the lag, projected on the up direction of the foot flat
  (the mean specific force over the detected stances; at the stance's end the heel has begun to rise, and a
  tilt of 2 deg there moves the height of a sensor 15 cm behind the pivot by 5 mm) and on the forward one (up
  crossed into the turn's axis, whose sense makes the heel rise). The turns are about the foot's lateral axis,
  so r along it is not seen (the pseudo-inverse leaves it out); along the other two it is. The height is above
  the turn's pivot: the twin's toe contact lies on its sole, so a twin whose sensor sits at this height turns in
  push-off as the recording's does, whatever the real pivot's height in the shoe.

Both readings need no template and no model of the gait: a twin whose swing is off reads them as the recording
does. Their standard errors are the jackknife over the stances. The height's fit leaves out the stances whose own
height lies more than ``settings.OUTLIER_SIGMAS`` robust standard deviations (1.4826 median absolute deviations)
from the median of all: a stance unlike the others (the walk's last, a turn) can carry most of the pooled fit's
weight (on gaitmap's left foot one stance, its own height -1.4 cm, moved the pooled height from 4.6 to 2.7 cm),
while a single stance's fit is too noisy on a consumer sensor to take the median of. Tested in
tests/test_loop_push_off.py.
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
    u = acc[start[:, None] - quiet + np.arange(quiet)].mean(1)
    angle = gyr[start[:, None] + np.arange(count)] / rate_hz  # (m, count, 3) rad, the body's turn over each sample
    size = np.linalg.norm(angle, axis=-1, keepdims=True)
    axis = np.divide(angle, size, out=np.zeros_like(angle), where=size > 0)
    c, s = np.cos(size)[..., None], np.sin(size)[..., None]
    turn = c * np.eye(3) - s * skew(axis) + (1.0 - c) * axis[..., :, None] * axis[..., None, :]  # by -angle (Rodrigues)
    out = np.empty((len(ends), count, 3))
    for k in range(count):
        out[:, k] = u
        u = (turn[:, k] @ u[..., None])[..., 0]
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


def _push_off(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, stances: np.ndarray):
    """What every reading takes from the recording: the sample rate (Hz), the window (samples), the margin kept
    either side of it for shifted reads, the (m, L, 9) rate, its derivative and u over the spans any shifted read
    may reach, and the (m, n, 3) specific force fitted; None for fewer than three stances with a full window.

    The samples read are taken as evenly spaced at the median rate."""
    rate = 1.0 / float(np.median(np.diff(t)))
    n = max(3, int(round(settings.PUSH_OFF_S * rate)))
    margin = int(math.ceil(settings.LAG_RANGE_MS / 1000.0 * rate)) + 2
    quiet = max(1, int(round(QUIET_S * rate)))
    ends = stances[:, 1]
    ends = ends[(ends - margin - quiet >= stances[:, 0]) & (ends + n + margin < len(t))]
    if len(ends) < 3:
        return None
    span = ends[:, None] + np.arange(-margin, n + margin)
    on_span = np.concatenate([gyr[span], (np.gradient(gyr, axis=0) * rate)[span],
                              _gravity_reaction(acc, gyr, ends, -margin, n + 2 * margin, rate)], axis=-1)
    return rate, n, margin, on_span, acc[ends[:, None] + np.arange(n)]


def _normal_equations(on_span: np.ndarray, f: np.ndarray, rate: float, margin: int, taus_ms: np.ndarray):
    """Per stance and lag, the least-squares system of (r, b) with the rate, its derivative and u read ``taus_ms``
    (T,) later (linear interpolation between samples): D^T D (m, T, 6, 6), D^T y (m, T, 6), y^T y (m, T), and the
    rates read (m, T, n, 3).

    Every sample's three rows of D are [A, I] with A = S(dw/dt) + S(w)^2 = S(dw/dt) + w w^T - |w|^2 I, so D^T D
    is [[sum A^T A, sum A^T], [sum A, n I]] and D^T y is [sum A^T y, sum y]."""
    m, n = f.shape[:2]
    read = margin + np.arange(n) + np.asarray(taus_ms, float)[:, None] / 1000.0 * rate  # (T, n)
    i = np.floor(read).astype(int)
    share = (read - i)[None, :, :, None]
    w, w_dot, u = np.split(on_span[:, i] * (1.0 - share) + on_span[:, i + 1] * share, 3, axis=-1)
    turn = skew(w_dot) + w[..., :, None] * w[..., None, :] - np.sum(w * w, axis=-1)[..., None, None] * np.eye(3)
    rows = turn.reshape(m, len(read), 3 * n, 3)  # the three axes of every sample as rows
    y = f[:, None] - u
    stacked = y.reshape(m, len(read), 3 * n)
    summed = turn.sum(axis=2)
    normal = np.empty((m, len(read), 6, 6))
    normal[..., :3, :3] = rows.swapaxes(-1, -2) @ rows
    normal[..., :3, 3:] = summed.swapaxes(-1, -2)
    normal[..., 3:, :3] = summed
    normal[..., 3:, 3:] = n * np.eye(3)
    moment = np.concatenate([(rows.swapaxes(-1, -2) @ stacked[..., None])[..., 0], y.sum(axis=2)], axis=-1)
    return normal, moment, np.sum(stacked * stacked, axis=-1), w


def _solve(normal: np.ndarray, moment: np.ndarray) -> np.ndarray:
    """(..., 6) least-squares (r, b); a lever axis the turns leave unseen (a turn about one axis cannot show the
    lever along it) takes no part."""
    size, axes = np.linalg.eigh(normal)  # the pseudo-inverse of a symmetric positive semi-definite matrix
    inverse = np.divide(1.0, size, out=np.zeros_like(size), where=size > 1e-10 * size[..., -1:])
    return ((axes * inverse[..., None, :]) @ (axes.swapaxes(-1, -2) @ moment[..., None]))[..., 0]


def _jackknife(values: np.ndarray) -> float:
    """Standard error from the leave-one-out values (m,)."""
    m = len(values)
    return math.sqrt((m - 1) / m * float(np.sum((values - values.mean()) ** 2)))


def push_off_lag(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, stances: np.ndarray) -> tuple[float, float]:
    """The gyro's lag behind the accelerometer (ms, > 0: the gyro's samples come later) and its jackknife standard
    error (module docstring); NaN for fewer than three stances with a full push-off window.

    Parameters
    ----------
    t : (N,) s; acc : (N, 3) m/s^2 specific force; gyr : (N, 3) rad/s.
    stances : (m, 2) sample indices [start, end) of the detected stances of regular strides.
    """
    prepared = _push_off(t, acc, gyr, stances)
    if prepared is None:
        return math.nan, math.nan
    rate, n, margin, on_span, f = prepared
    taus = np.arange(-settings.LAG_RANGE_MS, settings.LAG_RANGE_MS + settings.LAG_STEP_MS / 2, settings.LAG_STEP_MS)
    normal, moment, energy, _ = _normal_equations(on_span, f, rate, margin, taus)  # (m, T, ...)
    # the sums over all stances, then over all but one (the jackknife), solved in one call
    normal = np.concatenate([normal.sum(0)[None], normal.sum(0) - normal])
    moment = np.concatenate([moment.sum(0)[None], moment.sum(0) - moment])
    energy = np.concatenate([energy.sum(0)[None], energy.sum(0) - energy])
    residual = energy - np.einsum("kti,kti->kt", moment, _solve(normal, moment))
    lags = np.array([_parabola_minimum(taus, cost) for cost in residual])
    return float(lags[0]), _jackknife(lags[1:])


def push_off_height(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, stances: np.ndarray,
                    lag_ms: float = 0.0) -> tuple[float, float, float]:
    """The sensor's height above the push-off's pivot (m), its jackknife standard error (m) and its distance ahead
    of the pivot along the foot (m; behind it < 0), read with the gyro ``lag_ms`` late over the stances that are not
    outliers (module docstring); NaN for fewer than three stances with a full push-off window.

    Parameters
    ----------
    t : (N,) s; acc : (N, 3) m/s^2 specific force; gyr : (N, 3) rad/s.
    stances : (m, 2) sample indices [start, end) of the detected stances of regular strides.
    lag_ms : ms, the gyro's lag behind the accelerometer (:func:`push_off_lag`).
    """
    prepared = _push_off(t, acc, gyr, stances)
    if prepared is None:
        return math.nan, math.nan, math.nan
    rate, _, margin, on_span, f = prepared
    normal, moment, _, w = (x[:, 0] for x in _normal_equations(on_span, f, rate, margin, np.array([lag_ms])))
    up = np.mean([acc[start:end].mean(0) for start, end in stances], axis=0)  # the foot flat's specific force
    up /= np.linalg.norm(up)
    axis = w.sum((0, 1))  # the turn's axis: heel rising, toes down
    forward = np.cross(axis - up * (axis @ up), up)
    forward /= np.linalg.norm(forward)
    own = _solve(normal, moment)[:, :3] @ up  # each stance's own height
    spread = 1.4826 * np.median(np.abs(own - np.median(own)))  # the scatter's sigma, outliers aside
    kept = np.flatnonzero(np.abs(own - np.median(own)) <= settings.OUTLIER_SIGMAS * spread)
    normal, moment = normal[kept], moment[kept]
    m = len(kept)
    levers = _solve(np.stack([normal.sum(0)] + [normal[np.arange(m) != j].sum(0) for j in range(m)]),
                    np.stack([moment.sum(0)] + [moment[np.arange(m) != j].sum(0) for j in range(m)]))[:, :3]
    heights = levers @ up
    return float(heights[0]), _jackknife(heights[1:]), float(levers[0] @ forward)
