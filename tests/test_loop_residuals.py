"""Residual metrics of the loop: zero against oneself, noise level between seeds, and the laws of single terms."""

import dataclasses

import numpy as np
import pytest

from gaitsim.loop import effects as fx
from gaitsim.loop import residuals, settings
from gaitsim.loop.signature import signature
from gaitsim.scenario import scenario_from_dict
from gaitsim.simulate import simulate_walk


def _walk(seed: int, sensor: dict | None = None, **sections):
    doc = {"path": {"kind": "straight", "length_m": 14.0}, "sampling": {"rate_hz": 200.0},
           "sensor": {"preset": "vn200", **(sensor or {})}, **sections}
    rec = simulate_walk(scenario_from_dict(doc), seed=seed)
    return rec, signature(rec.t, rec.acc, rec.gyr, rec.truth.t, rec.truth.pos)


@pytest.fixture(scope="module")
def reference_pair():
    return _walk(1), _walk(2)


def test_a_recording_has_no_residual_against_itself(reference_pair):
    (_, sig), _ = reference_pair
    res = residuals.compare(sig, sig)
    assert len(res) >= 17
    assert all(abs(r.value) < 1e-9 for r in res.values())


def test_two_seeds_of_one_walk_differ_at_the_noise_level(reference_pair):
    (_, a), (_, b) = reference_pair
    res = residuals.compare(a, b)
    z = np.array([r.z for r in res.values()])
    # stride variability and sensor noise only: at most one residual of ~18 may pass 3 sigma by chance
    assert np.sum(z > settings.NOISE_LEVEL) <= 1, {k: round(r.z, 1) for k, r in res.items()}


def test_stance_creep_reads_as_stance_velocity():
    # the rolling foot's own stance velocity (pitch rate x site height) is switched off: on a foot that does not
    # turn in foot flat the creep plateau covers the core stance, and the forward velocity there is the creep
    # (reference = truth)
    still = {"heel_rise_rate_start_dps": 0.0, "heel_rise_growth_dps3": 0.0, "loading_roll_rate_dps": 0.0,
             "pronation_rate_dps": 0.0, "stance_rate_sd_frac": 0.0}
    _, sig = _walk(3, micromotion={**still, "creep_velocity_mps": [0.02, 0.0, 0.0]})
    assert sig.scalars["stance_velocity"].value == pytest.approx(0.02, abs=0.001)


@pytest.mark.parametrize("delay_ms", [-4.0, 4.0, 8.0])
def test_a_gyro_delay_adds_itself_to_acc_gyro_lag(reference_pair, delay_ms):
    """A pure delay of the gyro (its samples linearly interpolated at t - delay, numpy only) moves the push-off
    lag by the delay, at 200 Hz (5 ms samples), to half a millisecond."""
    (rec, base), _ = reference_pair
    gyr = np.stack([np.interp(rec.t - delay_ms / 1000.0, rec.t, g) for g in rec.gyr.T], axis=1)
    delayed = signature(rec.t, rec.acc, gyr, rec.truth.t, rec.truth.pos)
    assert residuals.compare(delayed, base)["acc_gyro_lag"].value == pytest.approx(delay_ms, abs=0.5)


def test_mount_yaw_turns_the_swing_axis_by_the_same_angle(reference_pair):
    (_, base), _ = reference_pair
    _, turned = _walk(1, {"mounting_misalignment": [[0.0, 0.0, 6.0], "deg"]})
    assert residuals.compare(turned, base)["swing_axis_yaw"].value == pytest.approx(6.0, abs=0.1)


def test_accelerometer_scale_shows_in_the_rest_norm(reference_pair):
    (_, base), _ = reference_pair
    _, scaled = _walk(1, {"accel_misalignment": [np.diag([1.01] * 3).tolist(), "1"]})
    res = residuals.compare(scaled, base)["rest_acc_norm"]
    assert res.measured / res.twin == pytest.approx(1.01, abs=2e-4)


def _rest_noise(rec, acc, gyr) -> tuple[float, ...]:
    """(lag 1, lag 2) of the accelerometer's rest noise, then the gyro's."""
    sig = signature(rec.t, acc, gyr)
    return tuple(sig.scalars[f"rest_{s}_noise_lag{k}"].value for s in ("acc", "gyro") for k in (1, 2))


def test_the_rest_noise_reads_white_and_a_numpy_rc_stage_reads_its_closed_form(reference_pair):
    """The first difference of white noise has autocorrelation -1/2 at lag 1 and 0 at lag 2 (in blocks of 32 samples,
    less their mean and straight line, the estimate reads -0.471 and -0.014: 200,000 samples); after a first-order
    stage y[k] = b y[k-1] + (1 - b) x[k] (numpy, here on the gyro alone) it has -(1 - b) / 2 and -b (1 - b) / 2,
    and the accelerometer's stay white. A slow sway of the resting foot (1 Hz, 3.5 times the accelerometer noise's
    sd) changes neither sensor's."""
    (rec, _), _ = reference_pair
    white = _rest_noise(rec, rec.acc, rec.gyr)
    assert white == pytest.approx((-0.47, -0.01, -0.47, -0.01), abs=0.05)  # ~3 se over the walk's ~18 blocks
    b = np.exp(-2 * np.pi * 25.0 / 200.0)
    smoothed = rec.gyr.copy()
    for k in range(1, len(smoothed)):
        smoothed[k] = b * smoothed[k - 1] + (1 - b) * rec.gyr[k]
    expected = (*white[:2], -(1 - b) / 2, -b * (1 - b) / 2)
    assert _rest_noise(rec, rec.acc, smoothed) == pytest.approx(expected, abs=0.05)
    sway = 0.05 * np.sin(2 * np.pi * 1.0 * rec.t)[:, None] * np.array([1.0, 1.0, 0.0])
    assert _rest_noise(rec, rec.acc + sway, rec.gyr) == pytest.approx(white, abs=0.01)


def test_gyro_delay_shows_as_negative_acc_gyro_lag(reference_pair):
    (_, base), _ = reference_pair
    _, skewed = _walk(1, {"accel_gyro_skew": [8.0, "ms"]})
    # skew > 0 samples the gyro later, so its features arrive earlier relative to the accelerometer's
    lag = residuals.compare(skewed, base)["acc_gyro_lag"]
    assert lag.value == pytest.approx(-8.0, abs=0.5)
    assert lag.z > 3


def test_too_short_a_recording_is_refused():
    rec, _ = _walk(1)
    n = int(3.0 * 200)
    with pytest.raises(ValueError, match="regular strides"):
        signature(rec.t[:n], rec.acc[:n], rec.gyr[:n])


def test_clipping_shows_as_flat_tops_and_a_sharp_peak_does_not():
    from gaitsim.loop.effects import clipped_runs

    t = np.arange(1000) / 200.0
    force = sum(60.0 * np.exp(-(((t - hit) / 0.01) ** 2)) for hit in (0.5, 1.5, 2.5, 3.5, 4.5))  # on samples
    acc = np.stack([force, 0.1 * force, np.full_like(t, 9.81)], axis=1)
    assert clipped_runs(acc) == 0  # the samples beside a 10 ms peak read 78 % of it
    assert clipped_runs(np.clip(acc, -40.0, 40.0)) == 5  # three samples beyond the range at each peak


def test_scale_effects_compose_on_the_twins_matrix_instead_of_replacing_it():
    """An axis scale named after another (or after the twin's own misalignment) multiplies that axis's row of the
    twin's matrix: its magnitude is the axis's own error, and neither effect erases the other."""
    twin = np.eye(3) * 1.02 + 0.001
    x = np.array(fx.BY_NAME["accel_scale_x"].changes(3.0, {"accel_misalignment": twin.tolist()})["sensor"][
        "accel_misalignment"][0])
    np.testing.assert_allclose(x, twin * [[1.03], [1.0], [1.0]])
    y = np.array(fx.BY_NAME["accel_scale_y"].changes(-1.0, {"accel_misalignment": x.tolist()})["sensor"][
        "accel_misalignment"][0])
    np.testing.assert_allclose(y, twin * [[1.03], [0.99], [1.0]])


def test_an_effect_fitted_on_the_edge_of_its_search_range_is_not_named():
    """A magnitude on the edge of the searched range did not bracket a minimum: the fit is no estimate, and the
    loop does not name it however much it lowers the misfit (x-io's short walk once named an 8 Hz bandwidth,
    the lower edge)."""
    from gaitsim.loop.attribution import Fit
    fit = Fit(fx.BY_NAME["bandwidth"], 8.0, {}, {}, None, q_before=50.0, q_after=5.0, fraction=0.9,
              total_before=80.0, total_after=20.0)
    assert fit.acceptable
    assert not dataclasses.replace(fit, at_bound=True).acceptable
