"""The compiled quaternion helpers (nav._numba.quat) equal nav.quaternion to round-off."""

import numpy as np
import pytest

from nav import quaternion as Q
from nav._numba import quat as NQ

ROUND_OFF = 1e-14  # values are O(1): a few ulps of float64


@pytest.fixture(scope="module")
def rng():
    return np.random.default_rng(11)


def test_product_equals_multiply(rng):
    for a, b in zip(rng.normal(size=(50, 4)), rng.normal(size=(50, 4))):
        np.testing.assert_allclose(NQ.qmul(*a, *b), Q.multiply(a, b), rtol=0, atol=ROUND_OFF)


def test_rotation_equals_rotate_and_ignores_the_norm(rng):
    for q, v in zip(rng.normal(size=(50, 4)), rng.normal(size=(50, 3))):
        unit = q / np.linalg.norm(q)
        expected = Q.rotate(unit, v)
        np.testing.assert_allclose(NQ.qrot(*unit, *v), expected, rtol=0, atol=ROUND_OFF)
        np.testing.assert_allclose(NQ.qrot(*(3.0 * q), *v), expected, rtol=0, atol=ROUND_OFF)


@pytest.mark.parametrize("scale", [1e-9, 1e-7, 1e-3, 1.0, 3.0])
def test_exponential_equals_from_rotvec_on_both_sides_of_the_series_switch(rng, scale):
    for phi in scale * rng.normal(size=(20, 3)):
        np.testing.assert_allclose(NQ.qexp(*phi), Q.from_rotvec(phi), rtol=0, atol=ROUND_OFF)


def test_matrix_equals_to_matrix(rng):
    C = np.empty((3, 3))
    for q in rng.normal(size=(50, 4)):
        unit = q / np.linalg.norm(q)
        NQ.qmatrix(unit, C)
        np.testing.assert_allclose(C, Q.to_matrix(unit), rtol=0, atol=ROUND_OFF)


def test_normalised_has_unit_norm_and_the_same_direction(rng):
    for q in rng.normal(size=(50, 4)):
        n = np.array(NQ.qnormalised(*q))
        assert abs(np.linalg.norm(n) - 1.0) < ROUND_OFF
        np.testing.assert_allclose(n * np.linalg.norm(q), q, rtol=1e-14)
