"""The twin's gait-shape and sensor-position fits: exact recovery where the model is exact, linearity laws."""

import numpy as np
import pytest

from gaitsim.loop import gait_fit, mount_fit, settings, twin
from gaitsim.loop.signature import signature
from gaitsim.scenario import fill, scenario_from_dict
from gaitsim.simulate import simulate_walk
from gaitsim.world.gait import GaitParams, ImpactParams

SHAPE = {"heel_rocker_frac": 0.12, "foot_flat_frac": 0.28, "push_off_frac": 0.2, "swing_frac": 0.4,
         "pitch_heel_strike_deg": -24.0, "pitch_rate_heel_strike_dps": 180.0, "pitch_accel_heel_strike_dps2": 4000.0,
         "pitch_toe_off_deg": 52.0, "pitch_rate_toe_off_dps": 260.0, "pitch_accel_toe_off_dps2": -6000.0}
SLAP = {"slap_rate_dps": 150.0, "slap_duration_s": 0.06}


def test_model_profile_angle_is_the_integral_of_its_rate():
    model = gait_fit.model_profile(GaitParams(), ImpactParams())
    step = model.period_s / len(model.rate)
    integral = np.concatenate([[0.0], np.cumsum(0.5 * (model.rate[1:] + model.rate[:-1]) * step)])
    np.testing.assert_allclose(model.angle, integral, atol=0.05 * np.abs(model.angle).max())
    assert abs(model.rate[0]) <= settings.QUIET_RATE_DPS  # the phase origin is where the rate falls quiet
    assert model.period_s == pytest.approx(GaitParams().cycle_s, rel=1e-3)


def test_fit_recovers_a_gait_from_its_own_profile():
    """Measured = the model of a gait far from the defaults: the fit, started from the defaults at that cadence,
    reproduces the profile and the events."""
    cadence = GaitParams(cadence_steps_per_min=100.0)
    truth = gait_fit.model_profile(fill(GaitParams, SHAPE, "[gait]", cadence), fill(ImpactParams, SLAP, "[impact]"))
    changes, quality = gait_fit.fit_pitch_profile(truth, cadence, ImpactParams())
    # of a profile spanning -400..+300 deg/s; the fit stops in a shallow minimum (~5 deg/s) that trades the heel
    # strike rate against the slap (see below)
    assert quality["rms_rate_misfit_fit_dps"] < 6.0
    fitted = changes["gait"]
    # the pitch rate pins toe off and heel strike in the cycle; heel off is weakly determined (the push-off
    # starts from rest with a flat rate) and so is the split of the heel rocker's rate between strike and slap
    assert fitted["foot_flat_frac"] + fitted["push_off_frac"] == pytest.approx(0.48, abs=0.02)
    assert fitted["heel_rocker_frac"] == pytest.approx(SHAPE["heel_rocker_frac"], abs=0.03)
    assert fitted["pitch_toe_off_deg"] == pytest.approx(SHAPE["pitch_toe_off_deg"], abs=3.0)
    np.testing.assert_allclose(quality["pitch_extremes_twin_deg"], quality["pitch_extremes_measured_deg"], atol=1.0)


def test_accelerometer_profiles_are_linear_in_the_sensor_position():
    """The law the position fit rests on: f(r) = f(0) + J r exactly (same walk and seed), so a site half way
    between two probes reads the mean of their profiles."""
    doc = {"path": {"kind": "straight", "length_m": 8.0}, "sampling": {"rate_hz": 200.0},
           "gait": {"stand_start_s": 1.0, "stand_end_s": 1.0}}

    def at(site):
        return simulate_walk(scenario_from_dict({**doc, "mount": twin.mount_table(site)}), seed=3)

    a, b = at([0.0, 0.0, 0.02]), at([0.2, 0.04, 0.08])
    mid = at([0.1, 0.02, 0.05])
    strides = signature(a.t, a.acc, a.gyr).strides
    profiles = [mount_fit._acc_profiles(r, strides) for r in (a, b, mid)]
    np.testing.assert_allclose(profiles[2], 0.5 * (profiles[0] + profiles[1]), atol=1e-9 * np.abs(profiles[0]).max())


def test_sensor_position_is_recovered_on_a_heel_mounted_recording():
    # The stance rates' stride-to-stride variation is switched off: with the default 30 % it moves the mean
    # profiles of 8 strides enough to shift x of a heel mount by 1.5-3 cm (x of a site near the heel contact is
    # the weakly determined coordinate; measured -0.013 m on 12 m and -0.025 m on 30 m against -0.04 m).
    doc = {"path": {"kind": "straight", "length_m": 12.0}, "sampling": {"rate_hz": 200.0},
           "gait": {"stand_start_s": 1.0, "stand_end_s": 1.0}, "micromotion": {"stance_rate_sd_frac": 0.0}}
    rec = simulate_walk(scenario_from_dict({**doc, "mount": {"site": "heel"}}), seed=4)
    sig = signature(rec.t, rec.acc, rec.gyr)
    g = GaitParams()
    phases = mount_fit.contact_phases(g.heel_rocker_frac, g.foot_flat_frac, g.push_off_frac)
    site, quality = mount_fit.fit_lever_arm(
        sig, lambda r: simulate_walk(scenario_from_dict({**doc, "mount": twin.mount_table(r)}), seed=5), phases)
    np.testing.assert_allclose(site[[0, 2]], [-0.04, 0.05], atol=0.015)  # the heel mount of the foot model
    assert quality["rms_acc_misfit_fitted_site_mps2"] < 0.5 * quality["rms_acc_misfit_default_site_mps2"]
