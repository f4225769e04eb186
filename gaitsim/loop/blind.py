"""Blind tests of the loop: synthetic recordings carrying effects that their metadata does not declare.

Each case simulates a short straight walk with the vn200 noise preset plus one or two effects, withholds the
sensor parameters (``withhold = true``) and strips the recording to what a measured one carries
(:func:`gaitsim.measured.reference.as_measured`: IMU samples, the sampling rate, and the true positions as a 100 Hz
position reference, like a motion tracker). The loop then fits its own twin without the effect.

``gyro_scale`` is outside the library on purpose (a 5 % gyro scale factor): the loop must report it as
unexplained rather than name a wrong effect. ``no_effect`` carries nothing undeclared: the loop must name no
effect there (a false alarm).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from nav.constants import STANDARD_GRAVITY
from nav.recording import Recording

from ..measured.reference import as_measured
from ..scenario import scenario_from_dict
from ..simulate import simulate_walk
from . import attribution, settings


@dataclass(frozen=True)
class BlindCase:
    """Effects switched on in the synthetic recording: (library effect or "outside", true magnitude, unit),
    the scenario sections that switch them on, and the loop rounds needed."""

    name: str
    truths: tuple
    sections: dict = field(default_factory=dict)
    sensor: dict = field(default_factory=dict)
    rounds: int = 1


def _diag(value: float) -> list:
    return [[value, 0.0, 0.0], [0.0, value, 0.0], [0.0, 0.0, value]]


CASES = (
    BlindCase("stance_roll", (("stance_roll", 12.0, "deg/s"),), {"micromotion": {"stance_roll_rate_dps": 12.0}}),
    BlindCase("stance_rotation", (("stance_rotation", float(np.linalg.norm([3.0, 4.0, -5.0])), "deg/s"),),
              {"micromotion": {"stance_rotation_dps": [3.0, 4.0, -5.0]}}),
    BlindCase("stance_creep", (("stance_creep", 0.025, "m/s"),),
              {"micromotion": {"creep_velocity_mps": [0.025, 0.0, 0.0]}}),
    BlindCase("impact_ringing", (("impact_ringing", 40.0, "m/s^2"),),
              {"impact": {"ringing_hz": 60.0, "ringing_accel_mps2": 40.0}}),
    BlindCase("bandwidth", (("bandwidth", 20.0, "Hz"),), sensor={"accel_bandwidth": [20.0, "Hz"],
                                                                "gyro_bandwidth": [20.0, "Hz"]}),
    BlindCase("accel_gyro_skew", (("accel_gyro_skew", 5.0, "ms"),), sensor={"accel_gyro_skew": [5.0, "ms"]}),
    BlindCase("mount_yaw", (("mount_yaw", 8.0, "deg"),), sensor={"mounting_misalignment": [[0.0, 0.0, 8.0], "deg"]}),
    BlindCase("accel_scale", (("accel_scale", 2.0, "%"),), sensor={"accel_misalignment": [_diag(1.02), "1"]}),
    BlindCase("saturation", (("saturation", 5 * STANDARD_GRAVITY, "m/s^2"),), sensor={"accel_range": [5.0, "g"]}),
    BlindCase("outside_gyro_scale", (("outside", 5.0, "%"),), sensor={"gyro_misalignment": [_diag(1.05), "1"]}),
    BlindCase("no_effect", (("none", 0.0, "-"),), rounds=3),
    BlindCase("roll_and_scale", (("stance_roll", 12.0, "deg/s"), ("accel_scale", 2.0, "%")),
              {"micromotion": {"stance_roll_rate_dps": 12.0}}, {"accel_misalignment": [_diag(1.02), "1"]},
              rounds=2),
)
BY_NAME = {c.name: c for c in CASES}


def blind_recording(case: BlindCase, seed: int = settings.BLIND_SEED) -> Recording:
    """The synthetic "measured" recording of ``case`` (module docstring)."""
    doc = {"path": {"kind": "straight", "length_m": settings.BLIND_WALK_LENGTH_M},
           "sampling": {"rate_hz": settings.BLIND_RATE_HZ},
           "sensor": {"preset": "vn200", "withhold": True, **case.sensor}, **case.sections}
    rec = simulate_walk(scenario_from_dict(doc, f"<blind {case.name}>"), seed=seed)
    return as_measured(rec, settings.BLIND_REFERENCE_RATE_HZ)


def run_case(case: BlindCase) -> attribution.LoopResult:
    """Run the loop on the case's recording (as many rounds as the case needs)."""
    return attribution.run_loop(blind_recording(case), max_rounds=case.rounds)


def table_rows(case: BlindCase, result: attribution.LoopResult) -> list[dict]:
    """One row per true effect: found effect, fitted magnitude, residual before/after, nav discrepancy."""
    nav = result.navigation_summary().get("nav_final_error", {})
    rows = []
    named = [a for a in result.attributions if a["effect"] != "unexplained"]
    for k, (effect, magnitude, unit) in enumerate(case.truths):
        if effect == "none":  # a false alarm is the first effect named at all
            att = named[0] if named else {"effect": "none"}
        else:
            att = result.attributions[k] if k < len(result.attributions) else {}
        rows.append({
            "case": case.name, "true_effect": effect, "true_magnitude": magnitude, "unit": unit,
            "found_effect": att.get("effect"), "fitted_magnitude": att.get("magnitude"),
            "residual": att.get("residual"), "residual_before": att.get("residual_before"),
            "residual_after": att.get("residual_after"), "uncertainty_after": att.get("uncertainty_after"),
            "nav_final_error_discrepancy_before_m": nav.get("discrepancy_before", math.nan),
            "nav_final_error_discrepancy_after_m": nav.get("discrepancy_after", math.nan),
        })
    return rows
