"""Scores (nav.metrics): sign conventions, drift fit, alignment, confusion, run summaries."""

import math

import numpy as np
import pytest

from nav import metrics


def straight_north(n=1001, length=100.0):
    t = np.linspace(0.0, 100.0, n)
    pos = np.stack([np.zeros(n), length * t / t[-1], np.zeros(n)], -1)
    return t, pos


def yaw_quat(yaw):
    return np.stack([np.cos(yaw / 2), 0 * yaw, 0 * yaw, np.sin(yaw / 2)], -1)


def test_short_and_left_estimate_signs():
    t, truth = straight_north()
    est = truth * np.array([1.0, 0.98, 1.0]) + np.array([-0.5, 0.0, 0.0]) * (t / t[-1])[:, None]
    s = metrics.score(t, est, t, truth)
    assert s["along_track_error_m"] == pytest.approx(2.0, rel=1e-12)  # 2 m short: positive
    assert s["along_track_error_pct"] == pytest.approx(2.0, rel=1e-12)
    assert s["length_ratio"] == pytest.approx(0.98, rel=1e-12)
    assert s["perpendicular_error_m"] == pytest.approx(0.5, rel=1e-12)  # west of a walk north = left
    assert s["final_error_m"] == pytest.approx(math.hypot(2.0, 0.5), rel=1e-12)


def test_heading_drift_from_attitude_and_from_track():
    t, truth = straight_north()
    rate = math.radians(0.028)  # deg/s -> rad/s
    q_true = yaw_quat(np.full(len(t), np.pi / 2))
    q_est = yaw_quat(np.pi / 2 + rate * t)
    s = metrics.score(t, truth, t, truth, q_est, q_true)
    assert s["heading_drift_deg_per_s"] == pytest.approx(0.028, rel=1e-9)
    assert s["heading_drift_deg_per_100m"] == pytest.approx(0.028 * 100.0 / 100.0 * 100, rel=1e-6)
    assert s["heading_drift_source"].startswith("attitude")
    # a track turned by a constant angle seen from the start: zero drift, not a rate
    c, s_ = np.cos(0.01), np.sin(0.01)
    turned = truth @ np.array([[c, -s_, 0], [s_, c, 0], [0, 0, 1]]).T
    with pytest.warns(metrics.HeadingDriftWarning, match="no estimate and reference attitude"):
        fallback = metrics.score(t, turned, t, truth)
    assert fallback["heading_drift_deg_per_s"] == pytest.approx(0.0, abs=1e-12)
    assert fallback["track_heading_drift_deg_per_s"] == fallback["heading_drift_deg_per_s"]
    assert "no estimate and reference attitude" in fallback["heading_drift_source"]


def test_track_heading_drift_is_reported_beside_the_attitude_drift():
    t, truth = straight_north()
    rate = math.radians(0.05)  # rad/s: the estimate's track turns left at this rate from the start
    heading = rate * t
    step = np.diff(truth[:, 1], prepend=0.0)
    est = np.column_stack([-np.cumsum(step * np.sin(heading)), np.cumsum(step * np.cos(heading)), truth[:, 2]])
    q_true = yaw_quat(np.full(len(t), np.pi / 2))
    s = metrics.score(t, est, t, truth, yaw_quat(np.pi / 2 + heading), q_true)
    assert s["heading_drift_deg_per_s"] == pytest.approx(0.05, rel=1e-9)
    # seen from the start, a track turning at a constant rate turns at half that rate (the chord's angle)
    assert s["track_heading_drift_deg_per_s"] == pytest.approx(0.025, rel=0.05)


def test_ate_after_se2_alignment_removes_a_rigid_motion():
    t, truth = straight_north()
    truth[:, 0] = np.sin(truth[:, 1] / 10.0)  # a wiggly path so the rotation is determined
    c, s_ = np.cos(0.2), np.sin(0.2)
    est = truth @ np.array([[c, -s_, 0], [s_, c, 0], [0, 0, 1]]).T + [3.0, -1.0, 0.0]
    scores = metrics.score(t, est, t, truth)
    assert scores["ate_m"] > 3.0
    assert scores["ate_se2_m"] < 1e-9


def test_primary_scores_alone_equal_those_of_the_full_score():
    t, truth = straight_north()
    truth[:, 0] = np.sin(truth[:, 1] / 10.0)
    est = truth * [1.0, 0.98, 1.0] + [0.1, 0.0, 0.0]
    q_true = yaw_quat(np.full(len(t), np.pi / 2))
    q_est = yaw_quat(np.pi / 2 + 1e-4 * t)
    stationary = (np.arange(len(t)) % 50) < 20
    full = metrics.score(t, est, t, truth, q_est, q_true, stationary)
    primary = metrics.score(t, est, t, truth, q_est, q_true, stationary, secondary=False)
    left_out = {"path_length_ratio", "stride_length_ratio", "track_heading_drift_deg_per_s", "ate_se2_m"}
    assert set(full) - set(primary) == left_out
    assert all(primary[k] == full[k] for k in primary)


def test_finite_rows_is_every_value_finite():
    a = np.ones((6, 3))
    a[1, 0], a[3, 2], a[4, 1] = np.nan, np.inf, -np.inf
    np.testing.assert_array_equal(metrics.finite_rows(a), [True, False, True, False, False, True])


def test_confusion_counts():
    det = np.array([1, 1, 0, 0, 1], bool)
    true = np.array([1, 0, 0, 1, 1], bool)
    c = metrics.confusion(det, true)
    assert (c["true_positive"], c["false_positive"], c["false_negative"], c["true_negative"]) == (2, 1, 1, 1)
    assert c["precision"] == pytest.approx(2 / 3) and c["recall"] == pytest.approx(2 / 3)


def test_stance_match_counts_runs():
    true = np.zeros(60, bool)
    for a, b in ((5, 10), (15, 20), (25, 30), (35, 40), (45, 50)):
        true[a:b] = True
    det = np.zeros(60, bool)
    det[6:8] = det[8:9] = True       # stance 1 found by one run (6..8 is one run)
    det[18:27] = True                # one run over stances 2 and 3: merged
    det[36] = det[38] = True         # stance 4 found by two runs: split
    det[42:44] = det[55:57] = True   # two runs in the swing: spurious
    m = metrics.stance_match(det, true)        # stance 5 (45..50) is missed
    assert m == {"true_stances": 5, "detected_runs": 6, "found": 4, "missed": 1, "found_fraction": 0.8,
                 "merged": 1, "spurious": 2, "split": 1}
    assert metrics.stance_match(true, true) == {"true_stances": 5, "detected_runs": 5, "found": 5, "missed": 0,
                                                "found_fraction": 1.0, "merged": 0, "spurious": 0, "split": 0}
    with pytest.raises(ValueError, match="equal 1-D shapes"):
        metrics.stance_match(det[:-1], true)


def test_three_sigma_ellipse_of_known_covariance():
    rng = np.random.default_rng(0)
    cov = np.array([[4.0, 1.5], [1.5, 1.0]])
    pts = rng.multivariate_normal([1.0, -2.0], cov, 200_000)
    e = metrics.error_ellipse(pts)
    values, vectors = np.linalg.eigh(cov)
    assert e["semi_major_m"] == pytest.approx(3 * math.sqrt(values[1]), rel=0.01)
    assert e["semi_minor_m"] == pytest.approx(3 * math.sqrt(values[0]), rel=0.01)
    expected_angle = math.degrees(math.atan2(vectors[1, 1], vectors[0, 1]))
    assert math.cos(math.radians(e["angle_deg"] - expected_angle)) ** 2 == pytest.approx(1.0, abs=1e-4)


def test_summary_over_runs():
    runs = [{"along_track_error_m": a, "perpendicular_error_m": p, "name": "x"} for a, p in [(1, 0), (2, 1), (3, -1)]]
    s = metrics.summarise_runs(runs)
    assert s["along_track_error_m"]["mean"] == 2.0 and s["along_track_error_m"]["std"] == pytest.approx(1.0)
    assert "name" not in s and s["runs"] == 3
    assert s["end_point_ellipse_3sigma"]["centre_m"] == [2.0, 0.0]


def test_loops_have_no_along_track_axis():
    t = np.linspace(0, 10, 101)
    loop = np.stack([np.cos(t * 2 * np.pi / 10) - 1, np.sin(t * 2 * np.pi / 10), 0 * t], -1) * 5
    s = metrics.score(t, loop + [0.1, 0.0, 0.0], t, loop)
    assert math.isnan(s["along_track_error_m"]) and s["final_error_m"] == pytest.approx(0.1, rel=1e-9)


def test_stride_length_ratio_sees_the_stance_points_not_the_swing_path():
    """Steps of 1.4 m (stance 0.5 s, swing 0.5 s): an estimate 2 % short at every stance, with a sideways
    swing wiggle the reference lacks, has a stride length ratio of 0.98 exactly, while its sampled path
    length ratio is inflated by the wiggle."""
    t = np.arange(0.0, 20.0, 0.01)
    cycle = np.floor(t)  # stride index
    phase = t - cycle
    swing = np.clip((phase - 0.5) / 0.5, 0.0, 1.0)
    along = 1.4 * (cycle + swing)
    truth = np.stack([along, np.zeros_like(t), np.zeros_like(t)], -1)
    est = np.stack([0.98 * along, 0.15 * np.sin(np.pi * swing), np.zeros_like(t)], -1)
    stationary = phase < 0.5
    s = metrics.score(t, est, t, truth, stationary=stationary)
    assert s["stride_length_ratio"] == pytest.approx(0.98, rel=1e-12)
    assert s["path_length_ratio"] > 1.0
    assert "stride_length_ratio" not in metrics.score(t, est, t, truth)
