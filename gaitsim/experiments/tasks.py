"""One Monte Carlo task: a walk simulated once, then every sensor variant and filter variant asked of it.

Tasks are JSON dicts (see :func:`walk_task`) so the runner can store, resume and distribute them; the result
depends on the task only (seeds live in it), never on the worker or the order of completion.
"""

from __future__ import annotations

import numpy as np

from nav.pipeline import run_variants
from nav.recording import Recording

from ..imu.config import sensor_from_table
from ..scenario import scenario_from_dict
from ..simulate import sense, simulate_world
from .setup import NavSettings

TRACK_POINTS = 200  # decimated track kept for figures
SCORES = ("along_track_error_m", "perpendicular_error_m", "final_error_m", "length_ratio", "heading_drift_deg_per_s",
          "ate_m")  # what a task keeps of each variant's scores (nav.metrics), besides the stationary fraction


def _nav_options(nav: NavSettings, variant: dict):
    changes = {}
    if variant.get("calibration"):
        changes["calibration"] = variant["calibration"]
        changes["calibration_terms"] = tuple(variant.get("calibration_terms", ("bias", "misalignment", "g_sensitivity")))
    if variant.get("stance_velocity"):
        changes["stance_velocity"] = variant["stance_velocity"]
    for key in ("threshold", "detector"):
        if key in variant:
            changes[key] = variant[key]
    return nav.options(**changes)


def walk_task_spec(key: str, scenario: dict, seed: int, run: int, nav: dict, sensors: dict, variants: list[dict],
                   keep: tuple = ()) -> dict:
    """A :func:`walk_task` task: its keys, in the order the studies store them."""
    return {"key": key, "scenario": scenario, "seed": seed, "run": run, "nav": nav, "sensors": sensors,
            "variants": variants, "keep_tracks": list(keep)}


def walk_task(task: dict) -> dict:
    """Simulate the task's walk once and navigate it under each variant.

    Task keys: ``scenario`` (scenario dict), ``seed``, ``run``, ``nav`` (NavSettings fields), ``sensors``
    ({name: [sensor] table or None for the ideal sensor}), ``variants`` (list of {name, sensor, and optional
    calibration, calibration_terms, stance_velocity, threshold, detector}), ``keep_tracks`` (variant names).

    Returns {"variants": {name: scores}, "walk": {...}} with the scores the reports use.
    """
    scenario = scenario_from_dict(task["scenario"], task["key"])
    nav = NavSettings(**task["nav"])
    truth, events, meta = simulate_world(scenario, task["seed"], task["run"])
    recordings: dict[str, Recording] = {}
    for name, table in task["sensors"].items():  # common random numbers across sensor variants
        sensor = None if table is None else sensor_from_table(table, f"{task['key']} sensor {name}")
        recordings[name] = sense(truth, events, meta, sensor, task["seed"], task["run"])
    results = {}
    for name, recording in recordings.items():  # a recording's variants together: its input checks run once
        variants = [v for v in task["variants"] if v["sensor"] == name]
        navigated = run_variants(recording, [_nav_options(nav, v) for v in variants], secondary=False)
        results.update({v["name"]: solution_score for v, solution_score in zip(variants, navigated)})
    out = {}
    keep = set(task.get("keep_tracks", ()))
    for variant in task["variants"]:
        sol, score = results[variant["name"]]
        entry = {k: float(score[k]) for k in SCORES}
        entry["stationary_fraction"] = float(sol.stationary.mean())
        if variant["name"] in keep:
            idx = np.linspace(sol.start, len(sol.t) - 1, TRACK_POINTS).astype(int)
            entry["track_xy"] = np.round(sol.pos[idx, :2], 4).tolist()
        out[variant["name"]] = entry
    stance = np.linalg.norm(events.stance_displacement, axis=1).sum()
    return {"variants": out, "walk": {"duration_s": float(truth.t[-1]), "strides": int(len(events.t_ic) - 1),
                                      "true_stance_displacement_m": float(stance)}}
