"""Rigid-body kinematics of a foot from three motion-capture markers, and its alignment to a foot IMU.

Used by the gaitmap loader; generic enough for any three-marker foot set:

- :func:`marker_frame` builds the foot pose from heel, toe and lateral (5th metatarsal) markers;
- :func:`body_kinematics` differentiates it (angular rate, angular acceleration, origin acceleration);
- :func:`estimate_time_offset` finds the clock offset between two sampled signals by cross-correlation;
- :func:`rotation_between` (Kabsch) and :func:`fit_lever_arm` find the sensor's mount rotation and position on the
  marker body from the IMU's angular rate and specific force.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.signal import butter, filtfilt

from nav import quaternion as quat
from nav.constants import DEFAULT_GRAVITY

GRAVITY_WORLD = np.array([0.0, 0.0, -DEFAULT_GRAVITY])
"""m/s^2, gravity in a z-up world frame."""


def lowpass(values: np.ndarray, cutoff_hz: float, rate_hz: float) -> np.ndarray:
    """Zero-phase 4th-order Butterworth low-pass along axis 0 (no delay, so both clocks stay comparable)."""
    b, a = butter(4, cutoff_hz / (0.5 * rate_hz))
    return filtfilt(b, a, values, axis=0)


def marker_frame(heel: np.ndarray, toe: np.ndarray, lateral: np.ndarray, side: str) -> tuple[np.ndarray, np.ndarray]:
    """Foot pose from three markers in a right-handed z-up world frame.

    Body axes: x from the heel marker toward the toe marker; z normal to the marker plane, pointing up; y = z × x
    (to the left). The lateral marker lies on the foot's left for a left foot and on its right for a right foot,
    which fixes the sign of the plane normal.

    Parameters
    ----------
    heel, toe, lateral : (M, 3) m, marker positions in the world frame.
    side : "left" or "right".

    Returns
    -------
    origin : (M, 3) m, the centroid of the three markers.
    rotation : (M, 3, 3) body->world rotation matrices (columns are the body axes in world coordinates).
    """
    if side not in ("left", "right"):
        raise ValueError(f"marker_frame: side={side!r}; allowed: 'left', 'right'")
    x_axis = toe - heel
    x_axis = x_axis / np.linalg.norm(x_axis, axis=1, keepdims=True)
    normal = np.cross(toe - heel, lateral - heel) * (1.0 if side == "left" else -1.0)
    y_axis = np.cross(normal, x_axis)
    y_axis = y_axis / np.linalg.norm(y_axis, axis=1, keepdims=True)
    z_axis = np.cross(x_axis, y_axis)
    origin = (heel + toe + lateral) / 3.0
    return origin, np.stack([x_axis, y_axis, z_axis], axis=2)


@dataclass
class BodyKinematics:
    """Smoothed kinematics of a marker body on the motion-capture clock.

    Attributes
    ----------
    rotation : (M, 3, 3) body->world.
    rate_body : (M, 3) rad/s, angular rate in the body frame.
    rate_world : (M, 3) rad/s, angular rate in the world frame.
    ang_acc_world : (M, 3) rad/s^2, angular acceleration in the world frame.
    origin_acc : (M, 3) m/s^2, acceleration of the body origin in the world frame.
    """

    rotation: np.ndarray
    rate_body: np.ndarray
    rate_world: np.ndarray
    ang_acc_world: np.ndarray
    origin_acc: np.ndarray

    def point_specific_force(self, lever_arm: np.ndarray) -> np.ndarray:
        """(M, 3) m/s^2 specific force, world frame, of the body-fixed point ``origin + R lever_arm`` (m, body)."""
        arm_world = self.rotation @ lever_arm
        w = self.rate_world
        centripetal = np.cross(w, np.cross(w, arm_world))
        return self.origin_acc + np.cross(self.ang_acc_world, arm_world) + centripetal - GRAVITY_WORLD


def body_kinematics(origin: np.ndarray, rotation: np.ndarray, rate_hz: float, cutoff_hz: float) -> BodyKinematics:
    """Differentiate a sampled pose after a zero-phase low-pass.

    Parameters
    ----------
    origin : (M, 3) m, world.
    rotation : (M, 3, 3) body->world.
    rate_hz : Hz, sampling rate of the pose.
    cutoff_hz : Hz, low-pass cutoff applied to position and rotation-matrix entries before differentiating.
    """
    dt = 1.0 / rate_hz
    smooth_rotation = lowpass(rotation, cutoff_hz, rate_hz)
    rotation_rate = np.gradient(smooth_rotation, dt, axis=0)
    omega_skew = np.einsum("nji,njk->nik", smooth_rotation, rotation_rate)  # R^T dR/dt = [w_body]x
    rate_body = 0.5 * np.stack(
        [omega_skew[:, 2, 1] - omega_skew[:, 1, 2], omega_skew[:, 0, 2] - omega_skew[:, 2, 0],
         omega_skew[:, 1, 0] - omega_skew[:, 0, 1]], axis=1)
    rate_world = np.einsum("nij,nj->ni", smooth_rotation, rate_body)
    smooth_origin = lowpass(origin, cutoff_hz, rate_hz)
    return BodyKinematics(
        rotation=smooth_rotation,
        rate_body=rate_body,
        rate_world=rate_world,
        ang_acc_world=np.gradient(rate_world, dt, axis=0),
        origin_acc=np.gradient(np.gradient(smooth_origin, dt, axis=0), dt, axis=0),
    )


def estimate_time_offset(t_ref: np.ndarray, signal_ref: np.ndarray, t_imu: np.ndarray, signal_imu: np.ndarray,
                         max_offset: float = 0.1, step: float = 0.0005) -> tuple[float, float]:
    """Clock offset between a reference signal and an IMU signal by cross-correlation.

    The offset ``d`` is defined by ``t_ref = t_imu + d`` for the same physical instant (``d > 0``: the reference
    clock is ahead of the IMU clock). The reference signal is evaluated by cubic spline at ``t_imu + d`` for a grid
    of ``d`` and correlated with the IMU signal; the correlation peak is refined by a parabola through the grid
    maximum and its neighbours.

    Parameters
    ----------
    t_ref, signal_ref : (M,) s and signal on the reference clock (NaN-free).
    t_imu, signal_imu : (N,) s and the same physical signal on the IMU clock, filtered to the same bandwidth.
    max_offset : s, search range +-max_offset.
    step : s, grid step.

    Returns
    -------
    offset : s.
    peak_correlation : Pearson correlation at the grid maximum (dimensionless).
    """
    offsets = np.arange(-max_offset, max_offset + 0.5 * step, step)
    inside = (t_imu > t_ref[0] + max_offset) & (t_imu < t_ref[-1] - max_offset)
    spline = CubicSpline(t_ref, signal_ref)
    imu = signal_imu[inside]
    corr = np.array([np.corrcoef(spline(t_imu[inside] + d), imu)[0, 1] for d in offsets])
    k = int(np.clip(np.argmax(corr), 1, len(corr) - 2))
    curvature = corr[k - 1] - 2.0 * corr[k] + corr[k + 1]
    shift = 0.5 * (corr[k - 1] - corr[k + 1]) / curvature if curvature < 0 else 0.0
    return float(offsets[k] + shift * step), float(corr[k])


def rotation_between(vectors_from: np.ndarray, vectors_to: np.ndarray) -> np.ndarray:
    """Proper rotation ``R`` minimising ``sum |to_k - R from_k|^2`` (Kabsch / Wahba).

    Parameters
    ----------
    vectors_from, vectors_to : (K, 3) paired vectors (any unit, the same for both).

    Returns
    -------
    (3, 3) rotation matrix with det +1.
    """
    u, _, vt = np.linalg.svd(vectors_from.T @ vectors_to)
    d = np.sign(np.linalg.det(vt.T @ u.T))
    return vt.T @ np.diag([1.0, 1.0, d]) @ u.T


def fit_lever_arm(kin: BodyKinematics, imu_specific_force_world: np.ndarray,
                  use: np.ndarray) -> tuple[np.ndarray, float]:
    """Body-fixed point whose motion-capture specific force best matches the IMU's (linear least squares).

    Model: ``f_imu_world = a_origin - g + (alpha x + w x w x) R r`` with ``r`` the point in the body frame.

    Parameters
    ----------
    kin : marker-body kinematics on the motion-capture clock.
    imu_specific_force_world : (M, 3) m/s^2, the IMU's specific force rotated into the world frame and resampled on
        the motion-capture clock (same bandwidth as ``kin``).
    use : (M,) bool, samples to fit on.

    Returns
    -------
    lever_arm : (3,) m, in the marker body frame, from the marker origin.
    residual_rms : m/s^2, RMS vector residual of the fit.
    """
    w = quat.skew(kin.rate_world[use])
    design = np.einsum("nij,njk->nik", quat.skew(kin.ang_acc_world[use]) + w @ w, kin.rotation[use])
    target = imu_specific_force_world[use] - kin.origin_acc[use] + GRAVITY_WORLD
    lever_arm, *_ = np.linalg.lstsq(design.reshape(-1, 3), target.reshape(-1), rcond=None)
    residual = target - design @ lever_arm
    return lever_arm, float(np.sqrt(np.mean(np.sum(residual**2, axis=1))))
