"""Blind tests: synthetic recordings with undeclared effects; the loop must name them and close the gap.

Noise level: a residual is at the noise level when |value| <= 3 x its uncertainty (stride-to-stride standard
error of recording and twin combined; see gaitsim.loop.residuals). Navigation: the predicted-versus-measured
discrepancy of the final position error (m) must drop at least 3x, or to the navigation noise floor
(NAV_FLOOR, 0.05 m: the twin walks other strides than the recording, so its final error differs by that much
with no effect missing) when a third of the starting discrepancy lies below that floor; effects that do not
move navigation beyond the floor must leave it there.
"""

import pytest

from gaitsim.loop import attribution, blind, settings

_RESULTS = {}
NAV_FLOOR_M = settings.NAV_FLOOR["nav_final_error"]
SINGLE = [c for c in blind.CASES if len(c.truths) == 1 and c.truths[0][0] not in ("outside", "none")]


def result(name: str) -> attribution.LoopResult:
    if name not in _RESULTS:
        _RESULTS[name] = blind.run_case(blind.BY_NAME[name])
    return _RESULTS[name]


def _nav(res):
    return res.navigation_summary()["nav_final_error"]


@pytest.mark.parametrize("case", SINGLE, ids=[c.name for c in SINGLE])
def test_single_undeclared_effect_is_named_fitted_and_closed(case):
    res = result(case.name)
    effect, magnitude, _unit = case.truths[0]
    first = res.attributions[0]
    assert first["effect"] == effect, first
    assert first["magnitude"] == pytest.approx(magnitude, rel=0.25)
    assert abs(first["residual_after"]) <= settings.NOISE_LEVEL * first["uncertainty_after"], first
    nav = _nav(res)
    assert nav["discrepancy_after"] <= max(nav["discrepancy_before"] / 3, NAV_FLOOR_M), nav


def test_at_least_five_effects_are_covered():
    assert len({c.truths[0][0] for c in SINGLE}) >= 5


def test_effect_outside_the_library_is_reported_unexplained():
    res = result("outside_gyro_scale")
    assert res.attributions, "a 5 % gyro scale factor must leave a significant residual"
    assert res.attributions[0]["effect"] == "unexplained", res.attributions[0]


def test_no_effect_is_named_on_a_recording_without_undeclared_effects():
    res = result("no_effect")
    assert all(a["effect"] == "unexplained" for a in res.attributions), res.attributions


def test_two_effects_are_both_found_in_order_of_size():
    res = result("roll_and_scale")
    found = [a["effect"] for a in res.attributions[:2]]
    assert sorted(found) == ["accel_scale", "stance_roll"], res.attributions
    assert res.attributions[0]["z_before"] >= res.attributions[1]["z_before"]
    truths = dict((name, magnitude) for name, magnitude, _ in blind.BY_NAME["roll_and_scale"].truths)
    for a in res.attributions[:2]:
        assert a["magnitude"] == pytest.approx(truths[a["effect"]], rel=0.25)
    nav = _nav(res)
    assert nav["discrepancy_after"] * 3 <= nav["discrepancy_before"], nav
