"""Wall time of the sim-to-real loop on one recording, on one worker process and on two (issue 12: under 60 s on
2 cores).

    PYTHONPATH=$PWD python3 benchmarks/loop_time.py [--recordings gaitmap-healthy/left xio-ngimu/short_walk]

For each recording: :func:`gaitsim.loop.attribution.run_loop` with ``workers`` = 1 and 2 (the default budget of effects)
plus writing its report (:func:`gaitsim.loop.report.write_result`), each in this process, timed on the wall
clock with the machine's load average before and after (timings are only comparable at a similar load). The
attributions of the two runs are compared and must be identical: the worker count changes where the
simulations run, not what they give.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
import warnings
from pathlib import Path

from gaitsim.loop import attribution, report
from gaitsim.measured import load_dataset


def load(spec: str):
    """The shared recording ``dataset/name``."""
    dataset, name = spec.split("/")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the loaders' data-quality counts are tested elsewhere
        recordings = {r.meta["recording"]: r for r in load_dataset(dataset)}
    return recordings[name]


def timed_loop(rec, workers: int, folder: Path) -> tuple[float, list]:
    """Wall seconds of the loop and its report on ``workers`` processes, and the attributions."""
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = attribution.run_loop(rec, workers=workers)
    report.write_result(result, folder, "benchmark")
    return time.perf_counter() - start, result.attributions


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--recordings", nargs="+", default=["gaitmap-healthy/left", "xio-ngimu/short_walk"])
    args = parser.parse_args()
    print(f"{os.cpu_count()} cores")
    for spec in args.recordings:
        rec = load(spec)
        times, found = {}, {}
        for workers in (1, 2):
            load_before = os.getloadavg()[0]
            with tempfile.TemporaryDirectory() as tmp:
                times[workers], found[workers] = timed_loop(rec, workers, Path(tmp))
            print(f"{spec}: {workers} worker(s) {times[workers]:.1f} s (load average {load_before:.1f} -> "
                  f"{os.getloadavg()[0]:.1f})", flush=True)
        same = repr(found[1]) == repr(found[2])
        print(f"{spec}: two workers {times[1] / times[2]:.2f}x one; attributions identical: {same}")
        if not same:
            raise SystemExit(f"{spec}: the attributions differ between one and two workers")


if __name__ == "__main__":
    main()
