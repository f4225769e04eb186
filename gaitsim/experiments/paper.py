"""The seed paper's study as Monte Carlo tasks: compensation table, ablation, threshold sweep, heading walk,
error budget and sensitivity. Tasks are built here; :mod:`gaitsim.experiments.report` turns results into files.

Variants of the filter pipeline (all with the scenario's [nav] detector and filter):

raw              no readout calibration, zero stance pseudo-velocity
before           the calibration terms of ``before_calibration_terms`` removed, zero pseudo-velocity -- the
                 paper's "before" (scenarios/paper.toml says which terms and why)
calibration      step 1: the full estimated calibration (bias, misalignment, g-sensitivity)
stance_velocity  step 2 alone: "before" plus the fitted stance pseudo-velocity
both             steps 1 and 2
<term>_only      ablation: one calibration term alone

Sensitivity variants (the detector ones are the exceptions to the [nav] detector):

grade:<preset>         the preset's sensor, no readout calibration; ``grade:<preset> oracle`` the same with the
                       true stance labels, which separates the detector's share of the error from the sensor's
detector:<name>        "before" with detector <name> at its matched threshold (:func:`.setup.matched_thresholds`)
before adaptive        (cadence and mount rows) "before" with the adaptive SHOE (nav.adaptive_detector, floor =
                       the [nav] threshold): a 50 ms window against the [nav] detector's W samples
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..imu.presets import get_preset
from .setup import ExperimentSettings, NavSettings, patched
from .tasks import walk_task_spec

ALL_TERMS = ["bias", "misalignment", "g_sensitivity"]


def _si_table(preset: str, **terms) -> dict:
    """A [sensor] table: ``preset`` with the named terms copied in SI from the paper-vn200 / vn200 presets."""
    table = {"preset": preset}
    units = {"accel_noise_density": "m/s^2/sqrt(Hz)", "gyro_noise_density": "rad/s/sqrt(Hz)", "accel_bias": "m/s^2",
             "gyro_bias": "rad/s", "accel_misalignment": "1", "gyro_misalignment": "1",
             "gyro_g_sensitivity": "rad/s/(m/s^2)", "accel_bias_instability": "m/s^2",
             "gyro_bias_instability": "rad/s", "accel_bias_instability_tau": "s", "gyro_bias_instability_tau": "s"}
    for key, source in terms.items():
        table[key] = [np.asarray(get_preset(source)[key]).tolist(), units[key]]
    return table


def budget_sensors() -> dict:
    """Each sensor error source alone (values of the paper-vn200 preset)."""
    return {
        "white_noise": _si_table("ideal", accel_noise_density="vn200", gyro_noise_density="vn200"),
        "bias_instability": _si_table("ideal", accel_bias_instability="vn200", gyro_bias_instability="vn200",
                                      accel_bias_instability_tau="vn200", gyro_bias_instability_tau="vn200"),
        "constant_bias": _si_table("ideal", accel_bias="paper-vn200", gyro_bias="paper-vn200"),
        "misalignment": _si_table("ideal", accel_misalignment="paper-vn200", gyro_misalignment="paper-vn200"),
        "g_sensitivity": _si_table("ideal", gyro_g_sensitivity="paper-vn200"),
    }


def compensation_variants(cal: str, stance: str, before_terms: list[str]) -> list[dict]:
    base = {"sensor": "paper"}
    out = [
        {"name": "raw", **base},
        {"name": "before", **base, "calibration": cal, "calibration_terms": before_terms},
        {"name": "calibration", **base, "calibration": cal, "calibration_terms": ALL_TERMS},
        {"name": "stance_velocity", **base, "calibration": cal, "calibration_terms": before_terms,
         "stance_velocity": stance},
        {"name": "both", **base, "calibration": cal, "calibration_terms": ALL_TERMS, "stance_velocity": stance},
    ]
    out += [{"name": f"{term}_only", **base, "calibration": cal, "calibration_terms": [term]}
            for term in ALL_TERMS if [term] != before_terms]
    return out


def build_tasks(doc: dict, nav: NavSettings, exp: ExperimentSettings, runs: int, seed: int, cal: str,
                stance: str, detector_thresholds: dict[str, float] | None = None) -> list[dict]:
    """Every task of the reproduction (see the module docstring).

    ``detector_thresholds``: {detector: threshold in its own statistic's units} for the sensitivity's detector
    rows (:func:`~.setup.matched_thresholds`); a detector without one runs at the [nav] threshold (the adaptive
    SHOE's floor is a SHOE threshold).
    """
    detector_thresholds = detector_thresholds or {}
    nav_d = dataclasses.asdict(nav)
    paper_sensor = doc["sensor"]
    before = list(exp.before_calibration_terms)
    tasks = []

    def task(key, scenario, run, sensors, variants, keep=()):
        tasks.append(walk_task_spec(key, scenario, seed, run, nav_d, sensors, variants, keep))

    for r in range(runs):
        sensors = {"paper": paper_sensor}
        variants = compensation_variants(cal, stance, before)
        if r < exp.threshold_sweep_runs:
            variants += [{"name": f"before@{thr:.0f}", "sensor": "paper", "calibration": cal,
                          "calibration_terms": before, "threshold": thr} for thr in exp.threshold_sweep]
        if r < exp.sensitivity_runs:
            for preset in exp.sensitivity_presets:
                sensors[preset] = {"preset": preset}
                variants += [{"name": f"grade:{preset}", "sensor": preset},
                             {"name": f"grade:{preset} oracle", "sensor": preset, "detector": "oracle"}]
            variants += [{"name": f"detector:{d}", "sensor": "paper", "calibration": cal, "calibration_terms": before,
                          "detector": d, "threshold": detector_thresholds.get(d, nav.threshold)}
                         for d in exp.sensitivity_detectors]
        task(f"main/run-{r:03d}", doc, r, sensors, variants, keep=("before", "both"))

    length = exp.heading_walk_length_m
    heading_doc = patched(doc, path={**doc["path"], "length_m": length},
                          sensor=_si_table("ideal", gyro_g_sensitivity="paper-vn200"))
    task("heading/run-000", heading_doc, 0, {"g_only": heading_doc["sensor"]},
         [{"name": "g_sensitivity_alone", "sensor": "g_only"}], keep=("g_sensitivity_alone",))

    still = patched(doc, micromotion={"enabled": False})
    for r in range(exp.budget_runs):
        sensors = budget_sensors()
        variants = [{"name": name, "sensor": name} for name in sensors]
        task(f"budget/sensor-run-{r:03d}", still, r, sensors, variants)
        task(f"budget/kinematics-run-{r:03d}", still, r, {"ideal": None}, [{"name": "kinematics", "sensor": "ideal"}])
        task(f"budget/micromotion-run-{r:03d}", doc, r, {"ideal": None},
             [{"name": "micromotion", "sensor": "ideal"}])

    sens_variants = [{"name": "before", "sensor": "paper", "calibration": cal, "calibration_terms": before},
                     {"name": "before adaptive", "sensor": "paper", "calibration": cal, "calibration_terms": before,
                      "detector": "adaptive"},
                     {"name": "calibration", "sensor": "paper", "calibration": cal, "calibration_terms": ALL_TERMS}]
    default_gait = doc.get("gait", {}).get("cadence_steps_per_min", 84.0)
    default_mount = doc.get("mount", {}).get("site", "toes")
    for r in range(exp.sensitivity_runs):
        for cadence in exp.sensitivity_cadences:
            if cadence != default_gait:
                task(f"sensitivity/cadence-{cadence:.0f}-run-{r:03d}", patched(doc, gait={"cadence_steps_per_min": cadence}),
                     r, {"paper": paper_sensor}, sens_variants)
        for mount in exp.sensitivity_mounts:
            if mount != default_mount:
                task(f"sensitivity/mount-{mount}-run-{r:03d}", patched(doc, mount={"site": mount}), r,
                     {"paper": paper_sensor}, sens_variants)
    return tasks


def quick_overrides(doc: dict, exp: ExperimentSettings) -> tuple[dict, ExperimentSettings, int]:
    """--quick: few runs and short walks, for the test suite (same code paths as the full run)."""
    doc = patched(doc, path={**doc["path"], "length_m": 14.0})
    exp = dataclasses.replace(exp, calibration_walks=1, threshold_sweep=exp.threshold_sweep[::4],
                              threshold_sweep_runs=2, heading_walk_length_m=21.0, budget_runs=2,
                              sensitivity_runs=1, sensitivity_cadences=exp.sensitivity_cadences[:2],
                              sensitivity_mounts=exp.sensitivity_mounts[:2], cycle_count=8)
    return doc, exp, 3
