"""`gaitsim generate` end to end: simulated seconds per wall second, interpreter start and imports included.

    PYTHONPATH=$PWD python benchmarks/generate_speed.py [--runs 1] [--repeats 3] [--compare OTHER_CHECKOUT]

Times ``python3 -m gaitsim.cli generate scenarios/paper.toml --out DIR --runs N --no-progress`` as a fresh
process started in the repository root (so this checkout's code runs), best of ``--repeats``, and prints real
time (the recordings' simulated duration) over wall time and the CPU seconds of all its processes; with
``--compare`` another checkout's command is timed in turns with this one (so both share the load). Then, in
this process (imports already paid), the split of one run over the steps ``generate`` takes: the truth
(``simulate_world``), the sensor (``sense``) and writing the folder (``write_recording_into``, with the worker
processes ``generate`` uses); what the end-to-end wall time has beyond their sum is interpreter start, imports
and the scenario's parsing. Timings are informative only: other jobs share the machine.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "scenarios/paper.toml"


def end_to_end(roots: list[Path], runs: int, repeats: int) -> dict[Path, tuple[float, float, float]]:
    """Per checkout root: (best wall time s, its CPU time s (all processes), simulated s of all runs) of the
    generate command as a fresh process started there; the checkouts take turns, so they share the load."""
    from nav.recording import list_runs, read_recording

    best = {root: (float("inf"), float("nan"), float("nan")) for root in roots}
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(repeats):
            for k, root in enumerate(roots):
                out = Path(tmp) / f"out{k}-{i}"
                before = resource.getrusage(resource.RUSAGE_CHILDREN)
                t0 = time.perf_counter()
                subprocess.run([sys.executable, "-m", "gaitsim.cli", "generate", str(SCENARIO), "--out", str(out),
                                "--runs", str(runs), "--no-progress"], cwd=root, check=True,
                               stdout=subprocess.DEVNULL)
                wall = time.perf_counter() - t0
                after = resource.getrusage(resource.RUSAGE_CHILDREN)
                if wall < best[root][0]:
                    folders = list_runs(out) if runs > 1 else [out]
                    simulated = sum(float(read_recording(f).t[-1] - read_recording(f).t[0]) for f in folders)
                    cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
                    best[root] = (wall, cpu, simulated)
    return best


def split() -> dict[str, float]:
    """Wall seconds of each step of one run, in this process."""
    from gaitsim.scenario import load_scenario
    from gaitsim.simulate import sense, simulate_world
    from nav.recording import write_recording_into
    from nav.storage import format_workers

    scenario = load_scenario(SCENARIO)
    sense(*simulate_world(scenario, scenario.seed), scenario.sensor, scenario.seed)  # warm: lazy imports
    times = {}
    t0 = time.perf_counter()
    world = simulate_world(scenario, scenario.seed)
    times["truth (simulate_world)"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    rec = sense(*world, scenario.sensor, scenario.seed)
    times["sensor (sense)"] = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        write_recording_into(rec, Path(tmp), workers=format_workers())  # as generate writes
        times["writing (write_recording_into)"] = time.perf_counter() - t0
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1, help="runs generated per command (default 1)")
    parser.add_argument("--repeats", type=int, default=3, help="commands timed; the best counts (default 3)")
    parser.add_argument("--compare", type=Path, default=None,
                        help="another checkout (e.g. an older commit's worktree) timed in turns with this one")
    args = parser.parse_args()
    roots = [ROOT] + ([args.compare.resolve()] if args.compare else [])
    results = end_to_end(roots, args.runs, args.repeats)
    for root, (wall, cpu, simulated) in results.items():
        print(f"{root}: gaitsim generate {SCENARIO.relative_to(ROOT)} --runs {args.runs}: {simulated:.1f} s simulated "
              f"in {wall:.2f} s wall (best of {args.repeats}; {cpu:.2f} CPU s in all its processes) -> "
              f"{simulated / wall:.0f}x real time")
    print(f"load average now {os.getloadavg()[0]:.1f}; the split of this checkout's run:")
    wall = results[ROOT][0]
    steps = split()
    for name, seconds in steps.items():
        print(f"  {name:32s} {seconds:6.3f} s")
    rest = wall / args.runs - sum(steps.values())
    print(f"  {'start, imports, rest (per run)':32s} {rest:6.3f} s")


if __name__ == "__main__":
    main()
