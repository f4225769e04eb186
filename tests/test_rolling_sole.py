"""The rolling sole's geometry: heel on the ground below the transfer range, toe on the ground above it, the
contact moving monotonically from heel to toe in between, rolling without slip, C4 joins."""

import numpy as np
import pytest

from gaitsim.world import smooth
from gaitsim.world.profile import RollingSole

L = 0.2


@pytest.fixture(params=[0.5, 9.4])
def sole(request):
    return RollingSole(L, np.deg2rad(request.param), 0.0)


def test_heel_then_toe_on_the_ground(sole):
    b = sole.half
    heel_side = np.linspace(-0.5, -b, 50)
    toe_side = np.linspace(b, 1.0, 50)
    np.testing.assert_allclose(sole.heel_height(heel_side), 0.0, atol=1e-15)
    np.testing.assert_allclose(sole.contact_offset(heel_side), 0.0, atol=1e-15)
    # the toe (L ahead of the heel on the foot's x axis) is exactly on the ground: heel height L sin(pitch)
    np.testing.assert_allclose(sole.heel_height(toe_side), L * np.sin(toe_side), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(sole.contact_offset(toe_side), L * np.cos(toe_side), rtol=1e-12)


def test_contact_moves_monotonically_from_heel_to_toe(sole):
    """Projected on the foot's heel-toe line (x axis (cos p, -sin p) in the sagittal plane), the contact point
    (s' forward, s down from the heel point) runs from the heel (0) to the toe (L)."""
    pitch = np.linspace(-sole.half, sole.half, 2001)
    along = sole.contact_offset(pitch) * np.cos(pitch) + sole.heel_height(pitch) * np.sin(pitch)
    assert np.all(np.diff(along) >= -1e-12 * L)
    assert along[0] == pytest.approx(0.0, abs=1e-12) and along[-1] == pytest.approx(L, rel=1e-9)


def test_rolling_without_slip_moves_the_heel_by_its_height():
    """dX/dpitch = s + contact radius: the heel's forward travel rate is its height above the rolling centre."""
    radius = 0.01
    sole = RollingSole(L, np.deg2rad(4.0), radius)
    pitch = np.linspace(-0.2, 0.6, 801)
    stack = np.zeros((smooth.NDER, pitch.size))
    stack[0], stack[1] = pitch, 1.0  # unit pitch rate: time derivatives are pitch derivatives
    travel, height = sole.heel(stack)
    np.testing.assert_allclose(travel[1], height[0] + radius, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(height[1], sole.contact_offset(pitch), rtol=1e-12, atol=1e-15)
    assert travel[0][np.argmin(np.abs(pitch))] == pytest.approx(0.0, abs=1e-15)  # zero at the level foot


def test_joins_are_c4(sole):
    for join in (-sole.half, sole.half):
        below = sole._stacks(np.array([join - 1e-12]))
        above = sole._stacks(np.array([join + 1e-12]))
        for lo, hi in zip(below, above):
            scale = np.abs(sole._stacks(np.linspace(-1, 1, 2001))[1]).max(axis=1) + 1e-12
            assert np.all(np.abs(lo[:, 0] - hi[:, 0]) < 1e-6 * scale)
