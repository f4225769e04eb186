"""How long each part of `gaitsim reproduce` takes (full run, into a temporary folder; 2 worker processes).

Run: python benchmarks/reproduce_time.py
"""

import tempfile
import time

from gaitsim.experiments.reproduce import reproduce


def main() -> None:
    with tempfile.TemporaryDirectory() as out:
        t0 = time.perf_counter()
        summary = reproduce(out, progress=False)
        total = time.perf_counter() - t0
    for part, seconds in summary["timings_s"].items():
        print(f"{part:45s} {seconds:7.1f} s")
    print(f"{'total (including figures and report)':45s} {total:7.1f} s")


if __name__ == "__main__":
    main()
