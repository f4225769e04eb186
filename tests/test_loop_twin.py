"""The twin fit recovers the gait and mount of a simulated recording that declares neither."""

import math

import numpy as np
import pytest

import nav
from gaitsim.loop import settings, twin
from gaitsim.loop.signature import signature
from gaitsim.measured.reference import as_measured
from gaitsim.scenario import scenario_from_dict
from gaitsim.simulate import simulate_walk


@pytest.fixture(scope="module")
def fitted():
    doc = {"path": {"kind": "polyline", "waypoints_m": [[0, 0], [10, 0], [10, 6]], "corner_radius_m": 1.0},
           "sampling": {"rate_hz": 200.0}, "sensor": {"preset": "vn200", "withhold": True,
                      "mounting_misalignment": [[12.0, -8.0, 10.0], "deg"]},
           "gait": {"cadence_steps_per_min": 100.0, "stride_length_m": 1.25, "pitch_toe_off_deg": 55.0},
           }
    rec = as_measured(simulate_walk(scenario_from_dict(doc), seed=5), reference_rate_hz=100.0)
    sig = signature(rec.t, rec.acc, rec.gyr, rec.reference.t, rec.reference.pos)
    sol = nav.navigate(rec, settings.NAV_OPTIONS)
    return rec, twin.fit_twin(rec, sig, sol, twin.TwinSimulator())


def test_measured_recording_carries_no_gait_or_sensor_parameters(fitted):
    rec, _ = fitted
    assert rec.truth is None and rec.events is None
    assert set(rec.meta) == {"sampling", "reference"}


def test_cadence_stride_length_and_mount_are_recovered(fitted):
    _, fit = fitted
    gait = fit.document()["gait"]
    assert gait["cadence_steps_per_min"] == pytest.approx(100.0, rel=0.02)
    assert gait["stride_length_m"] == pytest.approx(1.25, rel=0.03)
    roll, pitch, yaw = np.degrees(fit.scenario.sensor["mounting_misalignment"])
    assert roll == pytest.approx(12.0, abs=0.5) and pitch == pytest.approx(-8.0, abs=0.5)
    quality = fit.notes["mount_fit"]
    assert yaw == pytest.approx(10.0, abs=max(0.5, 3 * quality["recording_swing_axis_yaw_se_deg"]))
    # the fitted twin's swing axis is the recording's (the yaw fit's own criterion, to its iteration)
    assert quality["twin_swing_axis_yaw_at_fitted_yaw_deg"] == pytest.approx(quality["recording_swing_axis_yaw_deg"],
                                                                              abs=0.2)


def test_the_turn_becomes_a_polyline_of_the_walked_length(fitted):
    _, fit = fitted
    assert fit.document()["path"]["kind"] == "polyline"
    pts = fit.document()["path"]["waypoints_m"]
    length = sum(math.dist(a, b) for a, b in zip(pts, pts[1:]))
    assert length == pytest.approx(16.0, rel=0.1)


def test_matched_statistics_agree(fitted):
    _, fit = fitted
    m, t = fit.notes["measured_statistics"], fit.notes["twin_statistics"]
    assert t["period_s"] == pytest.approx(m["period_s"], rel=0.02)
    assert t["swing_height_m"] == pytest.approx(m["swing_height_m"], rel=0.1)
    shape = fit.notes["gait_shape_fit"]
    # of a profile spanning +-500 deg/s; the recording and its twin draw their own stride-to-stride stance rates
    assert shape["rms_rate_misfit_fit_dps"] < 12.0
    np.testing.assert_allclose(shape["pitch_extremes_twin_deg"], shape["pitch_extremes_measured_deg"], atol=2.0)
    assert fit.document()["gait"]["pitch_toe_off_deg"] == pytest.approx(55.0, abs=4.0)


def test_sensor_position_on_the_foot_is_found(fitted):
    _, fit = fitted
    site = np.array(fit.notes["mount_fit"]["site_m"])
    np.testing.assert_allclose(site[[0, 2]], [0.2, 0.04], atol=0.02)  # the default mount: top of the toes


def test_noise_is_matched_to_the_static_part(fitted):
    rec, fit = fitted
    sim = twin.TwinSimulator()(fit)
    q0, q1 = 20, 200  # the first second is standing in both
    ratio = sim.gyr[q0:q1].std(0) / rec.gyr[q0:q1].std(0)
    assert ratio == pytest.approx([1, 1, 1], rel=0.25)


def test_a_sensor_change_reuses_the_simulated_walk(fitted):
    _, fit = fitted
    simulate = twin.TwinSimulator()
    base = simulate(fit)
    biased = simulate(fit.with_changes({"sensor": {"accel_bias": [[0.1, -0.2, 0.05], "m/s^2"]}}))
    assert biased.truth is base.truth  # the walk was simulated once
    np.testing.assert_allclose(biased.acc - base.acc, np.tile([0.1, -0.2, 0.05], (len(base.t), 1)), atol=1e-9)
    np.testing.assert_array_equal(biased.gyr, base.gyr)
