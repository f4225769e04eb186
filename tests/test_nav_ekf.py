"""Laws of the error-state EKF (nav.ekf): ZUPT convergence, noise scaling, bias estimation, batch identity, RTS."""

import math

import numpy as np
import pytest

from nav import quaternion as Q
from nav._numba import ekf as kernels
from nav.ekf import FilterConfig, run_filter, run_filter_batch

G = 9.81
FS = 800.0


def static(n, fs=FS, acc=(0.0, 0.0, G), gyr=(0.0, 0.0, 0.0), noise=(0.0, 0.0), seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / fs
    a = np.tile(acc, (n, 1)) + rng.normal(0, noise[0], (n, 3))
    w = np.tile(gyr, (n, 1)) + rng.normal(0, noise[1], (n, 3))
    return t, a, w


def test_zupts_on_a_static_imu_drive_velocity_to_zero():
    t, acc, gyr = static(1600)
    out = run_filter(t, acc, gyr, np.ones(len(t), bool), [1, 0, 0, 0], vel0=[0.2, -0.1, 0.05],
                     config=FilterConfig(p0_vel=0.5))
    v0 = np.linalg.norm([0.2, -0.1, 0.05])
    assert np.linalg.norm(out.vel[0]) < 1e-3 * v0  # first update: P_vv >> R, K ~ 1
    assert np.max(np.abs(out.vel[800:])) < 1e-6 * v0 and np.max(np.abs(out.vel[-1])) < 1e-7
    assert out.skipped_updates == 0


def test_static_imu_with_zupts_does_not_move():
    t, acc, gyr = static(8000)
    for states in (9, 15, 24):
        out = run_filter(t, acc, gyr, np.ones(len(t), bool), [1, 0, 0, 0], pos0=[1, 2, 3],
                         config=FilterConfig(states=states))
        assert np.max(np.abs(out.pos - [1, 2, 3])) < 1e-12
        assert np.all(out.p_diag > 0)


def test_heading_frame_stance_velocity_is_rotated_by_the_heading():
    t, acc, gyr = static(2400)
    yaw = math.radians(90.0)
    out = run_filter(t, acc, gyr, np.ones(len(t), bool), Q.from_euler_zyx(yaw, 0.0, 0.0),
                     stance_velocity=[0.01, 0.0, 0.0], config=FilterConfig(p0_vel=0.5))
    # the sensor reads rest, the pseudo-measurement says 1 cm/s forward: the estimate settles between them,
    # pointing north (forward at yaw 90 deg)
    v = out.vel[-1]
    assert v[1] > 1e-3 and abs(v[0]) < 1e-6 * v[1] and abs(v[2]) < 1e-6 * v[1]


@pytest.mark.parametrize("fs", [400.0, 800.0])
def test_process_noise_is_a_density_scaled_by_the_interval(fs):
    # level, unaided, 9 states: horizontal velocity variance = s_v0^2 + q_a T + g^2 (s_tilt^2 T^2 + q_g T^3 / 3),
    # the same at any sample rate
    T = 5.0
    t, acc, gyr = static(int(T * fs) + 1, fs=fs)
    cfg = FilterConfig(acc_noise_density=0.02, gyr_noise_density=1e-3, p0_vel=0.01, p0_tilt=1e-3)
    out = run_filter(t, acc, gyr, np.zeros(len(t), bool), [1, 0, 0, 0], config=cfg)
    expected = 0.01**2 + 0.02**2 * T + G**2 * (1e-3**2 * T**2 + 1e-3**2 * T**3 / 3)
    assert out.p_diag[-1, 3] == pytest.approx(expected, rel=2e-3)
    assert out.p_diag[-1, 5] == pytest.approx(0.01**2 + 0.02**2 * T, rel=1e-9)  # vertical: no tilt coupling


def test_fifteen_states_estimate_a_gyro_bias_with_zupts():
    # level static sensor, gyro bias on x and y: ZUPTs observe the tilt it causes, so the bias becomes observable
    b = np.array([2e-3, -1e-3, 0.0])
    t, acc, gyr = static(16000, gyr=b, noise=(0.01, 1e-3), seed=2)
    out = run_filter(t, acc, gyr, np.ones(len(t), bool), [1, 0, 0, 0], config=FilterConfig(states=15))
    np.testing.assert_allclose(out.bias_gyr[-1, :2], b[:2], atol=1e-4)
    assert np.max(np.abs(out.pos[-1])) < 1e-3


def test_zaru_needs_bias_states_and_unknown_sizes_are_rejected():
    with pytest.raises(ValueError, match="zaru"):
        FilterConfig(states=9, zaru=True)
    with pytest.raises(ValueError, match="states"):
        FilterConfig(states=21)
    with pytest.raises(ValueError, match="zupt_sigma"):
        FilterConfig(zupt_sigma=0.0)


def test_zaru_estimates_the_full_gyro_bias_including_yaw():
    b = np.array([1e-3, -2e-3, 3e-3])
    t, acc, gyr = static(4000, gyr=b, noise=(0.0, 1e-4), seed=3)
    out = run_filter(t, acc, gyr, np.ones(len(t), bool), [1, 0, 0, 0], config=FilterConfig(states=15, zaru=True))
    np.testing.assert_allclose(out.bias_gyr[-1], b, atol=2e-5)


def walk_like(runs, n, seed):
    """Random walk-like signals: periodic rest, noisy motion, per-run noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / FS
    phase = (np.arange(n) % 900) / 900
    moving = phase > 0.4
    acc = np.tile([0.0, 0.0, G], (runs, n, 1)) + rng.normal(0, 0.02, (runs, n, 3))
    gyr = rng.normal(0, 0.002, (runs, n, 3))
    swing = np.sin(2 * np.pi * (phase - 0.4) / 0.6)[None, :, None] * moving[None, :, None]
    acc = acc + swing * np.array([3.0, 0.2, 2.0])
    gyr = gyr + swing * np.array([0.1, 4.0, 0.05])
    stationary = np.tile(~moving, (runs, 1))
    return t, acc, gyr, stationary


@pytest.mark.parametrize("rts", [False, True])
def test_batch_equals_single_runs(rts):
    runs, n = 3, 4000
    t, acc, gyr, st = walk_like(runs, n, seed=4)
    q0 = Q.from_euler_zyx(np.array([0.1, 1.0, -2.0]), 0.0, 0.0)
    start = np.array([0, 5, 17])
    pv = np.random.default_rng(5).normal(0, 0.01, (runs, n, 3))
    cfg = FilterConfig(states=15, zaru=True)
    batch = run_filter_batch(t, acc, gyr, st, q0, start=start, config=cfg, stance_velocity=pv, rts=rts)
    for r in range(runs):
        single = run_filter(t, acc[r], gyr[r], st[r], q0[r], start=start[r], config=cfg, stance_velocity=pv[r],
                            rts=rts)
        for name in ("pos", "vel", "quat", "bias_gyr", "p_diag"):
            assert np.array_equal(getattr(batch, name)[r], getattr(single, name), equal_nan=True), name
        assert np.isnan(single.pos[: start[r]]).all()


def test_without_history_the_estimates_hold_the_last_sample_and_the_trajectory_is_unchanged():
    runs, n = 2, 3000
    t, acc, gyr, st = walk_like(runs, n, seed=7)
    q0 = Q.from_euler_zyx(np.array([0.3, -1.0]), 0.0, 0.0)
    cfg = FilterConfig(states=24, zaru=True)
    start = np.array([0, 11])
    for full, last in ((run_filter(t, acc[1], gyr[1], st[1], q0[1], start=11, config=cfg),
                        run_filter(t, acc[1], gyr[1], st[1], q0[1], start=11, config=cfg, history=False)),
                       (run_filter_batch(t, acc, gyr, st, q0, start=start, config=cfg),
                        run_filter_batch(t, acc, gyr, st, q0, start=start, config=cfg, history=False))):
        for name in ("pos", "vel", "quat"):
            np.testing.assert_array_equal(getattr(last, name), getattr(full, name))
        for name in ("bias_acc", "bias_gyr", "gsens", "p_diag"):
            kept, every = getattr(last, name), getattr(full, name)
            assert kept.shape[-2] == 1 and every.shape[-2] == n
            np.testing.assert_array_equal(kept[..., 0, :], every[..., -1, :])
    with pytest.raises(ValueError, match="rts=True needs history=True"):
        run_filter(t, acc[0], gyr[0], st[0], q0[0], config=cfg, rts=True, history=False)


def test_covariance_stays_positive_on_a_noisy_walk():
    t, acc, gyr, st = walk_like(1, 9000, seed=6)
    for states in (9, 15, 24):
        out = run_filter(t, acc[0], gyr[0], st[0], [1, 0, 0, 0], config=FilterConfig(states=states))
        assert out.skipped_updates == 0
        assert np.all(np.isfinite(out.p_diag)) and np.all(out.p_diag > 0)


def test_rts_smoother_removes_a_velocity_ramp_between_zupt_windows():
    # vertical accelerometer bias b, rest - 2 s without ZUPTs - rest. Filtered: the vertical velocity error ramps
    # to b T in the gap and is only found at the second window. With a random-walk velocity model the smoother
    # spreads that innovation linearly over the gap, which removes a linear ramp (up to the small ZUPT-window
    # residuals); the end sample is the filter's own.
    b, n = 0.05, 4800
    t, acc, gyr = static(n, acc=(0.0, 0.0, G + b))
    st = np.zeros(n, bool)
    st[:1600] = st[3200:] = True
    filt = run_filter(t, acc, gyr, st, [1, 0, 0, 0])
    smooth = run_filter(t, acc, gyr, st, [1, 0, 0, 0], rts=True)
    np.testing.assert_array_equal(smooth.pos[-1], filt.pos[-1])
    gap = slice(1600, 3200)
    ramp = b * 2.0
    assert np.max(np.abs(filt.vel[gap, 2])) > 0.9 * ramp
    assert np.max(np.abs(smooth.vel[gap, 2])) < 1e-3 * ramp
    assert np.max(np.abs(smooth.pos[gap, 2])) < 0.05 * np.max(np.abs(filt.pos[gap, 2]))


def test_read_only_inputs_reuse_the_compiled_filter():
    """An array's read-only flag is part of its numba type: read-only inputs (broadcast views, a memory-mapped
    recording) are handed over as writable arrays, so they run the filter already compiled for writable ones
    instead of compiling it again (about a minute)."""
    n = 400
    t = np.arange(n) / 100.0
    acc = np.tile([0.0, 0.0, 9.81], (n, 1))
    gyr = np.zeros((n, 3))
    stationary = np.ones(n, bool)
    writable = run_filter(t, acc, gyr, stationary, [1.0, 0, 0, 0], stance_velocity=np.zeros((n, 3)))
    compiled = set(kernels.filter_run.signatures)

    def read_only(x):
        return np.broadcast_to(np.asarray(x), np.shape(x))

    again = run_filter(read_only(t), read_only(acc), read_only(gyr), read_only(stationary), [1.0, 0, 0, 0],
                       vel0=read_only(np.zeros(3)), pos0=read_only(np.zeros(3)),
                       stance_velocity=read_only(np.zeros((n, 3))))
    assert set(kernels.filter_run.signatures) == compiled
    np.testing.assert_array_equal(again.pos, writable.pos)
    # the batch broadcasts what the runs share: each run is handed to the same compiled filter
    batch = run_filter_batch(t, np.stack([acc, acc]), np.stack([gyr, gyr]), stationary, [[1.0, 0, 0, 0]] * 2,
                             stance_velocity=np.zeros(3))
    assert set(kernels.filter_run.signatures) == compiled
    np.testing.assert_array_equal(batch.pos[1], writable.pos)
