"""End-to-end laws of nav.pipeline on walks with exact truth: ZUPT length loss, compensation hooks, heading."""

from pathlib import Path

import numpy as np
import pytest
from nav_synthetic import synthetic_walk

from gaitsim.scenario import load_scenario
from gaitsim.simulate import simulate_walk
from nav import calibration, pipeline
from nav.ekf import FilterConfig
from nav.recording import Recording, Reference
from nav.zupt_velocity import (StanceVelocityProfile, load_stance_velocity, save_stance_velocity,
                               stance_velocities, to_heading_frame)

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def walk():
    return synthetic_walk()


def in_window_displacement(truth, stationary):
    inside = stationary[:-1] & stationary[1:]
    return float(np.sum(np.linalg.norm(np.diff(truth.pos, axis=0)[inside], axis=1)))


def test_exact_walk_with_true_stance_velocity_has_no_length_error(walk):
    v = np.where(walk.truth.stance[:, None], to_heading_frame(walk.truth.vel, walk.truth.quat), 0.0)
    sol, score = pipeline.run(walk, pipeline.NavOptions(detector="oracle", stance_velocity=v))
    assert score["info"]["mechanisation"] == "increments"
    assert abs(score["along_track_error_m"]) < 1e-6
    assert score["final_error_3d_m"] < 1e-6


def test_zero_velocity_loses_the_stance_displacement_inside_the_zupt_windows(walk):
    # the creep is zero at the window edges, so a hard ZUPT loses exactly what moves inside the windows
    loss_expected = in_window_displacement(walk.truth, walk.truth.stance)
    hard = pipeline.NavOptions(detector="oracle", filter=FilterConfig(zupt_sigma=0.001))
    _, score = pipeline.run(walk, hard)
    assert score["along_track_error_m"] == pytest.approx(loss_expected, rel=0.01)
    # the default (softer) ZUPT noise lets the stance velocity error leak into the swing: still within 10 %
    _, score = pipeline.run(walk, pipeline.NavOptions(detector="oracle"))
    assert score["along_track_error_m"] == pytest.approx(loss_expected, rel=0.10)
    assert abs(score["perpendicular_error_m"]) < 1e-9


def test_fitted_stance_velocity_profile_removes_the_loss(walk, tmp_path):
    options = pipeline.NavOptions(detector="shoe")
    prepared = pipeline.prepare(walk, options)
    stances = stance_velocities(walk.truth.vel, walk.truth.quat, prepared.stationary)[1:-1]  # strides only
    model = StanceVelocityProfile.fit(stances, knots=41, metadata=prepared.info["detector"])
    path = save_stance_velocity(model, tmp_path / "model.json")
    loaded = load_stance_velocity(path)
    np.testing.assert_array_equal(loaded.velocity, model.velocity)
    _, before = pipeline.run(walk, options)
    _, after = pipeline.run(walk, pipeline.NavOptions(detector="shoe", stance_velocity=str(path)))
    assert before["along_track_error_m"] > 0.04
    assert abs(after["along_track_error_m"]) < 0.05 * before["along_track_error_m"]


def test_calibration_step_undoes_a_known_sensor_error(walk):
    cal = calibration.Calibration(
        b_a=[0.05, -0.03, 0.02], M_a=np.eye(3) + 1e-3 * np.array([[1, 2, 0], [0, -1, 3], [1, 0, 2]]),
        b_g=[1e-3, -2e-3, 5e-4], M_g=np.eye(3) + 1e-3 * np.array([[2, 0, 1], [1, 1, 0], [0, 2, -1]]),
        G_g=3e-5 * np.ones((3, 3)), source="test")
    acc, gyr = cal.distort(walk.acc, walk.gyr)
    distorted = Recording(walk.t, acc, gyr, {}, walk.truth)
    opts = dict(detector="oracle", method="rk4")
    _, ideal = pipeline.run(walk, pipeline.NavOptions(**opts))
    _, raw = pipeline.run(distorted, pipeline.NavOptions(**opts))
    _, fixed = pipeline.run(distorted, pipeline.NavOptions(**opts, calibration=cal))
    assert raw["final_error_m"] > 0.05
    assert fixed["final_error_m"] == pytest.approx(ideal["final_error_m"], abs=1e-6)


def test_heading_from_the_reference_first_leg(walk):
    # no truth: the heading comes from the reference's first 3 m; the solution must then match the truth run
    ref_only = Recording(walk.t, walk.acc, walk.gyr, {}, reference=Reference(walk.truth.t, walk.truth.pos))
    sol_ref, score_ref = pipeline.run(ref_only, pipeline.NavOptions(detector="shoe", method="rk4"))
    sol_truth, _ = pipeline.run(walk, pipeline.NavOptions(detector="shoe", method="rk4"))
    assert score_ref["scored_against"] == "reference"
    assert sol_ref.info["alignment"]["heading_source"] == "reference first leg"
    assert np.nanmax(np.abs(sol_ref.pos - sol_truth.pos)) < 1e-3


def test_batch_navigation_equals_single_navigation():
    recs = [synthetic_walk(strides=3, creep=c) for c in (0.01, 0.02, 0.03)]
    options = pipeline.NavOptions(detector="shoe", filter=FilterConfig(states=15))
    batch = pipeline.navigate(recs, options)
    for rec, b in zip(recs, batch):
        single = pipeline.navigate(rec, options)
        ok = np.isfinite(single.pos[:, 0])
        assert np.max(np.abs(b.pos[ok] - single.pos[ok])) <= 1e-12
        assert b.start == single.start


def test_variants_of_one_recording_are_checked_once_and_equal_navigating_each(walk, monkeypatch):
    checked = []
    check = pipeline.check_recording
    monkeypatch.setattr(pipeline, "check_recording", lambda *args, **kw: checked.append(1) or check(*args, **kw))
    variants = [pipeline.NavOptions(detector="shoe", method="rk4"),
                pipeline.NavOptions(detector="oracle", method="rk4", filter=FilterConfig(states=15)),
                pipeline.NavOptions(detector="shoe", method="rk4", gravity=9.80)]
    together = pipeline.run_variants(walk, variants, secondary=False)
    assert len(checked) == 2  # one per gravity
    for options, (sol, score) in zip(variants, together):
        alone, full = pipeline.run(walk, options)
        np.testing.assert_array_equal(sol.pos, alone.pos)
        np.testing.assert_array_equal(sol.quat, alone.quat)
        assert set(score) < set(full)
        np.testing.assert_equal(score, {k: full[k] for k in score})  # NaN equal to NaN (the oracle's threshold)
        assert "ate_se2_m" in full and "ate_se2_m" not in score


# ------------------------------------------------------------------------------------------- the simulator's walk
@pytest.fixture(scope="module")
def simulated():
    return simulate_walk(load_scenario(ROOT / "scenarios/straight_100m.toml"), seed=1)


def test_simulated_walk_true_stance_velocity_error_below_1mm_per_100m(simulated):
    tr = simulated.truth
    v = np.where(tr.stance[:, None], to_heading_frame(tr.vel, tr.quat), 0.0)
    _, score = pipeline.run(simulated, pipeline.NavOptions(detector="oracle", stance_velocity=v))
    assert score["distance_m"] == pytest.approx(99.6, abs=0.01)
    assert abs(score["along_track_error_m"]) < 1e-3 * score["distance_m"] / 100
    assert score["final_error_m"] < 1e-3


def test_simulated_walk_zero_velocity_loss_is_bracketed(simulated):
    # The simulator's foot still moves at the edges of the labelled stance (about 10 mm/s in, 30 mm/s at heel
    # off), so the loss is NOT only the displacement inside the windows: a ZUPT also zeroes the exit velocity,
    # whose error the swing carries until the next window, where the filter's velocity-position correlation
    # takes part of it back. The loss must lie between the in-window displacement (lower bound) and the loss of
    # a hard velocity reset without that correlation (upper bound).
    tr = simulated.truth
    _, score = pipeline.run(simulated, pipeline.NavOptions(detector="oracle"))
    inside = in_window_displacement(tr, tr.stance)
    axis = (tr.pos[-1] - tr.pos[0]) / np.linalg.norm(tr.pos[-1] - tr.pos[0])
    v = tr.vel @ axis
    exit_velocity = np.zeros_like(v)  # velocity at the last stance sample, held through the next swing
    last = np.maximum.accumulate(np.where(tr.stance, np.arange(len(v)), 0))
    exit_velocity[~tr.stance] = v[last[~tr.stance]]
    lag = np.where(tr.stance, v, exit_velocity)
    reset_loss = float(np.sum(0.5 * (lag[1:] + lag[:-1]) * np.diff(tr.t)))
    assert inside < score["along_track_error_m"] < reset_loss
