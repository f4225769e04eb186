"""How the sensor sits on the foot: its yaw read from the swing axis, its height read from the push-off, its
position along the foot fitted to the recording's accelerometer profiles.

The yaw (:func:`fit_yaw`) is the angle about the sensor's z between the sensor's x and the foot's. The foot
swings about its lateral axis, so a yaw of the sensor turns the dominant rotation axis of each stride, as the
sensor sees it, by the same angle (``swing_axis_yaw``; tests/test_loop_residuals.py); what the twin's own foot
adds (its stance roll and swing yaw) is in both the recording and the twin and cancels in the difference. Fitted
first, before the profiles below (the yaw mixes the accelerometer's x and y) and before any effect: a sensor
turned on the shoe is part of the twin, like its roll and pitch read from gravity, not an error to be found.

The height is the push-off's reading (:func:`gaitsim.loop.push_off.push_off_height`: the lever of a rigid turn
about the still toe contact, from the recording's own gyro and accelerometer), which the twin's swing, gait shape
and stance model do not enter. Fitted with the profiles below, the height went to its bound 0 on every shared
recording (gaitmap's Vicon pose puts the sensor 4.2-4.8 cm above the floor): the profiles' misfit in the contact
phases (several m/s^2, a twin whose foot does not move as the real one) pulls it there.

For a given foot motion the specific force at a foot point r (foot frame, from the heel contact) is linear in r:
``f(r) = C^T (a_heel - g) + alpha x r + w x (w x r)`` in the foot frame, then turned by the sensor's mounting
rotation. Phase profiles (means over strides of the signal resampled on the gait phase) are linear too. So the
twin is simulated three times on the same walk and seed (its mount site at the toes, then moved
``settings.PROBE_M``
along x and z), giving the profiles as ``P(r) = P_0 + J (r - r_0)`` exactly; the lever arm is the bounded
linear least-squares fit of the recording's three accelerometer profiles in the contact phases, with the height
held at the push-off's reading (both fitted where the push-off gives none). The strides are segmented once, on the
first simulation, so that every probe is cut at the same instants (its sensor noise is the same draw, and
cancels in the differences).

Bounds (``settings.SITE_BOUNDS_M``): the sensor lies on the shoe, between 8 cm behind the heel contact and 5 cm ahead of
the toe contact, within 7 cm of the mid line, up to 12 cm above the sole.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import lsq_linear

from ..world.foot import FootModel
from . import settings
from .signature import Signature, signature
from .strides import phase_resample

ACC_CHANNELS = ("acc_x", "acc_y", "acc_z")


def _acc_profiles(rec, strides: np.ndarray) -> np.ndarray:
    """(3 * P,) accelerometer phase profiles (m/s^2) of ``rec`` cut at the given strides, channel after channel."""
    return phase_resample(rec.t, rec.acc, strides).mean(0).T.ravel()


def contact_phases(heel_rocker_frac: float, foot_flat_frac: float, push_off_frac: float) -> np.ndarray:
    """(P,) bool: the phases (from the gyro onset, ~foot flat) in which the foot turns about a ground contact:
    foot flat and push-off [0, foot flat + push-off] and the heel rocker [1 - heel rocker, 1)."""
    phase = np.linspace(0.0, 1.0, settings.PHASE_POINTS, endpoint=False)
    return (phase <= foot_flat_frac + push_off_frac) | (phase >= 1.0 - heel_rocker_frac)


def fit_yaw(measured: Signature, simulate_with_yaw, start_deg: float = 0.0) -> tuple[float, dict]:
    """Yaw (deg) of the sensor on the foot that puts the twin's swing axis where the recording's is.

    Each of ``settings.YAW_ITERATIONS`` steps adds the remaining ``swing_axis_yaw`` difference (recording minus
    twin) to the yaw; a second step takes up what the mount's roll and pitch make of a turn about the sensor's z.

    Parameters
    ----------
    measured : the recording's signature.
    simulate_with_yaw : yaw (deg) -> simulated :class:`nav.recording.Recording` of the twin with that sensor yaw.
    start_deg : deg, the yaw the steps start from (the twin's current one when it is re-fitted).

    Returns
    -------
    yaw : deg, within ``settings.YAW_BOUND_DEG`` (beyond it the frame check calls it a frame, not a mount).
    quality : the recording's swing-axis yaw and its standard error, and the twin's at the start and at the fitted
        yaw (deg).
    """
    bound = settings.YAW_BOUND_DEG
    target = measured.scalars["swing_axis_yaw"]
    yaw, seen = float(start_deg), []
    for _ in range(settings.YAW_ITERATIONS + 1):
        sim = simulate_with_yaw(yaw)
        seen.append(signature(sim.t, sim.acc, sim.gyr).scalars["swing_axis_yaw"].value)
        if len(seen) > settings.YAW_ITERATIONS:
            break
        yaw = float(np.clip(yaw + target.value - seen[-1], -bound, bound))
    return yaw, {"yaw_deg": yaw, "recording_swing_axis_yaw_deg": target.value,
                 "recording_swing_axis_yaw_se_deg": target.se, "twin_swing_axis_yaw_at_start_deg": seen[0],
                 "twin_swing_axis_yaw_at_fitted_yaw_deg": seen[-1]}


def fit_lever_arm(measured: Signature, simulate_at, phases: np.ndarray, height_m: float = math.nan
                  ) -> tuple[np.ndarray, dict]:
    """Lever arm (m, foot frame from the heel contact) that best reproduces the measured accelerometer profiles.

    Only the ``phases`` where the foot turns about a ground contact are compared (:func:`contact_phases`): there
    the twin's motion is the real foot's rotation about the same point, while its swing is a smooth stand-in
    whose accelerations would bias the fit. In those phases the foot turns mainly about its lateral axis, so
    the position along the foot and the height are well determined and the side offset is not: it is kept
    on the mid line (y = 0).

    Parameters
    ----------
    measured : the recording's signature.
    simulate_at : site (3,) m -> simulated :class:`nav.recording.Recording` of the twin with its IMU there.
    phases : (P,) bool, the phases compared.
    height_m : m, the sensor's height above the sole (the push-off's reading), held within the bounds; NaN: fitted
        with the position along the foot.

    Returns
    -------
    site : (3,) m.
    quality : rms misfit of the three accelerometer profiles (m/s^2) at the default site (the toes) and at
        the fitted one, and where the height came from.
    """
    origin = np.array(FootModel().lever_arm)
    base = simulate_at(origin)
    sig = signature(base.t, base.acc, base.gyr)
    use = np.tile(phases, len(ACC_CHANNELS))
    p0 = _acc_profiles(base, sig.strides)[use]
    jac = np.stack([(_acc_profiles(simulate_at(origin + settings.PROBE_M * np.eye(3)[i]), sig.strides)[use] - p0)
                    / settings.PROBE_M
                    for i in (0, 2)], axis=1)  # profiles are linear in the site: P = p0 + jac (x - x0, z - z0)
    target = np.concatenate([measured.profiles[c].mean for c in ACC_CHANNELS])[use]
    low, high = (np.array(b)[[0, 2]] for b in settings.SITE_BOUNDS_M)
    xz0 = origin[[0, 2]]
    held = bool(np.isfinite(height_m))
    height = float(np.clip(height_m, low[1], high[1])) if held else math.nan
    free = [0] if held else [0, 1]
    shown = target - p0 - (jac[:, 1] * (height - xz0[1]) if held else 0.0)  # what the free coordinates fit
    found = lsq_linear(jac[:, free], shown + jac[:, free] @ xz0[free], bounds=(low[free], high[free]))
    site = np.array([found.x[0], 0.0, height if held else found.x[1]])
    misfit = target - p0 - jac @ (site[[0, 2]] - xz0)
    return site, {"rms_acc_misfit_default_site_mps2": float(np.sqrt(np.mean((target - p0) ** 2))),
                  "rms_acc_misfit_fitted_site_mps2": float(np.sqrt(np.mean(misfit ** 2))),
                  "phases_compared": int(phases.sum()), "site_m": site.tolist(),
                  "height_from": "push-off" if held else "accelerometer profiles"}
