"""Initial alignment: roll and pitch from the first stationary window, heading given.

At rest the accelerometer reads the reaction to gravity, f_b = C^T (0, 0, g); with C = Rz(yaw) Ry(pitch)
Rx(roll) that gives roll = atan2(f_y, f_z) and pitch = atan2(-f_x, sqrt(f_y^2 + f_z^2)). Heading (yaw) is not
observable from the accelerometer and is an input.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import quaternion as quat
from .recording import RecordingError

DEFAULT_MIN_SAMPLES = 20  # OpenShoe aligns on the first 20 samples


@dataclass(frozen=True)
class Alignment:
    """Initial attitude and where it came from.

    Attributes
    ----------
    start : index of the first sample of the stationary window (navigation starts here).
    end : one past its last sample.
    quat0 : (4,) attitude body->world (w, x, y, z).
    roll, pitch, yaw : rad.
    mean_specific_force : (3,) m/s^2, the window mean the tilt came from.
    """

    start: int
    end: int
    quat0: np.ndarray
    roll: float
    pitch: float
    yaw: float
    mean_specific_force: np.ndarray


def stationary_runs(stationary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Start indices and one-past-end indices of the runs of True in a (N,) boolean array."""
    s = np.asarray(stationary, bool).astype(np.int8)
    edges = np.diff(np.concatenate([[0], s, [0]]))
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)


def merged_runs(t: np.ndarray, stationary: np.ndarray, gap_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The runs of True in ``stationary`` (N,) bool, merged where one starts less than ``gap_s`` (s) after the
    last sample of the one before on the clock ``t`` (N,) s: a stance the detector broke into pieces.

    Returns
    -------
    bounds : (m, 2) int, sample indices [start, end) of each merged group.
    runs : (n, 2) int, sample indices [start, end) of every run.
    group : (n,) int, the group of each run.
    """
    starts, ends = stationary_runs(stationary)
    t = np.asarray(t, float)
    new = np.concatenate([[True], t[starts[1:]] - t[ends[:-1] - 1] >= gap_s])[:len(starts)]
    group = np.cumsum(new) - 1
    last = np.concatenate([new[1:], [True]])[:len(starts)]
    return np.column_stack([starts[new], ends[last]]), np.column_stack([starts, ends]), group


def first_stationary_window(stationary: np.ndarray, min_samples: int = DEFAULT_MIN_SAMPLES) -> tuple[int, int]:
    """(start, end) of the first run of at least ``min_samples`` stationary samples.

    Raises
    ------
    RecordingError if there is none (recording too short to align, or no rest at all).
    """
    starts, ends = stationary_runs(stationary)
    long_enough = np.flatnonzero(ends - starts >= min_samples)
    if len(long_enough) == 0:
        longest = int((ends - starts).max()) if len(starts) else 0
        raise RecordingError(
            f"cannot align: no stationary window of at least {min_samples} samples (longest found: {longest} "
            f"samples of {len(stationary)}); the recording is too short or never at rest"
        )
    i = long_enough[0]
    return int(starts[i]), int(ends[i])


def tilt_from_specific_force(mean_acc: np.ndarray) -> tuple[float, float]:
    """(roll, pitch) in rad from a mean specific force at rest (m/s^2, body frame)."""
    fx, fy, fz = np.asarray(mean_acc, float)
    return math.atan2(fy, fz), math.atan2(-fx, math.hypot(fy, fz))


def align(acc: np.ndarray, stationary: np.ndarray, yaw: float = 0.0,
          min_samples: int = DEFAULT_MIN_SAMPLES) -> Alignment:
    """Level the sensor on the first stationary window and apply the given heading.

    Parameters
    ----------
    acc : (N, 3) m/s^2 specific force.
    stationary : (N,) bool, detector output.
    yaw : rad, heading of the body x axis counter-clockwise from east.
    min_samples : shortest usable stationary window, samples.
    """
    start, end = first_stationary_window(stationary, min_samples)
    mean_acc = np.asarray(acc, float)[start:end].mean(axis=0)
    roll, pitch = tilt_from_specific_force(mean_acc)
    q0 = quat.from_euler_zyx(yaw, pitch, roll)
    return Alignment(start, end, q0, roll, pitch, float(yaw), mean_acc)


def yaw_of(q: np.ndarray) -> np.ndarray:
    """Heading (rad, counter-clockwise from east) of the body x axis of attitudes q (..., 4).

    The angle of the first column of :func:`nav.quaternion.to_matrix` (its two entries computed alone, with the
    same expressions: the same floats).
    """
    w, x, y, z = np.moveaxis(np.asarray(q, float), -1, 0)
    return np.arctan2(2 * (x * y + w * z), 1 - 2 * (y * y + z * z))


def first_leg_direction(t: np.ndarray, pos: np.ndarray, t0: float, leg_length: float = 3.0) -> tuple[float, float]:
    """Direction (rad from east) and time of the point where a track first leaves a circle around its start.

    Parameters
    ----------
    t : (M,) s, pos : (M, 3) m -- a track (truth or reference); t0 : s, start of navigation.
    leg_length : m, horizontal distance from the start that ends the "first leg".

    Returns
    -------
    (direction, time); direction is NaN when the track never gets that far.
    """
    t = np.asarray(t, float)
    pos = np.asarray(pos, float)
    keep = (t >= t0) & np.all(np.isfinite(pos), axis=1)
    t, pos = t[keep], pos[keep]
    if len(t) == 0:
        return math.nan, math.nan
    d = pos[:, :2] - pos[0, :2]
    far = np.flatnonzero(np.hypot(d[:, 0], d[:, 1]) >= leg_length)
    if len(far) == 0:
        return math.nan, math.nan
    i = far[0]
    return math.atan2(d[i, 1], d[i, 0]), float(t[i])
