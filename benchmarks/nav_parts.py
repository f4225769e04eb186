"""Where the 15-state forward filter's time goes: its compiled parts timed one by one in the same process.

    PYTHONPATH=$PWD python benchmarks/nav_parts.py [--repeats 5] [--calls 200000]

Each part is called ``--calls`` times in a compiled loop on the 99.6 m walk's samples (scenarios/straight_100m.toml)
and a covariance built from the filter's own variances at a stance sample; printed in ns of CPU time per call (the
best of ``--repeats``), next to the whole filter per sample (rk4, every sample's estimates kept) and the SHOE
detector per sample that nav_speed.py's ratios include. The ZUPT update is timed on a copy of P restored before each
call; the copy's own time, timed alone, is subtracted. The state count is passed as a literal, as the filter passes
it (numba compiles a kernel per literal: its loops are unrolled for it). Besides the covariance algebra, a sample
costs the nominal state's advance by the increments, the store of its estimates (and variances) and, at a stance
sample, the injection of the correction (quaternion exponential, product, normalisation).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from numba import njit

from gaitsim.scenario import load_scenario
from gaitsim.simulate import simulate_walk
from nav import detectors
from nav._numba.covariance import flat_covariances, joseph_update, propagate, row_stride, update_buffers
from nav._numba.ekf import _inject, _store
from nav._numba.strapdown import MODE_POINT_SAMPLES, apply_increment, increment_buffers, interval_increments
from nav.alignment import align
from nav.ekf import FilterConfig, run_filter
from nav_speed import best_cpu_seconds  # a sibling script (benchmarks/ is on the path)

ROOT = Path(__file__).resolve().parents[1]
STATES = 15


@njit
def _propagations(P, calls, t, fhat, C, power):
    """``calls`` covariance propagations over the recording's intervals (P grows without updates; the time per
    call does not depend on its values, which stay finite and normal)."""
    a = C @ fhat
    for c in range(calls):
        k = c % (t.shape[0] - 1)
        propagate(P, STATES, t[k + 1] - t[k], a, C, fhat, power)


@njit
def _updates(P0, calls, restore_only, z, r_var):
    """``calls`` velocity updates (H selects states 3:6), each on a fresh copy of P0 (or the copy alone)."""
    n = STATES
    P = P0.copy()
    h_col = np.zeros((3, 4), np.int64)
    h_val = np.zeros((3, 4))
    h_cnt = np.ones(3, np.int64)
    for r in range(3):
        h_col[r, 0] = 3 + r
        h_val[r, 0] = 1.0
    dx = np.empty(n)
    K = np.empty((n, 3))
    s = np.empty(3)
    work = update_buffers(n)
    for _ in range(calls):
        for i in range(P.size):
            P[i] = P0[i]
        if not restore_only:
            joseph_update(P, n, h_col, h_val, h_cnt, 3, z, r_var, dx, K, s, work)
    return P


@njit
def _increments(calls, t, acc, gyr):
    """``calls`` RK4 increments over the recording's intervals, zero biases."""
    dq, du, ds, fhat, weights = increment_buffers()
    ba = np.zeros(3)
    bg = np.zeros(3)
    G = np.zeros(9)
    total = 0.0
    for c in range(calls):
        k = c % (t.shape[0] - 1)
        interval_increments(MODE_POINT_SAMPLES, k, t, acc, gyr, ba, bg, G, dq, du, ds, fhat, weights)
        total += dq[0]
    return total


@njit
def _increment_table(t, acc, gyr):
    """Every interval's RK4 increments, zero biases: (N - 1, 10) rows of dq (4), du (3), ds (3)."""
    table = np.empty((t.shape[0] - 1, 10))
    dq, du, ds, fhat, weights = increment_buffers()
    zero3, zero9 = np.zeros(3), np.zeros(9)
    for k in range(table.shape[0]):
        interval_increments(MODE_POINT_SAMPLES, k, t, acc, gyr, zero3, zero3, zero9, dq, du, ds, fhat, weights)
        table[k, :4], table[k, 4:7], table[k, 7:] = dq, du, ds
    return table


@njit
def _advances(calls, t, table, gravity):
    """``calls`` advances of the nominal state (attitude, velocity, position) by the increments of ``table``
    (:func:`_increment_table`)."""
    q = np.array([1.0, 0.0, 0.0, 0.0])
    v = np.zeros(3)
    p = np.zeros(3)
    dq, du, ds, _, _ = increment_buffers()
    for c in range(calls):
        k = c % table.shape[0]
        for i in range(4):  # the filter's increment buffers, filled as interval_increments fills them
            dq[i] = table[k, i]
        for i in range(3):
            du[i], ds[i] = table[k, 4 + i], table[k, 7 + i]
        apply_increment(q, v, p, dq, du, ds, t[k + 1] - t[k], gravity)
    return q[0]


@njit
def _stores(calls, n_samples, P):
    """``calls`` stores of a sample's estimates and variances into every-sample outputs of ``n_samples`` rows."""
    quat, vel, pos = np.empty((n_samples, 4)), np.empty((n_samples, 3)), np.empty((n_samples, 3))
    bias_acc, bias_gyr, gsens = np.empty((n_samples, 3)), np.empty((n_samples, 3)), np.empty((n_samples, 9))
    p_diag = np.empty((n_samples, STATES))
    q, v, p, ba, bg, G = np.ones(4), np.ones(3), np.ones(3), np.ones(3), np.ones(3), np.ones(9)
    for c in range(calls):
        k = c % n_samples
        _store(k, q, v, p, ba, bg, G, quat, vel, pos, bias_acc, bias_gyr, gsens)
        for i in range(STATES):
            p_diag[k, i] = P[i * (row_stride(STATES) + 1)]
    return quat[0, 0]


@njit
def _injections(calls, dx):
    """``calls`` injections of the error estimate ``dx`` into a nominal state, its sign alternated (so that the state
    stays near its start)."""
    q = np.array([1.0, 0.0, 0.0, 0.0])
    v, p, ba, bg, G = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(9)
    minus = -dx
    for c in range(calls):
        _inject(dx if c % 2 == 0 else minus, STATES, q, v, p, ba, bg, G)
    return q[0]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="timed repeats, best kept (default 5)")
    parser.add_argument("--calls", type=int, default=200_000, help="calls per timed part (default 200000)")
    args = parser.parse_args(argv)

    rec = simulate_walk(load_scenario(ROOT / "scenarios" / "straight_100m.toml"), seed=1)
    det = detectors.detect("shoe", rec.t, rec.acc, rec.gyr)
    alignment = align(rec.acc, det.stationary)
    cfg = FilterConfig(states=STATES)

    def whole():
        return run_filter(rec.t, rec.acc, rec.gyr, det.stationary, alignment.quat0, start=alignment.start,
                          config=cfg, method="rk4")

    # P: the filter's variances at a stance sample mid-walk, correlated by a second of propagation (a swing)
    stance_samples = np.flatnonzero(det.stationary)
    stance = stance_samples[len(stance_samples) // 2]
    sol = whole()
    C = np.eye(3)
    fhat = np.array([0.0, 0.0, cfg.gravity])
    P0 = flat_covariances(np.diag(sol.p_diag[stance]))  # held as the filter holds it
    power = np.zeros(STATES)
    power[3:9] = [cfg.acc_noise_density ** 2] * 3 + [cfg.gyr_noise_density ** 2] * 3
    _propagations(P0, 800, rec.t, fhat, C, power)  # correlate the states, as a stride's swing does
    z = np.array([0.01, -0.02, 0.005])
    r_var = np.full(3, cfg.zupt_sigma ** 2)
    calls = args.calls
    dx = np.concatenate([np.full(6, 1e-3), np.full(3, 1e-4), np.full(6, 1e-5)])  # a ZUPT's size of correction
    _increments(10, rec.t, rec.acc, rec.gyr)  # compile
    _updates(P0, 10, False, z, r_var)
    table = _increment_table(rec.t, rec.acc, rec.gyr)
    _advances(10, rec.t, table, cfg.gravity)
    _stores(10, rec.n, P0)
    _injections(10, dx)

    def cpu(fn):
        return best_cpu_seconds(fn, args.repeats)

    parts = {
        "SHOE detection, per sample": cpu(lambda: detectors.detect("shoe", rec.t, rec.acc, rec.gyr)) / rec.n,
        "whole filter, per sample": cpu(whole) / rec.n,
        "RK4 increments, per interval": cpu(lambda: _increments(calls, rec.t, rec.acc, rec.gyr)) / calls,
        "covariance propagation, per interval": cpu(lambda: _propagations(P0.copy(), calls, rec.t, fhat, C,
                                                                          power)) / calls,
        "nominal state advance, per interval": cpu(lambda: _advances(calls, rec.t, table, cfg.gravity)) / calls,
        "store of the estimates and variances, per sample": cpu(lambda: _stores(calls, rec.n, P0)) / calls,
        "injection of a correction, per update": cpu(lambda: _injections(calls, dx)) / calls,
    }
    restore = cpu(lambda: _updates(P0, calls, True, z, r_var))
    update = cpu(lambda: _updates(P0, calls, False, z, r_var))
    parts["ZUPT update (Joseph, 3 rows), per update"] = (update - restore) / calls
    share = det.stationary[alignment.start:].mean()
    width = max(len(k) for k in parts)
    for label, seconds in parts.items():
        print(f"  {label:<{width}}  {seconds * 1e9:7.0f} ns")
    print(f"  stance share of the samples: {share:.3f} (one ZUPT update each)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
