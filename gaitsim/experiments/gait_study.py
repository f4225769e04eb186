"""The gait study (issue 17): the seed paper's pipelines across gait kinds and cadences.

An experiment scenario with ``[experiment] study = "gaits"`` (scenarios/gait_study.toml) is run by ``gaitsim run``
through this module instead of the paper reproduction. Its [experiment] table holds the paper's calibration keys
(lab seed, tracked calibration walks, tracker, stance profile knots, the "before" terms, workers) and

``gaits``  list of "kind@cadence" (kinds of :mod:`gaitsim.world.gaits`, cadence in steps/min), each walked along
           the scenario's [path] with the kind's speed-dependent defaults at that cadence.

Per gait: the readout calibration of the scenario's sensor (one simulated lab, shared), the stance
pseudo-velocity fitted from tracked calibration walks *of that gait* (the paper's step 2 is "the expected
residual velocity for the gait and threshold"), then ``runs`` Monte Carlo walks navigated by the paper's
pipelines: ``before`` (the "before" calibration terms, zero pseudo-velocity) and ``both`` (full calibration and
the gait's pseudo-velocity). Reported per gait and pipeline: the length underestimate, 100 (1 - length ratio) %
(positive: the estimate is short), and the heading drift (deg/s), mean and spread over runs.

Outputs (``out``): gait_study.json (settings, every task and its per-run scores, the summary), gait_study.png,
gait_study.md, calibration.json and the fitted stance pseudo-velocities under stance/ (the inputs a test needs to
recompute one run and compare it with the committed JSON).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np

from nav.files import publish_into, write_json, write_text_atomic
from nav.metrics import summarise_runs

from ..errors import ScenarioError
from ..scenario import load_scenario, scenario_from_dict
from ..world.gaits import KINDS
from .paper import compensation_variants
from .reproduce import working_folder
from .runner import run_tasks
from .setup import calibrate_sensor, fit_stance_velocity, patched, scenario_doc, settings_from_scenario
from .tasks import walk_task, walk_task_spec

STUDY = "gaits"
PIPELINES = ("before", "both")
QUICK_LENGTH_M = 14.0


def parse_gaits(value, where: str) -> list[tuple[str, float]]:
    """[(kind, cadence steps/min)] of the ``gaits`` list ("kind@cadence"); errors name the entry."""
    if not (isinstance(value, list) and value):
        raise ScenarioError(f"{where}: gaits = {value!r} must be a non-empty list of \"kind@cadence\"")
    out = []
    for entry in value:
        kind, _, cadence = str(entry).partition("@")
        try:
            rate = float(cadence)
        except ValueError:
            rate = math.nan
        if kind not in KINDS[1:] or not math.isfinite(rate):
            raise ScenarioError(f"{where}: gaits entry {entry!r} is not allowed; write \"kind@cadence\" with kind one "
                                f"of {', '.join(KINDS[1:])} and the cadence in steps/min")
        out.append((kind, rate))
    return out


def study_tasks(doc: dict, gaits: list[tuple[str, float]], nav_fields: dict, runs: int, seed: int, cal: str,
                stances: dict[str, str], before_terms: list[str]) -> list[dict]:
    """Monte Carlo tasks (see :func:`gaitsim.experiments.tasks.walk_task`) of every gait and run."""
    tasks = []
    for kind, cadence in gaits:
        label = gait_label(kind, cadence)
        variants = [v for v in compensation_variants(cal, stances[label], before_terms) if v["name"] in PIPELINES]
        for r in range(runs):
            tasks.append(walk_task_spec(f"gaits/{label}/run-{r:03d}", gait_doc(doc, kind, cadence), seed, r,
                                        nav_fields, {"paper": doc["sensor"]}, variants))
    return tasks


def gait_label(kind: str, cadence: float) -> str:
    return f"{kind}-{cadence:g}"


def gait_doc(doc: dict, kind: str, cadence: float) -> dict:
    """The scenario document walked at gait ``kind`` and ``cadence`` steps/min (the kind's defaults)."""
    return patched(doc, gait={"kind": kind, "cadence_steps_per_min": float(cadence)})


def gait_summary(scores: list[dict]) -> dict:
    """Length underestimate (%) and heading drift (deg/s) over runs: mean, std, min, max."""
    rows = [{"length_underestimate_pct": 100.0 * (1.0 - s["length_ratio"]),
             "heading_drift_deg_per_s": s["heading_drift_deg_per_s"], "final_error_m": s["final_error_m"]}
            for s in scores]
    return summarise_runs(rows)


def run_study(out: str | Path, scenario_path: str | Path, quick: bool = False, workers: int | None = None,
              scheduler: str | None = None, progress: bool = True) -> dict:
    """Run the gait study of ``scenario_path`` into ``out`` (built in a working folder, published on success);
    returns the summary (also in gait_study.json)."""
    out = Path(out)
    scenario = load_scenario(scenario_path)
    table = dict(scenario.experiment)
    where = f"{scenario.source} [experiment]"
    if table.pop("study", None) != STUDY:
        raise ScenarioError(f"{where}: study = {scenario.experiment.get('study')!r}; the gait study needs "
                            f"study = {STUDY!r}")
    gaits = parse_gaits(table.pop("gaits", None), where)
    nav, exp = settings_from_scenario(dataclasses.replace(scenario, experiment=table))
    if scenario.sensor is None:
        raise ScenarioError(f"{scenario.source}: the gait study needs a [sensor] table (its pipelines calibrate it)")
    doc = scenario_doc(scenario)
    runs = scenario.runs
    if quick:
        doc = patched(doc, path={**doc["path"], "length_m": QUICK_LENGTH_M})
        exp = dataclasses.replace(exp, calibration_walks=1)
        gaits, runs = gaits[:2], 1
    for kind, cadence in gaits:  # every gait validated before anything is written
        scenario_from_dict(gait_doc(doc, kind, cadence), f"{scenario.source} gait {gait_label(kind, cadence)}")
    workers = None if scheduler else (exp.workers if workers is None else workers)

    final, out = out, working_folder(out)
    (out / "stance").mkdir(parents=True, exist_ok=True)
    cal = calibrate_sensor(scenario, exp, out)
    stances = {}
    for kind, cadence in gaits:
        label = gait_label(kind, cadence)
        folder = out / "stance" / label
        folder.mkdir(exist_ok=True)
        stances[label] = str(fit_stance_velocity(gait_doc(doc, kind, cadence), nav, exp, cal, folder)[0])
    before = list(exp.before_calibration_terms)
    tasks = study_tasks(doc, gaits, dataclasses.asdict(nav), runs, scenario.seed, str(cal), stances, before)
    results = run_tasks(walk_task, tasks, out / ("cache-quick" if quick else "cache"), workers=workers,
                        scheduler=scheduler, progress=progress)

    per_gait: dict[str, dict] = {}
    for task, res in zip(tasks, results):
        label = task["key"].split("/")[1]
        for name in PIPELINES:
            per_gait.setdefault(label, {}).setdefault(name, []).append(res["variants"][name])
    summary = {label: {name: gait_summary(scores) for name, scores in pipes.items()}
               for label, pipes in per_gait.items()}
    relative = {str(Path(p)): str(Path(p).relative_to(out)) for p in [str(cal), *stances.values()]}
    document = {"scenario": str(scenario_path), "quick": quick, "runs": runs, "nav": dataclasses.asdict(nav),
                "gaits": [gait_label(k, c) for k, c in gaits], "summary": summary,
                "tasks": [_relative_task(t, relative) for t in tasks], "scores": results}
    write_json(out / "gait_study.json", document)
    _figure(out / "gait_study.png", summary)
    write_text_atomic(out / "gait_study.md", _markdown(summary, scenario_path, runs))
    publish_into(out, final)
    return document


def _relative_task(task: dict, relative: dict[str, str]) -> dict:
    """The task with its input paths relative to the output folder (the JSON outlives the working folder)."""
    variants = [{k: relative.get(v, v) if isinstance(v, str) else v for k, v in variant.items()}
                for variant in task["variants"]]
    return {**task, "variants": variants}


def _markdown(summary: dict, scenario_path, runs: int) -> str:
    lines = [f"# Gait study ({scenario_path}, {runs} runs per gait)", "",
             "Length underestimate 100 (1 - length ratio) % (positive: short) and heading drift (deg/s), mean +- sd "
             "over runs, before and after the paper's compensation (full readout calibration and the gait's own "
             "stance pseudo-velocity).", "",
             "| gait | length underestimate before % | after % | heading drift before deg/s | after deg/s |",
             "|---|---|---|---|---|"]
    for label, pipes in summary.items():
        cells = [f"{pipes[p][m]['mean']:.2f} +- {_sd(pipes[p][m]['std'])}"
                 for m in ("length_underestimate_pct",) for p in PIPELINES]
        cells += [f"{pipes[p]['heading_drift_deg_per_s']['mean']:.4f}" for p in PIPELINES]
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _sd(value: float) -> str:
    return "-" if not math.isfinite(value) else f"{value:.2f}"


def _figure(path: Path, summary: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = list(summary)
    x = np.arange(len(labels))
    fig, axes = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    for ax, metric, unit in ((axes[0], "length_underestimate_pct", "length underestimate (%)"),
                             (axes[1], "heading_drift_deg_per_s", "heading drift (deg/s)")):
        for shift, name in ((-0.15, "before"), (0.15, "both")):
            mean = [summary[g][name][metric]["mean"] for g in labels]
            sd = [np.nan_to_num(summary[g][name][metric]["std"]) for g in labels]
            ax.errorbar(x + shift, mean, yerr=sd, fmt="o", capsize=3,
                        label="before compensation" if name == "before" else "after (calibration + stance velocity)")
        ax.axhline(0.0, color="0.6", lw=0.8)
        ax.set_ylabel(unit)
    axes[0].legend(fontsize=8)
    axes[1].set_xticks(x, labels, rotation=30, ha="right")
    axes[0].set_title("The paper's pipelines across gaits (mean +- sd over runs)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
