"""The compiled filter (nav.ekf, block covariance algebra, adjoint smoother) equals the dense numpy reference
(nav.ekf_reference, textbook Joseph update and Rauch-Tung-Striebel pass) to round-off on a short noisy walk."""

import numpy as np
import pytest

from nav import quaternion as Q
from nav.ekf import FilterConfig, run_filter
from nav.ekf_reference import run_reference_filter
from nav_synthetic import synthetic_walk

STRIDES = 2  # 4.8 s at 800 Hz: 3841 samples, three stance windows


def noisy_walk(seed=3):
    """The synthetic walk seen by a biased, g-sensitive, noisy IMU (SI units), started 40 samples in."""
    rec = synthetic_walk(strides=STRIDES, stand=1.0)
    rng = np.random.default_rng(seed)
    n = len(rec.t)
    gsens = rng.normal(0.0, 2e-4, (3, 3))
    acc = rec.acc + [0.05, -0.03, 0.08] + rng.normal(0.0, 0.02, (n, 3))
    gyr = rec.gyr + [2e-3, -1e-3, 3e-3] + rec.acc @ gsens.T + rng.normal(0.0, 2e-3, (n, 3))
    start = 40
    truth = rec.truth
    stance_velocity = rng.normal(0.0, 0.005, (n, 3))
    return rec.t, acc, gyr, truth.stance, truth.quat[start], truth.vel[start], truth.pos[start], start, \
        stance_velocity


@pytest.mark.parametrize("states", [9, 15, 24])
@pytest.mark.parametrize("rts", [False, True])
@pytest.mark.parametrize("method", ["rk4", "increments"])
def test_compiled_filter_equals_the_numpy_reference(states, rts, method):
    t, acc, gyr, stationary, q0, v0, p0, start, stance_velocity = noisy_walk()
    if method == "increments":  # exact-increment samples: dv, dtheta over each interval (last row unused)
        h = np.append(np.diff(t), t[-1] - t[-2])[:, None]
        acc, gyr = acc * h, gyr * h
    q0 = Q.multiply(Q.from_rotvec(np.array([0.01, -0.02, 0.05])), q0)  # a start error for the filter to find
    config = FilterConfig(states=states, zaru=states >= 15, level_sigma=0.01)
    args = (t, acc, gyr, stationary, q0, v0, p0, start, config, method, stance_velocity, rts)
    compiled, reference = run_filter(*args), run_reference_filter(*args)
    assert compiled.skipped_updates == reference.skipped_updates == 0
    tolerances = {"pos": 1e-9, "vel": 1e-9, "quat": 1e-10, "bias_acc": 1e-9, "bias_gyr": 1e-10, "gsens": 1e-9}
    for name, atol in tolerances.items():
        a, b = getattr(compiled, name), getattr(reference, name)
        np.testing.assert_array_equal(np.isnan(a), np.isnan(b), err_msg=name)
        np.testing.assert_allclose(a[start:], b[start:], rtol=0, atol=atol, err_msg=name)
    # filtered variances (the smoother leaves them filtered): relative round-off of a propagated covariance
    np.testing.assert_allclose(compiled.p_diag[start:], reference.p_diag[start:], rtol=1e-8, atol=0)
    # the smoother did change the estimate (the comparison above is not of two filtered runs)
    if rts:
        filtered = run_filter(*args[:-1], rts=False)
        assert np.max(np.abs(filtered.pos[start:] - compiled.pos[start:])) > 1e-3
