"""The loop on a run: strides cut where a running foot is never still, a running twin, an effect found on it.

The recordings are simulated runs of a consumer sensor (bmi160: turn-on offsets, noise, 16-bit outputs) at 200 Hz,
stripped to what a measured recording carries (IMU samples and a 100 Hz position reference); the effect is put
into the samples by the test's own numpy lines.
"""

import dataclasses

import numpy as np
import pytest

import nav
from gaitsim.loop import attribution, settings, twin
from gaitsim.loop.frame import check_frame
from gaitsim.loop.signature import signature
from gaitsim.loop.strides import stance_intervals
from gaitsim.measured import axes
from gaitsim.measured.reference import as_measured
from gaitsim.scenario import scenario_from_dict
from gaitsim.simulate import simulate_walk


def _run(kind: str, cadence: float, seed: int):
    doc = {"path": {"kind": "straight", "length_m": 36.0}, "gait": {"kind": kind, "cadence_steps_per_min": cadence},
           "sampling": {"rate_hz": 200.0}, "sensor": {"preset": "bmi160", "withhold": True}}
    return as_measured(simulate_walk(scenario_from_dict(doc), seed=seed), reference_rate_hz=100.0)


@pytest.fixture(scope="module")
def rearfoot():
    return _run("run-rearfoot", 175.0, 21)


@pytest.fixture(scope="module")
def forefoot():
    return _run("run-forefoot", 155.0, 22)


def _twin(rec):
    sig = signature(rec.t, rec.acc, rec.gyr, rec.reference.t, rec.reference.pos, gravity=rec.gravity)
    fitted = twin.fit_twin(rec, sig, nav.navigate(rec, settings.NAV_OPTIONS), twin.TwinSimulator())
    simulated = twin.TwinSimulator()(fitted)
    return sig, fitted, signature(simulated.t, simulated.acc, simulated.gyr, gravity=simulated.gravity)


def test_a_short_anchored_run_is_a_stance_a_short_fixed_one_only_alone_where_the_anchor_acted():
    t = np.arange(600) / 200.0
    stationary = np.zeros(600, bool)
    stationary[:100] = True  # a rest
    stationary[130:137] = True  # 30 ms, 0.15 s after the rest: a swing crossing the fixed threshold
    stationary[250:258] = True  # 35 ms: a running stance the anchor marked
    stationary[400:406] = True  # 25 ms, 0.7 s from any other stance: a stance the fixed test passed briefly
    anchored = np.zeros(600, bool)
    assert settings.MIN_STANCE_S > 0.035
    # a walk (the anchor acted nowhere): every short run is dropped
    assert stance_intervals(t, stationary, anchored, 0.5).tolist() == [[0, 100]]
    anchored[252:256] = True
    assert stance_intervals(t, stationary, anchored, 0.5).tolist() == [[0, 100], [250, 258], [400, 406]]


def test_the_strides_of_a_run_are_cut(rearfoot, forefoot):
    # the fixed SHOE finds a few of these stances at most; the anchored one marks each stride's calmest 50-120 ms,
    # or the fixed test passes it for a few samples, and the loop keeps both
    for rec, cadence in ((rearfoot, 175.0), (forefoot, 155.0)):
        sig = signature(rec.t, rec.acc, rec.gyr, gravity=rec.gravity)
        between = np.diff(rec.t[sig.stance_runs[:, 0]])[1:-1]  # stance to stance, off and onto the rests left out
        assert np.round(between / (120.0 / cadence)).tolist() == [1.0] * len(between)  # none missed, none split
        assert len(between) >= int(36.0 / 2.4) - 2
        assert len(sig.strides) >= 0.8 * len(between)  # regular strides (gyro onset to onset) for the signature
        assert check_frame(rec).is_body_frame


@pytest.mark.parametrize("text", ["x,-y,-z", "y,-x,z", "-x,-y,z", "x,y,-z", "z,y,-x"])
def test_the_frame_laws_hold_on_a_run(forefoot, text):
    """Whatever signed permutation (a mirror included) a logger applied to a run, the frame check's map undoes it:
    gravity at rest, the toes-down swing about +y, and the stride closure's handedness hold for a running foot."""
    applied = axes.parse_axis_map(text)
    found = check_frame(axes.remapped(forefoot, applied))
    np.testing.assert_array_equal(found.axes @ applied, np.eye(3))
    assert not found.is_body_frame


@pytest.mark.parametrize("which, strike", [("rearfoot", "run-rearfoot"), ("forefoot", "run-forefoot")])
def test_the_twin_of_a_run_is_a_run_with_its_strike(which, strike, request):
    rec = request.getfixturevalue(which)
    sig, fitted, twin_sig = _twin(rec)
    kind = fitted.notes["gait_kind"]
    assert kind["speed_mps"] >= settings.WALK_RUN_SPEED_MPS and kind["kind"] == strike
    gait = fitted.scenario.walk.gait
    assert gait.heel_rocker_frac + gait.foot_flat_frac + gait.push_off_frac < 0.5  # a flight phase
    assert gait.forefoot_strike == (strike == "run-forefoot")
    # the running foot's peaks, which a walking twin halves (a walking twin of such a run peaked at ~520 deg/s)
    for name, rel in (("gyr_peak", 0.2), ("acc_peak", 0.3), ("stance_gyro", 0.3)):
        assert twin_sig.scalars[name].value == pytest.approx(sig.scalars[name].value, rel=rel), name


def test_a_walk_keeps_a_walking_twin():
    doc = {"path": {"kind": "straight", "length_m": 20.0}, "sampling": {"rate_hz": 200.0},
           "gait": {"kind": "walk", "cadence_steps_per_min": 125.0}, "sensor": {"preset": "bmi160", "withhold": True}}
    rec = as_measured(simulate_walk(scenario_from_dict(doc), seed=23), reference_rate_hz=100.0)
    _, fitted, _ = _twin(rec)
    assert fitted.notes["gait_kind"]["kind"] == "walk"
    assert fitted.notes["gait_kind"]["speed_mps"] == pytest.approx(125.0 / 120.0 * 2 * 0.84, rel=0.05)
    assert not fitted.scenario.walk.gait.forefoot_strike


TAU = 0.004  # s, the gyro delay put into the run
DELAY_GROUP = pytest.mark.xdist_group("loop-running-delay")  # both tests on one worker: the fixture runs once


@pytest.fixture(scope="module")
def delayed_runs(rearfoot):
    """The loop on the run and on the run with its gyro samples read at t - TAU (the test's own interpolation)."""
    gyr = np.stack([np.interp(rearfoot.t - TAU, rearfoot.t, g) for g in rearfoot.gyr.T], axis=1)
    delayed = dataclasses.replace(rearfoot, gyr=gyr)
    return attribution.run_loop(rearfoot, max_effects=3), attribution.run_loop(delayed, max_effects=3)


@DELAY_GROUP
def test_a_gyro_delay_on_a_run_is_read_by_the_push_off_lag(delayed_runs):
    """The push-off lag (the gyro's turn against the accelerometer's where the foot pivots on its toe) reads the
    delay itself, on a running twin."""
    untouched, found = delayed_runs
    assert found.twin_before.notes["gait_kind"]["kind"] == "run-rearfoot"
    lag = [r.measured.signature.scalars["acc_gyro_lag"] for r in (untouched, found)]
    assert lag[1].value - lag[0].value == pytest.approx(1e3 * TAU, abs=3 * np.hypot(lag[0].se, lag[1].se))
    before = {a["effect"] for a in untouched.attributions if a["effect"] != "unexplained"}
    assert before == {"accel_bias_x", "accel_bias_z"}  # the BMI160's own offsets (0.34, 0.23 m/s^2), named together


@DELAY_GROUP
@pytest.mark.xfail(strict=True, reason=(
    "known gap: the lag residual of a running twin sits at the noise level (its comparison noise is the running "
    "twin's), so the delay shows in the forward stride closure, which the x offset moves too: the joint fit of "
    "the linear effects names a z scale with an x offset (2.5 %, 0.80 m/s^2; the sensor's own 0.34) and no set "
    "with the skew is among the best. The greedy rounds named a skew of -5.7 ms here before the joint fit."))
def test_a_gyro_delay_on_a_run_is_named_a_skew(delayed_runs):
    _, found = delayed_runs
    named = {a["effect"]: a["magnitude"] for a in found.attributions if a["effect"] != "unexplained"}
    assert named["accel_gyro_skew"] == pytest.approx(-1e3 * TAU, rel=0.5)
