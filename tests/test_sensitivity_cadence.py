"""The paper walk at 70 steps/min (the reproduction's cadence-70 sensitivity rows): where the [nav] SHOE's lost
length comes from, and that the adaptive SHOE finds every stance once there."""

from pathlib import Path

import numpy as np
import pytest

from gaitsim.experiments.setup import patched, scenario_doc, settings_from_scenario
from gaitsim.scenario import load_scenario, scenario_from_dict
from gaitsim.simulate import simulate_walk
from nav.alignment import stationary_runs
from nav.metrics import stance_match
from nav.pipeline import prepare

PAPER = Path(__file__).resolve().parents[1] / "scenarios" / "paper.toml"


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
