"""Blind tests: effects injected into realistic uncalibrated recordings by numpy (gaitsim.loop.blind), not by the
simulator; the loop must name each library effect with its magnitude within 25 % of the equivalent figure, beyond
what it names on the untouched recording, and leave the effect outside the library unexplained.

The full table (every case on both sensors, the issue's acceptance of 5 of 6 library effects per sensor) is a
study: `gaitsim loop blind --out results/loop/blind` writes it, the committed copy says where it stands, and a test
here re-runs one case and checks it against the committed row. Each case is its own test (xdist spreads them).
"""

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from gaitsim.imu.presets import get_preset
from gaitsim.loop import blind, residuals, transfer
from gaitsim.loop.twin import TwinSimulator

_UNTOUCHED = {}
_VERDICTS = {}
LIBRARY_CASES = [c for c in blind.CASES if c.named != ("unexplained",)]
COMMITTED = Path(__file__).resolve().parents[1] / "results" / "loop" / "blind" / "blind.json"


def untouched(sensor: str):
    if sensor not in _UNTOUCHED:
        _UNTOUCHED[sensor] = blind.run(sensor, None)
    return _UNTOUCHED[sensor]


def verdict(sensor: str, case: blind.BlindCase) -> dict:
    """The row of the blind table: the case judged against the untouched run's named and estimated effects."""
    key = (sensor, case.name)
    if key not in _VERDICTS:
        result = blind.run(sensor, case)
        _VERDICTS[key] = blind.verdict(case, result, untouched(sensor),
                                       blind.untouched_estimates(case, result, untouched(sensor)))
    return _VERDICTS[key]


def on_sensor_worker(sensor: str):
    """The mark that runs every test of ``sensor``'s blind walk on one xdist worker (``--dist loadgroup``), so
    that the untouched run each of them is judged against (10-20 s) is computed once per session."""
    return pytest.mark.xdist_group(f"blind-{sensor}")


def by_sensor():
    """The blind sensors as test parameters, each on its sensor's worker."""
    return [pytest.param(s, marks=[on_sensor_worker(s)]) for s in blind.SENSORS]


def preset_errors(sensor: str) -> set:
    """The library effects that name an error the preset ``sensor`` really has: an accelerometer bias on every
    axis with a fixed bias or a turn-on spread, a scale on every axis whose diagonal term differs from 1,
    g-sensitivity where G_g is not zero (a yaw of the sensor on the foot is the twin's, not an effect)."""
    p = get_preset(sensor).parameters
    errors = set()
    for i, axis in enumerate("xyz"):
        if p["accel_bias"][i] or p["accel_bias_repeatability"][i]:
            errors.add(f"accel_bias_{axis}")
        for kind in ("accel", "gyro"):
            if p[f"{kind}_misalignment"][i, i] != 1.0:
                errors.add(f"{kind}_scale_{axis}")
    if np.any(p["gyro_g_sensitivity"]):
        errors.add("g_sensitivity")
    return errors


@pytest.mark.parametrize("sensor", by_sensor())
def test_untouched_recording_names_only_errors_its_sensor_has(sensor):
    """What the loop names on an untouched recording must be an error its preset really has (:func:`preset_errors`):
    no gait or timing effect, no scale error of a sensor without one. The BMI160 walk's turn-on offsets (-75,
    13.5, 12 mg) are explained by no single-axis effect (alone, a z scale error stands in for them, and the x
    offset, read as a 4.3 deg mount pitch at rest, then shows as a stance rotation): the joint fit of the linear
    effects (gaitsim.loop.attribution.fit_joint) names the x and z offsets together."""
    named = blind.named_effects(untouched(sensor))
    assert set(named) <= preset_errors(sensor), named


@pytest.mark.parametrize("sensor", by_sensor())
def test_effect_outside_the_library_is_reported_unexplained(sensor):
    row = verdict(sensor, blind.BY_NAME["gyro_bias_ramp"])
    assert "rest_gyro_change" in row["unexplained_beyond_untouched"], row
    assert row["found"], row


@pytest.mark.parametrize("sensor", by_sensor())
def test_a_gyro_delay_injected_by_numpy_is_named_as_a_skew_of_its_size(sensor):
    """A 4 ms gyro delay (numpy interpolation) is the library's accelerometer-gyro skew of -4 ms, named within
    25 % beyond the untouched recording on both uncalibrated sensors."""
    row = verdict(sensor, blind.BY_NAME["gyro_delay"])
    assert row["found_as"] == "named" and row["found_effect"] == "accel_gyro_skew", row
    assert row["found_magnitude"] == pytest.approx(-4.0, rel=0.25)


@pytest.mark.parametrize("sensor", by_sensor())
def test_a_first_order_low_pass_injected_by_numpy_is_named_by_its_form_and_cutoff(sensor):
    """A first-order low-pass at 25 Hz (numpy exponential smoothing of both sensors, blind.low_pass) whitens the
    rest noise no more (rest_*_noise_lag1, _lag2: gaitsim.loop.signature) and is named as the library's stage of
    the same form, a first-order front end without zeros (the digital forms read the noise's lag 2 far off), at its
    cutoff within 25 %: 24.6 Hz on paper-vn200, 29.5 on bmi160, whose twin's stride peak |a|, 13 % below the
    recording's even without the low-pass (its impacts fitted short), pulls the cutoff up."""
    row = verdict(sensor, blind.BY_NAME["low_pass"])
    assert (row["found_as"], row["found_effect"]) == ("named", "bandwidth_analogue"), row
    assert row["found_magnitude"] == pytest.approx(25.0, rel=0.25)


@on_sensor_worker("paper-vn200")
def test_an_extra_g_sensitivity_is_the_change_from_what_the_sensors_own_anisotropic_g_sensitivity_reads_as():
    """paper-vn200's own G_g (G_xx +0.0041, G_zz -0.0022 deg/s/(m/s^2)) turns the stride's roll closure as an
    isotropic k of about 0.02 would (the isotropic effect's x and z paths nearly cancel in roll), too little to
    be named on the untouched walk alone. With 0.02 more on every axis the loop names about twice that; the
    case is credited with the change of the loop's estimate, which must be the injected 0.02 within 25 %."""
    row = verdict("paper-vn200", blind.BY_NAME["g_sensitivity"])
    own = row["untouched_estimated"]["g_sensitivity"]
    largest = np.degrees(np.abs(get_preset("paper-vn200").parameters["gyro_g_sensitivity"])).max()
    assert own > 2 * largest, row  # the projection of the anisotropic matrix exceeds every element of it
    assert (row["found_as"], row["found_effect"]) == ("named", "g_sensitivity"), row
    assert row["found_magnitude"] == pytest.approx(0.02, rel=0.25)


@pytest.mark.parametrize("sensor", by_sensor())
def test_at_least_five_of_the_six_library_effects_are_named_within_25_percent(sensor):
    """The issue's acceptance on each uncalibrated sensor's walk: of the six library effects injected by numpy,
    at least five are named, beyond the untouched recording, within 25 % of the equivalent figure (paper-vn200
    misses its x accelerometer scale, 2.65 % for 2; bmi160 its 0.02 deg/s/(m/s^2) g-sensitivity, below the noise
    of its stride closure)."""
    rows = [verdict(sensor, case) for case in LIBRARY_CASES]
    assert sum(row["found"] for row in rows) >= 5, {r["case"]: (r["found_effect"], r["found_magnitude"]) for r in rows}


@on_sensor_worker("paper-vn200")
def test_one_case_of_the_committed_blind_table_is_what_the_code_gives():
    """The committed table is regenerated by `gaitsim loop blind`: its mount-rotation row on paper-vn200 (found
    by the twin's yaw, 6.00 for 6 deg) must still come out of the code, to round-off."""
    committed = {(r["sensor"], r["case"]): r for r in json.loads(COMMITTED.read_text())}
    row = verdict("paper-vn200", blind.BY_NAME["mount_yaw"])
    stored = committed[("paper-vn200", "mount_yaw")]
    assert row["found"] == stored["found"] and row["found_effect"] == stored["found_effect"]
    assert row["found_magnitude"] == pytest.approx(stored["found_magnitude"], rel=1e-6)
    assert row["found_magnitude"] == pytest.approx(6.0, rel=0.25)


@on_sensor_worker("paper-vn200")
def test_a_recordings_own_effects_moved_onto_its_default_twin_give_back_its_fitted_twin():
    """Law of the held-out transfer (gaitsim.loop.transfer): re-applying a recording's accepted magnitudes to
    its default twin in the context of that twin reproduces the loop's final misfit, so a held-out row differs
    from the source's own fit only through the target recording."""
    result = untouched("paper-vn200")
    simulate = TwinSimulator()
    effects = transfer.accepted_effects(result)
    assert effects, "the untouched recording names its accelerometer bias"
    again = transfer.score(result, transfer.with_effects(result, effects, simulate), simulate)
    assert again["q_signature"] == pytest.approx(residuals.signature_misfit(result.residuals_after), rel=1e-9)
    default = transfer.score(result, result.twin_before, simulate)
    assert default["q_signature"] == pytest.approx(residuals.signature_misfit(result.residuals_before), rel=1e-9)
    assert again["q_signature"] < default["q_signature"]


@on_sensor_worker("paper-vn200")
def test_a_transferred_twin_that_shows_no_strides_scores_an_infinite_misfit():
    """A held-out row never stops the command: an effect moved onto a twin where it smooths the strides away
    (a 1 Hz low-pass) gives an infinite misfit and the reason, not an exception."""
    result = untouched("paper-vn200")
    simulate = TwinSimulator()
    scored = transfer.transferred_score(result, [("bandwidth_first_order", 1.0), ("gyro_scale_y", 1.0)], simulate)
    assert scored["q_signature"] == float("inf") and "strides" in scored["failed"]


def _result(*attributions, yaw_deg=0.0):
    """A loop result as the verdict reads it: the attribution records and the yaw of the twin's mount fit."""
    sensor = {"mounting_misalignment": np.radians([0.0, 0.0, yaw_deg])}
    return SimpleNamespace(attributions=list(attributions),
                           twin_after=SimpleNamespace(scenario=SimpleNamespace(sensor=sensor)))


def test_an_injected_effect_that_only_fits_as_well_as_the_named_one_is_not_counted_as_named():
    """The verdict credits the injected effect when named within 25 %; when the loop named another form of it
    and the injected form only fit as well (``equivalent``), the row says so and ``found`` stays False."""
    low_pass, mount = blind.BY_NAME["low_pass"], blind.BY_NAME["mount_yaw"]
    untouched = _result()
    as_good = {"effect": "bandwidth_first_order", "magnitude": 36.0, "residual": "hf40",
               "equivalent": [{"effect": "bandwidth_analogue", "magnitude": 24.5}]}
    row = blind.verdict(low_pass, _result(as_good), untouched)
    assert (row["found"], row["found_as"]) == (False, "equivalent")
    far = {**as_good, "equivalent": [{"effect": "bandwidth_analogue", "magnitude": 33.0}]}
    assert blind.verdict(low_pass, _result(far), untouched)["found_as"] is None
    named = {**as_good, "effect": "bandwidth_analogue", "magnitude": 26.0, "equivalent": []}
    assert (blind.verdict(low_pass, _result(named), untouched)["found_as"]) == "named"
    other_family = {"effect": "gyro_scale_z", "magnitude": 3.0, "residual": "profile_gyr_x", "equivalent": []}
    assert blind.verdict(mount, _result(other_family), untouched)["found_as"] is None
    # a mount rotation is found by the change of the final twin's yaw (its mount fit), whatever else is named
    row = blind.verdict(mount, _result(yaw_deg=-15.5), _result(yaw_deg=-21.0))
    assert row["found"] and row["found_magnitude"] == pytest.approx(5.5)
    row = blind.verdict(mount, _result(other_family, yaw_deg=-15.5), _result(yaw_deg=-21.0))
    assert row["found"] and row["found_magnitude"] == pytest.approx(5.5)
    assert not blind.verdict(mount, _result(yaw_deg=-18.0), _result(yaw_deg=-21.0))["found"]  # 3 deg: 50 % off
    # the change from the untouched run's estimate of an effect it did not name counts, the estimate alone not
    g_sensitivity = blind.BY_NAME["g_sensitivity"]
    doubled = {"effect": "g_sensitivity", "magnitude": 0.044, "residual": "closure_roll", "equivalent": []}
    row = blind.verdict(g_sensitivity, _result(doubled), untouched, {"g_sensitivity": 0.0215})
    assert row["found"] and row["found_magnitude"] == pytest.approx(0.0225) and not row["found_subtracting_named"]
    assert not blind.verdict(g_sensitivity, _result(doubled), untouched)["found"]  # 0.044 for 0.02
    assert not blind.verdict(g_sensitivity, _result(doubled), untouched, {"g_sensitivity": 0.04})["found"]
    # a yaw the twin's fit moved does not count for another case
    assert blind.TWIN_YAW not in blind.verdict(low_pass, _result(yaw_deg=3.0), untouched)["named_beyond_untouched"]
