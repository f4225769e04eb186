"""Flat-earth ENU strapdown mechanisation (attitude, velocity, position), unaided.

Two ways to integrate, both exact for what they are given (never forward Euler):

``"rk4"``
    point samples of specific force and angular rate: each interval [t_k, t_k+1] is integrated by RK4 on the
    body-frame relative motion, with the mid-interval samples interpolated by a cubic through the four
    neighbouring samples (:func:`mid_samples`). Fourth order in the sample interval.
``"increments"``
    exact increments over each interval (``dv``: m/s in the body frame at t_k, ``dth``: rad rotation vector of
    ``q_k^* ⊗ q_k+1``; see nav.recording.Truth): attitude and velocity are exact, position is the trapezoid of
    the velocities (its error telescopes to ``h^2/12`` times the change in acceleration).

World frame ENU with gravity (0, 0, -gravity); quaternions (w, x, y, z) body->world.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .constants import DEFAULT_GRAVITY
from .compiled import kernel_array
from ._numba.strapdown import MODE_INCREMENTS, MODE_POINT_SAMPLES, strapdown_run

METHODS = ("rk4", "increments")


def mid_samples(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Values at the interval midpoints (t_k + t_k+1)/2 by cubic Lagrange interpolation.

    Parameters
    ----------
    t : (N,) s, strictly increasing (need not be uniform).
    x : (N, ...) samples (any unit).

    Returns
    -------
    (N, ...) array; row k is the value at the middle of [t_k, t_k+1] from samples k-1..k+2 (the cubic is
    shifted inward at both ends; a quadratic/linear is used if N < 4). The last row repeats x[-1] (no interval).
    """
    t = np.asarray(t, float)
    x = np.asarray(x, float)
    n = len(t)
    out = np.empty_like(x)
    out[-1] = x[-1]
    if n < 2:
        return out
    order = min(4, n)
    # first stencil sample for interval k: k-1, clipped so that the stencil stays inside the recording
    first = np.clip(np.arange(n - 1) - (1 if order == 4 else 0), 0, n - order)
    stencil = first[:, None] + np.arange(order)[None, :]  # (N-1, order)
    tm = 0.5 * (t[:-1] + t[1:])
    ts = t[stencil]
    weights = np.ones((n - 1, order))
    for j in range(order):
        for m in range(order):
            if m != j:
                weights[:, j] *= (tm - ts[:, m]) / (ts[:, j] - ts[:, m])
    out[:-1] = np.einsum("kj,kj...->k...", weights, x[stencil])
    return out


@dataclass
class Trajectory:
    """A navigation trajectory on the samples of a recording.

    Attributes
    ----------
    t : (N,) s.
    quat : (N, 4) body->world attitude (w, x, y, z).
    vel : (N, 3) m/s, world ENU.
    pos : (N, 3) m, world ENU.
    """

    t: np.ndarray
    quat: np.ndarray
    vel: np.ndarray
    pos: np.ndarray


def integrate(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, quat0: np.ndarray, vel0=(0.0, 0.0, 0.0),
              pos0=(0.0, 0.0, 0.0), gravity: float = DEFAULT_GRAVITY, method: str = "rk4") -> Trajectory:
    """Unaided strapdown from the first sample.

    Parameters
    ----------
    t : (N,) s, strictly increasing.
    acc : (N, 3) m/s^2 specific force (``method="rk4"``) or m/s velocity increments ``dv`` ("increments").
    gyr : (N, 3) rad/s angular rate ("rk4") or rad rotation-vector increments ``dth`` ("increments").
    quat0 : (4,) initial attitude body->world (w, x, y, z).
    vel0 : (3,) m/s, pos0 : (3,) m, initial velocity and position (world ENU).
    gravity : m/s^2, magnitude of the gravity vector (0, 0, -gravity).
    method : "rk4" or "increments" (see the module docstring).

    Returns
    -------
    Trajectory on the N samples.
    """
    t = kernel_array(t, float)
    acc = kernel_array(acc, float)
    gyr = kernel_array(gyr, float)
    n = len(t)
    quat = np.empty((n, 4))
    vel = np.empty((n, 3))
    pos = np.empty((n, 3))
    q0 = np.asarray(quat0, float) / np.linalg.norm(quat0)
    strapdown_run(mechanisation_mode(method), t, acc, gyr, 0, q0, kernel_array(vel0, float), kernel_array(pos0, float),
                  float(gravity), quat, vel, pos)
    return Trajectory(t=t, quat=quat, vel=vel, pos=pos)


def mechanisation_mode(method: str) -> int:
    """The compiled kernels' code for ``method`` (they interpolate the mid samples of "rk4" themselves, with
    the weights of :func:`mid_samples`)."""
    if method not in METHODS:
        raise ValueError(f"strapdown method {method!r} is not one of {METHODS}")
    return MODE_INCREMENTS if method == "increments" else MODE_POINT_SAMPLES
