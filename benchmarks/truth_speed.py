"""Truth-simulator speed: simulated seconds per wall second for the 99.6 m walk at 800 Hz on one core.

Run: python benchmarks/truth_speed.py [--repeats 5]   (prints the figure the README reports: the best of the
repeats, on the wall clock and on the process's CPU clock, which waiting for a busy core does not inflate)
"""

import argparse
import os
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

from gaitsim.scenario import load_scenario  # noqa: E402
from gaitsim.simulate import simulate_world  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=5, help="runs of the walk; the best counts (default 5)")
    args = parser.parse_args()
    if args.repeats < 1:
        parser.error(f"--repeats {args.repeats} must be >= 1")
    scenario = load_scenario(ROOT / "scenarios/straight_100m.toml")
    best = {"wall": float("inf"), "CPU": float("inf")}
    for _ in range(args.repeats):
        start = {"wall": time.perf_counter(), "CPU": time.process_time()}
        truth, _, _ = simulate_world(scenario, scenario.seed)
        best["wall"] = min(best["wall"], time.perf_counter() - start["wall"])
        best["CPU"] = min(best["CPU"], time.process_time() - start["CPU"])
    simulated = truth.t[-1]
    print(f"truth of the 99.6 m walk: {len(truth.t)} samples at {scenario.rate_hz:.0f} Hz, {simulated:.1f} s simulated; "
          f"load average {os.getloadavg()[0]:.2f}")
    for clock, seconds in best.items():
        print(f"{clock} time {seconds:.3f} s (best of {args.repeats}) -> {simulated / seconds:.0f}x real time, "
              f"{len(truth.t) / seconds:,.0f} samples/s")


if __name__ == "__main__":
    main()
