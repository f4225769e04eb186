"""The reproduction's sensitivity rows: at 70 steps/min where the [nav] SHOE's lost length comes from and that the
adaptive SHOE finds every stance once there; each detector's threshold in its own statistic's units."""

from pathlib import Path

import numpy as np
import pytest

from gaitsim.errors import ScenarioError
from gaitsim.experiments.setup import (calibration_walks, matched_thresholds, patched, scenario_doc,
                                       settings_from_scenario)
from gaitsim.scenario import load_scenario, scenario_from_dict
from gaitsim.simulate import simulate_walk
from nav import detectors
from nav.alignment import stationary_runs
from nav.calibration import load_calibration
from nav.metrics import stance_match
from nav.pipeline import prepare

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "scenarios" / "paper.toml"


@pytest.fixture(scope="module")
def walk70():
    """A 15 m version of the paper's walk at 70 steps/min with the ideal sensor, and the [nav] settings."""
    scenario = load_scenario(PAPER)
    nav, _ = settings_from_scenario(scenario)
    doc = patched(scenario_doc(scenario), gait={"cadence_steps_per_min": 70.0})
    doc["path"]["length_m"] = 15.0
    del doc["sensor"]
    return simulate_walk(scenario_from_dict(doc, "paper walk at 70 steps/min"), run=0), nav


def test_the_fixed_shoe_zeroes_the_moving_foot_at_the_late_swing_rate_zero_crossing(walk70):
    """Each detected run outside ground contact (initial contact .. toe off) lies at 70-90 % of the swing, where
    the pitch rate passes through zero at the toe-up peak while the foot still moves forward at > 0.5 m/s: a
    3-sample (3.75 ms) window sees |omega| and |f| - g under SHOE's gate there."""
    rec, nav = walk70
    ev = rec.events
    stationary = prepare(rec, nav.options()).stationary
    false_updates = 0
    for a, b in zip(*stationary_runs(stationary)):
        k = np.searchsorted(ev.t_ic, rec.t[a], side="right") - 1
        if k >= 0 and rec.t[a] < ev.t_to[k]:
            continue  # inside a ground contact
        swing = ev.t_ic[k + 1] - ev.t_to[k]
        phase = (rec.t[a] - ev.t_to[k]) / swing
        assert 0.7 < phase < 0.9, phase
        assert np.all(np.abs(np.degrees(rec.truth.gyr[a:b, 1])) < 15.0)
        assert np.all(np.linalg.norm(rec.truth.vel[a:b], axis=1) > 0.5)
        false_updates += 1
    assert false_updates >= 2


def test_the_adaptive_shoe_finds_every_stance_once_and_no_swing(walk70):
    rec, nav = walk70
    stationary = prepare(rec, nav.options(detector="adaptive")).stationary
    match = stance_match(stationary, rec.truth.stance)
    assert match["found"] == match["true_stances"] >= 8
    assert match["merged"] == match["spurious"] == match["split"] == 0


def test_each_detector_marks_the_shoe_share_at_its_own_threshold():
    """On (short) calibration walks, every statistic at its matched threshold marks the share of samples SHOE marks
    at the [nav] threshold, to one window; ARE, SHOE without its accelerometer term, gets a lower number."""
    scenario = load_scenario(PAPER)
    nav, exp = settings_from_scenario(scenario)
    doc = scenario_doc(scenario)
    doc["path"]["length_m"] = 10.0
    calibration = ROOT / "results" / "calibration.json"
    matched = matched_thresholds(doc, nav, exp, calibration, ("shoe", "are", "mv", "mag", "adaptive"))
    assert set(matched) == {"shoe", "are", "mv", "mag"}  # the adaptive SHOE's floor is a SHOE threshold
    assert matched["shoe"] == nav.threshold
    assert matched["are"] < nav.threshold
    options = nav.options()
    cal = load_calibration(calibration)
    walks = [cal.correct(rec.acc, rec.gyr, terms=exp.before_calibration_terms) for rec in calibration_walks(doc, exp)]
    samples = sum(len(acc) for acc, _ in walks)
    shares = {name: detectors.marked_share(
        [detectors.statistic(name, acc, gyr, options.sigma_a, options.sigma_g, options.window) for acc, gyr in walks],
        options.window, gamma) for name, gamma in matched.items()}
    for name, share in shares.items():
        assert share == pytest.approx(shares["shoe"], abs=options.window / samples), name


def test_an_unknown_sensitivity_detector_is_refused_by_name(tmp_path):
    text = PAPER.read_text().replace('sensitivity_detectors = ["shoe"', 'sensitivity_detectors = ["sheo"')
    bad = tmp_path / "paper.toml"
    bad.write_text(text)
    with pytest.raises(ScenarioError, match="sensitivity_detectors.*sheo"):
        settings_from_scenario(load_scenario(bad))
