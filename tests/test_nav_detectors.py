"""Zero-velocity detectors (nav.detectors): statistics against hand computations, window semantics, conversions."""

import math

import numpy as np
import pytest

from conftest import DATA, needs_data
from gaitsim.measured import load_dataset
from nav import detectors as D
from nav.constants import DEFAULT_SIGMA_A

G = 9.81


def signals(n=40, seed=0):
    rng = np.random.default_rng(seed)
    acc = np.array([0.3, -0.2, G]) + rng.normal(0, 0.5, (n, 3))
    gyr = rng.normal(0, 0.3, (n, 3))
    return np.arange(n) / 100.0, acc, gyr


def hand_statistics(acc, gyr, sa, sg, w):
    """Anchors §2 formulas, one window at a time with explicit sums."""
    out = {k: [] for k in ("shoe", "are", "mv", "mag")}
    for k in range(len(acc) - w + 1):
        ya, yw = acc[k:k + w], gyr[k:k + w]
        mean = ya.mean(axis=0)
        u = mean / np.linalg.norm(mean)
        out["shoe"].append(sum(np.sum((ya[l] - G * u) ** 2) / sa**2 + np.sum(yw[l] ** 2) / sg**2 for l in range(w)) / w)
        out["are"].append(sum(np.sum(yw[l] ** 2) for l in range(w)) / (sg**2 * w))
        out["mv"].append(sum(np.sum((ya[l] - mean) ** 2) for l in range(w)) / (sa**2 * w))
        out["mag"].append(sum((np.linalg.norm(ya[l]) - G) ** 2 for l in range(w)) / (sa**2 * w))
    return {k: np.array(v) for k, v in out.items()}


@pytest.mark.parametrize("window", [1, 3, 5])
@pytest.mark.parametrize("name", ["shoe", "are", "mv", "mag"])
def test_statistic_equals_hand_computation(name, window):
    _, acc, gyr = signals()
    sa, sg = 0.01, math.radians(0.1)
    got = D.statistic(name, acc, gyr, sa, sg, window, G)
    np.testing.assert_allclose(got, hand_statistics(acc, gyr, sa, sg, window)[name], rtol=1e-9, atol=1e-6)


def bits(x):
    return np.ascontiguousarray(x).view(np.uint64)


@pytest.mark.parametrize("window", [1, 2, 3, 5, 9])
def test_compiled_shoe_statistic_is_the_numpy_one_bit_for_bit(window):
    # a miscalibrated, quantised, clipped sensor with NaN samples, in a batch of runs with its own leading axes
    rng = np.random.default_rng(window)
    acc = np.array([0.3, -0.2, G]) + rng.normal(0, 1, (2, 3, 500, 3)) * np.geomspace(1e-3, 30, 500)[:, None]
    gyr = rng.normal(0, 1, acc.shape) * np.geomspace(1e-4, 10, 500)[:, None]
    acc, gyr = np.clip(np.round(acc, 3), -156.9, 156.9), np.round(gyr, 4)
    acc[0, 1, 100], gyr[1, 2, 300] = np.nan, np.nan
    got = D.statistic("shoe", acc, gyr, 0.01, math.radians(0.1), window, G)
    want = D.numpy_statistic("shoe", acc, gyr, 0.01, math.radians(0.1), window, G)
    assert got.shape == want.shape == (2, 3, 500 - window + 1)
    np.testing.assert_array_equal(bits(got), bits(want))
    assert np.isnan(got[0, 1, 100 - window + 1: 101]).all() and np.isnan(got[1, 2, 300 - window + 1: 301]).all()
    # one run alone, a strided view and a gyro broadcast against the batch give the same windows
    np.testing.assert_array_equal(bits(D.statistic("shoe", acc[1, 0], gyr[1, 0], 0.01, math.radians(0.1), window, G)),
                                  bits(want[1, 0]))
    np.testing.assert_array_equal(bits(D.statistic("shoe", acc[..., ::-1, :], gyr[..., ::-1, :], 0.01,
                                                   math.radians(0.1), window, G)),
                                  bits(D.numpy_statistic("shoe", acc[..., ::-1, :], gyr[..., ::-1, :], 0.01,
                                                         math.radians(0.1), window, G)))
    np.testing.assert_array_equal(bits(D.statistic("shoe", acc, gyr[0, 0], 0.01, math.radians(0.1), window, G)),
                                  bits(D.numpy_statistic("shoe", acc, np.broadcast_to(gyr[0, 0], acc.shape), 0.01,
                                                         math.radians(0.1), window, G)))


@needs_data("xio-ngimu")
def test_compiled_shoe_statistic_is_the_numpy_one_on_a_measured_recording():
    rec = load_dataset("xio-ngimu", DATA)[0]
    got = D.statistic("shoe", rec.acc, rec.gyr, 0.01, math.radians(0.1), 3, G)
    np.testing.assert_array_equal(bits(got), bits(D.numpy_statistic("shoe", rec.acc, rec.gyr, 0.01,
                                                                      math.radians(0.1), 3, G)))


def test_the_compiled_shoe_refuses_samples_that_are_not_three_axes():
    _, acc, gyr = signals()
    with pytest.raises(ValueError, match=r"shape \(40, 2\).*allowed \(\.\.\., N, 3\)"):
        D.statistic("shoe", acc[:, :2], gyr[:, :2], 0.01, 0.01, 3)


def test_a_window_longer_than_the_recording_is_refused_by_both_paths():
    _, acc, gyr = signals(n=4)
    for statistic in (D.statistic, D.numpy_statistic):
        with pytest.raises(ValueError, match="window 5 samples is not in 1..4"):
            statistic("shoe", acc, gyr, 0.01, 0.01, 5)


def test_shoe_uses_each_windows_own_gravity_direction():
    # a still sensor tilted differently in two halves: per-window gravity direction makes both halves quiet
    n = 20
    f1 = G * np.array([0.0, 0.0, 1.0])
    f2 = G * np.array([np.sin(0.5), 0.0, np.cos(0.5)])
    acc = np.vstack([np.tile(f1, (n, 1)), np.tile(f2, (n, 1))])
    stat = D.statistic("shoe", acc, np.zeros_like(acc), 0.01, 0.01, 3, G)
    quiet = np.r_[0:n - 2, n:2 * n - 2]
    assert np.max(stat[quiet]) < 1e-6
    # windows straddling the tilt change are loud: spread (2/3) |f1 - f2|^2 alone gives > 5e4
    assert np.min(np.delete(stat, quiet)) > (2 / 3) * np.sum((f1 - f2) ** 2) / (0.01**2 * 3)
    # gaitmap's whole-recording gravity direction would call the still halves loud
    u = acc.mean(axis=0) / np.linalg.norm(acc.mean(axis=0))
    assert np.sum((f1 - G * u) ** 2) / 0.01**2 > 1e4


def test_all_w_samples_of_a_quiet_window_are_marked():
    n, w = 30, 4
    t = np.arange(n) / 100.0
    gyr = np.full((n, 3), 1.0)
    gyr[10:14] = 0.0  # exactly one window (k = 10) is quiet
    acc = np.tile([0.0, 0.0, G], (n, 1))
    res = D.detect("are", t, acc, gyr, threshold=1.0, sigma_g=0.1, window=w)
    assert np.flatnonzero(res.stationary).tolist() == [10, 11, 12, 13]
    assert res.params == D.DetectorParams("are", 1.0, DEFAULT_SIGMA_A, 0.1, w, pytest.approx(100.0), G)


def test_batch_detection_equals_single_runs():
    runs = [signals(seed=s) for s in range(3)]
    acc = np.stack([r[1] for r in runs])
    gyr = np.stack([r[2] for r in runs])
    batch = D.detect("shoe", runs[0][0], acc, gyr, threshold=5e5, sigma_a=0.5, sigma_g=0.3)
    for i, (t, a, g) in enumerate(runs):
        single = D.detect("shoe", t, a, g, threshold=5e5, sigma_a=0.5, sigma_g=0.3)
        np.testing.assert_array_equal(batch.stationary[i], single.stationary)
        np.testing.assert_allclose(batch.statistic[i], single.statistic, rtol=1e-14)


def test_statistic_does_not_depend_on_where_the_window_sits():
    # the same quiet window at the start and after a long, loud recording gives the same statistic
    rng = np.random.default_rng(3)
    quiet = np.array([0.0, 0.0, G]) + rng.normal(0, 0.01, (5, 3))
    loud = np.array([0.0, 0.0, G]) + rng.normal(0, 50.0, (200_000, 3))
    acc = np.vstack([quiet, loud, quiet])
    gyr = np.zeros_like(acc)
    stat = D.statistic("shoe", acc, gyr, 0.01, 0.01, 5, G)
    assert stat[-1] == pytest.approx(stat[0], rel=1e-9)


def test_oracle_reports_the_true_labels_and_its_nature():
    stance = np.array([0, 1, 1, 0, 1], bool)
    res = D.oracle(np.arange(5) / 800.0, stance)
    np.testing.assert_array_equal(res.stationary, stance)
    assert res.params.name == "oracle" and res.params.fs == pytest.approx(800.0)


def test_bad_detector_inputs_are_rejected():
    t, acc, gyr = signals()
    with pytest.raises(ValueError, match="not one of"):
        D.detect("glrt2", t, acc, gyr)
    with pytest.raises(ValueError, match="window"):
        D.detect("shoe", t, acc, gyr, window=0)
    with pytest.raises(ValueError, match="positive"):
        D.detect("shoe", t, acc, gyr, sigma_a=0.0)


def test_threshold_conversion_exact_rescaling():
    a = D.openshoe_convention(0.01, math.radians(0.1))
    b = D.openshoe_convention(0.02, math.radians(0.2))
    conv = D.convert_threshold(3e4, a, b)
    assert conv.exact and conv.threshold == pytest.approx(7.5e3, rel=1e-12)
    # and the statistic really scales by that factor
    _, acc, gyr = signals()
    sa = D.statistic("shoe", acc, gyr, a.sigma_a, a.sigma_g, 3)
    sb = D.statistic("shoe", acc, gyr, b.sigma_a, b.sigma_g, 3)
    np.testing.assert_allclose(sb, sa * 0.25, rtol=1e-12)


def test_gaitmap_default_threshold_lands_near_openshoe_walking_values():
    # anchors §2: rescaled to OpenShoe's sigmas, typical walking thresholds land near 2.5-3e4
    conv = D.convert_threshold(2310129700, D.gaitmap_convention(), D.openshoe_convention())
    assert not conv.exact and "semantics" in conv.note and "gyro gate" in conv.note
    assert conv.threshold == pytest.approx(1.3e-7 * 2310129700 / 0.1**2, rel=1e-9)
    assert 2.5e4 < conv.threshold < 3.5e4
    pyshoe = D.convert_threshold(3e4, D.openshoe_convention(), D.pyshoe_convention())
    assert pyshoe.threshold == pytest.approx(3e4) and not pyshoe.exact  # same sigmas, different windows


def test_runs_closer_than_the_gap_merge_into_one_stance():
    from nav.alignment import merged_runs

    t = np.arange(20) * 0.01
    stationary = np.zeros(20, bool)
    stationary[[2, 3, 5, 6, 12, 13]] = True  # runs [2, 4), [5, 7), [12, 14): 0.02 s and 0.06 s apart
    bounds, runs, group = merged_runs(t, stationary, 0.03)
    np.testing.assert_array_equal(bounds, [[2, 7], [12, 14]])
    np.testing.assert_array_equal(runs, [[2, 4], [5, 7], [12, 14]])
    np.testing.assert_array_equal(group, [0, 0, 1])
    assert merged_runs(t, np.zeros(20, bool), 0.03)[0].shape == (0, 2)


@pytest.mark.parametrize("name", ["shoe", "are", "mv", "mag"])
@pytest.mark.parametrize("fraction", [0.05, 0.3, 0.7, 1.0])
def test_threshold_for_fraction_is_the_smallest_reaching_the_share(name, fraction):
    """Over two recordings of different lengths, the returned gamma marks at least ``fraction`` of all samples,
    and the largest statistic value below it (the next smaller candidate) marks less."""
    window = 3
    stats = [D.statistic(name, acc, gyr, 0.01, math.radians(0.1), window, G)
             for _, acc, gyr in (signals(200, seed=1)[:3], signals(333, seed=2)[:3])]
    gamma = D.threshold_for_fraction(stats, window, fraction)
    assert D.marked_share(stats, window, gamma) >= fraction
    below = np.concatenate(stats)
    below = below[below < gamma]
    if below.size:
        assert D.marked_share(stats, window, below.max()) < fraction


def test_a_threshold_round_trips_through_its_own_share():
    """SHOE at gamma marks a share; the threshold found for that share marks exactly the same samples."""
    _, acc, gyr = signals(500, seed=3)
    stat = D.statistic("shoe", acc, gyr, 1.0, 1.0, 3, G)
    gamma = float(np.median(stat))
    again = D.threshold_for_fraction([stat], 3, D.marked_share([stat], 3, gamma))
    np.testing.assert_array_equal(D.spread_marks(stat < again, 3), D.spread_marks(stat < gamma, 3))


def test_are_matched_to_shoe_gets_a_lower_threshold_in_its_own_units():
    """ARE is SHOE without the accelerometer term (T_are <= T_shoe window by window), so at SHOE's share of
    stationary samples ARE's threshold cannot be higher; handing it SHOE's number would mark more."""
    _, acc, gyr = signals(600, seed=4)
    sa, sg = 0.3, 0.2
    shoe = D.statistic("shoe", acc, gyr, sa, sg, 3, G)
    are = D.statistic("are", acc, gyr, sa, sg, 3, G)
    assert np.all(are <= shoe + 1e-9)
    gamma = float(np.quantile(shoe, 0.4))
    share = D.marked_share([shoe], 3, gamma)
    matched = D.threshold_for_fraction([are], 3, share)
    assert matched < gamma
    assert D.marked_share([are], 3, gamma) > share


def test_threshold_for_fraction_refuses_a_share_outside_0_1():
    with pytest.raises(ValueError, match="fraction"):
        D.threshold_for_fraction([np.ones(5)], 3, 0.0)
