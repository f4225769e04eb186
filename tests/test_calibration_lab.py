"""The simulated calibration lab: recovery of the paper's errors, honest uncertainties, the Fig. 8 shaker law."""

import numpy as np
import pytest
from scipy.signal import butter, sosfreqz

from gaitsim.imu.calibration_lab import run_lab, shaker_g_sensitivity, table_orientations
from gaitsim.imu.presets import get_preset
from nav.calibration import load_calibration, z_scores

FREQS = np.array([10.0, 40.0, 80.0, 120.0, 160.0])


def quiet(spec):
    """The same sensor without any random term (for exact laws)."""
    return spec.replace(gyro_noise_density=0.0, accel_noise_density=0.0, gyro_bias_instability=0.0,
                        accel_bias_instability=0.0)


def test_table_orientations_are_the_24_axis_rotations():
    rotations = table_orientations()
    assert rotations.shape == (24, 3, 3)
    np.testing.assert_allclose(np.linalg.det(rotations), 1.0)
    assert len({r.tobytes() for r in rotations}) == 24


def test_lab_recovers_the_paper_errors_with_vn200_noise(tmp_path):
    spec = get_preset("paper-vn200")
    truth = spec.deterministic()
    cal = run_lab(spec, np.random.default_rng(7), out_path=tmp_path / "cal.json")
    assert np.max(np.abs(cal.G_g - truth.G_g)) < 0.05 * np.max(np.abs(truth.G_g))
    assert np.max(np.abs(cal.M_a - truth.M_a)) < 1e-4
    assert np.max(np.abs(cal.M_g - truth.M_g)) < 1e-4
    assert np.max(np.abs(cal.b_g - truth.b_g)) < np.deg2rad(0.005)  # deg/s: the bias drifts ~10 deg/h
    assert np.max(np.abs(cal.b_a - truth.b_a)) < 1e-3
    np.testing.assert_array_equal(load_calibration(tmp_path / "cal.json").G_g, cal.G_g)


def test_lab_is_exact_without_noise():
    spec = quiet(get_preset("paper-vn200"))
    truth = spec.deterministic()
    cal = run_lab(spec, np.random.default_rng(0), cycles=1, dwell_s=1.0, settle_s=0.1)
    for name in ("b_a", "M_a", "b_g", "M_g", "G_g"):
        np.testing.assert_allclose(getattr(cal, name), getattr(truth, name), rtol=0, atol=1e-11)


def test_uncertainties_cover_the_errors_across_seeds():
    spec = get_preset("paper-vn200")
    truth = spec.deterministic()
    z = {name: [] for name in ("b_a", "M_a", "b_g", "M_g", "G_g")}
    for seed in range(20):
        cal = run_lab(spec, np.random.default_rng(100 + seed), rate_hz=200.0)
        for name, values in z_scores(cal, truth).items():
            z[name].append(values.ravel())
    everything = np.concatenate([np.concatenate(v) for v in z.values()])
    assert np.mean(np.abs(everything) > 3.0) < 0.01  # 20 seeds x 33 elements
    assert 0.6 < np.std(everything) < 1.3
    for name, values in z.items():
        assert 0.4 < np.std(np.concatenate(values)) < 1.6, name


def test_shaker_flat_without_bandwidth():
    spec = get_preset("paper-vn200")
    G = spec["gyro_g_sensitivity"]
    exact = shaker_g_sensitivity(quiet(spec), np.random.default_rng(0), FREQS, dwell_s=2.0)
    for estimate in (exact.G, exact.G_amplitude):
        np.testing.assert_allclose(estimate, np.broadcast_to(G, estimate.shape), rtol=0, atol=1e-12)
    noisy = shaker_g_sensitivity(spec, np.random.default_rng(1), FREQS)
    z = (noisy.G[:, 2, 2] - G[2, 2]) / noisy.sigma[:, 2, 2]
    assert np.all(np.abs(z) < 3.5)
    assert np.max(np.abs(noisy.G[:, 2, 2] / G[2, 2] - 1)) < 0.1


def test_shaker_with_bandwidth_follows_the_filter_response():
    cutoff = 200.0
    spec = quiet(get_preset("paper-vn200")).replace(gyro_bandwidth=cutoff, accel_bandwidth=cutoff)
    G = spec["gyro_g_sensitivity"]
    _, response = sosfreqz(butter(2, cutoff, fs=800.0, output="sos"), worN=FREQS, fs=800.0)
    table = shaker_g_sensitivity(spec, np.random.default_rng(0), FREQS, dwell_s=2.0, reference="table")
    np.testing.assert_allclose(table.G[:, 2, 2] / G[2, 2], response.real, atol=1e-6)
    np.testing.assert_allclose(table.G_amplitude[:, 2, 2] / G[2, 2], np.abs(response), atol=1e-6)
    own = shaker_g_sensitivity(spec, np.random.default_rng(0), FREQS, dwell_s=2.0, reference="imu")
    M_a = spec["accel_misalignment"]
    np.testing.assert_allclose(own.G_amplitude[:, 2, 2], G[2, 2] / M_a[2, 2], rtol=1e-5)
    assert np.abs(response[-1]) == pytest.approx(0.884, abs=1e-3)  # bent by 12 % at 160 Hz
