"""Zero-velocity detectors across gaits (issue 17): the fixed SHOE against the adaptive-threshold SHOE.

    python3 -m benchmarks.detector_gaits [--runs 3] [--jobs 2] [--part walk|gaits|measured|all]

Accuracy, not speed. Three parts:

walk      the paper's walk (scenarios/paper.toml: 99.6 m, 800 Hz, toes mount) at 60..130 steps/min with the
          ideal, vn200 and paper-vn200 sensors (no readout calibration), the scenario's [nav] detector settings.
gaits     the simulator's gait kinds (gaitsim/world/gaits.py) with the ideal and vn200 sensors, judged with
          nav's defaults (``NavOptions()``, what a user's recording gets: the anchored SHOE) against the
          same with ``detector="shoe"`` (OpenShoe's fixed test alone), ``detector="adaptive"`` and the adaptive
          window without adaptation (ratio 0: a fixed threshold over 50 ms, separating the two changes): walking 60..130 steps/min (100 m), a walk at 100 steps/min
          stopping 4 s every 8 strides (100 m), rearfoot and forefoot running at 150/165/180 steps/min (200 m).
          Issue 17's acceptance per case: >= 98 % of true stances found, no merged strides, final error <= 3 %
          of the distance, and no cadence with more than twice the error per metre of a neighbour. The running
          cases are also run with a consumer-grade sensor (bmi160 preset, not judged): what a missed stance costs
          when the sensor drifts.
measured  the shared recordings (gaitmap-healthy, ucr-fgo, xio-ngimu) with the candidates of the gaits part
          (nav's defaults, sigma_g 0.1 deg/s; the adaptive SHOE; the 50 ms window without adaptation), scored
          as tests/test_nav_measured.py does: track RMSE (ate_m) where there is a reference, start-to-end
          distance (loop closure) for x-io. The fixed SHOE is also run at nine neighbouring
          settings (W 2/3/4 samples x threshold 2e4/3e4/4e4) to show how much a recording's score moves under
          small detector changes: the yardstick for "no worse".

Per simulated case: true stances (the truth's labelled stance: a walk's foot flat, a run's ground contact),
found, merged, ZUPTs in the swing (detected runs touching no ground contact, initial contact to toe off), and the
final error in % of the walked distance (mean and worst over runs). Deterministic from the scenario's seed.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import tomllib
import warnings
from pathlib import Path

import numpy as np

from gaitsim.experiments.setup import NavSettings, patched, settings_from_scenario
from gaitsim.scenario import load_scenario, scenario_from_dict
from gaitsim.simulate import simulate_walk
from gaitsim.world.truth import within_intervals
from nav.adaptive_detector import AdaptiveThreshold
from nav.metrics import stance_match
from nav.pipeline import NavOptions, run

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "scenarios" / "paper.toml"
WALK_CADENCES = (60, 70, 80, 84, 90, 100, 110, 120, 130)
SENSORS = ("ideal", "vn200", "paper-vn200")
GAIT_SENSORS = ("ideal", "vn200")  # the sensors issue 17's acceptance names
# running only: what missed stances cost a consumer-grade sensor (not judged). Its uncalibrated gyro carries the
# attitude between the runs' rests to 1.08-1.15 m/s (median, 165 and 180 steps/min), past nav.checks' 1 m/s, but
# no other gyro scale closes those strides better, so nav flags them instead of refusing them
CONSUMER_SENSOR = "bmi160"
GAIT_WALK_CADENCES = (60, 70, 80, 90, 100, 110, 120, 130)
GAIT_RUN_CADENCES = (150, 165, 180)
WALK_LENGTH_M = 100.0
RUN_LENGTH_M = 200.0
STOPS = {"stop_every_strides": 8, "stop_duration_s": 4.0}


def walk_doc(doc: dict, cadence: float, sensor: str) -> dict:
    """The paper scenario at ``cadence`` steps/min with sensor "ideal", "vn200" (the datasheet preset) or
    "paper-vn200" (the scenario's own: VN-200 noise plus the paper's biases, misalignment and g-sensitivity)."""
    out = patched(doc, gait={"cadence_steps_per_min": float(cadence)})
    if sensor == "ideal":
        del out["sensor"]
    elif sensor != "paper-vn200":
        out["sensor"] = {"preset": sensor}
    return out


def gait_doc(kind: str, cadence: float, sensor: str, stops: bool = False) -> dict:
    """A straight walk or run north of gait ``kind`` at ``cadence`` steps/min (its speed-dependent defaults), toes
    mount, 800 Hz, sensor "ideal" or a preset name; with ``stops``, stop-and-go (``STOPS``)."""
    running = kind.startswith("run")
    doc = {"scenario": {"name": f"{kind}-{cadence:g}", "seed": 17},
           "path": {"kind": "straight", "length_m": RUN_LENGTH_M if running else WALK_LENGTH_M, "yaw_deg": 90.0},
           "gait": {"kind": kind, "cadence_steps_per_min": float(cadence), **(STOPS if stops else {})}}
    if sensor != "ideal":
        doc["sensor"] = {"preset": sensor}
    return doc


def gait_cases() -> list[tuple[str, dict, float]]:
    """(label, scenario document, distance m) of every case of the "gaits" part."""
    cases = []
    for sensor in GAIT_SENSORS:
        for cadence in GAIT_WALK_CADENCES:
            cases.append((f"walk {cadence} {sensor}", gait_doc("walk", cadence, sensor), WALK_LENGTH_M))
        cases.append((f"stop-and-go 100 {sensor}", gait_doc("walk", 100, sensor, stops=True), WALK_LENGTH_M))
        for kind in ("run-rearfoot", "run-forefoot"):
            for cadence in GAIT_RUN_CADENCES:
                cases.append((f"{kind} {cadence} {sensor}", gait_doc(kind, cadence, sensor), RUN_LENGTH_M))
    for kind in ("run-rearfoot", "run-forefoot"):
        for cadence in GAIT_RUN_CADENCES:
            cases.append((f"{kind} {cadence} {CONSUMER_SENSOR}", gait_doc(kind, cadence, CONSUMER_SENSOR),
                          RUN_LENGTH_M))
    return cases


def detectors_under_test(nav: NavSettings) -> dict[str, NavOptions]:
    """The scenario's fixed SHOE and the adaptive SHOE with the same floor and sigmas (default adaptation)."""
    fixed = nav.options()
    return {"shoe": fixed, "adaptive": dataclasses.replace(fixed, detector="adaptive")}


def default_candidates() -> dict[str, NavOptions]:
    """nav's defaults (the anchored SHOE), OpenShoe's fixed SHOE under them, the adaptive SHOE on the same floor,
    and the adaptive window without adaptation (ratio 0)."""
    anchored = NavOptions()
    fixed = dataclasses.replace(anchored, detector="shoe")
    adaptive = dataclasses.replace(anchored, detector="adaptive")
    return {"anchored (default)": anchored, "fixed shoe": fixed, "adaptive": adaptive,
            "50 ms window, ratio 0": dataclasses.replace(adaptive, adaptive=AdaptiveThreshold(ratio=0.0))}


def simulated_rows(label: str, doc: dict, distance: float, options: dict[str, NavOptions], runs: int) -> list:
    scenario = scenario_from_dict(doc, label)
    per = {name: [] for name in options}
    for r in range(runs):
        rec = simulate_walk(scenario, run=r)
        contact = within_intervals(rec.t, rec.events.t_ic, rec.events.t_to)  # the foot touches the ground
        for name, opt in options.items():
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # possible-clipping notes of the running-timing walks
                sol, score = run(rec, opt)
            found = stance_match(sol.stationary, rec.truth.stance)
            swing = stance_match(sol.stationary, contact)
            per[name].append((found["true_stances"], found["found"], found["merged"], swing["spurious"],
                              100 * score["final_error_m"] / distance))
    rows = []
    for name, values in per.items():
        v = np.array(values, float)
        rows.append((label, name, int(v[:, 0].sum()), int(v[:, 1].sum()), int(v[:, 2].sum()), int(v[:, 3].sum()),
                     float(v[:, 4].mean()), float(v[:, 4].max())))
    return rows


def _case_rows(case: tuple, options: dict[str, NavOptions], runs: int) -> list:
    label, doc, distance = case
    return simulated_rows(label, doc, distance, options, runs)


def gait_rows(options: dict[str, NavOptions], runs: int, jobs: int) -> list:
    """Rows of every "gaits" case, computed over ``jobs`` processes (each case is seeded by its scenario, so the
    rows do not depend on ``jobs``)."""
    cases = gait_cases()
    if jobs <= 1:
        return [row for case in cases for row in _case_rows(case, options, runs)]
    from concurrent.futures import ProcessPoolExecutor
    from functools import partial

    with ProcessPoolExecutor(jobs) as pool:
        return [row for rows in pool.map(partial(_case_rows, options=options, runs=runs), cases) for row in rows]


def acceptance(rows: list) -> None:
    """Issue 17's per-case criteria (>= 98 % found, none merged, error <= 3 %) and, per detector, whether they
    hold for every case."""
    ok = {}
    for label, name, true, found, merged, _swing, mean, worst in rows:
        if label.split()[-1] not in GAIT_SENSORS:
            continue
        passed = found >= 0.98 * true and merged == 0 and worst <= 3.0
        ok.setdefault(name, []).append((label, passed))
    for name, seq in ok.items():
        failed = [label for label, passed in seq if not passed]
        print(f"- {name}: {len(seq) - len(failed)}/{len(seq)} cases pass"
              + (f"; fails: {', '.join(failed)}" if failed else ""))


def print_rows(rows: list) -> None:
    print("| case | detector | true stances | found | merged | swing ZUPTs | final error % (mean) | worst % |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r[0]} | {r[1]} | {r[2]} | {r[3]} | {r[4]} | {r[5]} | {r[6]:.2f} | {r[7]:.2f} |", flush=True)


def neighbour_check(rows: list) -> None:
    """Cadences whose error per metre is more than twice a neighbour's (issue 17's smoothness criterion)."""
    by = {}
    for label, name, *_, mean, _worst in rows:
        words = label.split()
        if words[0] != "stop-and-go":  # a single case: no neighbours
            by.setdefault((name, words[0], words[-1]), []).append((label, mean))
    for (name, gait, sensor), seq in by.items():
        jumps = [f"{a} -> {b} ({ea:.2f} -> {eb:.2f} %)" for (a, ea), (b, eb) in zip(seq, seq[1:])
                 if max(ea, eb) > 2 * min(ea, eb)]
        print(f"- {name}, {gait}, {sensor}: " + ("; ".join(jumps) if jumps else "no neighbour more than 2x apart"))


def measured_rows() -> list:
    from gaitsim.measured import load_dataset

    nearby = [NavOptions(detector="shoe", window=w, threshold=g) for w in (2, 3, 4) for g in (2e4, 3e4, 4e4)]
    rows = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the loaders' data-quality notes are tested elsewhere
        for dataset in ("gaitmap-healthy", "ucr-fgo", "xio-ngimu"):
            for rec in load_dataset(dataset):
                key = "final_error_m" if dataset == "xio-ngimu" else "ate_m"

                def score(options, rec=rec, key=key):
                    return run(rec, options)[1][key]

                spread = [score(o) for o in nearby]
                rows.append((dataset, rec.meta["recording"], key,
                             *(score(o) for o in default_candidates().values()), min(spread), max(spread)))
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3, help="runs per simulated case (default 3)")
    parser.add_argument("--jobs", type=int, default=1, help="processes for the gaits part (default 1)")
    parser.add_argument("--part", choices=("walk", "gaits", "measured", "all"), default="all")
    args = parser.parse_args(argv)
    with open(PAPER, "rb") as fh:
        doc = tomllib.load(fh)
    nav, _ = settings_from_scenario(load_scenario(PAPER))
    options = detectors_under_test(nav)
    adaptive = AdaptiveThreshold()
    print(f"fixed SHOE: threshold {nav.threshold:g}, sigma_a {nav.sigma_a_mps2} m/s^2, sigma_g {nav.sigma_g_dps} "
          f"deg/s, W {nav.window} samples; adaptive: same floor and sigmas, ratio {adaptive.ratio:g}, span "
          f"{adaptive.span_s} s, window {adaptive.window_s} s; {args.runs} runs per case\n")
    if args.part in ("walk", "all"):
        rows = []
        for sensor in SENSORS:
            for cadence in WALK_CADENCES:
                rows += simulated_rows(f"walk {cadence} {sensor}", walk_doc(doc, cadence, sensor),
                                       doc["path"]["length_m"], options, args.runs)
        print_rows(rows)
        print()
        neighbour_check(rows)
        print()
    if args.part in ("gaits", "all"):
        print(f"gaits: nav defaults (anchored SHOE, threshold {NavOptions().threshold:g}, W {NavOptions().window} "
              f"samples, sigma_g {math.degrees(NavOptions().sigma_g):g} deg/s) against the fixed and the adaptive "
              "SHOE on the same settings\n")
        rows = gait_rows(default_candidates(), args.runs, args.jobs)
        print_rows(rows)
        print()
        neighbour_check(rows)
        print()
        acceptance(rows)
        print()
    if args.part in ("measured", "all"):
        names = " | ".join(default_candidates())
        print(f"| dataset | recording | score (m) | {names} | fixed SHOE, 9 nearby settings: min | max |")
        print("|---|---|---|" + "---|" * (len(default_candidates()) + 2))
        for ds, name, key, *scores in measured_rows():
            print(f"| {ds} | {name} | {key} | " + " | ".join(f"{v:.3f}" for v in scores) + " |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
