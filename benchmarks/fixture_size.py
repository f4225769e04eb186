"""Size of a 100 m, 800 Hz fixture on disk in each storage form, and what the default form keeps exact.

The recording: ``scenarios/straight_100m.toml`` (99.6 m, 800 Hz) with the vn200 sensor (a noisy imu table
compresses worse than the ideal sensor's). Forms (:mod:`nav.storage`): gzip-compressed CSV (the default), plain
CSV, and either with a Parquet twin (needs pyarrow). Exactness is measured by reading the default form back:
the largest difference of every column group from the simulated values (0 = bit-identical).

Run: python benchmarks/fixture_size.py   (prints the table the README reports; write and read times are
informative only: other jobs share the machine)
"""

from __future__ import annotations

import dataclasses
import importlib.util
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from gaitsim.imu.presets import get_preset
from gaitsim.scenario import load_scenario
from gaitsim.simulate import simulate_walk
from nav.recording import TRUTH_COLUMNS, read_recording, write_recording

ROOT = Path(__file__).resolve().parents[1]
MB = 1e6


def folder_mb(folder: Path) -> dict[str, float]:
    """MB per file of a folder, and the total."""
    sizes = {p.name: p.stat().st_size / MB for p in sorted(folder.iterdir())}
    return {**sizes, "total": sum(sizes.values())}


def largest_differences(written: np.ndarray, read: np.ndarray) -> dict[str, float]:
    """Largest |read - written| of each truth column group (pos, vel, q, dv, ...: the name before ``_``), in the
    group's SI unit."""
    groups = np.array([name.split("_")[0] for name in TRUTH_COLUMNS])
    largest = np.max(np.abs(read - written), axis=0)
    return {g: float(largest[groups == g].max()) for g in dict.fromkeys(groups)}


def main() -> None:
    scenario = dataclasses.replace(load_scenario(ROOT / "scenarios/straight_100m.toml"), sensor=get_preset("vn200"))
    rec = simulate_walk(scenario, seed=scenario.seed)
    print(f"99.6 m walk, vn200 sensor, {scenario.rate_hz:.0f} Hz: {rec.n} samples, {rec.t[-1] - rec.t[0]:.1f} s")
    forms = [("csv.gz", False), ("csv", False), ("csv.gz", True)]
    if importlib.util.find_spec("pyarrow") is None:
        forms = forms[:2]
        print("(pyarrow not installed: no Parquet twin row)")
    work = Path(tempfile.mkdtemp(prefix="fixture-size-"))
    try:
        print("\n| form | imu | truth | events | total | write s | read s |\n|---|---|---|---|---|---|---|")
        for form, parquet in forms:
            folder = work / f"{form}-{parquet}"
            t0 = time.perf_counter()
            write_recording(rec, folder, form=form, parquet=parquet)
            t1 = time.perf_counter()
            back = read_recording(folder)
            t2 = time.perf_counter()
            mb = folder_mb(folder)
            part = {name: sum(v for k, v in mb.items() if k.startswith(name + ".")) for name in ("imu", "truth",
                                                                                                 "events")}
            label = form + (" + Parquet twin" if parquet else "")
            print(f"| {label} | {part['imu']:.1f} MB | {part['truth']:.1f} MB | {part['events']:.3f} MB | "
                  f"**{mb['total']:.1f} MB** | {t1 - t0:.1f} | {t2 - t1:.1f} |")
            if (form, parquet) == ("csv.gz", False):
                imu_exact = (np.array_equal(back.t, rec.t) and np.array_equal(back.acc, rec.acc)
                             and np.array_equal(back.gyr, rec.gyr))
                differences = largest_differences(rec.truth.as_table(), back.truth.as_table())
        print(f"\ndefault form read back: imu table bit-identical: {imu_exact}; truth, largest difference per "
              "column group: " + ", ".join(f"{g} {d:.2g}" for g, d in differences.items()))
    finally:
        shutil.rmtree(work)


if __name__ == "__main__":
    main()
