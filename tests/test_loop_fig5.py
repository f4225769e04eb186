"""The Fig. 5 residuals of the loop and the stance-kinematics effect that explains them (issue 11, point 4).

Recording and twin are swept by the same code (gaitsim.stance.sweep through gaitsim.loop.fig5): a walk compared
with itself has no Fig. 5 residual, two seeds of one walk differ at the noise level. The effect scales the four
stance rotation rates of the [micromotion] table and nothing else, and is never tried without a position track.
Blind-style cases: walks whose stance rates are halved or doubled by the test's own scenario lines.
"""

import numpy as np
import pytest

from gaitsim.loop import attribution as att
from gaitsim.loop import effects as fx
from gaitsim.loop import command, fig5, residuals, settings
from gaitsim.loop import twin as tw
from gaitsim.loop.navigation import NavReference
from gaitsim.loop.signature import signature
from gaitsim.measured.reference import as_measured
from gaitsim.scenario import scenario_from_dict
from gaitsim.simulate import simulate_walk

TRACK = NavReference("track")
DEFAULT_RATES = {"heel_rise_rate_start_dps": 3.0, "heel_rise_growth_dps3": 13.0, "loading_roll_rate_dps": 29.0,
                 "pronation_rate_dps": 4.5}  # the simulator's defaults (gaitsim.world.gait.MicroMotionParams)


def _doc(length_m: float, micromotion: dict | None = None) -> dict:
    return {"path": {"kind": "straight", "length_m": length_m}, "sampling": {"rate_hz": 200.0},
            "sensor": {"preset": "vn200"}, **({"micromotion": micromotion} if micromotion else {})}


def _recording(seed: int, length_m: float = 14.0, micromotion: dict | None = None):
    """A simulated walk as a measured recording would carry it (IMU samples and a 100 Hz position track)."""
    return as_measured(simulate_walk(scenario_from_dict(_doc(length_m, micromotion)), seed=seed), 100.0)


@pytest.fixture(scope="module")
def two_seeds():
    return [att.measure(_recording(seed), TRACK) for seed in (1, 2)]


def test_a_recording_has_the_fig5_residuals_and_none_against_itself(two_seeds):
    side, _ = two_seeds
    res = residuals.compare(side.signature, side.signature)
    assert set(fig5.NUMBERS) <= set(res)
    for name in fig5.NUMBERS:
        assert res[name].value == 0.0 and res[name].uncertainty > 0, name
        assert res[name].unit == fig5.NUMBERS[name][2]


def test_two_seeds_of_one_walk_differ_by_their_bootstrap_uncertainty_only(two_seeds):
    a, b = two_seeds
    res = residuals.compare(a.signature, b.signature)
    z = {name: res[name].z for name in fig5.NUMBERS}
    assert all(v <= settings.NOISE_LEVEL for v in z.values()), z


def test_the_fig5_numbers_follow_the_rolling_foot(two_seeds):
    """The default foot rolls in foot flat (site velocity = pitch rate x height): a few mm/s inside the windows,
    growing as the threshold widens them; a still foot has none."""
    side, _ = two_seeds
    level = side.signature.scalars["fig5_window_velocity_level_mps"].value
    assert 0.001 < level < 0.01
    still = {key: 0.0 for key in DEFAULT_RATES} | {"stance_rate_sd_frac": 0.0}
    sig = att.measure(_recording(1, micromotion=still), TRACK).signature.scalars
    assert abs(sig["fig5_window_velocity_level_mps"].value) < 2e-4


def test_without_a_track_there_are_no_fig5_residuals_and_the_report_says_why(two_seeds):
    side, _ = two_seeds
    rec = side.recording
    none = att.measure(rec, NavReference("none"))
    assert not set(fig5.NUMBERS) & set(none.signature.scalars)
    assert "no continuous position track" in fig5.summary({}, {}, "none")["absent_because"]


def _twin(micromotion: dict | None = None) -> tw.Twin:
    return tw.Twin(scenario_from_dict(_doc(14.0, micromotion), "<test twin>"))


def _flat(doc: dict) -> dict:
    return {(section, key): value for section, table in doc.items() if isinstance(table, dict)
            for key, value in table.items()}


def _differ(a, b) -> bool:
    """Whether two scenario values differ (numbers and number lists by relative 1e-9, anything else exactly)."""
    try:
        return not np.allclose(np.asarray(a, float), np.asarray(b, float), rtol=1e-9, atol=0.0)
    except (TypeError, ValueError):
        return a != b


@pytest.mark.parametrize("factor", [0.5, 2.0])
def test_stance_kinematics_scales_the_four_rates_and_nothing_else(two_seeds, factor):
    side, _ = two_seeds
    rates = {key: 1.5 * value for key, value in DEFAULT_RATES.items()}  # a twin whose rates are not the defaults
    twin = _twin({**rates, "creep_velocity_mps": [0.002, 0.0, 0.0]})
    ctx = fx.context(side.recording, twin.scenario, side.signature, side.signature)
    effect = fx.BY_NAME["stance_kinematics"]
    before = _flat(twin.document())
    after = _flat(twin.with_changes(effect.changes(factor, ctx)).document())
    assert set(after) == set(before)
    changed = {key for key in before if _differ(before[key], after[key])}
    assert changed == {("micromotion", key) for key in DEFAULT_RATES}
    for key, value in rates.items():
        assert after[("micromotion", key)] == pytest.approx(factor * value, rel=1e-9)
    same = _flat(twin.with_changes(effect.changes(1.0, ctx)).document())
    assert not any(_differ(before[key], same[key]) for key in before)


def test_stance_kinematics_is_not_tried_without_the_fig5_residuals(two_seeds):
    side, _ = two_seeds
    bare = signature(side.recording.t, side.recording.acc, side.recording.gyr)  # no track: no Fig. 5 numbers
    twin = _twin()
    effect = fx.BY_NAME["stance_kinematics"]
    assert not fx.applicable(effect, fx.context(side.recording, twin.scenario, bare, bare))
    assert fx.applicable(effect, fx.context(side.recording, twin.scenario, side.signature, side.signature))


def _scaled_rates_loop(factor: float, max_effects: int):
    """The loop on a 20 m walk whose four stance rates are ``factor`` times the simulator's defaults, written
    here as scenario numbers, not through the effect."""
    scaled = {key: factor * value for key, value in DEFAULT_RATES.items()}
    return att.run_loop(_recording(3, 20.0, scaled), max_effects=max_effects)


def test_halved_stance_rates_are_named_stance_kinematics_of_half_the_twins():
    """A stiffer foot (every stance rate halved): the loop names stance_kinematics with a factor within 30 % of
    0.5 (measured 0.468, the sensor at the push-off's height; 0.465 with the height at 0, after an accelerometer-gyro
    skew of -0.75 ms named first for the acc_gyro_lag the slower roll-over moves)."""
    named = {a["effect"]: a["magnitude"] for a in _scaled_rates_loop(0.5, 2).attributions}
    assert named.get("stance_kinematics") == pytest.approx(0.5, rel=0.3), named


def test_doubled_stance_rates_are_named_stance_kinematics_of_twice_the_twins():
    """Measured 1.971. Named since the twin's sensor sits at the push-off's height: with the height fitted on the
    accelerometer profiles (at 0, on the sole, where a rolling foot does not move it) the doubled rates left
    stance_rotation the smaller misfit (a strict xfail until then)."""
    named = {a["effect"]: a["magnitude"] for a in _scaled_rates_loop(2.0, 1).attributions}
    assert named.get("stance_kinematics") == pytest.approx(2.0, rel=0.3), named


def test_the_kinematics_cross_validation_pairs_stay_within_a_dataset_and_go_from_gaitmap_to_ucr():
    labels = dict.fromkeys(["gaitmap-healthy/left", "gaitmap-healthy/right", "ucr-fgo/left", "xio-ngimu/short_walk"])
    pairs = set(command.kinematics_pairs(labels))
    assert pairs == {("gaitmap-healthy/left", "gaitmap-healthy/right"), ("gaitmap-healthy/right", "gaitmap-healthy/left"),
                     ("gaitmap-healthy/left", "ucr-fgo/left"), ("gaitmap-healthy/right", "ucr-fgo/left")}
