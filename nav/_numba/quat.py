"""Quaternion helpers on scalars for the compiled loops: (w, x, y, z), body->world, as in nav.quaternion.

Each function is the scalar twin of a function of nav.quaternion (named in its docstring); the tests hold
them equal to round-off.
"""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True)
def qmul(a0, a1, a2, a3, b0, b1, b2, b3):
    """Hamilton product ``a ⊗ b`` as a 4-tuple (nav.quaternion.multiply)."""
    return (
        a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
        a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
        a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
        a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0,
    )


@njit(cache=True)
def qrot(q0, q1, q2, q3, v0, v1, v2):
    """Rotate v by the rotation of q (nav.quaternion.rotate); q need not be unit (divides by |q|^2)."""
    nn = q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3
    t0 = 2.0 * (q2 * v2 - q3 * v1)
    t1 = 2.0 * (q3 * v0 - q1 * v2)
    t2 = 2.0 * (q1 * v1 - q2 * v0)
    r0 = v0 * nn + q0 * t0 + (q2 * t2 - q3 * t1)
    r1 = v1 * nn + q0 * t1 + (q3 * t0 - q1 * t2)
    r2 = v2 * nn + q0 * t2 + (q1 * t1 - q2 * t0)
    return r0 / nn, r1 / nn, r2 / nn


@njit(cache=True)
def qexp(p0, p1, p2):
    """Unit quaternion of the rotation vector p in rad (nav.quaternion.from_rotvec)."""
    a = math.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
    if a < 1e-6:
        k = 0.5 - a * a / 48.0
    else:
        k = math.sin(0.5 * a) / a
    return math.cos(0.5 * a), k * p0, k * p1, k * p2


@njit(cache=True)
def qmatrix(q, C):
    """Body->world rotation matrix of the unit quaternion q (4,) into C (3, 3) (nav.quaternion.to_matrix)."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    C[0, 0] = 1 - 2 * (y * y + z * z)
    C[0, 1] = 2 * (x * y - w * z)
    C[0, 2] = 2 * (x * z + w * y)
    C[1, 0] = 2 * (x * y + w * z)
    C[1, 1] = 1 - 2 * (x * x + z * z)
    C[1, 2] = 2 * (y * z - w * x)
    C[2, 0] = 2 * (x * z - w * y)
    C[2, 1] = 2 * (y * z + w * x)
    C[2, 2] = 1 - 2 * (x * x + y * y)


@njit(cache=True)
def qnormalised(q0, q1, q2, q3):
    """q / |q| as a 4-tuple."""
    norm = math.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    return q0 / norm, q1 / norm, q2 / norm, q3 / norm
