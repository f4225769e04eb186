"""Quaternion and rotation helpers, vectorised over leading axes.

Convention used everywhere in the project: quaternions are (w, x, y, z), unit
norm, and rotate body-frame vectors into the world frame, ``v_w = q ⊗ v_b ⊗ q*``.
This is MuJoCo's order; scipy needs ``scalar_first=True`` to read them.
"""

from __future__ import annotations

import numpy as np


def multiply(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Hamilton product ``p ⊗ q`` of (..., 4) arrays."""
    pw, px, py, pz = np.moveaxis(np.asarray(p, float), -1, 0)
    qw, qx, qy, qz = np.moveaxis(np.asarray(q, float), -1, 0)
    return np.stack(
        [
            pw * qw - px * qx - py * qy - pz * qz,
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
        ],
        axis=-1,
    )


def conjugate(q: np.ndarray) -> np.ndarray:
    """Conjugate (inverse for unit quaternions) of (..., 4) arrays."""
    q = np.asarray(q, float)
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) body->world from unit quaternions (..., 4)."""
    w, x, y, z = np.moveaxis(np.asarray(q, float), -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=-2,
    )


def from_matrix(c: np.ndarray) -> np.ndarray:
    """Unit quaternions (..., 4) with w >= 0 from rotation matrices (..., 3, 3)."""
    c = np.asarray(c, float)
    tr = np.trace(c, axis1=-2, axis2=-1)
    cand = np.stack(
        [
            np.stack([1 + tr, c[..., 2, 1] - c[..., 1, 2], c[..., 0, 2] - c[..., 2, 0], c[..., 1, 0] - c[..., 0, 1]], -1),
            np.stack([c[..., 2, 1] - c[..., 1, 2], 1 + 2 * c[..., 0, 0] - tr, c[..., 0, 1] + c[..., 1, 0], c[..., 0, 2] + c[..., 2, 0]], -1),
            np.stack([c[..., 0, 2] - c[..., 2, 0], c[..., 0, 1] + c[..., 1, 0], 1 + 2 * c[..., 1, 1] - tr, c[..., 1, 2] + c[..., 2, 1]], -1),
            np.stack([c[..., 1, 0] - c[..., 0, 1], c[..., 0, 2] + c[..., 2, 0], c[..., 1, 2] + c[..., 2, 1], 1 + 2 * c[..., 2, 2] - tr], -1),
        ],
        axis=-2,
    )
    # pick the numerically best-conditioned row (largest diagonal term)
    diag = np.stack([1 + tr, 1 + 2 * c[..., 0, 0] - tr, 1 + 2 * c[..., 1, 1] - tr, 1 + 2 * c[..., 2, 2] - tr], -1)
    best = np.argmax(diag, axis=-1)
    q = np.take_along_axis(cand, best[..., None, None], axis=-2)[..., 0, :]
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return np.where(q[..., :1] < 0, -q, q)


def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate body vectors ``v`` (..., 3) into the world frame by ``q`` (..., 4)."""
    q = np.asarray(q, float)
    v = np.asarray(v, float)
    u = q[..., 1:]
    w = q[..., :1]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def from_rotvec(phi: np.ndarray) -> np.ndarray:
    """Quaternions (..., 4) from rotation vectors (..., 3) in rad (exact exponential map)."""
    phi = np.asarray(phi, float)
    angle = np.linalg.norm(phi, axis=-1, keepdims=True)
    half = 0.5 * angle
    # sin(a/2)/a with its Taylor series near zero
    small = angle < 1e-6
    k = np.where(small, 0.5 - angle**2 / 48.0, np.sin(half) / np.where(small, 1.0, angle))
    return np.concatenate([np.cos(half), k * phi], axis=-1)


def to_rotvec(q: np.ndarray) -> np.ndarray:
    """Rotation vectors (..., 3) in rad of unit quaternions (..., 4), angle in [0, pi]."""
    q = np.asarray(q, float)
    q = np.where(q[..., :1] < 0, -q, q)
    s = np.linalg.norm(q[..., 1:], axis=-1, keepdims=True)
    angle = 2.0 * np.arctan2(s, q[..., :1])
    small = s < 1e-9
    k = np.where(small, 2.0 / np.where(small, q[..., :1], 1.0), angle / np.where(small, 1.0, s))
    return k * q[..., 1:]


def from_euler_zyx(yaw: np.ndarray, pitch: np.ndarray, roll: np.ndarray) -> np.ndarray:
    """Quaternions of R = Rz(yaw) Ry(pitch) Rx(roll) (intrinsic z-y'-x''), angles in rad."""
    cy, sy = np.cos(0.5 * np.asarray(yaw)), np.sin(0.5 * np.asarray(yaw))
    cp, sp = np.cos(0.5 * np.asarray(pitch)), np.sin(0.5 * np.asarray(pitch))
    cr, sr = np.cos(0.5 * np.asarray(roll)), np.sin(0.5 * np.asarray(roll))
    return np.stack(
        [
            cy * cp * cr + sy * sp * sr,
            cy * cp * sr - sy * sp * cr,
            cy * sp * cr + sy * cp * sr,
            sy * cp * cr - cy * sp * sr,
        ],
        axis=-1,
    )


def to_euler_zyx(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(yaw, pitch, roll) in rad of R = Rz(yaw) Ry(pitch) Rx(roll)."""
    w, x, y, z = np.moveaxis(np.asarray(q, float), -1, 0)
    yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    pitch = np.arcsin(np.clip(2 * (w * y - z * x), -1.0, 1.0))
    roll = np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    return yaw, pitch, roll


def skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrices (..., 3, 3) with ``skew(a) @ b == cross(a, b)``."""
    v = np.asarray(v, float)
    z = np.zeros_like(v[..., 0])
    return np.stack(
        [
            np.stack([z, -v[..., 2], v[..., 1]], -1),
            np.stack([v[..., 2], z, -v[..., 0]], -1),
            np.stack([-v[..., 1], v[..., 0], z], -1),
        ],
        axis=-2,
    )
