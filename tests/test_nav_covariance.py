"""The compiled covariance algebra on its flat storage (nav._numba.covariance: rows padded to a fixed stride) equals
the dense matrix algebra to round-off, keeps P exactly symmetric and leaves the padding exactly zero."""

import numpy as np
import pytest

from nav import quaternion as Q
from nav._numba.covariance import dense_covariances, flat_covariances, joseph_update, propagate, update_buffers

H_STEP = 1.0 / 800.0  # s


def dense_transition(n, h, C, f):
    """Phi = I + F h of the module docstring's error state, written out densely."""
    F = np.zeros((n, n))
    F[0:3, 3:6] = np.eye(3)
    F[3:6, 6:9] = -Q.skew(C @ f)
    if n >= 15:
        F[3:6, 9:12] = -C
        F[6:9, 12:15] = -C
    if n == 24:  # d(G f)_i / dG[i, c] = f_c, G row-major in states 15:24
        F[6:9, 15:24] = -C @ np.kron(np.eye(3), f[None, :])
    return np.eye(n) + F * h


def random_case(n, seed):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(n, n)) * np.geomspace(1e-1, 1e-4, n)  # states of very different sizes, as in the filter
    C = Q.to_matrix(Q.from_rotvec(rng.normal(size=3)))
    f = rng.normal(size=3) + [0.0, 0.0, 9.81]
    return rng, A @ A.T, C, f


@pytest.mark.parametrize("n", [9, 15, 24])
def test_propagation_equals_dense_phi_p_phi_t_plus_q(n):
    rng, P, C, f = random_case(n, n)
    power = rng.uniform(0.0, 1e-3, n)
    X = flat_covariances(P)
    propagate(X, n, H_STEP, C @ f, C, f, power)
    result, padding = dense_covariances(X, n)
    Phi = dense_transition(n, H_STEP, C, f)
    expected = Phi @ P @ Phi.T + np.diag(power) * H_STEP
    np.testing.assert_allclose(result, expected, rtol=0, atol=1e-13 * np.abs(expected).max())
    np.testing.assert_array_equal(result, result.T)
    assert not padding.any()


@pytest.mark.parametrize("n", [9, 15, 24])
@pytest.mark.parametrize("m", [1, 3])
def test_joseph_update_equals_the_dense_joseph_form(n, m):
    rng, P, _, _ = random_case(n, 100 + n)
    columns = [3, 4, 5][:m] if m == 3 else [2]  # the ZUPT's velocity rows, the level update's height row
    h_col = np.zeros((3, 4), np.int64)
    h_val = np.zeros((3, 4))
    h_cnt = np.zeros(3, np.int64)
    H = np.zeros((m, n))
    for r, c in enumerate(columns):
        h_col[r, 0], h_val[r, 0], h_cnt[r] = c, 1.0, 1
        H[r, c] = 1.0
    z = rng.normal(0.0, 0.01, 3)
    r_var = np.full(3, 1e-4)
    X = flat_covariances(P)
    dx, K, s = np.empty(n), np.empty((n, 3)), np.empty(3)
    assert joseph_update(X, n, h_col, h_val, h_cnt, m, z, r_var, dx, K, s, update_buffers(n))
    result, padding = dense_covariances(X, n)
    R = np.diag(r_var[:m])
    gain = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
    keep = np.eye(n) - gain @ H
    expected = keep @ P @ keep.T + gain @ R @ gain.T
    np.testing.assert_allclose(result, expected, rtol=0, atol=1e-12 * np.abs(expected).max())
    np.testing.assert_array_equal(result, result.T)
    assert not padding.any()
    np.testing.assert_allclose(dx, gain @ z[:m], rtol=1e-12, atol=0)


def test_a_non_positive_innovation_leaves_p_untouched():
    n = 15
    P = np.eye(n)
    P[3, 3] = -2.0  # S = P[3, 3] + R < 0
    X = flat_covariances(P)
    h_col, h_val, h_cnt = np.zeros((3, 4), np.int64), np.zeros((3, 4)), np.zeros(3, np.int64)
    h_col[0, 0], h_val[0, 0], h_cnt[0] = 3, 1.0, 1
    before = X.copy()
    assert not joseph_update(X, n, h_col, h_val, h_cnt, 1, np.zeros(3), np.full(3, 1e-4), np.empty(n),
                             np.empty((n, 3)), np.empty(3), update_buffers(n))
    np.testing.assert_array_equal(X, before)
