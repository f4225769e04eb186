"""Stride closure: unaided strapdown from one stance to the next, and what it fails to close.

Between two stances the foot starts and ends at (nearly) the same velocity and level, so integrating the sensor
over one stride must give back the same velocity and the tilt the accelerometer reads at the next stance. What
does not close is what the sensor gets wrong while the foot moves: a gyro scale or g-sensitivity mis-turns
gravity during the pitch excursion, an accelerometer scale leaves a share of the vertical force, a time skew
between the two sensors mis-projects the specific force while the foot turns fast, and a mirrored (left-handed)
frame turns gravity the wrong way. A proper rotation of the sensor frame changes none of this.

Per stride (from the middle third of one detected stance to the middle third of the next):

- the attitude starts level from the mean specific force over the first middle third (heading 0) and is
  propagated with the gyro less the bias found at rest; the velocity starts at zero;
- ``velocity`` (m/s): the mean integrated velocity over the next middle third, in the heading frame of the
  start (forward = the sensor's x at the start, left, up);
- ``tilt`` (deg): the angle between the gravity direction the gyro carried to the next stance and the one the
  accelerometer reads there, about the sensor's x and y axes at that stance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nav import quaternion as quat
from nav.alignment import tilt_from_specific_force
from nav.strapdown import integrate


@dataclass
class Closure:
    """What one recording's strides fail to close (module docstring).

    Attributes
    ----------
    velocity : (n, 3) m/s, forward, left, up per stride.
    tilt : (n, 2) deg, about the sensor's x and y axes per stride.
    """

    velocity: np.ndarray
    tilt: np.ndarray


def _middle_third(start: int, end: int) -> slice:
    third = (end - start) // 3
    return slice(start + third, end - third) if end - start >= 6 else slice(start, end)


def stride_closure(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, stances: np.ndarray, next_stances: np.ndarray,
                   gravity: float, gyro_bias: np.ndarray) -> Closure:
    """Closure of every stride from stance ``stances[k]`` to ``next_stances[k]`` (module docstring).

    Parameters
    ----------
    t : (N,) s.  acc : (N, 3) m/s^2.  gyr : (N, 3) rad/s.
    stances, next_stances : (n, 2) int, sample indices [start, end) of each stride's stance and the next one.
    gravity : m/s^2.
    gyro_bias : (3,) or (N, 3) rad/s, subtracted from the gyro (from the rests, found the same way on the
        recording and its twin: :func:`gaitsim.loop.signature.rest_gyro_bias`).
    """
    velocity, tilt = [], []
    rates = np.asarray(gyr, float) - np.asarray(gyro_bias, float)
    for (a0, a1), (b0, b1) in zip(stances, next_stances):
        first, last = _middle_third(a0, a1), _middle_third(b0, b1)
        i0 = (first.start + first.stop) // 2
        roll, pitch = tilt_from_specific_force(acc[first].mean(0))
        run = integrate(t[i0:last.stop], acc[i0:last.stop], rates[i0:last.stop],
                        quat.from_euler_zyx(0.0, pitch, roll), gravity=gravity)
        inside = slice(last.start - i0, last.stop - i0)
        velocity.append(run.vel[inside].mean(0))
        carried = quat.to_matrix(run.quat[(inside.start + inside.stop) // 2]).T @ np.array([0.0, 0.0, 1.0])
        read = acc[last].mean(0) / np.linalg.norm(acc[last].mean(0))
        tilt.append(np.degrees(np.cross(carried, read)[:2]))
    return Closure(np.array(velocity).reshape(-1, 3), np.array(tilt).reshape(-1, 2))


def following(stances: np.ndarray, all_stances: np.ndarray) -> np.ndarray:
    """(n, 2) the stance of ``all_stances`` that follows each of ``stances`` (the last one repeats itself when
    none follows)."""
    index = np.searchsorted(all_stances[:, 0], stances[:, 0], side="right")
    return all_stances[np.minimum(index, len(all_stances) - 1)]
