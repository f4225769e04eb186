"""Zero-velocity detectors across gaits (issue 17): the fixed SHOE against the adaptive-threshold SHOE.

    python3 -m benchmarks.detector_gaits [--runs 3] [--part walk|run|measured|all]

Accuracy, not speed. Three parts:

walk      the paper's walk (scenarios/paper.toml: 99.6 m, 800 Hz, toes mount) at 60..130 steps/min with the
          ideal, vn200 and paper-vn200 sensors (no readout calibration), the scenario's [nav] detector settings.
run       NOT a running model: the same walking model pushed to running timing (150-180 steps/min, 36 %
          contact with a flight phase, 2.4 m strides, faster swing and harder impacts), with the stance roll of
          the walk (18 deg/s) and a faster one (60 deg/s) standing in for a stance that never comes to rest.
          Its peaks (900-1100 deg/s, 10-19 g) are only roughly those of measured running; a few impacts exceed
          the VN-200's 16 g range.
measured  the shared recordings (gaitmap-healthy, ucr-fgo, xio-ngimu) with NavOptions defaults (sigma_g 0.1
          deg/s), scored as tests/test_nav_measured.py does: track RMSE (ate_m) where there is a reference,
          start-to-end distance (loop closure) for x-io. The fixed SHOE is also run at nine neighbouring
          settings (W 2/3/4 samples x threshold 2e4/3e4/4e4) to show how much a recording's score moves under
          small detector changes: the yardstick for "no worse".

Per simulated case: true stances (foot flat), found, merged, ZUPTs in the swing (detected runs touching no
ground contact, initial contact to toe off), and the final error in % of the walked distance (mean and worst
over runs). Deterministic from the scenario's seed.
"""

from __future__ import annotations

import argparse
import dataclasses
import tomllib
import warnings
from pathlib import Path

import numpy as np

from gaitsim.experiments.setup import NavSettings, patched, settings_from_scenario
from gaitsim.scenario import load_scenario, scenario_from_dict
from gaitsim.simulate import simulate_walk
from nav.adaptive_detector import AdaptiveThreshold
from nav.metrics import stance_match
from nav.pipeline import NavOptions, run

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "scenarios" / "paper.toml"
WALK_CADENCES = (60, 70, 80, 84, 90, 100, 110, 120, 130)
RUN_CADENCES = (150, 170, 180)
RUN_STANCE_ROLL_DPS = (18.0, 60.0)
RUN_LENGTH_M = 200.0
SENSORS = ("ideal", "vn200", "paper-vn200")


def walk_doc(doc: dict, cadence: float, sensor: str) -> dict:
    """The paper scenario at ``cadence`` steps/min with sensor "ideal", "vn200" (the datasheet preset) or
    "paper-vn200" (the scenario's own: VN-200 noise plus the paper's biases, misalignment and g-sensitivity)."""
    out = patched(doc, gait={"cadence_steps_per_min": float(cadence)})
    if sensor == "ideal":
        del out["sensor"]
    elif sensor != "paper-vn200":
        out["sensor"] = {"preset": sensor}
    return out


def running_timing_doc(doc: dict, cadence: float, sensor: str, stance_roll_dps: float) -> dict:
    """The walking model at running timing (see the module docstring: not a running model)."""
    out = patched(
        walk_doc(doc, cadence, sensor),
        path={**doc["path"], "length_m": RUN_LENGTH_M},
        gait={"stride_length_m": 2.4, "heel_rocker_frac": 0.08, "foot_flat_frac": 0.14, "push_off_frac": 0.14,
              "swing_frac": 0.64, "pitch_heel_strike_deg": -12.0, "pitch_toe_off_deg": 55.0,
              "pitch_rate_toe_off_dps": 500.0, "pitch_rate_heel_strike_dps": 150.0, "swing_height_m": 0.15},
        impact={"heel_strike_velocity_mps": [0.5, 0.0, -0.6], "heel_strike_duration_s": 0.015,
                "slap_rate_dps": 250.0, "slap_duration_s": 0.03},
        micromotion={"stance_roll_rate_dps": stance_roll_dps, "creep_ramp_s": 0.02, "settle_duration_s": 0.04,
                     "heel_off_duration_s": 0.06},
    )
    return out


def detectors_under_test(nav: NavSettings) -> dict[str, NavOptions]:
    """The scenario's fixed SHOE and the adaptive SHOE with the same floor and sigmas (default adaptation)."""
    fixed = nav.options()
    return {"shoe": fixed, "adaptive": dataclasses.replace(fixed, detector="adaptive")}


def ground_contact(rec) -> np.ndarray:
    """(N,) bool: initial contact <= t < toe off of some stride (the foot touches the ground)."""
    idx = np.searchsorted(rec.events.t_ic, rec.t, side="right") - 1
    inside = idx >= 0
    inside[inside] = rec.t[inside] < rec.events.t_to[idx[inside]]
    return inside


def simulated_rows(label: str, doc: dict, distance: float, options: dict[str, NavOptions], runs: int) -> list:
    scenario = scenario_from_dict(doc, label)
    per = {name: [] for name in options}
    for r in range(runs):
        rec = simulate_walk(scenario, run=r)
        contact = ground_contact(rec)
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


def print_rows(rows: list) -> None:
    print("| case | detector | true stances | found | merged | swing ZUPTs | final error % (mean) | worst % |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r[0]} | {r[1]} | {r[2]} | {r[3]} | {r[4]} | {r[5]} | {r[6]:.2f} | {r[7]:.2f} |", flush=True)


def neighbour_check(rows: list) -> None:
    """Cadences whose error per metre is more than twice a neighbour's (issue 17's smoothness criterion)."""
    by = {}
    for label, name, *_, mean, _worst in rows:
        sensor = label.split()[-1]
        by.setdefault((name, sensor), []).append((label, mean))
    for (name, sensor), seq in by.items():
        jumps = [f"{a} -> {b} ({ea:.2f} -> {eb:.2f} %)" for (a, ea), (b, eb) in zip(seq, seq[1:])
                 if max(ea, eb) > 2 * min(ea, eb)]
        print(f"- {name}, {sensor}: " + ("; ".join(jumps) if jumps else "no neighbour more than 2x apart"))


def measured_rows() -> list:
    from gaitsim.measured import load_dataset

    nearby = [NavOptions(window=w, threshold=g) for w in (2, 3, 4) for g in (2e4, 3e4, 4e4)]
    rows = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the loaders' data-quality notes are tested elsewhere
        for dataset in ("gaitmap-healthy", "ucr-fgo", "xio-ngimu"):
            for rec in load_dataset(dataset):
                key = "final_error_m" if dataset == "xio-ngimu" else "ate_m"

                def score(options, rec=rec, key=key):
                    return run(rec, options)[1][key]

                spread = [score(o) for o in nearby]
                rows.append((dataset, rec.meta["recording"], key, score(NavOptions()),
                             score(NavOptions(detector="adaptive")), min(spread), max(spread)))
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3, help="runs per simulated case (default 3)")
    parser.add_argument("--part", choices=("walk", "run", "measured", "all"), default="all")
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
    if args.part in ("run", "all"):
        rows = []
        for sensor in SENSORS:
            for roll in RUN_STANCE_ROLL_DPS:
                for cadence in RUN_CADENCES:
                    rows += simulated_rows(f"running timing {cadence}, roll {roll:.0f} {sensor}",
                                           running_timing_doc(doc, cadence, sensor, roll), RUN_LENGTH_M, options,
                                           args.runs)
        print_rows(rows)
        print()
    if args.part in ("measured", "all"):
        print("| dataset | recording | score (m) | fixed SHOE | adaptive | fixed SHOE, 9 nearby settings: min | max |")
        print("|---|---|---|---|---|---|---|")
        for ds, name, key, fixed, adapt, lo, hi in measured_rows():
            print(f"| {ds} | {name} | {key} | {fixed:.3f} | {adapt:.3f} | {lo:.3f} | {hi:.3f} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
