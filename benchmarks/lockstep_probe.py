"""Probe for a lock-step batch: the 15-state covariance propagation over R runs at once, run index innermost.

    PYTHONPATH=$PWD python benchmarks/lockstep_probe.py [--runs 8 32 64 128] [--repeats 5]

nav's batch (nav._numba.ekf.filter_batch) runs each run's loop as a single run does, so it cannot beat a single
run per core. This probe measures what lock-step could give on the largest part of a sample, the propagation
``P <- Phi P Phi^T + Q``: the covariances of R runs are held as one (n, n, R) array and every block operation of
nav._numba.covariance.propagate becomes a loop over the runs. Each such loop is a single statement over a few
rows, so LLVM vectorises it across runs (a loop holding the whole column update, or copying the column out and
back, is not vectorised: its many row pointers exceed the aliasing checks LLVM will emit). The result is checked
bit-identical to nav's propagate per run, then both are timed in ns of CPU time per run and interval (best of
``--repeats``). It is a measurement, not part of the filter: the lock-step filter would also need the masked
updates and the per-run nominal state.
"""

from __future__ import annotations

import argparse

import numpy as np
from numba import njit

from nav._numba.covariance import dense_covariances, flat_covariances, propagate
from nav_speed import best_cpu_seconds  # a sibling script (benchmarks/ is on the path)

STATES = 15
STEPS = 20_000


@njit
def _column(X, j, h, a, C, first_row, ca, cg):
    """Column j of every run's X (n, n, R) <- Phi X[:, j] in place, rows first_row:9, as
    nav._numba.covariance._transition_column does it (forward, 15 states) with the runs innermost."""
    runs = X.shape[2]
    for i in range(3):
        if first_row < 6:
            for r in range(runs):
                ca[i, r] = C[i, 0, r] * X[9, j, r] + C[i, 1, r] * X[10, j, r] + C[i, 2, r] * X[11, j, r]
        for r in range(runs):
            cg[i, r] = C[i, 0, r] * X[12, j, r] + C[i, 1, r] * X[13, j, r] + C[i, 2, r] * X[14, j, r]
    if first_row == 0:  # position with the old velocity
        for i in range(3):
            for r in range(runs):
                X[i, j, r] = X[i, j, r] + h * X[3 + i, j, r]
    if first_row < 6:  # velocity with the old attitude
        for r in range(runs):
            X[3, j, r] = X[3, j, r] - h * ((a[1, r] * X[8, j, r] - a[2, r] * X[7, j, r]) + ca[0, r])
        for r in range(runs):
            X[4, j, r] = X[4, j, r] - h * ((a[2, r] * X[6, j, r] - a[0, r] * X[8, j, r]) + ca[1, r])
        for r in range(runs):
            X[5, j, r] = X[5, j, r] - h * ((a[0, r] * X[7, j, r] - a[1, r] * X[6, j, r]) + ca[2, r])
    for i in range(3):
        for r in range(runs):
            X[6 + i, j, r] = X[6 + i, j, r] - h * cg[i, r]


@njit
def propagate_runs(P, steps, h, a, C, power):
    """``steps`` propagations of every run's P (n, n, R) with a (3, R), C (3, 3, R), power (n,), in the order of
    nav._numba.covariance.propagate."""
    n, runs = P.shape[0], P.shape[2]
    ca = np.empty((3, runs))
    cg = np.empty((3, runs))
    for _ in range(steps):
        for j in range(n):
            _column(P, j, h, a, C, 0, ca, cg)
        for i in range(9):
            for j in range(i + 1, 9):
                for r in range(runs):
                    P[i, j, r], P[j, i, r] = P[j, i, r], P[i, j, r]
            for j in range(9, n):
                for r in range(runs):
                    P[j, i, r] = P[i, j, r]
        for j in range(9):
            _column(P, j, h, a, C, 3 * (j // 3), ca, cg)
        for i in range(9):
            for j in range(i + 1, 9):
                for r in range(runs):
                    P[i, j, r] = P[j, i, r]
        for i in range(n):
            for r in range(runs):
                P[i, i, r] += power[i] * h


@njit
def propagate_each(P, steps, h, a, C, f, power):
    """``steps`` propagations of each run's P (R, n * W), flat as nav holds it, by nav's propagate, one run after
    the other."""
    for _ in range(steps):
        for r in range(P.shape[0]):
            propagate(P[r], STATES, h, a[r], C[r], f[r], power)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, nargs="+", default=[8, 32, 64, 128], help="run counts R")
    parser.add_argument("--repeats", type=int, default=5, help="timed repeats, best kept (default 5)")
    args = parser.parse_args(argv)
    rng = np.random.default_rng(0)
    h = 1 / 800
    power = np.r_[[0.0] * 3, [3e-4] * 3, [8e-12] * 6, [0.0] * 3]
    for runs in args.runs:
        A = rng.normal(size=(runs, STATES, STATES)) * 1e-3
        P = A @ A.transpose(0, 2, 1)
        C = np.array([np.linalg.qr(rng.normal(size=(3, 3)))[0] for _ in range(runs)])
        f = rng.normal(size=(runs, 3)) + [0.0, 0.0, 9.81]
        a = np.einsum("rij,rj->ri", C, f)
        lanes = (np.ascontiguousarray(P.transpose(1, 2, 0)), np.ascontiguousarray(a.T),
                 np.ascontiguousarray(C.transpose(1, 2, 0)))
        flat = flat_covariances(P)  # held as nav holds it
        each, together = flat.copy(), lanes[0].copy()
        propagate_each(each, 50, h, a, C, f, power)
        propagate_runs(together, 50, h, lanes[1], lanes[2], power)
        if not np.array_equal(dense_covariances(each, STATES)[0], together.transpose(2, 0, 1)):
            print(f"R={runs}: lock-step differs from nav's propagate")
            return 1
        one = best_cpu_seconds(lambda: propagate_each(flat.copy(), STEPS, h, a, C, f, power), args.repeats)
        lock = best_cpu_seconds(lambda: propagate_runs(lanes[0].copy(), STEPS, h, lanes[1], lanes[2], power),
                                args.repeats)
        scale = 1e9 / (STEPS * runs)
        print(f"  R={runs:4d}: one run after another {one * scale:5.0f} ns, lock-step {lock * scale:5.0f} ns per run "
              f"and interval (bit-identical)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
