"""Stride closure: unaided strapdown from one stillness of the foot to the next, and what it fails to close.

Between two stances the foot starts and ends at (nearly) the same velocity and level, so integrating the sensor
over one stride must give back zero velocity and the tilt the accelerometer reads at the next stance. What does
not close is what the sensor gets wrong while the foot moves: a gyro scale or unit, or a g-sensitivity, mis-turns
gravity during the pitch excursion; an accelerometer scale leaves a share of the vertical force; a time skew
between the two sensors mis-projects the specific force while the foot turns fast; a mirrored (left-handed)
frame turns gravity the wrong way. A proper rotation of the sensor frame changes none of this.

Per stride, with the sample windows the caller chooses (:func:`stride_closure`):

- the attitude starts level from the mean specific force over the ``level`` window (heading 0) and is carried
  by the gyro (less ``gyro_bias``, if given) from the ``start`` sample, with zero velocity (RK4 strapdown,
  :func:`nav.strapdown.integrate`), to the last sample of the ``end`` window;
- ``velocity`` (m/s): the mean integrated velocity over the ``end`` window, in the heading frame of the start
  (forward = the sensor's x at the start, left, up);
- ``tilt`` (rad): ``carried x read``, the cross product of the gravity direction the gyro carried to the middle
  sample of the ``end`` window and the one the accelerometer reads as the mean over the ``read`` window, both in
  the sensor frame there: the rotation axis from the one to the other, of length the sine of the angle between
  them (the small-angle tilt about the sensor's axes); ``angle`` (rad, 0..pi): that angle itself.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import quaternion as quat
from .alignment import tilt_from_specific_force
from .strapdown import integrate


@dataclass
class StrideClosure:
    """What each stride fails to close (module docstring).

    Attributes
    ----------
    velocity : (n, 3) m/s, forward, left, up in the start's heading frame.
    tilt : (n, 3) rad, carried x read gravity direction in the sensor frame at the end (length sin(angle)).
    angle : (n,) rad, angle between the carried and the read gravity direction, 0..pi.
    """

    velocity: np.ndarray
    tilt: np.ndarray
    angle: np.ndarray


def stride_closure(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, level: np.ndarray, start: np.ndarray,
                   end: np.ndarray, read: np.ndarray, gravity: float,
                   gyro_bias: np.ndarray | None = None) -> StrideClosure:
    """Closure of every stride, each over its own sample windows (module docstring).

    Parameters
    ----------
    t : (N,) s, strictly increasing.  acc : (N, 3) m/s^2 specific force.  gyr : (N, 3) rad/s.
    level : (n, 2) int, sample indices [first, stop) whose mean specific force levels the start attitude.
    start : (n,) int, sample at which the integration starts (at rest, velocity zero).
    end : (n, 2) int, sample indices [first, stop) over which the integrated velocity is averaged; the integration
        runs to ``stop - 1`` and the carried attitude is taken at the middle sample ``(first + stop) // 2``.
        ``start <= first < stop <= N``.
    read : (n, 2) int, sample indices [first, stop) whose mean specific force is the measured gravity direction.
    gravity : m/s^2.
    gyro_bias : (3,) or (N, 3) rad/s, subtracted from the gyro; None subtracts nothing.

    Returns
    -------
    StrideClosure with one row per stride.
    """
    rates = gyr if gyro_bias is None else np.asarray(gyr, float) - np.asarray(gyro_bias, float)
    tilts = np.array([tilt_from_specific_force(acc[l0:l1].mean(0)) for l0, l1 in level]).reshape(-1, 2)
    quat0 = quat.from_euler_zyx(0.0, tilts[:, 1], tilts[:, 0])
    velocity, carried = np.empty((len(start), 3)), np.empty((len(start), 4))
    for k, (i0, (e0, e1)) in enumerate(zip(start, end)):
        run = integrate(t[i0:e1], acc[i0:e1], rates[i0:e1], quat0[k], gravity=gravity)
        velocity[k] = run.vel[e0 - i0:e1 - i0].mean(0)
        carried[k] = run.quat[(e0 + e1) // 2 - i0]
    carried = quat.to_matrix(carried)[:, 2]  # the world's up in the sensor frame: the last row of body->world
    measured = np.array([acc[r0:r1].mean(0) for r0, r1 in read]).reshape(-1, 3)
    measured /= np.linalg.norm(measured, axis=1, keepdims=True)
    tilt = np.cross(carried, measured)
    angle = np.arctan2(np.linalg.norm(tilt, axis=1), np.einsum("ij,ij->i", carried, measured))
    return StrideClosure(velocity, tilt, angle)
