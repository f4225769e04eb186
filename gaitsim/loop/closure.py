"""Stride closure of the loop: from the middle third of one detected stance to the middle third of the next.

The physics (unaided strapdown over one stride, and the velocity and tilt it fails to close) is
:func:`nav.closure.stride_closure`; this module picks its windows for detected stances. The attitude is levelled
on the middle third of the stance and the integration starts at its middle sample; the velocity is averaged and
the gravity direction read over the middle third of the next stance, so that heel-strike and roll-over at the
stances' edges stay out. The gyro bias found at rest is removed first, so that it does not read as a scale or
time error of the sensor.
"""

from __future__ import annotations

import numpy as np

from nav.closure import StrideClosure, stride_closure


def middle_thirds(stances: np.ndarray) -> np.ndarray:
    """(n, 2) sample indices [start, end) of the middle third of each stance [start, end) (the whole stance when
    it is shorter than 6 samples)."""
    stances = np.asarray(stances).reshape(-1, 2)
    length = stances[:, 1] - stances[:, 0]
    third = np.where(length >= 6, length // 3, 0)
    return np.column_stack([stances[:, 0] + third, stances[:, 1] - third])


def closure_between_stances(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, stances: np.ndarray,
                            next_stances: np.ndarray, gravity: float, gyro_bias: np.ndarray) -> StrideClosure:
    """Closure of every stride from stance ``stances[k]`` to ``next_stances[k]`` (module docstring).

    Parameters
    ----------
    t : (N,) s.  acc : (N, 3) m/s^2.  gyr : (N, 3) rad/s.
    stances, next_stances : (n, 2) int, sample indices [start, end) of each stride's stance and the next one.
    gravity : m/s^2.
    gyro_bias : (3,) or (N, 3) rad/s, subtracted from the gyro (from the rests, found the same way on the
        recording and its twin: :func:`gaitsim.loop.signature.rest_gyro_bias`).

    Returns
    -------
    StrideClosure: velocity (n, 3) m/s forward, left, up; tilt (n, 3) rad, of which x and y are the tilt about the
    sensor's axes at the next stance.
    """
    first, last = middle_thirds(stances), middle_thirds(next_stances)
    return stride_closure(t, acc, gyr, first, first.sum(axis=1) // 2, last, last, gravity, gyro_bias)


def following(stances: np.ndarray, all_stances: np.ndarray) -> np.ndarray:
    """(n, 2) the stance of ``all_stances`` that follows each of ``stances`` (the last one repeats itself when
    none follows)."""
    index = np.searchsorted(all_stances[:, 0], stances[:, 0], side="right")
    return all_stances[np.minimum(index, len(all_stances) - 1)]
