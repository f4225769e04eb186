"""A scenario simulated: the world's truth, the one sensor stage, and recording folders written atomically.

>>> from gaitsim.scenario import load_scenario
>>> from gaitsim.simulate import simulate_walk
>>> rec = simulate_walk(load_scenario("scenarios/straight_100m.toml"), seed=1)   # doctest: +SKIP

A run's randomness comes from two independent generators (:func:`run_generators`): the gait's stride
variability and the sensor's errors, so experiments can vary one alone. The returned
:class:`nav.recording.Recording` carries the truth, the per-stance events and the IMU output: the ideal sensor
(the truth itself) unless the scenario has a [sensor] section.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from tqdm import tqdm

from nav import storage
from nav.constants import STANDARD_GRAVITY
from nav.files import atomic_output_dir
from nav.recording import Events, Recording, Truth, write_recording_into

from . import __version__
from .imu.model import SensorSpec, apply_sensor
from .scenario import Scenario, section_table
from .world.gait import LABELLED_STANCES
from .world.truth import simulate_truth

IDEAL_SENSOR = {"name": "ideal", "withheld": False, "note": "imu.csv holds the exact truth (no sensor model)"}


def run_generators(seed: int, run: int = 0) -> tuple[np.random.Generator, np.random.Generator]:
    """Independent generators (gait variability, sensor errors) of run ``run`` of a scenario seeded ``seed``."""
    ss = np.random.SeedSequence(entropy=seed, spawn_key=(run,))
    gait_ss, sensor_ss = ss.spawn(2)
    return np.random.default_rng(gait_ss), np.random.default_rng(sensor_ss)


def describe(scenario: Scenario, seed: int, run: int) -> dict:
    """meta.json content of a simulated recording (the sensor part is added by :func:`sense`)."""
    w = scenario.walk
    return {
        "generator": f"gaitsim {__version__}",
        "scenario": scenario.name,
        "scenario_file": scenario.source,
        "seed": seed,
        "run": run,
        "frames": {
            "world": "ENU, z up, flat non-rotating earth",
            "body": "IMU sensor axes; with the default mount x toward the toes, y left, z up when the foot is flat",
            "quaternion": "(w, x, y, z), body to world",
        },
        "sampling": {"rate_hz": scenario.rate_hz, "gravity_mps2": scenario.gravity},
        "path": scenario.path_table,
        "gait": section_table(w.gait),
        "impact": section_table(w.impact),
        "micromotion": section_table(w.micro),
        "mount": section_table(scenario.mount),
        "stance_label": LABELLED_STANCES[w.gait.labelled_stance],
    }


def simulate_world(scenario: Scenario, seed: int, run: int = 0) -> tuple[Truth, Events, dict]:
    """Truth, events and meta (without its sensor part) of run ``run`` of ``scenario`` seeded ``seed``."""
    gait_rng, _ = run_generators(seed, run)
    truth, events = simulate_truth(scenario.walk, scenario.mount, scenario.rate_hz, scenario.gravity, gait_rng)
    return truth, events, describe(scenario, seed, run)


def sense(truth: Truth, events: Events, meta: dict, sensor: SensorSpec | None, seed: int, run: int = 0) -> Recording:
    """The sensor stage: ``sensor`` (None: the ideal sensor) applied to the truth with the sensor generator of
    run ``run`` seeded ``seed``, and the recording with ``meta`` plus the declared sensor."""
    if sensor is None:
        t, acc, gyr = truth.t.copy(), truth.acc.copy(), truth.gyr.copy()
        declared = dict(IDEAL_SENSOR)
    else:
        _, sensor_rng = run_generators(seed, run)
        t, acc, gyr = apply_sensor(sensor, truth.t, truth.acc, truth.gyr, sensor_rng)
        declared = sensor.declared()
    return Recording(t=t, acc=acc, gyr=gyr, meta={**meta, "sensor": declared}, truth=truth, events=events)


def simulate_walk(scenario: Scenario, seed: int | None = None, run: int = 0) -> Recording:
    """One run of ``scenario``: truth, events and the sensor output, deterministic from (seed, run).

    Parameters
    ----------
    scenario : Scenario
    seed : base seed; default the scenario's.
    run : run index; each run draws its own stride variability and sensor errors.
    """
    seed = scenario.seed if seed is None else seed
    return sense(*simulate_world(scenario, seed, run), scenario.sensor, seed, run)


def generate(scenario: Scenario, out: str | Path, seed: int | None = None, runs: int | None = None,
             overwrite: bool = False, form: str = storage.DEFAULT_FORM, parquet: bool = False,
             progress: bool = False, workers: int | None = None) -> list[Recording]:
    """Simulate ``runs`` runs of ``scenario`` and write them to ``out`` (nothing is left there on failure).

    With one run the recording is ``out`` itself; with several, ``out/run-000``, ``out/run-001``, ...
    ``form`` and ``parquet`` choose how the tables are stored (:func:`nav.recording.write_recording`);
    ``progress`` shows a progress bar over the runs; ``workers`` processes format the tables' text (default:
    :func:`nav.storage.format_workers`; the bytes are the same with any number).
    """
    workers = storage.format_workers() if workers is None else workers
    runs = scenario.runs if runs is None else runs
    if runs < 1:
        raise ValueError(f"runs = {runs}: must be >= 1")
    storage.check_form(form)
    if parquet:
        storage.require_pyarrow()
    recordings = []
    with atomic_output_dir(out, overwrite) as tmp:
        for r in tqdm(range(runs), desc=f"generate {scenario.name}", unit="run", disable=not progress or runs == 1):
            rec = simulate_walk(scenario, seed=seed, run=r)
            folder = tmp if runs == 1 else tmp / f"run-{r:03d}"
            folder.mkdir(exist_ok=True)
            write_recording_into(rec, folder, form=form, parquet=parquet, workers=workers)
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
        f"  peak specific force {fmag.max() / STANDARD_GRAVITY:.1f} g, peak angular rate {wmag.max():.0f} deg/s",
        f"  labelled stance {tr.stance.mean() * 100:.1f} % of samples, mean stance speed "
        f"{in_stance.mean() * 1000:.2f} mm/s, true stance displacement {np.linalg.norm(ev.stance_displacement, axis=1).sum():.3f} m",
        f"  sensor: {_sensor_name(rec.meta.get('sensor', {}))}",
    ]
    return "\n".join(lines)


def _sensor_name(declared: dict) -> str:
    if declared.get("withheld"):
        return "parameters withheld from the metadata"
    return declared.get("name", "ideal")
