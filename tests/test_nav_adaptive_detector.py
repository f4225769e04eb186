"""Adaptive-threshold SHOE (nav.adaptive_detector): the laws its threshold and marks obey."""

import math

import numpy as np
import pytest
from nav_synthetic import synthetic_walk

from nav import detectors as D
from nav.adaptive_detector import AdaptiveThreshold, detect_adaptive, gait_intensity
from nav.metrics import stance_match
from nav.pipeline import NavOptions, run

G = 9.81
FS = 800.0
SA, SG = 0.01, math.radians(0.07)
FLOOR = 3e4


def still(n, rng=None, acc_sd=0.0, gyr_sd=0.0):
    """n samples of a level sensor at rest, with optional white noise (m/s^2, rad/s)."""
    rng = rng or np.random.default_rng(0)
    acc = np.array([0.0, 0.0, G]) + rng.normal(0, 1, (n, 3)) * acc_sd
    gyr = rng.normal(0, 1, (n, 3)) * gyr_sd
    return np.arange(n) / FS, acc, gyr


def test_static_record_is_all_stationary_at_the_floor():
    # VN-200-like noise at 800 Hz: 0.039 m/s^2 and 0.1 deg/s per sample
    t, acc, gyr = still(8000, acc_sd=0.039, gyr_sd=math.radians(0.1))
    res = detect_adaptive(t, acc, gyr, FLOOR, SA, SG)
    assert res.stationary.all()
    np.testing.assert_array_equal(res.threshold, FLOOR)


@pytest.mark.parametrize("window_s", [0.00375, 0.05])
def test_without_adaptation_it_is_the_fixed_shoe(window_s):
    rng = np.random.default_rng(3)
    t, acc, gyr = still(3000, rng, acc_sd=0.5, gyr_sd=0.3)
    acc[1000:1400] = [0.0, 0.0, G]
    gyr[1000:1400] = 0.0
    adaptive = AdaptiveThreshold(ratio=0.0, window_s=window_s)
    res = detect_adaptive(t, acc, gyr, FLOOR, SA, SG, adaptive)
    fixed = D.detect("shoe", t, acc, gyr, FLOOR, SA, SG, adaptive.window_samples(FS))
    np.testing.assert_array_equal(res.stationary, fixed.stationary)
    np.testing.assert_array_equal(res.statistic, fixed.statistic)
    assert res.stationary[1000:1400].all() and res.stationary.sum() < 500


def test_window_is_a_duration():
    w = AdaptiveThreshold(window_s=0.05)
    assert [w.window_samples(fs) for fs in (60.0, 204.8, 400.0, 800.0)] == [3, 10, 20, 40]
    assert AdaptiveThreshold(window_s=0.001).window_samples(60.0) == 2  # at least two samples


def test_threshold_follows_the_peak_rate_within_the_span():
    # still, then one burst of 400 deg/s about y lasting 0.1 s at 5 s, still again
    t, acc, gyr = still(int(10 * FS))
    burst = slice(int(5 * FS), int(5.1 * FS))
    gyr[burst, 1] = math.radians(400.0)
    adaptive = AdaptiveThreshold(ratio=1e-3, span_s=2.0, window_s=0.05)
    res = detect_adaptive(t, acc, gyr, FLOOR, SA, SG, adaptive)
    expected = adaptive.ratio * (math.radians(400.0) / SG) ** 2  # a full window inside the burst
    start = np.arange(len(res.threshold)) / FS  # window start times, s
    w = adaptive.window_samples(FS) / FS
    near = (start > 5.1 - 1.0) & (start + w < 5.0 + 1.0)  # the burst's full window lies within span/2
    far = (start + w < 5.0 - 1.0 - w) | (start > 5.1 + 1.0 + w)
    assert expected > FLOOR
    np.testing.assert_allclose(res.threshold[near], expected, rtol=1e-12)
    np.testing.assert_array_equal(res.threshold[far], FLOOR)


def test_a_scaled_gait_scales_the_threshold_and_keeps_the_decisions():
    rec = synthetic_walk(strides=4)
    adaptive = AdaptiveThreshold(ratio=1e-3, window_s=0.05)
    base = detect_adaptive(rec.t, rec.acc, rec.gyr, 1.0, SA, SG, adaptive)
    moving = base.threshold > 4.0  # where ratio * M is above the floor for every scale below
    assert moving.mean() > 0.5
    for c in (0.5, 3.0):
        scaled = detect_adaptive(rec.t, rec.acc, c * rec.gyr, 1.0, SA, SG, adaptive)
        np.testing.assert_allclose(scaled.threshold[moving], c**2 * base.threshold[moving], rtol=1e-12)
    # with the accelerometer term removed (sigma_a huge) the statistic is the gyro energy: T and gamma both
    # scale by c^2, so every decision stays
    quiet_acc = dict(sigma_a=1e9, sigma_g=SG)
    one = detect_adaptive(rec.t, rec.acc, rec.gyr, 1e-6, adaptive=adaptive, **quiet_acc)
    three = detect_adaptive(rec.t, rec.acc, 3.0 * rec.gyr, 1e-6, adaptive=adaptive, **quiet_acc)
    np.testing.assert_array_equal(one.stationary, three.stationary)
    assert 0.1 < one.stationary.mean() < 0.9


def test_windows_are_marked_like_shoe():
    # a single quiet window of exactly W samples inside constant rotation: its W samples and no others
    adaptive = AdaptiveThreshold(ratio=0.0, window_s=0.005)  # W = 4 at 800 Hz
    w = adaptive.window_samples(FS)
    t, acc, gyr = still(200)
    gyr[:] = math.radians(50.0)
    gyr[100:100 + w] = 0.0
    res = detect_adaptive(t, acc, gyr, FLOOR, SA, SG, adaptive)
    assert np.flatnonzero(res.stationary).tolist() == list(range(100, 100 + w))


def test_a_rate_zero_crossing_shorter_than_the_window_is_not_a_stance():
    # the foot's pitch rate sweeps -400 -> +400 deg/s at 1600 deg/s^2 through zero while the specific force
    # stays at g (the late-swing instant behind the 70 steps/min failure); 0.2 s of true rest follows
    sweep = np.linspace(-400.0, 400.0, int(0.5 * FS))
    t, acc, gyr = still(len(sweep) + int(0.2 * FS) + int(0.1 * FS))
    gyr[:len(sweep), 1] = np.radians(sweep)
    gyr[len(sweep) + int(0.2 * FS):, 1] = math.radians(400.0)
    res = detect_adaptive(t, acc, gyr, FLOOR, SA, SG, AdaptiveThreshold(ratio=1e-3, window_s=0.05))
    crossing = slice(len(sweep) // 2 - 40, len(sweep) // 2 + 40)
    rest = slice(len(sweep) + 40, len(sweep) + int(0.2 * FS) - 40)
    assert not res.stationary[crossing].any()
    assert res.stationary[rest].all()
    # a 3-sample window (3.75 ms at 800 Hz) calls the crossing still
    assert D.detect("shoe", t, acc, gyr, FLOOR, SA, SG, 3).stationary[crossing].any()


@pytest.mark.parametrize("field, value", [("ratio", -1e-3), ("span_s", 0.0), ("window_s", -0.05),
                                          ("ratio", math.nan)])
def test_bad_parameters_are_refused_by_name(field, value):
    with pytest.raises(ValueError, match=field):
        AdaptiveThreshold(**{field: value})


def test_gait_intensity_is_the_sliding_peak_of_the_gyro_energy():
    rng = np.random.default_rng(1)
    gyr = rng.normal(0, 0.5, (500, 3))
    energy = D.statistic("are", np.zeros_like(gyr), gyr, 1.0, SG, 4)
    got = gait_intensity(gyr, SG, 4, 31)
    expected = [energy[max(0, k - 15):k + 16].max() for k in range(len(energy))]
    np.testing.assert_allclose(got, expected, rtol=1e-12)


def test_pipeline_runs_the_adaptive_detector_and_reports_it():
    rec = synthetic_walk(strides=6)
    sol, score = run(rec, NavOptions(detector="adaptive"))
    match = stance_match(sol.stationary, rec.truth.stance)
    assert match["found"] == match["true_stances"] and match["merged"] == 0 and match["spurious"] == 0
    assert score["final_error_m"] < 0.01 * 6 * 1.4
    assert score["detector"] == "adaptive"
    assert score["window_samples"] == 40
    assert score["info"]["detector"]["adaptation"] == {"ratio": 1e-3, "span_s": 2.5, "window_s": 0.05}
