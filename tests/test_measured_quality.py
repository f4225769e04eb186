"""Shared data-quality checks and the rigid-body alignment tools, on synthetic signals with known answers."""

import numpy as np
import pytest

from gaitsim.measured import mocap
from gaitsim.measured.quality import (
    frame_checks,
    jitter_stats,
    non_increasing_time_mask,
    saturation_counts,
    timestamp_report,
)
from nav import quaternion as quat


def test_non_increasing_rows_are_repeats_and_steps_back():
    t = np.array([0.0, 1.0, 1.0, 2.0, 1.5, 3.0, 3.0, 3.0])
    assert non_increasing_time_mask(t).tolist() == [False, False, True, False, True, False, True, True]
    report = timestamp_report(t)
    assert (report["repeated_time_rows"], report["backward_time_rows"], report["non_increasing_rows"]) == (3, 1, 4)


def test_jitter_stats_of_a_clock_with_one_lost_sample():
    t = np.cumsum(np.r_[0.0, np.full(99, 0.0025), 0.005, np.full(99, 0.0025)])
    stats = jitter_stats(t)
    assert stats["gaps"] == 1
    assert stats["rate_hz"] == pytest.approx(400.0, rel=1e-9)
    dt = np.diff(t)
    assert stats["jitter_rel"] == pytest.approx(dt.std() / 0.0025, rel=1e-9)


def test_saturation_counts_any_axis_from_the_fraction_of_full_scale():
    full = 16 * 9.80665
    acc = np.zeros((10, 3))
    acc[2, 0] = 0.995 * full  # counted (>= 0.99)
    acc[3, 1] = -full  # counted, negative rail
    acc[3, 2] = full  # same sample: counted once in "samples"
    acc[4, 2] = 0.98 * full  # not counted
    counts = saturation_counts(acc, full)
    assert counts["per_axis"] == [1, 1, 1]
    assert counts["samples"] == 2


def _synthetic_walk(forward_sign: float):
    """Still 0.5 s / swing 0.6 s cycles: heel-rise pitch (+0.76 rad) then a smaller toe-up pitch (-1.02 + 0.76)."""
    rate = 200.0
    still = np.zeros(int(0.5 * rate))
    s1 = np.arange(int(0.2 * rate)) / rate
    s2 = np.arange(int(0.4 * rate)) / rate
    swing = np.r_[6.0 * np.sin(np.pi * s1 / 0.2), -4.0 * np.sin(np.pi * s2 / 0.4)]
    cycle = np.r_[still, swing]
    pitch_rate = np.tile(cycle, 8)
    n = len(pitch_rate)
    t = np.arange(n) / rate
    gyr = np.zeros((n, 3))
    gyr[:, 1] = forward_sign * pitch_rate  # x and y flipped together when x points backward
    acc = np.tile([0.0, 0.0, 9.81], (n, 1))
    return t, acc, gyr


def test_frame_checks_tell_forward_from_backward_x():
    forward = frame_checks(*_synthetic_walk(+1.0))
    backward = frame_checks(*_synthetic_walk(-1.0))
    expected_deg = np.rad2deg(6.0 * 0.2 * 2 / np.pi)  # integral of the heel-rise half sine
    assert forward["forward_is_plus_x"] and not backward["forward_is_plus_x"]
    assert forward["pitch_excursion_deg"] == pytest.approx(expected_deg, rel=0.03)
    assert backward["pitch_excursion_deg"] == pytest.approx(-expected_deg, rel=0.03)
    assert forward["dominant_gyro_axis"] == 1
    assert forward["still_acc_norm"] == pytest.approx(9.81)


def test_time_offset_is_recovered_to_a_fraction_of_a_sample():
    rng = np.random.default_rng(3)
    t_ref = np.arange(0, 20, 0.01)
    t_imu = np.arange(0, 20, 1 / 204.8)
    freqs, phases = rng.uniform(0.3, 3.0, 6), rng.uniform(0, 2 * np.pi, 6)

    def signal(t):
        return np.sin(2 * np.pi * freqs[:, None] * t + phases[:, None]).sum(axis=0)

    true_offset = 0.020  # t_ref = t_imu + offset: the reference sees an event 20 ms later on its clock
    offset, corr = mocap.estimate_time_offset(t_ref, signal(t_ref - true_offset), t_imu, signal(t_imu))
    assert offset == pytest.approx(true_offset, abs=0.0005)
    assert corr > 0.999


def test_marker_frame_recovers_a_known_pose_for_both_feet():
    rot = quat.to_matrix(quat.from_euler_zyx(np.array([0.7]), np.array([-0.2]), np.array([0.1])))
    heel_b, toe_b = np.array([-0.10, 0.0, 0.0]), np.array([0.15, 0.0, 0.0])
    for side, lateral_y in (("left", 0.05), ("right", -0.05)):
        lateral_b = np.array([0.08, lateral_y, 0.0])
        centre = np.array([[1.0, 2.0, 0.05]])
        markers = [centre + (rot[0] @ p)[None, :] for p in (heel_b, toe_b, lateral_b)]
        origin, frame = mocap.marker_frame(*markers, side)
        np.testing.assert_allclose(frame[0], rot[0], atol=1e-12)
        np.testing.assert_allclose(origin[0], centre[0] + rot[0] @ ((heel_b + toe_b + lateral_b) / 3), atol=1e-12)


def test_lever_arm_and_mount_rotation_are_recovered_from_a_synthetic_rigid_body():
    rate = 100.0
    t = np.arange(0, 12, 1 / rate)
    yaw, pitch, roll = 0.3 * np.sin(0.7 * t), 0.5 * np.sin(2 * np.pi * 0.9 * t), 0.2 * np.sin(2 * np.pi * 1.3 * t + 1)
    rotation = quat.to_matrix(quat.from_euler_zyx(yaw, pitch, roll))
    origin = np.column_stack([1.2 * t, 0.1 * np.sin(2 * np.pi * 0.9 * t), 0.05 + 0.04 * np.sin(2 * np.pi * 0.9 * t)])
    lever_true = np.array([-0.07, 0.05, 0.01])
    mount_true = quat.to_matrix(quat.from_rotvec(np.array([0.45, 0.05, -0.1])))  # IMU -> marker body
    # exact kinematics from a finely sampled copy, then the IMU readings of the lever-arm point
    kin_fine = mocap.body_kinematics(origin, rotation, rate, cutoff_hz=20.0)
    force_world = kin_fine.point_specific_force(lever_true)
    force_imu = np.einsum("ji,nkj,nk->ni", mount_true, rotation, force_world)
    gyr_imu = kin_fine.rate_body @ mount_true
    kin = mocap.body_kinematics(origin, rotation, rate, cutoff_hz=6.0)
    use = (t > 0.5) & (t < t[-1] - 0.5)
    mount = mocap.rotation_between(gyr_imu[use], kin.rate_body[use])
    assert np.linalg.norm(quat.to_rotvec(quat.from_matrix(mount.T @ mount_true))) < 1e-3
    force_est = np.einsum("nij,jk,nk->ni", kin.rotation, mount, force_imu)
    lever, residual = mocap.fit_lever_arm(kin, force_est, use)
    np.testing.assert_allclose(lever, lever_true, atol=0.002)
    assert residual < 0.05
