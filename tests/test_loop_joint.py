"""The joint fit of the sensor's linear errors (gaitsim.loop.attribution.fit_joint, step 5b): the linearised set
selection on numpy-built slopes, and on a consumer sensor whose accelerometer offsets (x and z at once) no single
library effect explains."""

import numpy as np
import pytest

from gaitsim.loop import settings
from gaitsim.loop.attribution import linear_sets

BOUNDS = [(-6.0, 6.0)] * 5


def slopes(seed: int = 3, n: int = 40) -> dict:
    """Five effects' residual slopes (dz per unit magnitude), random and independent."""
    rng = np.random.default_rng(seed)
    return {i: rng.normal(0.0, 3.0, n) for i in range(5)}


def test_two_effects_at_once_are_found_with_their_magnitudes_and_no_third_member():
    """Residuals made by effects 1 and 3 together (plus noise well below the noise level) give back that pair
    with its magnitudes; a third member cannot lower the misfit by one residual at the noise level."""
    columns = slopes()
    noise = np.random.default_rng(8).normal(0.0, 0.2, 40)
    z0 = -(2.0 * columns[1] - 0.5 * columns[3]) + noise
    sets = linear_sets(columns, z0, BOUNDS, 3, {1})
    misfit, combo, magnitudes = sets[0]
    assert combo == (1, 3)
    np.testing.assert_allclose(magnitudes, [2.0, -0.5], atol=0.05)
    assert misfit == pytest.approx(noise @ noise, rel=0.2)
    assert len(sets) <= settings.JOINT_SUBSETS and all(len(c) == 2 for _, c, _ in sets)


def test_one_effect_alone_is_left_to_the_single_fits():
    columns = slopes()
    z0 = -1.5 * columns[2] + np.random.default_rng(8).normal(0.0, 0.2, 40)
    assert linear_sets(columns, z0, BOUNDS, 3, {2}) == []


def test_a_set_whose_magnitude_leaves_its_search_range_is_not_a_candidate():
    """Effect 1 at 2.0 needs a range reaching 2.0: with (-1, 1) the pair (1, 3) cannot be the answer."""
    columns = slopes()
    z0 = -(2.0 * columns[1] - 0.5 * columns[3])
    bounds = list(BOUNDS)
    bounds[1] = (-1.0, 1.0)
    assert all(1 not in combo for _, combo, _ in linear_sets(columns, z0, bounds, 3, {3}))


@pytest.mark.xdist_group("blind-paper-vn200")
def test_two_accelerometer_offsets_put_in_by_numpy_are_named_together():
    """The paper-vn200 blind walk with accelerometer offsets of -0.5 m/s^2 along x and +0.15 along z added by
    numpy: a mount pitch at rest takes the x offset and a z scale or offset the norm, so only the joint fit names
    them; with the sensor's own offsets (the seed paper's b_a) each within 25 %, and no scale error."""
    import dataclasses

    from gaitsim.imu.presets import PAPER_ACCEL_BIAS
    from gaitsim.loop import attribution, blind

    base = blind.base_recording("paper-vn200")
    added = np.array([-0.5, 0.0, 0.15])
    result = attribution.run_loop(dataclasses.replace(base, acc=base.acc + added), max_effects=settings.BLIND_EFFECTS)
    named = blind.named_effects(result)
    expected = added + np.array(PAPER_ACCEL_BIAS)
    assert named["accel_bias_x"] == pytest.approx(expected[0], rel=0.25), named
    assert named["accel_bias_z"] == pytest.approx(expected[2], rel=0.25), named
    assert not any("scale" in name for name in named), named
