"""Monte Carlo at scale: N walks of the paper scenario through the two headline pipelines, timed step by step.

    PYTHONPATH=$PWD python benchmarks/monte_carlo_scale.py [--walks 100] [--workers 2] [--no-dask]

Each walk is one task of :func:`gaitsim.experiments.tasks.walk_task` -- the function ``gaitsim reproduce`` runs --
with the paper's sensor (scenarios/paper.toml [sensor]) and the two headline variants of
:func:`gaitsim.experiments.paper.compensation_variants`: "before" (bias and misalignment removed) and "both" (the
full estimated calibration plus the fitted stance pseudo-velocity), i.e. one truth, one IMU model and two filter
runs per walk. The compensation is estimated once, as ``gaitsim reproduce`` does, from separate data (the
simulated calibration lab and tracked calibration walks with their own seeds); that one-off cost is printed apart.

The tasks run through :func:`gaitsim.experiments.runner.run_tasks` (its local process pool: forkserver workers
with one numba and one BLAS thread each), then again on a local Dask cluster through the same function's
``scheduler`` path, and the per-walk scores of the two are compared exactly (the maximum absolute difference must
be 0).

The per-step split is measured inside the workers by timing the functions ``walk_task`` calls (see
:data:`STEPS`); the step functions themselves are unchanged, so the results are those of the unwrapped code.
Each step is timed on the wall clock and on the worker thread's CPU clock. Scheduling overhead = wall time -
summed work / workers. The extrapolations to 1000 walks (see :func:`report`) assume the per-walk work and the
overhead per walk stay as measured.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import importlib
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from gaitsim.experiments import tasks as walk_tasks
from gaitsim.experiments.paper import compensation_variants
from gaitsim.experiments.runner import run_tasks
from gaitsim.experiments.setup import calibrate_sensor, fit_stance_velocity, scenario_doc, settings_from_scenario
from gaitsim.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[1]
HEADLINE = ("before", "both")  # the two pipelines of the paper's Table I
TARGET_WALKS = 1000
TARGET_S = 300.0  # the target: 1000 walks in 5 minutes

# step -> the (module, function) pairs whose time it sums; "compensation" runs inside nav.pipeline._prepare (the
# "checks, detection, alignment" step) and is subtracted from it, so every step is exclusive.
STEPS = {
    "truth": [("gaitsim.experiments.tasks", "simulate_world")],
    "IMU model": [("gaitsim.experiments.tasks", "sense")],
    "compensation": [("nav.pipeline", "_calibrate"), ("nav.pipeline", "_stance_velocity")],
    "checks, detection, alignment": [("nav.pipeline", "_prepare")],
    "filter": [("nav.pipeline", "run_filter"), ("nav.pipeline", "run_filter_batch")],
    "scoring": [("nav.pipeline", "score_solution")],
}
NESTED = {"checks, detection, alignment": "compensation"}  # outer step -> the step timed inside it


CLOCKS = {"wall": time.perf_counter, "cpu": time.thread_time}  # cpu: the calling thread's CPU time, s (a Dask
# worker's own threads do not count)


@contextlib.contextmanager
def timed_steps(seconds: dict[str, dict[str, float]]):
    """Wrap the functions of :data:`STEPS` so each call adds its time (s) on each of :data:`CLOCKS` to
    ``seconds[clock][step]``."""
    originals = []

    def timed(step, fn):
        def wrapper(*args, **kwargs):
            start = {clock: read() for clock, read in CLOCKS.items()}
            try:
                return fn(*args, **kwargs)
            finally:
                for clock, read in CLOCKS.items():
                    seconds[clock][step] += read() - start[clock]
        return wrapper

    try:
        for step, targets in STEPS.items():
            for clock in CLOCKS:
                seconds.setdefault(clock, {})[step] = 0.0
            for module_name, name in targets:
                module = importlib.import_module(module_name)
                fn = getattr(module, name)
                originals.append((module, name, fn))
                setattr(module, name, timed(step, fn))
        yield seconds
    finally:
        for module, name, fn in reversed(originals):
            setattr(module, name, fn)


def timed_walk(task: dict) -> dict:
    """``walk_task(task)`` and the seconds it spent per step on each clock:
    {"scores": ..., "seconds": {clock: {step: s}}}."""
    seconds: dict[str, dict[str, float]] = {}
    start = {clock: read() for clock, read in CLOCKS.items()}
    with timed_steps(seconds):
        scores = walk_tasks.walk_task(task)
    for clock, read in CLOCKS.items():
        total = read() - start[clock]
        for outer, inner in NESTED.items():
            seconds[clock][outer] -= seconds[clock][inner]
        seconds[clock]["rest of the task"] = total - sum(seconds[clock].values())
    return {"scores": scores, "seconds": seconds}


def build_walks(walks: int, out: Path) -> tuple[list[dict], float]:
    """The N walk tasks and the seconds spent estimating the compensation (calibration lab + stance fit)."""
    scenario = load_scenario(ROOT / "scenarios" / "paper.toml")
    nav, exp = settings_from_scenario(scenario)
    doc = scenario_doc(scenario)
    start = time.perf_counter()
    calibration = calibrate_sensor(scenario, exp, out)
    stance, _ = fit_stance_velocity(doc, nav, exp, calibration, out)
    setup_s = time.perf_counter() - start
    variants = [v for v in compensation_variants(str(calibration), str(stance), list(exp.before_calibration_terms))
                if v["name"] in HEADLINE]
    tasks = [walk_tasks.walk_task_spec(f"walk-{r:04d}", doc, scenario.seed, r, dataclasses.asdict(nav),
                                       {"paper": doc["sensor"]}, variants) for r in range(walks)]
    return tasks, setup_s


def run_timed(tasks: list[dict], out: Path, **backend) -> tuple[list[dict], float]:
    """Results of ``timed_walk`` over ``tasks`` through ``run_tasks`` (fresh folder: nothing reused), wall time (s)."""
    start = time.perf_counter()
    results = run_tasks(timed_walk, tasks, out, progress=False, **backend)
    return results, time.perf_counter() - start


def score_values(results: list[dict]) -> np.ndarray:
    """Every per-walk number (scores of both variants and the walk's own figures) in a fixed order."""
    values = []
    for result in results:
        scores = result["scores"]
        for name in HEADLINE:
            values += [scores["variants"][name][key] for key in sorted(scores["variants"][name])]
        values += [scores["walk"][key] for key in sorted(scores["walk"])]
    return np.array(values, float)


def report(results: list[dict], wall_s: float, workers: int, setup_s: float) -> None:
    """Print the per-walk cost by step, the overhead, the wall time and the extrapolation to 1000 walks.

    A step's steady cost is its median over the walks. Wall times include waiting for a core on a shared machine;
    CPU times (the worker's own) do not. Two extrapolations: at this load, the measured wall time per walk times
    1000; on an idle machine, the median CPU work per walk over the workers plus the one-off CPU cost of a fresh
    worker (what its walks took beyond the medians in sum: numba compilation or loading its cache) and the
    measured scheduling overhead.
    """
    n = len(results)
    steps = list(results[0]["seconds"]["wall"])
    print(f"{'step':30s} {'wall s/walk':>11s} {'CPU s/walk':>10s} {'CPU share':>9s}   (medians over the walks)")
    steady, one_off = {}, {}
    for clock in CLOCKS:
        seconds = {step: np.array([r["seconds"][clock][step] for r in results]) for step in steps}
        steady[clock] = {step: float(np.median(seconds[step])) for step in steps}
        one_off[clock] = sum(float(seconds[step].sum()) - n * steady[clock][step] for step in steps)
    work = {clock: sum(steady[clock].values()) for clock in CLOCKS}
    for step in steps:
        print(f"{step:30s} {steady['wall'][step]:11.4f} {steady['cpu'][step]:10.4f} "
              f"{steady['cpu'][step] / work['cpu']:9.1%}")
    print(f"{'steady work per walk':30s} {work['wall']:11.4f} {work['cpu']:10.4f}")
    print(f"one-off CPU per worker process: {one_off['cpu'] / workers:.1f} s (numba compile or cache load)")
    summed_work = sum(r["seconds"]["wall"][step] for r in results for step in steps)
    overhead = (wall_s - summed_work / workers) / n
    print(f"scheduling overhead: {overhead:.4f} s per walk (wall - summed work / {workers} workers, per walk)")
    print(f"wall time, {n} walks on {workers} workers: {wall_s:.1f} s ({wall_s / n:.3f} s per walk); "
          f"one-off compensation estimate (calibration lab + stance-velocity walks, parent): {setup_s:.1f} s")
    at_load = setup_s + TARGET_WALKS * wall_s / n
    idle = setup_s + one_off["cpu"] / workers + TARGET_WALKS * (work["cpu"] / workers + max(overhead, 0.0))
    for label, projected in (("at this load (wall per walk)", at_load), ("on an idle machine (CPU times)", idle)):
        verdict = "meets" if projected <= TARGET_S else "misses"
        print(f"extrapolated {label}: {TARGET_WALKS} walks on {workers} workers = {projected:.0f} s "
              f"({projected / 60:.1f} min) with the one-off estimate; {verdict} the {TARGET_S / 60:.0f}-minute target")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--walks", type=int, default=100, help="number of walks (default 100)")
    parser.add_argument("--workers", type=int, default=2, help="local pool and Dask workers (default 2)")
    parser.add_argument("--no-dask", action="store_true", help="skip the Dask run and its equality check")
    args = parser.parse_args()
    if args.walks < 1 or args.workers < 1:
        parser.error(f"--walks {args.walks} and --workers {args.workers} must both be >= 1")
    print(f"{args.walks} walks of scenarios/paper.toml, pipelines {', '.join(HEADLINE)}; "
          f"load average before: {', '.join(f'{x:.2f}' for x in os.getloadavg())}")
    with tempfile.TemporaryDirectory(prefix="monte-carlo-scale-") as tmp:
        tmp = Path(tmp)
        tasks, setup_s = build_walks(args.walks, tmp)
        results, wall_s = run_timed(tasks, tmp / "pool", workers=args.workers)
        print(f"\nlocal process pool (gaitsim.experiments.runner), {args.workers} workers:")
        report(results, wall_s, args.workers, setup_s)
        if not args.no_dask:
            import distributed

            with distributed.LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                                          dashboard_address=":0") as cluster, distributed.Client(cluster) as client:
                dask_results, dask_wall_s = run_timed(tasks, tmp / "dask", scheduler=client)
            print(f"\nlocal Dask cluster, {args.workers} workers x 1 thread:")
            report(dask_results, dask_wall_s, args.workers, setup_s)
            pool_values, dask_values = score_values(results), score_values(dask_results)
            same_nan = np.array_equal(np.isnan(pool_values), np.isnan(dask_values))
            finite = ~np.isnan(pool_values)
            difference = np.max(np.abs(pool_values[finite] - dask_values[finite]), initial=0.0)
            print(f"\nper-walk numbers, pool vs Dask: {pool_values.size} values, max abs difference {difference:g}, "
                  f"NaN at the same places: {same_nan}")
            if difference != 0.0 or not same_nan:
                raise SystemExit("pool and Dask results differ")
    print(f"load average after: {', '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
