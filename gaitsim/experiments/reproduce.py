"""``gaitsim reproduce``: the seed paper end to end, then beyond it, deterministic from scenarios/paper.toml.

Steps: the simulated calibration lab (own seed) -> stance pseudo-velocity from tracked calibration walks (own
seeds) -> Monte Carlo tasks through :func:`gaitsim.experiments.runner.run_tasks` (resumable, parallel, optionally
Dask) ->
gait-cycle analysis of run 0 -> tables, figures and results/README.md (:mod:`gaitsim.experiments.report`).
"""

from __future__ import annotations

import dataclasses
import shutil
import time
from pathlib import Path

import numpy as np

from nav.metrics import summarise_runs
from nav.files import publish_into, write_json

from ..errors import ScenarioError

from ..bundled import scenario_file
from .runner import run_tasks
from ..scenario import load_scenario, scenario_from_dict
from .tracker import TrackerSpec
from ..simulate import simulate_walk
from . import report
from .cycle import cycle_averages, detected_stance_s, predicted_length_loss
from .paper import build_tasks, quick_overrides
from .setup import (calibrate_sensor, fit_stance_velocity, matched_thresholds, scenario_doc,
                    settings_from_scenario, targets_from_scenario)
from .tasks import walk_task

PAPER = scenario_file("paper.toml")


def _collect(results: list[dict], tasks: list[dict], prefix: str) -> dict[str, list[dict]]:
    """Scores per variant name over the tasks whose key starts with ``prefix``."""
    out: dict[str, list[dict]] = {}
    for task, res in zip(tasks, results):
        if task["key"].startswith(prefix):
            for name, score in res["variants"].items():
                out.setdefault(name, []).append(score)
    return out


def working_folder(out: Path) -> Path:
    """Where a run of :func:`reproduce` into ``out`` is built: a hidden sibling kept after a failure or an
    interrupt (its Monte Carlo cache resumes the next run), moved into ``out`` when the run completes."""
    return out.parent / f".{out.name}.partial"


def reproduce(out: str | Path, scenario_path: str | Path = PAPER, quick: bool = False, workers: int | None = None,
              scheduler: str | None = None, progress: bool = True) -> dict:
    """Regenerate the report in ``out``; returns the summary numbers (also in ``out/summary.json``).

    Every input is validated before anything is written. The report is built in :func:`working_folder` and its
    files replace those of the same name in ``out`` only when everything succeeded (other files in ``out``
    stay); after a failure ``out`` is untouched and the working folder keeps the finished runs for the next call.
    """
    out = Path(out)
    timings = {}
    clock = time.perf_counter()
    scenario = load_scenario(scenario_path)
    nav, exp = settings_from_scenario(scenario)
    targets = targets_from_scenario(scenario)
    if scenario.sensor is None:
        raise ScenarioError(f"{scenario.source}: an experiment needs a [sensor] table (e.g. preset = \"paper-vn200\"): "
                            "its calibration lab and compensation study have nothing to calibrate without one")
    doc = scenario_doc(scenario)
    runs = scenario.runs
    if quick:
        doc, exp, runs = quick_overrides(doc, exp)
    if out.exists() and not out.is_dir():
        raise FileExistsError(f"{out}: exists and is not a folder; name a folder for the output")
    workers = None if scheduler else (exp.workers if workers is None else workers)
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise ScenarioError(f"workers = {workers!r}: must be an integer >= 1 (1 = serial)")
    final, out = out, working_folder(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.mkdir(exist_ok=True)
    cache = "cache-quick" if quick else "cache"
    if (final / cache).is_dir() and not (out / cache).exists():
        shutil.copytree(final / cache, out / cache)  # resume from the last complete run's Monte Carlo
    work = out / cache

    cal = calibrate_sensor(scenario, exp, out)
    stance, stance_info = fit_stance_velocity(doc, nav, exp, cal, out)
    detector_thresholds = matched_thresholds(doc, nav, exp, cal, exp.sensitivity_detectors)
    timings["calibration lab, stance-velocity walks and matched detector thresholds"] = time.perf_counter() - clock

    clock = time.perf_counter()
    tasks = build_tasks(doc, nav, exp, runs, scenario.seed, str(cal), str(stance), detector_thresholds)
    results = run_tasks(walk_task, tasks, work, workers=workers, scheduler=scheduler, progress=progress)
    timings[f"Monte Carlo ({len(tasks)} walks)"] = time.perf_counter() - clock

    clock = time.perf_counter()
    rec0 = simulate_walk(scenario_from_dict(doc, "cycle analysis"), seed=scenario.seed, run=0)
    tracker = TrackerSpec(exp.tracker_rate_hz, exp.tracker_resolution_m, exp.tracker_noise_m)
    thresholds = sorted(set(exp.fig4_thresholds) | set(exp.threshold_sweep))
    detector = nav.options()  # the [nav] detector settings in SI (converted once there)
    avg = cycle_averages(rec0, exp.cycle_count, detector.sigma_a, detector.sigma_g, detector.window,
                         thresholds, tracker, np.random.default_rng([scenario.seed, 7]))
    stance_s = detected_stance_s(avg)
    strides = results[0]["walk"]["strides"]
    predicted = predicted_length_loss(avg, avg.detected, strides)
    timings["gait-cycle analysis"] = time.perf_counter() - clock

    main = _collect(results, tasks, "main/")
    summary = {
        "quick": quick, "runs": runs, "scenario": Path(scenario_path).name, "nav": dataclasses.asdict(nav),
        "experiment": dataclasses.asdict(exp), "stance_velocity_fit": stance_info,
        "compensation": {v: summarise_runs(main[v]) for v in main if "@" not in v and ":" not in v},
        "headline_runs": {v: [{m: run[m] for m in (*report.METRICS, "heading_drift_deg_per_s")} for run in main[v]]
                          for v in ("before", "both")},
        "threshold_sweep": {float(v.split("@")[1]): [s["along_track_error_m"] for s in main[v]]
                            for v in main if v.startswith("before@")},
        "predicted_loss": {float(k): v for k, v in predicted.items()},
        "detected_stance": {float(k): v for k, v in stance_s.items()},
        "heading": _collect(results, tasks, "heading/")["g_sensitivity_alone"][0],
        "budget": {v: summarise_runs(s) for v, s in _collect(results, tasks, "budget/").items()},
        "sensitivity": _sensitivity(results, tasks, main),
        "sensitivity_detector_thresholds": detector_thresholds,
        "walk": {**results[0]["walk"], "stride_period_s": avg.cycle_s},
    }
    summary["timings_s"] = timings
    report.write(out, summary, main, avg, results, tasks, doc, targets)
    write_json(out / "summary.json", summary)
    publish_into(out, final)
    return summary


def _sensitivity(results, tasks, main) -> dict:
    rows = {}
    for task, res in zip(tasks, results):
        if task["key"].startswith("sensitivity/"):
            group = task["key"].split("/")[1].rsplit("-run-", 1)[0]
            for name, score in res["variants"].items():
                rows.setdefault(f"{group} {name}", []).append(score)
    for name, scores in main.items():
        if ":" in name:
            rows[name.replace(":", " ")] = scores
    return {k: summarise_runs(v) for k, v in rows.items()}
