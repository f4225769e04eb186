"""A simulated motion tracker: what the seed paper's magnetic tracker (Polhemus PATRIOT) saw of the foot.

The tracker samples the IMU-site position at its own rate (60 Hz), adds white measurement noise and rounds to
its resolution (1 mm); velocity is the central difference of the tracked positions, as in the paper. A central
difference spans two tracker periods (33 ms at 60 Hz): at the edge of a stance it reaches into the swing, so
:func:`velocity_within` gives the velocity of one stance from the differences that lie inside it only. Used to
draw Fig. 2-3 and to fit the stance pseudo-velocity model from *calibration walks* that have their own seeds,
never from the truth of the runs being scored.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicHermiteSpline

from nav.recording import Truth
from nav.series import resample


@dataclass(frozen=True)
class TrackerSpec:
    """Tracker characteristics.

    Attributes
    ----------
    rate_hz : Hz. Default 60 (PATRIOT).
    resolution_m : m, position quantisation. Default 0.001.
    noise_m : m, white position noise (1 sigma). Default 0.0005.
    """

    rate_hz: float = 60.0
    resolution_m: float = 0.001
    noise_m: float = 0.0005


@dataclass
class Track:
    """Tracked positions and the velocity derived from them.

    Attributes
    ----------
    t : (M,) s.   pos : (M, 3) m, world.   vel : (M, 3) m/s, central differences (ends one-sided).
    """

    t: np.ndarray
    pos: np.ndarray
    vel: np.ndarray


def track(truth: Truth, spec: TrackerSpec, rng: np.random.Generator) -> Track:
    """Sample the IMU-site trajectory like the tracker does.

    The truth is interpolated between its samples with a cubic Hermite spline on position and velocity (both
    exact), so the tracker's clock need not divide the IMU's.
    """
    t = np.arange(truth.t[0], truth.t[-1], 1.0 / spec.rate_hz)
    pos = CubicHermiteSpline(truth.t, truth.pos, truth.vel, axis=0)(t)
    pos = pos + spec.noise_m * rng.standard_normal(pos.shape)
    if spec.resolution_m > 0:
        pos = np.round(pos / spec.resolution_m) * spec.resolution_m
    vel = np.gradient(pos, t, axis=0)
    return Track(t=t, pos=pos, vel=vel)


def velocity_within(tracked: Track, t: np.ndarray) -> np.ndarray | None:
    """Tracked velocity at the times t of one interval (e.g. a detected stance), seen from inside it only.

    Only the central differences whose whole span (the tracker samples before and after) lies in
    [t[0], t[-1]] are used, interpolated linearly to t and held constant towards the interval's edges: a
    difference that straddles an edge averages in the motion outside (the heel-off or the landing) and biases
    the stance velocity there by the swing's acceleration times a tracker period.

    Parameters
    ----------
    tracked : the track (see :func:`track`).   t : (n,) s, increasing.

    Returns
    -------
    (n, 3) m/s world frame, or None when no central difference fits inside (an interval shorter than two tracker
    periods: the tracker cannot resolve a velocity there).
    """
    t = np.asarray(t, float)
    inner = np.zeros(len(tracked.t), bool)
    inner[1:-1] = (tracked.t[:-2] >= t[0]) & (tracked.t[2:] <= t[-1])
    if not inner.any():
        return None
    return resample(t, tracked.t[inner], tracked.vel[inner])
