"""Where the 15-state forward filter's time goes: its compiled parts timed one by one in the same process.

    PYTHONPATH=$PWD python benchmarks/nav_parts.py [--repeats 5] [--calls 200000]

Each part is called ``--calls`` times in a compiled loop on the 99.6 m walk's samples (scenarios/straight_100m.toml)
and a covariance built from the filter's own variances at a stance sample; printed in ns of CPU time per call (the
best of ``--repeats``), next to the whole filter per sample (rk4, every sample's estimates kept) and the SHOE
detector per sample that nav_speed.py's ratios include. The ZUPT update is timed on a copy of P restored before each
call; the copy's own time, timed alone, is subtracted.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from numba import njit

from gaitsim.scenario import load_scenario
from gaitsim.simulate import simulate_walk
from nav import detectors
from nav._numba.covariance import joseph_update, propagate, update_buffers
from nav._numba.strapdown import MODE_POINT_SAMPLES, increment_buffers, interval_increments
from nav.alignment import align
from nav.ekf import FilterConfig, run_filter
from nav_speed import best_time  # a sibling script (benchmarks/ is on the path)

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
    n = P0.shape[0]
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
        for i in range(n):
            for j in range(n):
                P[i, j] = P0[i, j]
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
    P0 = np.diag(sol.p_diag[stance]).copy()
    power = np.zeros(STATES)
    power[3:9] = [cfg.acc_noise_density ** 2] * 3 + [cfg.gyr_noise_density ** 2] * 3
    _propagations(P0, 800, rec.t, fhat, C, power)  # correlate the states, as a stride's swing does
    z = np.array([0.01, -0.02, 0.005])
    r_var = np.full(3, cfg.zupt_sigma ** 2)
    calls = args.calls
    _increments(10, rec.t, rec.acc, rec.gyr)  # compile
    _updates(P0, 10, False, z, r_var)

    def cpu(fn):
        return best_time(fn, args.repeats, time.process_time)

    parts = {
        "SHOE detection, per sample": cpu(lambda: detectors.detect("shoe", rec.t, rec.acc, rec.gyr)) / rec.n,
        "whole filter, per sample": cpu(whole) / rec.n,
        "RK4 increments, per interval": cpu(lambda: _increments(calls, rec.t, rec.acc, rec.gyr)) / calls,
        "covariance propagation, per interval": cpu(lambda: _propagations(P0.copy(), calls, rec.t, fhat, C,
                                                                          power)) / calls,
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
