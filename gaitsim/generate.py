"""Generate recordings from a scenario: one folder, or ``run-NNN`` folders for several runs, written atomically."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from nav.files import atomic_output_dir
from nav.recording import Recording, write_recording_into

from .scenario import Scenario
from .truth import simulate_walk


def generate(scenario: Scenario, out: str | Path, seed: int | None = None, runs: int | None = None,
             overwrite: bool = False) -> list[Recording]:
    """Simulate ``runs`` runs of ``scenario`` and write them to ``out`` (nothing is left there on failure).

    With one run the recording is ``out`` itself; with several, ``out/run-000``, ``out/run-001``, ...
    """
    runs = scenario.runs if runs is None else runs
    if runs < 1:
        raise ValueError(f"runs = {runs}: must be >= 1")
    recordings = []
    with atomic_output_dir(out, overwrite) as tmp:
        for r in range(runs):
            rec = simulate_walk(scenario, seed=seed, run=r)
            folder = tmp if runs == 1 else tmp / f"run-{r:03d}"
            folder.mkdir(exist_ok=True)
            write_recording_into(rec, folder)
            recordings.append(rec)
    return recordings


def summary(rec: Recording) -> str:
    """A few lines describing a simulated recording."""
    tr, ev = rec.truth, rec.events
    dist = np.sum(np.linalg.norm(np.diff(tr.pos[:, :2], axis=0), axis=1))
    fmag = np.linalg.norm(tr.acc, axis=1)
    wmag = np.rad2deg(np.linalg.norm(tr.gyr, axis=1))
    in_stance = np.linalg.norm(tr.vel[tr.stance], axis=1)
    lines = [
        f"scenario {rec.meta.get('scenario')}  seed {rec.meta.get('seed')}  run {rec.meta.get('run')}",
        f"  {rec.n} samples at {1 / np.median(np.diff(rec.t)):.0f} Hz, {tr.t[-1]:.2f} s, {len(ev.t_ic) - 1} strides",
        f"  IMU-site path length {dist:.3f} m, start-to-end {np.linalg.norm(tr.pos[-1, :2] - tr.pos[0, :2]):.3f} m",
        f"  peak specific force {fmag.max() / 9.81:.1f} g, peak angular rate {wmag.max():.0f} deg/s",
        f"  labelled stance {tr.stance.mean() * 100:.1f} % of samples, mean stance speed "
        f"{in_stance.mean() * 1000:.2f} mm/s, true stance displacement {np.linalg.norm(ev.stance_displacement, axis=1).sum():.3f} m",
        f"  sensor: {_sensor_name(rec.meta.get('sensor', {}))}",
    ]
    return "\n".join(lines)


def _sensor_name(declared: dict) -> str:
    if declared.get("withheld"):
        return "parameters withheld from the metadata"
    return declared.get("name", "ideal")
