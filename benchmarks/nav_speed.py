"""Throughput of the shared ZUPT-aided EKF (nav) against gaitmap's RtsKalman, side by side on one recording.

    python benchmarks/nav_speed.py [--repeats 3] [--runs 64]

Recording: the simulator's 99.6 m straight walk (scenarios/straight_100m.toml, 800 Hz) when gaitsim.simulate is
available, else a synthetic 75 s, 800 Hz walk-like signal. Both filters get the same point samples (ours: RK4
mechanisation) and run their own zero-velocity detector; times include detection. Compile time is excluded
(one warm-up call each). gaitmap is an optional extra (``pip install .[bench]``); without it only our numbers
are printed.

Printed: samples/s for our 15-state forward filter (keeping every sample's estimates, and keeping the trajectory
alone with the final estimates, ``history=False``, as nav.pipeline runs it), our 15-state and 9-state filters
with the RTS smoother (gaitmap's RtsKalman is a 9-state filter with a full RTS pass, so 9-state + RTS is the
like-for-like pair), gaitmap, the ratios, and the batch of 64 runs in one compiled call against the same 64 runs
one call each, of the filter alone (no detection), both keeping every run's result and both in samples per CPU
second of this process (what a core delivers whatever the load; wall-clock rates per thread are printed too but
fall when other jobs share the cores).
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numba
import numpy as np

from gaitsim.interop.gaitmap import to_gaitmap
from nav import detectors
from nav.constants import DEFAULT_GRAVITY
from nav.alignment import align
from nav.ekf import FilterConfig, run_filter, run_filter_batch
from nav.recording import Recording

ROOT = Path(__file__).resolve().parents[1]


def load_recording() -> tuple[Recording, str]:
    """The simulator's 99.6 m walk, or a synthetic walk-like signal when the simulator is absent."""
    try:
        from gaitsim.scenario import load_scenario
        from gaitsim.simulate import simulate_walk
    except ImportError:
        return synthetic_recording(), "synthetic 75 s walk-like signal, 800 Hz (gaitsim.simulate not installed)"
    rec = simulate_walk(load_scenario(ROOT / "scenarios" / "straight_100m.toml"), seed=1)
    return rec, f"gaitsim straight_100m (99.6 m, {rec.t[-1]:.1f} s, 800 Hz, ideal sensor)"


def synthetic_recording(duration=75.0, fs=800.0, seed=0) -> Recording:
    """Rest for 2 s, then 1.43 s strides: 40 % stance with sensor noise, swing with large smooth motion."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(duration * fs)) / fs
    phase = np.clip(t - 2.0, 0, None) % 1.43 / 1.43
    swing = (t > 2.0) & (phase > 0.4)
    shape = np.where(swing, np.sin(2 * np.pi * (phase - 0.4) / 0.6), 0.0)[:, None]
    acc = np.array([0.0, 0.0, DEFAULT_GRAVITY]) + shape * [20.0, 1.0, 15.0] + rng.normal(0, 0.02, (len(t), 3))
    gyr = shape * [0.5, 6.0, 0.3] + rng.normal(0, 0.003, (len(t), 3))
    return Recording(t=t, acc=acc, gyr=gyr)


def best_time(fn, repeats: int, clock=time.perf_counter) -> float:
    """Shortest time (s) of ``repeats`` calls on ``clock``: wall by default, ``time.process_time`` for the CPU time
    of all threads of this process."""
    times = []
    for _ in range(repeats):
        t0 = clock()
        fn()
        times.append(clock() - t0)
    return min(times)


def ours(rec: Recording, states: int, rts: bool, history: bool = True):
    """Detection (SHOE, OpenShoe defaults) + alignment + EKF on point samples."""
    det = detectors.detect("shoe", rec.t, rec.acc, rec.gyr)
    a = align(rec.acc, det.stationary)
    return run_filter(rec.t, rec.acc, rec.gyr, det.stationary, a.quat0, start=a.start,
                      config=FilterConfig(states=states), method="rk4", rts=rts, history=history)


def gaitmap_runner(rec: Recording):
    """A callable running gaitmap's RtsKalman on the recording, or None when gaitmap is not installed."""
    try:
        from gaitmap.trajectory_reconstruction import RtsKalman
    except ImportError:
        return None
    det = detectors.detect("shoe", rec.t, rec.acc, rec.gyr)
    q0 = align(rec.acc, det.stationary).quat0
    data, fs = to_gaitmap(rec)
    initial = np.array([q0[1], q0[2], q0[3], q0[0]])  # scipy order (x, y, z, w)

    def run(frame=data):
        return RtsKalman(initial_orientation=initial).estimate(frame, sampling_rate_hz=fs)

    run(data.iloc[:4000])  # compile gaitmap's numba kernels
    return run


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="timed repeats, best kept (default 3)")
    parser.add_argument("--runs", type=int, default=64, help="runs in the lock-step batch (default 64)")
    args = parser.parse_args(argv)

    rec, description = load_recording()
    n = rec.n
    print(f"recording: {description}; {n} samples")
    rows = {}
    for label, states, rts, history in (("nav 15-state, forward", 15, False, True),
                                        ("nav 15-state, forward, trajectory only", 15, False, False),
                                        ("nav 15-state + RTS", 15, True, True), ("nav 9-state + RTS", 9, True, True)):
        ours(rec, states, rts, history)  # compile / warm up
        rows[label] = n / best_time(lambda: ours(rec, states, rts, history), args.repeats)

    gaitmap = gaitmap_runner(rec)
    if gaitmap is None:
        print("gaitmap is not installed (optional extra: pip install '.[bench]'); skipping the comparison")
    else:
        rows["gaitmap RtsKalman (9-state + RTS)"] = n / best_time(gaitmap, args.repeats)
    width = max(len(k) for k in rows)
    for label, rate in rows.items():
        print(f"  {label:<{width}}  {rate:>12,.0f} samples/s")
    if gaitmap is not None:
        g = rows["gaitmap RtsKalman (9-state + RTS)"]
        print(f"  ratio nav 15-state forward / gaitmap : {rows['nav 15-state, forward'] / g:.1f}x  (target >= 15x)")
        print(f"  ratio nav 15-state forward, trajectory only / gaitmap : "
              f"{rows['nav 15-state, forward, trajectory only'] / g:.1f}x")
        print(f"  ratio nav 15-state + RTS  / gaitmap : {rows['nav 15-state + RTS'] / g:.1f}x")
        print(f"  ratio nav 9-state + RTS   / gaitmap : {rows['nav 9-state + RTS'] / g:.1f}x  (like for like; target >= 10x)")

    # batch: the same walk with independent sensor noise per run, all runs in one compiled call
    rng = np.random.default_rng(1)
    acc = rec.acc[None] + rng.normal(0, 0.01, (args.runs, n, 3))
    gyr = rec.gyr[None] + rng.normal(0, 1e-3, (args.runs, n, 3))
    det = detectors.detect("shoe", rec.t, acc, gyr)
    starts, quats = [], []
    for r in range(args.runs):  # alignment is per run (cheap); the filter below is one call
        a = align(acc[r], det.stationary[r])
        starts.append(a.start)
        quats.append(a.quat0)
    cfg = FilterConfig(states=15)

    def batch():
        return run_filter_batch(rec.t, acc, gyr, det.stationary, np.array(quats), start=np.array(starts), config=cfg,
                                history=False)

    def singles(runs=args.runs):
        # the results kept, as the batch keeps them: a run whose output is dropped hands its memory to the next,
        # which then costs no page faults, while the batch (or a user collecting results) pays for all of it
        return [run_filter(rec.t, acc[r], gyr[r], det.stationary[r], quats[r], start=starts[r], config=cfg,
                           history=False) for r in range(runs)]

    batch()  # compile
    singles(1)
    seconds = best_time(batch, args.repeats)
    cpu_batch = best_time(batch, args.repeats, time.process_time)
    cpu_single = best_time(singles, args.repeats, time.process_time) / args.runs
    threads = numba.get_num_threads()
    total = args.runs * n / seconds
    print(f"  batch {args.runs} runs x {n} samples, 15-state forward, trajectory only: {total:,.0f} samples/s wall on "
          f"{threads} threads ({total / threads:,.0f} per thread, {seconds:.2f} s); "
          f"{args.runs * n / cpu_batch:,.0f} samples per CPU second")
    print(f"  single runs of the same filter (no detection): {n / cpu_single:,.0f} samples per CPU second; "
          f"batch / single per CPU second: {cpu_single * args.runs / cpu_batch:.2f}x (target > 1)")
    if not math.isfinite(total):
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
