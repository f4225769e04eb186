"""Single-term sensitivities of a stance twin's length underestimate: results/stance/findings.md, "Candidates for
the rest".

The twin is the one ``gaitsim stance`` compares (:func:`gaitsim.stance.twin.match_timing`: the recording's gait,
rate and IMU site, the default stance model, seeded), simulated once and read by the ideal sensor (the baseline)
and by sensors that each carry one error term (:data:`TERMS`, [sensor] tables in datasheet units); the impact
ringing changes the walk itself (:data:`WORLD_TERMS`, [impact] tables). Every variant is swept at SHOE 1e4, 3e4
and 5e4 from point samples with RK4 (the real recording's path), against the twin's true site track, and the
length underestimate (%) and its change against the baseline (percentage points) are printed as a table.

Run from the repository root (it reads ../shared/data)::

    python3 -m studies.stance_terms                          # gaitmap-healthy/left, every term (~1 min)
    python3 -m studies.stance_terms ucr-fgo/right bandwidth  # named terms only
"""

from __future__ import annotations

import sys

import numpy as np

from gaitsim.scenario import scenario_from_dict
from gaitsim.simulate import sense, simulate_world
from gaitsim.stance.command import SITES, load_recordings
from gaitsim.stance.sweep import sweep
from gaitsim.stance.twin import TWIN_SEED, TwinSpec, match_timing, measure_gait

THRESHOLDS = (1e4, 3e4, 5e4)
# label -> [sensor] table of one error term on the ideal sensor
TERMS = {
    "accel_scale": ("accelerometer scale -1 % (all axes)", {"accel_misalignment": [np.diag([0.99] * 3).tolist(), "1"]}),
    "gyro_scale": ("gyro scale -1 % (all axes)", {"gyro_misalignment": [np.diag([0.99] * 3).tolist(), "1"]}),
    "accel_offset_x": ("accelerometer offset +10 mg along x (toes)", {"accel_bias": [[10.0, 0.0, 0.0], "mg"]}),
    "accel_offset_x_neg": ("accelerometer offset -10 mg along x", {"accel_bias": [[-10.0, 0.0, 0.0], "mg"]}),
    "accel_offset_z": ("accelerometer offset +10 mg along z", {"accel_bias": [[0.0, 0.0, 10.0], "mg"]}),
    "bmi160_accel_offset": ("one draw of the BMI160 data-sheet accelerometer offset spread (40 mg), no noise",
                            {"accel_bias_repeatability": [40.0, "mg"]}),
    "bmi160_noise": ("BMI160 data-sheet noise and quantisation only",
                     {"preset": "bmi160", "accel_bias_repeatability": [0.0, "mg"],
                      "gyro_bias_repeatability": [0.0, "deg/s"]}),
    "gyro_offset_y": ("gyro offset +0.1 deg/s on y", {"gyro_bias": [[0.0, 0.1, 0.0], "deg/s"]}),
    "bandwidth": ("sensor band limit 20 Hz (second-order digital)",
                  {"accel_bandwidth": [20.0, "Hz"], "gyro_bandwidth": [20.0, "Hz"]}),
    "bandwidth_10": ("sensor band limit 10 Hz (second-order digital)",
                     {"accel_bandwidth": [10.0, "Hz"], "gyro_bandwidth": [10.0, "Hz"]}),
}
# label -> [impact] table of one change of the walk (ideal sensor)
WORLD_TERMS = {
    "ringing": ("impact ringing 100 Hz, 50 m/s^2", {"ringing_hz": 100.0, "ringing_accel_mps2": 50.0}),
}


def twin_document(spec: str) -> dict:
    """The stance study's twin document of the shared recording ``dataset/recording`` with the ideal sensor."""
    dataset, name = spec.split("/")
    rec = dict(load_recordings(dataset))[name]
    site, _ = SITES[dataset]
    gait = measure_gait(rec, rec.reference.t, rec.reference.pos)
    return match_timing(gait, TwinSpec(mount=site, micromotion={"foot": name}))


def underestimates(doc: dict, world=None) -> np.ndarray:
    """Length underestimate (%) at :data:`THRESHOLDS` of the twin ``doc`` (its [sensor] table applied to
    ``world``, or to the walk the document simulates when ``world`` is None), RK4 on point samples."""
    scenario = scenario_from_dict(doc, "<stance term>")
    world = world if world is not None else simulate_world(scenario, TWIN_SEED)
    twin = sense(*world, scenario.sensor, TWIN_SEED)
    result = sweep(twin, twin.truth.t, twin.truth.pos, thresholds=THRESHOLDS, bootstrap=0, method="rk4",
                   quantities=("underestimate_pct",))
    return np.asarray(result.curves["underestimate_pct"].value)


def main(argv: list[str]) -> None:
    spec = argv[0] if argv else "gaitmap-healthy/left"
    chosen = argv[1:] or [*TERMS, *WORLD_TERMS]
    unknown = sorted(set(chosen) - set(TERMS) - set(WORLD_TERMS))
    if unknown:
        raise SystemExit(f"stance_terms: terms {unknown} unknown; allowed: {', '.join([*TERMS, *WORLD_TERMS])}")
    doc = twin_document(spec)
    world = simulate_world(scenario_from_dict(doc, "<stance term>"), TWIN_SEED)
    baseline = underestimates(doc, world)
    print(f"{spec} twin, RK4 on point samples, SHOE {' / '.join(f'{x:.0e}' for x in THRESHOLDS)}\n")
    print("| change | underestimate (%) | effect (points, mean over thresholds) |\n|---|---|---|")
    print(f"| none (ideal point samples) | {' / '.join(f'{x:.2f}' for x in baseline)} | |")
    for key in chosen:
        if key in TERMS:
            label, table = TERMS[key]
            values = underestimates({**doc, "sensor": table}, world)
        else:
            label, table = WORLD_TERMS[key]
            values = underestimates({**doc, "impact": table})
        print(f"| {label} | {' / '.join(f'{x:.2f}' for x in values)} | {np.mean(values - baseline):+.2f} |",
              flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
