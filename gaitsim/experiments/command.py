"""``gaitsim reproduce`` and ``gaitsim run``: thin command-line layers over :mod:`gaitsim.experiments.reproduce`."""

from __future__ import annotations

import os
from pathlib import Path

# one BLAS thread per worker process: the Monte Carlo parallelises over runs, not inside them (these libraries read
# the variables when they load; numba's thread count is set in each worker instead, see runner._start_worker)
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from ..scenario import load_scenario
from .gait_study import STUDY, run_study
from .reproduce import PAPER, reproduce


def _reproduce(args) -> int:
    summary = reproduce(args.out, PAPER, quick=args.quick, workers=args.workers, scheduler=args.scheduler,
                        progress=not args.no_progress)
    print((Path(args.out) / "README.md").read_text().split("## Headline")[0])
    print("timings: " + ", ".join(f"{k} {v:.1f} s" for k, v in summary["timings_s"].items()))
    return 0


def _run(args) -> int:
    if load_scenario(args.scenario).experiment.get("study") == STUDY:
        run_study(args.out, args.scenario, quick=args.quick, workers=args.workers, scheduler=args.scheduler,
                  progress=not args.no_progress)
        print(f"{args.out}/gait_study.md written")
        return 0
    summary = reproduce(args.out, args.scenario, quick=args.quick, workers=args.workers, scheduler=args.scheduler,
                        progress=not args.no_progress)
    print(f"{args.out}/README.md written; timings: " + ", ".join(f"{k} {v:.1f} s" for k, v in summary["timings_s"].items()))
    return 0


def _common(p) -> None:
    p.add_argument("--quick", action="store_true", help="few runs and short walks (what the tests exercise)")
    p.add_argument("--workers", type=int, default=None, help="local worker processes (default: the scenario's)")
    p.add_argument("--scheduler", default=None, help="Dask scheduler address (needs the 'dask' extra)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def add_parser(sub) -> None:
    rep = sub.add_parser("reproduce", help="regenerate results/: the seed paper end to end, and beyond")
    rep.add_argument("--out", default="results", help="output folder (default: results)")
    _common(rep)
    rep.set_defaults(func=_reproduce)
    run = sub.add_parser("run", help="run an experiment scenario (a scenario with [nav] and [experiment] tables): "
                                     "the paper reproduction, or the gait study with [experiment] study = \"gaits\"")
    run.add_argument("scenario", help="experiment scenario TOML (see scenarios/paper.toml, scenarios/gait_study.toml)")
    run.add_argument("--out", required=True, help="output folder")
    _common(run)
    run.set_defaults(func=_run)
