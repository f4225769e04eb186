"""Laws of the unaided strapdown (nav.strapdown): static, bias error growth, interpolation and integration order."""

import numpy as np
import pytest

from nav import quaternion as Q
from nav.strapdown import integrate, mid_samples

G = 9.81
FS = 800.0


def static(n, acc=(0.0, 0.0, G), gyr=(0.0, 0.0, 0.0)):
    t = np.arange(n) / FS
    return t, np.tile(acc, (n, 1)).astype(float), np.tile(gyr, (n, 1)).astype(float)


@pytest.mark.parametrize("method", ["rk4", "increments"])
def test_static_level_imu_does_not_drift(method):
    t, acc, gyr = static(8001)
    if method == "increments":  # exact increments of a still, level sensor
        acc, gyr = acc / FS, gyr / FS
        acc[-1] = gyr[-1] = 0.0
    tr = integrate(t, acc, gyr, [1, 0, 0, 0], pos0=[1.0, 2.0, 3.0], method=method)
    assert np.max(np.abs(tr.pos - [1.0, 2.0, 3.0])) < 1e-9
    assert np.max(np.abs(tr.vel)) < 1e-12
    assert np.max(np.abs(tr.quat - [1, 0, 0, 0])) < 1e-15


def test_accelerometer_bias_gives_half_b_t_squared():
    b = np.array([0.01, -0.02, 0.03])
    t, acc, gyr = static(8001, acc=(b[0], b[1], G + b[2]))
    tr = integrate(t, acc, gyr, [1, 0, 0, 0])
    expected = 0.5 * b * t[-1] ** 2
    np.testing.assert_allclose(tr.pos[-1], expected, rtol=1e-9)
    np.testing.assert_allclose(tr.vel[-1], b * t[-1], rtol=1e-9)


def test_gyro_bias_on_level_static_imu_follows_the_cubic_law():
    # A roll-rate bias b tilts the level sensor by b t; gravity's projection g sin(b t) accelerates it sideways.
    # Exact: y(t) = -g (t/b - sin(b t)/b^2). The (1/6) g b t^3 law is its small-angle expansion, whose relative
    # error is (b t)^2 / 20 to leading order; the integrator must match the exact form to 1e-9.
    b, n = 1e-3, 8001
    t, acc, gyr = static(n, gyr=(b, 0.0, 0.0))
    tr = integrate(t, acc, gyr, [1, 0, 0, 0])
    T = t[-1]
    exact = -G * (T / b - np.sin(b * T) / b**2)
    assert tr.pos[-1, 1] == pytest.approx(exact, rel=1e-9)
    cubic = -G * b * T**3 / 6
    assert tr.pos[-1, 1] == pytest.approx(cubic, rel=1.5 * (b * T) ** 2 / 20)
    assert abs(tr.pos[-1, 1] - cubic) > 0.5 * (b * T) ** 2 / 20 * abs(cubic)  # the expansion's error is real


def test_mid_samples_are_exact_for_cubics_on_irregular_time():
    rng = np.random.default_rng(1)
    t = np.cumsum(rng.uniform(0.5, 1.5, 40)) * 1e-3
    x = np.stack([2 - 3 * t + 5 * t**2 - 7 * t**3, 1 + t**3], -1)
    mid = mid_samples(t, x)
    tm = 0.5 * (t[:-1] + t[1:])
    expected = np.stack([2 - 3 * tm + 5 * tm**2 - 7 * tm**3, 1 + tm**3], -1)
    np.testing.assert_allclose(mid[:-1], expected, rtol=0, atol=1e-13)


def tumbling_motion(fs, duration=2.0):
    """Analytic motion: a rotation about a fixed tilted axis at a varying rate, with a smooth translation."""
    t = np.arange(int(duration * fs) + 1) / fs
    axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    angle = 2.0 * t + 0.5 * np.sin(3.0 * t)  # rad
    rate = 2.0 + 1.5 * np.cos(3.0 * t)
    q = Q.from_rotvec(angle[:, None] * axis)
    w = 1.3
    pos = np.stack([np.sin(w * t), 0.5 * (1 - np.cos(w * t)), 0.1 * np.sin(2 * w * t)], -1)
    vel = np.stack([w * np.cos(w * t), 0.5 * w * np.sin(w * t), 0.2 * w * np.cos(2 * w * t)], -1)
    accel = np.stack([-w * w * np.sin(w * t), 0.5 * w * w * np.cos(w * t), -0.4 * w * w * np.sin(2 * w * t)], -1)
    gyr = rate[:, None] * axis  # body rate equals world rate for a fixed-axis rotation
    acc = Q.rotate(Q.conjugate(q), accel - [0.0, 0.0, -G])
    return t, q, pos, vel, acc, gyr


def test_rk4_is_fourth_order_on_an_analytic_tumbling_motion():
    errors = []
    for fs in (100.0, 200.0):
        t, q, pos, vel, acc, gyr = tumbling_motion(fs)
        tr = integrate(t, acc, gyr, q[0], vel[0], pos[0], method="rk4")
        errors.append(np.linalg.norm(tr.pos[-1] - pos[-1]))
    # halving the interval divides a 4th-order error by 16 (interpolated mid-samples are 4th order too)
    assert errors[1] < 2e-8
    assert 10 < errors[0] / errors[1] < 24


def test_exact_increments_reproduce_the_motion():
    t, q, pos, vel, acc, gyr = tumbling_motion(400.0)
    dt = np.diff(t)[:, None]
    dv = np.zeros_like(vel)
    dth = np.zeros_like(vel)
    dv[:-1] = Q.rotate(Q.conjugate(q[:-1]), vel[1:] - vel[:-1] - np.array([0.0, 0.0, -G]) * dt)
    dth[:-1] = Q.to_rotvec(Q.multiply(Q.conjugate(q[:-1]), q[1:]))
    tr = integrate(t, dv, dth, q[0], vel[0], pos[0], method="increments")
    assert np.max(np.abs(tr.vel - vel)) < 1e-12
    assert np.max(np.abs(Q.to_rotvec(Q.multiply(Q.conjugate(q), tr.quat)))) < 1e-12
    # position is the trapezoid of exact velocities: error h^2/12 * (a(T) - a(0)) to leading order
    h = t[1] - t[0]
    assert np.max(np.abs(tr.pos - pos)) < 2 * h**2 / 12 * 1.3**2


def test_unknown_method_is_rejected():
    t, acc, gyr = static(10)
    with pytest.raises(ValueError, match="euler"):
        integrate(t, acc, gyr, [1, 0, 0, 0], method="euler")
