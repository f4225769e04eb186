"""Where the sensor sits on the foot: its lever arm fitted to the recording's accelerometer profiles.

For a given foot motion the specific force at a foot point r (foot frame, from the heel contact) is linear in r:
``f(r) = C^T (a_heel - g) + alpha x r + w x (w x r)`` in the foot frame, then turned by the sensor's mounting
rotation. Phase profiles (means over strides of the signal resampled on the gait phase) are linear too. So the
twin is simulated three times on the same walk and seed (its mount site at the toes, then moved
``settings.PROBE_M``
along x and z), giving the profiles as ``P(r) = P_0 + J (r - r_0)`` exactly; the lever arm is the bounded
linear least-squares fit of the recording's three accelerometer profiles in the contact phases. The strides are segmented once, on the
first simulation, so that every probe is cut at the same instants (its sensor noise is the same draw, and
cancels in the differences).

Bounds (``settings.SITE_BOUNDS_M``): the sensor lies on the shoe, between 8 cm behind the heel contact and 5 cm ahead of
the toe contact, within 7 cm of the mid line, up to 12 cm above the sole.
"""

from __future__ import annotations

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


def fit_lever_arm(measured: Signature, simulate_at, phases: np.ndarray) -> tuple[np.ndarray, dict]:
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

    Returns
    -------
    site : (3,) m.
    quality : rms misfit of the three accelerometer profiles (m/s^2) at the default site (the toes) and at
        the fitted one.
    """
    origin = np.array(FootModel().lever_arm)
    base = simulate_at(origin)
    sig = signature(base.t, base.acc, base.gyr)
    use = np.tile(phases, len(ACC_CHANNELS))
    p0 = _acc_profiles(base, sig.strides)[use]
    fitted_axes = (0, 2)
    jac = np.stack([(_acc_profiles(simulate_at(origin + settings.PROBE_M * np.eye(3)[i]), sig.strides)[use] - p0)
                    / settings.PROBE_M
                    for i in fitted_axes], axis=1)
    target = np.concatenate([measured.profiles[c].mean for c in ACC_CHANNELS])[use]
    low, high = (np.array(b)[list(fitted_axes)] for b in settings.SITE_BOUNDS_M)
    found = lsq_linear(jac, target - p0 + jac @ origin[list(fitted_axes)], bounds=(low, high))
    site = np.array([found.x[0], 0.0, found.x[1]])
    misfit = target - p0 - jac @ (found.x - origin[list(fitted_axes)])
    return site, {"rms_acc_misfit_default_site_mps2": float(np.sqrt(np.mean((target - p0) ** 2))),
                  "rms_acc_misfit_fitted_site_mps2": float(np.sqrt(np.mean(misfit ** 2))),
                  "phases_compared": int(phases.sum()), "site_m": site.tolist()}
