"""Truth-simulator speed: simulated seconds per wall second for the 99.6 m walk at 800 Hz on one core.

Run: python benchmarks/truth_speed.py   (prints the figure the README reports; best of 3 runs)
"""

import os
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

from gaitsim.scenario import load_scenario  # noqa: E402
from gaitsim.simulate import simulate_world  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    scenario = load_scenario(ROOT / "scenarios/straight_100m.toml")
    best = float("inf")
    for _ in range(3):
        t0 = time.perf_counter()
        truth, _, _ = simulate_world(scenario, scenario.seed)
        best = min(best, time.perf_counter() - t0)
    simulated = truth.t[-1]
    print(f"truth of the 99.6 m walk: {len(truth.t)} samples at {scenario.rate_hz:.0f} Hz, {simulated:.1f} s simulated")
    print(f"wall time {best:.3f} s (best of 3) -> {simulated / best:.0f}x real time, {len(truth.t) / best:,.0f} samples/s")


if __name__ == "__main__":
    main()
