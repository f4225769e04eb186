"""Allan deviation of simulated static data recovers each configured stochastic term (each term alone).

Lengths and taus are chosen so that the 10 % bounds sit at 3 or more standard errors of the estimate
(checked over seeds while writing the test); the seeds here are fixed.
"""

import numpy as np
import pytest

from gaitsim.imu import allan
from gaitsim.imu.model import SensorSpec, apply_sensor
from gaitsim.imu.presets import get_preset

RATE = 100.0


def static_run(parameters: dict, n: int, seed: int = 3):
    t = np.arange(n) / RATE
    still = np.zeros((n, 3))
    _, acc, gyr = apply_sensor(SensorSpec(parameters=parameters), t, still, still, np.random.default_rng(seed))
    return acc, gyr


def test_white_noise_density_recovered_per_axis():
    vn200 = get_preset("vn200")
    n_acc, n_gyr = vn200["accel_noise_density"], vn200["gyro_noise_density"]
    acc, gyr = static_run({"accel_noise_density": n_acc, "gyro_noise_density": n_gyr}, 20_000)
    for data, configured in ((acc, n_acc), (gyr, n_gyr)):
        taus, adev = allan.allan_deviation(data, RATE)
        recovered = allan.white_noise_density(taus, adev, (0.02, 1.0))
        np.testing.assert_allclose(recovered, configured, rtol=0.10)


def test_rate_random_walk_recovered_without_bias_instability():
    k_acc = 1e-4  # m/s^2/sqrt(s)
    k_gyr = np.deg2rad(0.1) / 60.0  # 0.1 deg/s/sqrt(h) in rad/s/sqrt(s)
    acc, gyr = static_run({"accel_random_walk": k_acc, "gyro_random_walk": k_gyr}, 100_000)
    for data, configured in ((acc, k_acc), (gyr, k_gyr)):
        taus, adev = allan.allan_deviation(data, RATE)
        recovered = allan.rate_random_walk(taus, adev, (1.0, 20.0))
        assert np.mean(recovered) == pytest.approx(configured, rel=0.10)
        np.testing.assert_allclose(recovered, configured, rtol=0.25)


def test_bias_instability_recovered_as_allan_floor_over_0_664():
    b_acc, b_gyr = 4e-4, np.deg2rad(10.0 / 3600.0)
    acc, gyr = static_run({"accel_bias_instability": b_acc, "gyro_bias_instability": b_gyr,
                           "accel_bias_instability_tau": 1.0, "gyro_bias_instability_tau": 1.0}, 200_000)
    for data, configured in ((acc, b_acc), (gyr, b_gyr)):
        taus, adev = allan.allan_deviation(data, RATE, clusters=allan.log_spaced_clusters(data.shape[0], 80))
        np.testing.assert_allclose(allan.bias_instability(adev), configured, rtol=0.10)
        # the hump sits where a first-order Gauss-Markov process puts it: 1.89 tau_c
        assert np.median(taus[np.argmax(adev, axis=0)]) == pytest.approx(1.89, rel=0.15)


def test_gauss_markov_peak_constants():
    """The peak of the Gauss-Markov Allan curve, found by maximising it, is the constant the simulator uses."""
    tau_ratio, sigma_ratio = allan.gauss_markov_peak()
    assert tau_ratio == pytest.approx(1.8927, abs=1e-3)
    assert sigma_ratio == pytest.approx(0.61736, abs=1e-4)
    assert (tau_ratio, sigma_ratio) == pytest.approx(allan.GAUSS_MARKOV_PEAK, rel=1e-9)


def test_overlapping_allan_matches_white_noise_law_at_every_tau():
    rng = np.random.default_rng(0)
    x = rng.standard_normal(200_000)  # density 1/sqrt(RATE) per sqrt(Hz)
    taus, adev = allan.allan_deviation(x, RATE, clusters=[1, 10, 100])
    np.testing.assert_allclose(adev, 1.0 / np.sqrt(RATE * taus), rtol=0.03)
