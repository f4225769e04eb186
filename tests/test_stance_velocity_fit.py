"""The stance pseudo-velocity fitted from tracked calibration walks (compensation step 2 of the paper)."""

import dataclasses

import pytest

from gaitsim.bundled import scenario_file
from gaitsim.experiments.paper import quick_overrides
from gaitsim.experiments.setup import calibrate_sensor, fit_stance_velocity, scenario_doc, settings_from_scenario
from gaitsim.scenario import load_scenario, scenario_from_dict
from gaitsim.simulate import simulate_walk
from nav.pipeline import run
from nav.zupt_velocity import load_stance_velocity


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    out = tmp_path_factory.mktemp("stance_fit")
    scenario = load_scenario(scenario_file("paper.toml"))
    nav, exp = settings_from_scenario(scenario)
    doc, exp, _ = quick_overrides(scenario_doc(scenario), exp)  # one 14 m calibration walk
    cal = calibrate_sensor(scenario, exp, out)
    path, info = fit_stance_velocity(doc, nav, exp, cal, out)
    options = nav.options(calibration=cal, calibration_terms=exp.before_calibration_terms)
    return scenario, doc, options, path, info


def test_fitted_stances_are_steps_not_the_rests_around_the_walk(fitted):
    scenario, doc, _, path, info = fitted
    model = load_stance_velocity(path)
    stride_s = 2 * 60.0 / doc.get("gait", {}).get("cadence_steps_per_min", 84.0)
    rate = scenario_from_dict(doc, "rate").rate_hz
    # a rest of the scored walk (longer than a stride) gets no pseudo-velocity
    assert model.max_samples < stride_s * rate
    assert info["stances"] >= 5 and info["stances_shorter_than_the_tracker_difference"] >= 1


def test_fitted_profile_removes_most_of_the_length_loss_of_an_independent_walk(fitted):
    scenario, doc, options, path, _ = fitted
    rec = simulate_walk(scenario_from_dict(doc, "scored"), seed=scenario.seed, run=0)  # not a calibration seed
    _, before = run(rec, options)
    _, after = run(rec, dataclasses.replace(options, stance_velocity=str(path)))
    assert before["along_track_error_m"] > 0.02
    # the tracker's noise (1 mm, 60 Hz, one calibration walk) leaves ~1 cm either way on 14 m
    assert abs(after["along_track_error_m"]) < 0.5 * before["along_track_error_m"]
