"""Laws of the IMU forward model (gaitsim.imu.model): each term alone, exactly or with a stated tolerance."""

import numpy as np
import pytest
from scipy.signal import butter, sosfreqz

from gaitsim.imu import kernels, model
from gaitsim.imu.model import SensorSpec, apply_sensor, mounting_rotation
from gaitsim.imu.presets import PRESET_NAMES, get_preset

RATE = 800.0


def walking_like_truth(n=4000, seed=0):
    """Smooth, rich truth: sums of sinusoids on top of gravity (m/s^2) and rates (rad/s)."""
    t = np.arange(n) / RATE
    rng = np.random.default_rng(seed)
    freqs = rng.uniform(0.5, 20.0, (6, 4))
    amps = rng.uniform(0.5, 5.0, (6, 4))
    signal = np.stack([(amps[c] * np.sin(2 * np.pi * freqs[c] * t[:, None])).sum(1) for c in range(6)], 1)
    acc = signal[:, :3] * 3.0 + np.array([0.0, 0.0, 9.81])
    gyr = signal[:, 3:]
    return t, acc, gyr


def only(**parameters) -> SensorSpec:
    return SensorSpec(name="test", parameters=parameters)


def run(spec, t, acc, gyr, seed=1, **kw):
    return apply_sensor(spec, t, acc, gyr, np.random.default_rng(seed), **kw)


def test_ideal_preset_is_the_identity_exactly():
    t, acc, gyr = walking_like_truth()
    t_m, acc_m, gyr_m = run(get_preset("ideal"), t, acc, gyr)
    assert np.array_equal(t_m, t) and np.array_equal(acc_m, acc) and np.array_equal(gyr_m, gyr)


def test_inputs_are_never_modified():
    t, acc, gyr = walking_like_truth()
    before = acc.copy(), gyr.copy()
    run(get_preset("paper-vn200"), t, acc, gyr)
    assert np.array_equal(acc, before[0]) and np.array_equal(gyr, before[1])


def test_only_g_sensitivity_adds_G_f():
    t, acc, gyr = walking_like_truth()
    G = np.deg2rad(np.array(get_preset("paper-vn200")["gyro_g_sensitivity"]))
    _, acc_m, gyr_m = run(only(gyro_g_sensitivity=G), t, acc, gyr)
    assert np.array_equal(acc_m, acc)
    np.testing.assert_allclose(gyr_m - gyr, acc @ G.T, rtol=0, atol=1e-15)


def test_only_accel_matrix_gives_M_f():
    t, acc, gyr = walking_like_truth()
    M = np.array(get_preset("paper-vn200")["accel_misalignment"])
    _, acc_m, gyr_m = run(only(accel_misalignment=M), t, acc, gyr)
    np.testing.assert_allclose(acc_m, acc @ M.T, rtol=0, atol=1e-13)
    assert np.array_equal(gyr_m, gyr)


def test_deterministic_model_inverts_exactly():
    t, acc, gyr = walking_like_truth()
    g2 = np.full((3, 3), 1e-6) + np.diag([3e-6, -2e-6, 1e-6])
    spec = get_preset("paper-vn200").replace(
        gyro_noise_density=0.0, accel_noise_density=0.0, gyro_bias_instability=0.0, accel_bias_instability=0.0,
        gyro_g2_sensitivity=g2)
    _, acc_m, gyr_m = run(spec, t, acc, gyr)
    acc_c, gyr_c = spec.deterministic().correct(acc_m, gyr_m)
    np.testing.assert_allclose(acc_c, acc, rtol=0, atol=1e-12)
    np.testing.assert_allclose(gyr_c, gyr, rtol=0, atol=1e-12)


def test_quantisation_step_equals_resolution():
    t = np.arange(4000) / RATE
    ramp = np.linspace(-3.0, 3.0, t.size)
    acc = np.column_stack([ramp, ramp * 0.5, ramp + 9.81])
    resolution = 0.0125
    _, acc_m, _ = run(only(accel_resolution=resolution), t, acc, np.zeros_like(acc))
    steps = np.diff(acc_m[:, 0])
    np.testing.assert_allclose(np.unique(np.round(steps[steps != 0], 12)), [resolution], rtol=1e-9)
    np.testing.assert_allclose(acc_m / resolution, np.round(acc_m / resolution), atol=1e-9)
    assert np.max(np.abs(acc_m - acc)) <= resolution / 2 + 1e-12


def test_quantisation_and_clipping_are_numpys_round_and_clip_exactly():
    """The compiled pass rounds halves to even and clips as np.round and np.clip do, bit for bit."""
    resolution, limit = 0.0625, 2.0  # exact binary steps: k + 1/2 steps are exact halves
    halves = (np.arange(-80, 80) + 0.5) * resolution
    values = np.concatenate([halves, np.random.default_rng(3).uniform(-3.0, 3.0, 3 * 2000 - halves.size)])
    acc = values.reshape(-1, 3)
    t = np.arange(acc.shape[0]) / RATE
    _, acc_m, _ = run(only(accel_resolution=resolution, accel_range=limit), t, acc, np.zeros_like(acc))
    assert np.array_equal(acc_m, np.clip(np.round(acc / resolution) * resolution, -limit, limit))


def every_term_on() -> SensorSpec:
    return get_preset("paper-vn200").replace(
        name="all terms", gyro_random_walk=1e-5, accel_random_walk=1e-4, gyro_bias_repeatability=1e-3,
        accel_bias_repeatability=1e-2, gyro_g2_sensitivity=np.full((3, 3), 1e-7), gyro_resolution=1e-4,
        accel_resolution=1e-3, gyro_bandwidth=250.0, accel_bandwidth=250.0, accel_temp_bias=1e-4,
        gyro_temp_bias=1e-5, accel_temp_scale=1e-4, gyro_temp_scale=1e-4, temperature=[20.0, 30.0],
        clock_error=50e-6, timestamp_jitter=1e-6, accel_gyro_skew=2e-4, mounting_misalignment=[0.01, -0.02, 0.03],
        gyro_bias_instability_tau=0.1)


def every_term_on_but_temperature() -> SensorSpec:
    """The deterministic terms' sums done in the noise pass (with temperature on, they are done before it)."""
    return every_term_on().replace(accel_temp_bias=0.0, gyro_temp_bias=0.0, accel_temp_scale=0.0,
                                   gyro_temp_scale=0.0)


@pytest.mark.parametrize("spec", [get_preset(name) for name in PRESET_NAMES] + [every_term_on(),
                                                                                   every_term_on_but_temperature()],
                         ids=[*PRESET_NAMES, "all-terms", "all-but-temperature"])
def test_compiled_kernels_and_numpy_reference_give_the_same_bits(spec, monkeypatch):
    t, acc, gyr = walking_like_truth(n=20_011)
    outputs = []
    for implementation in (kernels, model):
        monkeypatch.setattr(model, "_implementation", lambda n, chosen=implementation: chosen)
        outputs.append(run(spec, t, acc, gyr, seed=4))
    assert all(np.array_equal(a, b) for a, b in zip(*outputs))
    if spec.name != "ideal":
        assert not np.array_equal(outputs[0][1], acc)


@pytest.mark.parametrize("implementation", [kernels, model], ids=["compiled", "numpy"])
def test_a_sensor_with_biases_alone_leaves_its_truth_untouched_whatever_its_memory_order(implementation, monkeypatch):
    """Biases alone on every axis (identity matrices: the product distort skips, so the noise pass reads the
    truth itself): the output is distort's, byte for byte, for C- and F-ordered and read-only truth, and the
    truth is not written."""
    monkeypatch.setattr(model, "_implementation", lambda n: implementation)
    t, acc, gyr = walking_like_truth(n=5000)
    spec = only(accel_bias=[0.1, -0.2, 0.3], gyro_bias=[1e-3, -2e-3, 3e-3], accel_noise_density=1e-4)
    outputs = []
    for order in (np.ascontiguousarray, np.asfortranarray):
        acc_in, gyr_in = order(acc.copy()), order(gyr.copy())
        acc_in.flags.writeable = gyr_in.flags.writeable = False
        outputs.append(run(spec, t, acc_in, gyr_in)[1:])
        np.testing.assert_array_equal(acc_in, acc)
        np.testing.assert_array_equal(gyr_in, gyr)
    assert all(a.tobytes() == b.tobytes() for a, b in zip(*outputs))
    gyr_m = outputs[0][1]
    assert gyr_m.tobytes() == spec.deterministic().distort(acc, gyr)[1].tobytes()  # the gyro has no noise


@pytest.mark.parametrize("implementation", [kernels, model], ids=["compiled", "numpy"])
def test_deterministic_sums_in_the_noise_pass_are_distorts_bits(implementation, monkeypatch):
    """Without temperature terms the biases and G_g f are added in the noise pass: the bits of
    Calibration.distort, compared byte for byte, on inputs and biases holding signed zeros."""
    monkeypatch.setattr(model, "_implementation", lambda n: implementation)
    t, acc, gyr = walking_like_truth(n=5000)
    acc[::7], gyr[::5], gyr[1::5, 1] = -0.0, -0.0, 0.0
    limit = 1e3  # the clip makes the noise pass run; nothing reaches it
    for spec in (only(accel_bias=[-0.0, 0.0, 0.1], gyro_bias=[-0.0, -0.0, 0.0], accel_range=limit, gyro_range=limit,
                      gyro_misalignment=np.diag([1.0, 1.0, 1.001])),
                 only(gyro_g_sensitivity=np.full((3, 3), 1e-3), gyro_bias=[-0.0, 0.0, 1e-3], gyro_range=limit)):
        _, acc_m, gyr_m = run(spec, t, acc, gyr)
        expected = spec.deterministic().distort(acc, gyr)
        assert acc_m.tobytes() == expected[0].tobytes() and gyr_m.tobytes() == expected[1].tobytes()
        assert np.any(acc_m == 0.0) and np.any(gyr_m == 0.0)


def test_saturation_clips_exactly_at_range():
    t = np.arange(2000) / RATE
    ramp = np.linspace(-40.0, 40.0, t.size)
    gyr = np.column_stack([ramp, -ramp, ramp * 0.1])
    limit = np.deg2rad(2000.0)
    _, _, gyr_m = run(only(gyro_range=limit), t, np.zeros_like(gyr), gyr)
    assert gyr_m.max() == limit and gyr_m.min() == -limit
    inside = np.abs(gyr) < limit
    assert np.array_equal(gyr_m[inside], gyr[inside])


def test_bandwidth_starts_in_steady_state_and_has_the_butterworth_gain():
    t = np.arange(8000) / RATE
    still = np.tile([0.1, -0.2, 9.81], (t.size, 1))
    _, acc_m, _ = run(only(accel_bandwidth=100.0), t, still, np.zeros_like(still))
    np.testing.assert_allclose(acc_m, still, rtol=0, atol=1e-12)
    f = 60.0
    sine = np.column_stack([np.sin(2 * np.pi * f * t)] * 3)
    _, _, gyr_m = run(only(gyro_bandwidth=100.0), t, np.zeros_like(sine), sine)
    late = slice(4000, None)
    gain = np.sqrt(2 * np.mean(gyr_m[late, 0] ** 2))
    _, h = sosfreqz(butter(2, 100.0, fs=RATE, output="sos"), worN=[f], fs=RATE)
    assert gain == pytest.approx(abs(h[0]), rel=2e-3)


@pytest.mark.parametrize("order", [1, 2, 3])
def test_an_analogue_low_pass_has_the_analogue_filter_s_poles_unit_dc_gain_and_no_zero_at_nyquist(order):
    """filter_kind = "analogue": order 1 is the sampled RC stage y[k] = y[k-1] + a (x[k] - y[k-1]) with
    a = 1 - exp(-2 pi f_c / fs); any order keeps a constant input unchanged from the first sample and passes the
    Nyquist frequency, which the digital (bilinear) Butterworth of the same cutoff blocks."""
    fc = 60.0
    t = np.arange(8000) / RATE
    still = np.tile([0.1, -0.2, 9.81], (t.size, 1))
    analogue = dict(accel_bandwidth=fc, gyro_bandwidth=fc)
    _, acc_m, _ = run(only(**analogue).replace(filter_order=order, filter_kind="analogue"), t, still,
                      np.zeros_like(still))
    np.testing.assert_allclose(acc_m, still, rtol=0, atol=1e-12)
    alternating = np.column_stack([(-1.0) ** np.arange(t.size)] * 3)
    gains = {}
    for kind in ("analogue", "digital"):
        _, _, gyr_m = run(only(**analogue).replace(filter_order=order, filter_kind=kind), t,
                          np.zeros_like(alternating), alternating)
        gains[kind] = np.abs(gyr_m[4000:, 0]).max()
    assert gains["digital"] < 1e-6 < 0.01 < gains["analogue"]
    if order == 1:
        rng = np.random.default_rng(3)
        x = rng.normal(size=(t.size, 3))
        a = 1.0 - np.exp(-2.0 * np.pi * fc / RATE)
        expected = x.copy()
        for k in range(1, t.size):
            expected[k] = expected[k - 1] + a * (x[k] - expected[k - 1])
        _, _, gyr_m = run(only(**analogue).replace(filter_order=1, filter_kind="analogue"), t, np.zeros_like(x), x)
        np.testing.assert_allclose(gyr_m, expected, rtol=0, atol=1e-12)


def test_temperature_bias_and_scale_follow_the_ramp():
    t = np.arange(4000) / RATE
    acc = np.tile([1.0, -2.0, 9.81], (t.size, 1))
    slope, scale = np.array([1e-3, 2e-3, -1e-3]), np.array([1e-4, 0.0, -2e-4])
    spec = only(accel_temp_bias=slope, accel_temp_scale=scale, temperature=[20.0, 40.0], temperature_ref=25.0)
    _, acc_m, _ = run(spec, t, acc, np.zeros_like(acc))
    delta = (20.0 + 20.0 * (t - t[0]) / (t[-1] - t[0]) - 25.0)[:, None]
    np.testing.assert_allclose(acc_m, acc * (1 + scale * delta) + slope * delta, rtol=0, atol=1e-12)


def test_clock_error_and_skew_sample_truth_at_the_right_instants():
    t = np.arange(8000) / RATE
    w = 2 * np.pi * 3.0
    acc = np.column_stack([np.sin(w * t)] * 3)
    clock, skew = 200e-6, 1.5e-3
    t_m, acc_m, gyr_m = run(only(clock_error=clock, accel_gyro_skew=skew), t, acc, acc.copy())
    k = np.round((t_m - t[0]) * RATE).astype(int)
    np.testing.assert_allclose(t_m, t[0] + k / RATE, atol=1e-12)
    instants = t[0] + k / RATE / (1 + clock)
    np.testing.assert_allclose(acc_m[:, 0], np.sin(w * instants), atol=1e-7)
    np.testing.assert_allclose(gyr_m[:, 0], np.sin(w * (instants + skew)), atol=1e-7)
    # a fast clock takes more samples over the span; those whose gyro instant passes the end are dropped
    assert instants[-1] + skew <= t[-1] < instants[-1] + skew + 1 / RATE / (1 + clock)
    t_fast, _, _ = run(only(clock_error=clock), t, acc, acc.copy())
    assert t_fast.size == int((t.size - 1) * (1 + clock)) + 1 > t.size


def test_timestamp_jitter_has_the_configured_std():
    t = np.arange(20000) / RATE
    t_m, _, _ = run(only(timestamp_jitter=50e-6), t, np.zeros((t.size, 3)), np.zeros((t.size, 3)))
    assert np.std(t_m - t) == pytest.approx(50e-6, rel=0.03)


def test_mounting_misalignment_rotates_into_the_sensor_frame():
    t, acc, gyr = walking_like_truth(n=100)
    rpy = np.deg2rad([2.0, -3.0, 90.0])
    _, acc_m, gyr_m = run(only(mounting_misalignment=rpy), t, acc, gyr)
    rotation = mounting_rotation(rpy)
    np.testing.assert_allclose(acc_m, acc @ rotation, atol=1e-12)  # R^T f for each row
    np.testing.assert_allclose(gyr_m @ rotation.T, gyr, atol=1e-12)
    yaw_only = mounting_rotation(np.deg2rad([0.0, 0.0, 90.0]))
    np.testing.assert_allclose(yaw_only.T @ [1.0, 0.0, 0.0], [0.0, -1.0, 0.0], atol=1e-15)


def test_turn_on_bias_is_constant_in_a_run_and_spreads_across_runs():
    t = np.arange(200) / RATE
    zeros = np.zeros((t.size, 3))
    sigma = 0.01
    offsets = []
    for seed in range(300):
        _, acc_m, _ = run(only(accel_bias_repeatability=sigma), t, zeros, zeros, seed=seed)
        assert np.ptp(acc_m, axis=0).max() == 0.0
        offsets.append(acc_m[0])
    assert np.std(offsets) == pytest.approx(sigma, rel=0.1)


def test_gauss_markov_stationary_std():
    t = np.arange(200_000) / 100.0
    zeros = np.zeros((t.size, 3))
    instability = 1e-3
    spec = only(gyro_bias_instability=instability, gyro_bias_instability_tau=2.0)
    _, _, gyr_m = run(spec, t, zeros, zeros)
    assert np.std(gyr_m) == pytest.approx(0.664 / 0.6174 * instability, rel=0.05)


def test_each_term_draws_from_its_own_stream():
    t, acc, gyr = walking_like_truth()
    accel_only = only(accel_noise_density=1e-3)
    more = only(accel_noise_density=1e-3, gyro_noise_density=1e-4, gyro_random_walk=1e-4,
                accel_bias_repeatability=0.0, gyro_bias_instability=1e-4, timestamp_jitter=1e-6)
    _, acc_a, _ = run(accel_only, t, acc, gyr, seed=5)
    _, acc_b, gyr_b = run(more, t, acc, gyr, seed=5)
    assert np.array_equal(acc_a, acc_b)
    _, _, gyr_c = run(more.replace(gyro_random_walk=0.0, gyro_bias_instability=0.0), t, acc, gyr, seed=5)
    _, _, gyr_white = run(only(gyro_noise_density=1e-4), t, acc, gyr, seed=5)
    np.testing.assert_allclose(gyr_c, gyr_white, rtol=0, atol=0)
    assert not np.array_equal(gyr_b, gyr_c)


def test_seeded_runs_are_reproducible_and_seeds_differ():
    t, acc, gyr = walking_like_truth()
    spec = get_preset("bmi160")
    first = run(spec, t, acc, gyr, seed=11)
    again = run(spec, t, acc, gyr, seed=11)
    other = run(spec, t, acc, gyr, seed=12)
    assert all(np.array_equal(a, b) for a, b in zip(first, again))
    assert not np.array_equal(first[1], other[1])


def test_bad_inputs_are_refused():
    t, acc, gyr = walking_like_truth(n=50)
    with pytest.raises(ValueError, match=r"acc and gyr must be \(50, 3\)"):
        run(get_preset("vn200"), t, acc[:, :2], gyr)
    with pytest.raises(ValueError, match="temperature profile"):
        run(only(accel_temp_bias=1e-3), t, acc, gyr, temperature=np.zeros(7))
