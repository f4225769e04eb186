"""The anchored SHOE (nav.calm_anchor): the fixed test where it finds stances, one calm stretch per stride where it
does not, nothing in motion that is never calm. Signals are built here with numpy alone."""

import math

import numpy as np
import pytest
from nav_synthetic import synthetic_walk

from nav import detectors as D
from nav.calm_anchor import CalmAnchor, anchored_windows, detect_anchored

G = 9.81
SA, SG = 0.01, math.radians(0.1)
GAMMA0 = 3e4


def running(fs, calmest_dps, strides=12, cadence=165.0, duty=0.37, seed=0):
    """A foot IMU that never comes to rest: per stride (period 120/cadence s) a stance of ``duty`` of it whose rate
    about the sensor's y axis dips to ``calmest_dps[i]`` deg/s at 40 % of the stance and rises to 400 deg/s at its
    edges, then a swing lobe up to 1000 deg/s with +-20 m/s^2 on x; white noise of a consumer sensor.

    Returns t (s), acc (m/s^2), gyr (rad/s), the stance mask and the calmest instant of each stride (s)."""
    rng = np.random.default_rng(seed)
    period = 120.0 / cadence
    t = np.arange(int(strides * period * fs)) / fs
    stride, phase = np.divmod(t / period, 1.0)
    stride = stride.astype(int)
    in_stance = phase < duty
    tau = phase / duty  # 0..1 through the stance
    low = np.radians(np.asarray(calmest_dps, float))[stride]
    edge, peak = math.radians(400.0), math.radians(1000.0)
    shape = np.where(tau < 0.4, ((tau - 0.4) / 0.4) ** 2, ((tau - 0.4) / 0.6) ** 2)
    swing = np.sin(np.pi * (phase - duty) / (1 - duty))
    rate = np.where(in_stance, low + (edge - low) * shape, edge + (peak - edge) * swing)
    gyr = np.zeros((len(t), 3))
    gyr[:, 1] = rate
    acc = np.zeros((len(t), 3))
    acc[:, 2] = G
    acc[:, 0] = np.where(in_stance, 0.3 * np.sin(2 * np.pi * tau), 20.0 * np.sin(2 * np.pi * swing))
    acc += rng.normal(0.0, 0.05, acc.shape)
    gyr += rng.normal(0.0, math.radians(0.2), gyr.shape)
    calm_at = (np.arange(strides) + 0.4 * duty) * period
    return t, acc, gyr, in_stance, calm_at


def stretches(mask):
    edges = np.diff(np.concatenate(([0], mask.astype(np.int8), [0])))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


@pytest.mark.parametrize("fs", [200.0, 800.0])
def test_each_running_stride_gets_one_stretch_at_its_calmest_instant(fs):
    calmest = np.random.default_rng(1).uniform(25.0, 60.0, 12)  # deg/s: above the fixed gate (17 deg/s)
    t, acc, gyr, in_stance, calm_at = running(fs, calmest)
    fixed = D.detect("shoe", t, acc, gyr, GAMMA0, SA, SG, 3, G)
    assert not fixed.stationary.any()  # the fixed SHOE misses every stance
    res = detect_anchored(t, acc, gyr, GAMMA0, SA, SG, 3, CalmAnchor(), G)
    found = stretches(res.stationary)
    assert len(found) == len(calm_at)
    rate = np.degrees(np.abs(gyr[:, 1]))
    for (a, b), centre, low in zip(found, calm_at, calmest):
        assert in_stance[a:b].all()  # never in the swing
        assert t[a] <= centre <= t[b - 1]  # it holds the calmest instant
        # widen 4 on a gyro-dominated statistic: rates within 2x the calmest, plus the 20 ms average and the
        # W-sample spread at the ends
        assert np.median(rate[a:b]) < 2.0 * low and t[b - 1] - t[a] > 0.02


def test_stretch_duration_does_not_depend_on_the_sample_rate():
    calmest = np.full(12, 40.0)
    lengths = {}
    for fs in (200.0, 800.0):
        t, acc, gyr, _, _ = running(fs, calmest)
        found = stretches(detect_anchored(t, acc, gyr, GAMMA0, SA, SG, 3, CalmAnchor(), G).stationary)
        lengths[fs] = np.median([(b - a) / fs for a, b in found])
    # s: the same stretch but for the W-sample spread of the marks (2 samples: 10 ms at 200 Hz, 2.5 ms at 800 Hz)
    assert lengths[200.0] == pytest.approx(lengths[800.0], abs=0.01)


def test_wherever_the_fixed_test_finds_the_stance_it_is_the_fixed_test():
    rec = synthetic_walk(strides=8, fs=400.0)
    rng = np.random.default_rng(2)
    acc = rec.acc + rng.normal(0.0, 0.03, rec.acc.shape)
    gyr = rec.gyr + rng.normal(0.0, math.radians(0.15), rec.gyr.shape)
    fixed = D.detect("shoe", rec.t, acc, gyr, GAMMA0, SA, SG, 3, G)
    res = detect_anchored(rec.t, acc, gyr, GAMMA0, SA, SG, 3, CalmAnchor(), G)
    np.testing.assert_array_equal(res.stationary, fixed.stationary)
    np.testing.assert_array_equal(res.threshold, GAMMA0)
    assert res.params.name == "anchored" and res.params.adaptation["half_span_s"] == 0.5


def test_motion_that_is_never_calm_enough_gets_no_stretch():
    # calmest rate 150 deg/s: T ~ (150 / 0.1)^2 = 2.25e6, above the cap of 35 x 3e4
    t, acc, gyr, _, _ = running(400.0, np.full(12, 150.0))
    res = detect_anchored(t, acc, gyr, GAMMA0, SA, SG, 3, CalmAnchor(), G)
    assert not res.stationary.any()
    # a higher cap takes them
    assert detect_anchored(t, acc, gyr, GAMMA0, SA, SG, 3, CalmAnchor(cap=100.0), G).stationary.any()


def test_a_calm_stride_does_not_hide_its_neighbours_stance():
    # the fixed test finds stride 5 (5 deg/s); strides 4 and 6, 0.73 s away, still get their own stretches
    calmest = np.full(12, 40.0)
    calmest[5] = 5.0
    t, acc, gyr, in_stance, calm_at = running(400.0, calmest)
    res = detect_anchored(t, acc, gyr, GAMMA0, SA, SG, 3, CalmAnchor(), G)
    found = stretches(res.stationary)
    assert len(found) == 12 and all(in_stance[a:b].all() for a, b in found)


def test_windows_and_threshold_of_a_batch_are_those_of_each_run():
    stats = np.random.default_rng(4).uniform(3e4, 1e6, (3, 2000))
    anchored, gamma = anchored_windows(stats, GAMMA0, 400.0, CalmAnchor())
    for r in range(3):
        one, g = anchored_windows(stats[r], GAMMA0, 400.0, CalmAnchor())
        np.testing.assert_array_equal(anchored[r], one)
        np.testing.assert_array_equal(gamma[r], g)


@pytest.mark.parametrize("field,value", [("half_span_s", 0.0), ("widen", 0.5), ("cap", math.nan), ("calm_s", -1.0)])
def test_bad_settings_are_refused_by_name(field, value):
    with pytest.raises(ValueError, match=field):
        CalmAnchor(**{field: value})
