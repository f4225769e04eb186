"""A scenario with a sensor model: imu.csv differs from the truth exactly by the declared model."""

from pathlib import Path

import numpy as np

from gaitsim.imu.model import apply_sensor
from gaitsim.scenario import load_scenario, scenario_from_dict
from gaitsim.simulate import run_generators, simulate_walk

ROOT = Path(__file__).resolve().parents[1]


def test_paper_preset_recording_is_truth_through_the_declared_model():
    scen = load_scenario(ROOT / "scenarios/straight_100m_paper.toml")
    rec = simulate_walk(scen, seed=7, run=2)
    assert rec.meta["sensor"]["name"] == "paper-vn200"
    # the same sensor stream reproduces imu.csv bit for bit
    _, sensor_rng = run_generators(7, 2)
    t, acc, gyr = apply_sensor(scen.sensor, rec.truth.t, rec.truth.acc, rec.truth.gyr, sensor_rng)
    np.testing.assert_array_equal(acc, rec.acc)
    np.testing.assert_array_equal(gyr, rec.gyr)
    # and the deterministic part is exactly the declared b, M, G_g: what is left is the declared noise
    cal = scen.sensor.deterministic()
    acc_c, gyr_c = cal.correct(rec.acc, rec.gyr)
    fs = scen.rate_hz
    vrw = scen.sensor["accel_noise_density"] * np.sqrt(fs)
    arw = scen.sensor["gyro_noise_density"] * np.sqrt(fs)
    np.testing.assert_allclose(np.std(acc_c - rec.truth.acc, axis=0) / vrw, 1, atol=0.05)
    np.testing.assert_allclose(np.std(gyr_c - rec.truth.gyr, axis=0) / arw, 1, atol=0.05)


def test_noise_free_paper_sensor_differs_from_truth_exactly_by_b_m_g():
    doc = {"path": {"kind": "straight", "length_m": 5.0}, "gait": {"stand_start_s": 0.6, "stand_end_s": 0.6},
           "sensor": {"preset": "paper-vn200", "accel_noise_density": [0.0, "mg/sqrt(Hz)"],
                      "gyro_noise_density": [0.0, "deg/s/sqrt(Hz)"], "accel_bias_instability": [0.0, "mg"],
                      "gyro_bias_instability": [0.0, "deg/h"], "accel_bias_repeatability": [0.0, "mg"],
                      "gyro_bias_repeatability": [0.0, "deg/h"]}}
    scen = scenario_from_dict(doc, "noise-free")
    rec = simulate_walk(scen)
    cal = scen.sensor.deterministic()
    f, w = rec.truth.acc, rec.truth.gyr
    np.testing.assert_allclose(rec.acc, f @ cal.M_a.T + cal.b_a, atol=1e-12)
    np.testing.assert_allclose(rec.gyr, w @ cal.M_g.T + f @ cal.G_g.T + cal.b_g, atol=1e-12)
