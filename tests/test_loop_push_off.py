"""The push-off (gaitsim.loop.push_off): a rigid turn about a still point, made with numpy alone, reads the delay put
on its gyro; and two walks of different gaits with their sensors in step read the same lag."""

import warnings

import numpy as np
import pytest

from conftest import needs_data
from gaitsim.loop import twin
from gaitsim.loop.push_off import push_off_height, push_off_lag
from gaitsim.measured import load_dataset
from gaitsim.loop.signature import signature
from gaitsim.scenario import scenario_from_dict
from gaitsim.simulate import simulate_walk

G = 9.81


def turns_about_a_still_point(rate_hz=400.0, strides=8, lever=(0.12, 0.01, 0.06), bias=(0.05, -0.02, 0.1)):
    """Rest 0.6 s, then a pitch turn of 60 deg in 0.25 s (a smooth bump of rate) about a point that does not move,
    then back in 0.35 s, per stride; the sensor at ``lever`` (m, body frame) from the point. Returns t, f, w and
    the stances [start, end) (the rests)."""
    period, rest, turn, back = 1.2, 0.6, 0.25, 0.35
    t = np.arange(0.0, strides * period + rest, 1.0 / rate_hz)
    phase = t % period
    on, ret = (phase >= rest) & (phase < rest + turn), phase >= rest + turn
    x = np.where(on, (phase - rest) / turn, 0.0)
    y = np.where(ret, (phase - rest - turn) / back, 0.0)
    amplitude = np.radians(60.0)
    # theta rises by amplitude along a C2 smoothstep, then falls back along another
    smooth = lambda s: s**3 * (10 - 15 * s + 6 * s**2)  # noqa: E731
    d1 = lambda s: 30 * s**2 * (1 - s) ** 2  # noqa: E731
    d2 = lambda s: 60 * s * (1 - s) * (1 - 2 * s)  # noqa: E731
    theta = amplitude * np.where(on, smooth(x), np.where(ret, 1 - smooth(y), 0.0))
    rate = amplitude * np.where(on, d1(x) / turn, np.where(ret, -d1(y) / back, 0.0))
    accel = amplitude * np.where(on, d2(x) / turn**2, np.where(ret, -d2(y) / back**2, 0.0))
    w = np.column_stack([np.zeros_like(t), rate, np.zeros_like(t)])
    w_dot = np.column_stack([np.zeros_like(t), accel, np.zeros_like(t)])
    r = np.asarray(lever)
    # body frame: f = w_dot x r + w x (w x r) + R^T (0, 0, g), R a turn by theta about y
    up = np.column_stack([-np.sin(theta) * G, np.zeros_like(t), np.cos(theta) * G])
    f = np.cross(w_dot, r) + np.cross(w, np.cross(w, r)) + up + np.asarray(bias)
    starts = np.flatnonzero(np.diff((phase < rest).astype(int)) == 1) + 1
    ends = np.flatnonzero(np.diff((phase < rest).astype(int)) == -1) + 1
    stances = np.column_stack([np.concatenate([[0], starts])[:len(ends)], ends])
    return t, f, w, stances


@pytest.mark.parametrize("delay_ms", [0.0, -3.0, 2.5, 6.0])
def test_a_rigid_turn_about_a_still_point_reads_the_gyro_delay(delay_ms):
    t, f, w, stances = turns_about_a_still_point()
    late = np.column_stack([np.interp(t - delay_ms / 1000.0, t, c) for c in w.T])
    value, se = push_off_lag(t, f, late, stances)
    assert value == pytest.approx(delay_ms, abs=0.1)
    assert se < 0.1


def test_too_few_stances_give_no_lag():
    t, f, w, stances = turns_about_a_still_point(strides=2)
    assert np.isnan(push_off_lag(t, f, w, stances[:2])[0])


def _lag_of_walk(cadence: float, **gait) -> float:
    doc = {"path": {"kind": "straight", "length_m": 14.0}, "sampling": {"rate_hz": 200.0},
           "gait": {"kind": "walk", "cadence_steps_per_min": cadence, **gait}, "sensor": {"preset": "ideal"}}
    rec = simulate_walk(scenario_from_dict(doc), seed=4)
    return signature(rec.t, rec.acc, rec.gyr).scalars["acc_gyro_lag"].value


def test_walks_of_different_pace_read_the_same_lag_with_their_sensors_in_step():
    """Gait-shape independence: a slow and a fast walk (their swing and push-off differ) read lags within half a
    millisecond of each other when the sensors are in step."""
    assert _lag_of_walk(75.0) == pytest.approx(_lag_of_walk(115.0), abs=0.5)


@pytest.mark.parametrize("cadence", [75.0, 115.0])
def test_the_walking_toe_release_lies_beyond_the_lag_s_window_up_to_115_steps_per_min(cadence):
    """The walking kind's toe release (the contact accelerating forward over the push-off's last 40 ms) is not
    the rigid turn the lag is read from; up to 115 steps/min it lies beyond the 0.12 s window and the walk reads
    what it reads on a fixed toe. (Faster, it enters the window, and the reading is wrong: +0.45 against +0.86 ms
    at 120 and -3.9 against +0.81 at 125 steps/min; at 130 the best fit lies on the search's -15 ms edge.)"""
    assert _lag_of_walk(cadence) == pytest.approx(_lag_of_walk(cadence, toe_release_accel_mps2=0.0), abs=0.05)


@pytest.mark.parametrize("delay_ms", [0.0, 4.0])
def test_a_rigid_turn_about_a_still_point_reads_the_sensor_lever(delay_ms):
    """The lever of a numpy-made turn about a still point, read at the gyro's lag: its component along the rest's
    up (the height above the pivot) and along the foot (ahead of the pivot); the lateral component, along the turn's
    axis, is not seen and takes no part."""
    t, f, w, stances = turns_about_a_still_point(lever=(-0.07, 0.03, 0.055))
    late = np.column_stack([np.interp(t - delay_ms / 1000.0, t, c) for c in w.T])
    lag, _ = push_off_lag(t, f, late, stances)
    height, se, ahead = push_off_height(t, f, late, stances, lag)
    assert height == pytest.approx(0.055, abs=1e-3)
    assert ahead == pytest.approx(-0.07, abs=1e-3)
    assert se < 1e-3


@pytest.mark.parametrize("site", [(0.05, 0.0, 0.045), (0.12, 0.0, 0.08), (0.2, 0.0, 0.02)])
def test_a_simulated_foot_shows_its_sensor_height_on_a_consumer_sensor(site):
    """On a simulated walk (rolling sole, stance micro-motion, a miscalibrated BMI160 with its biases, scale and
    misalignment) the push-off reads the sensor's height above the sole within 7 mm: the twin's toe contact, on
    its sole, is the pivot of its push-off. (Ideal and VN-200 sensors read within 3 mm over seeds 6-8, the rolling
    sole's contact moving a little; the BMI160's calibration errors move the reading by up to 5 mm.)"""
    doc = {"path": {"kind": "straight", "length_m": 14.0}, "sampling": {"rate_hz": 200.0},
           "sensor": {"preset": "bmi160"}, "mount": twin.mount_table(site)}
    rec = simulate_walk(scenario_from_dict(doc), seed=6)
    sig = signature(rec.t, rec.acc, rec.gyr)
    height, se, _ = push_off_height(rec.t, rec.acc, rec.gyr, sig.stances, sig.scalars["acc_gyro_lag"].value)
    assert height == pytest.approx(site[2], abs=0.007)
    assert se < 0.003


@needs_data("gaitmap-healthy")
def test_gaitmap_sensors_read_the_height_the_vicon_pose_gives():
    """Both gaitmap feet: the push-off height against the 4.2-4.8 cm above the floor in foot flat that the
    Vicon pose puts the NilsPod at (gaitsim.stance.command.SITES), within 1.5 cm (read: 5.5 and 5.8 cm; the
    shoe's forefoot rolls, so its push-off pivot is not quite a point on the floor). The sensor's accelerometer
    profiles, fitted for the height before, put it at 0."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the loader's data-quality counts are tested elsewhere
        recordings = load_dataset("gaitmap-healthy")
    for rec in recordings:
        sig = signature(rec.t, rec.acc, rec.gyr)
        height, se, _ = push_off_height(rec.t, rec.acc, rec.gyr, sig.stances, sig.scalars["acc_gyro_lag"].value)
        assert abs(height - 0.045) <= 0.015, (rec.meta["recording"], height, se)
        assert se < 0.003
