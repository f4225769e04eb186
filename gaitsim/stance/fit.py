"""Fit of the rolling-foot stance model (:class:`gaitsim.world.gait.MicroMotionParams`) to measured feet.

What is fitted is kinematics, not navigation: the foot-flat profiles (:mod:`gaitsim.stance.profiles`) of the
angular rate's magnitude and its sagittal component and, where the track is the IMU site itself (gaitmap's
Vicon pose at the sensor's lever arm), the site's forward and vertical velocity, over the foot flat
(forefoot contact to heel off). A track of another point of the foot (UCR's undocumented "foot position")
moves differently from the IMU by the rotation times the unknown offset, so it constrains the rates only. Each recording's twin (:mod:`gaitsim.stance.twin`, ``FIT_STRIDES`` strides) is simulated with the
candidate parameters and read with the same recipe. Residuals, on the foot-flat phases u in [0, 1]:

- angular rate: ``log((twin + 2) / (measured + 2)) / 0.15`` (deg/s): relative, as the zero-velocity gates
  are (sigma_g sqrt(gamma): 7 to 16 deg/s over the thresholds studied), so a 30 vs 36 deg/s transient weighs
  as little as a 7 vs 8.4 deg/s floor;
- sagittal rate (which moves the site forward): ``(twin - measured) / 2 deg/s``;
- velocities: ``(twin - measured) / (tolerance + 0.1 |measured|)`` (tolerance 2 mm/s forward, 4 mm/s
  vertical), weighted 1 where the measured rate is below ``GATE_DPS`` (where the detector's windows live)
  and ``OUTSIDE_WEIGHT`` elsewhere.

They are stacked over the recordings and minimised by bounded least squares (``scipy.optimize.least_squares``)
over the parameters of :data:`FITTED` (TOML units), mapped to [0, 1] between their bounds. The navigation curves (length underestimate, windows,
in-window velocity) are not in the objective: they are what the fitted model has to predict.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from nav.recording import Recording

from ..errors import ScenarioError
from .profiles import Profiles, foot_flat_profiles
from .twin import simulate

FIT_STRIDES = 12
# (TOML key of [micromotion], lower bound, upper bound, start)
FITTED = (
    ("heel_rise_rate_start_dps", -5.0, 10.0, 1.0),
    ("heel_rise_growth_dps3", 0.0, 200.0, 30.0),
    ("loading_roll_rate_dps", 0.0, 80.0, 25.0),
    ("loading_duration_s", 0.03, 0.2, 0.13),
    ("pronation_rate_dps", 0.0, 15.0, 5.0),
    ("contact_radius_m", 0.0, 0.03, 0.005),
    ("contact_transfer_pitch_deg", 0.2, 10.0, 2.0),
    ("creep_forward_mps", 0.0, 0.01, 0.001),
)
TOLERANCE = {"rate_dps": 0.15, "sagittal_rate_dps": 2.0, "forward_velocity_mps": 0.002,
             "vertical_velocity_mps": 0.004}
RATE_OFFSET_DPS = 2.0
GATE_DPS = 16.0  # deg/s, the zero-velocity gate at the largest threshold studied (0.07 deg/s x sqrt(5e4))
OUTSIDE_WEIGHT = 0.3
MAX_EVALUATIONS = 200


@dataclass
class Target:
    """One recording to fit: its name, measured profiles, the twin document at its gait (without a stance
    model), and the profile channels that count (vertical velocity only where the track is the IMU site)."""

    name: str
    measured: Profiles
    twin_doc: dict
    channels: tuple


def make_target(name: str, rec: Recording, track_t: np.ndarray, track_pos: np.ndarray, twin_doc: dict,
                site_track: bool) -> Target:
    """A :class:`Target` from a recording, its site track (t (M,) s, pos (M, 3) m) and its twin document;
    ``site_track`` says whether the track is the IMU site itself."""
    channels = ("rate_dps", "sagittal_rate_dps") + (
        ("forward_velocity_mps", "vertical_velocity_mps") if site_track else ())
    return Target(name, foot_flat_profiles(rec, track_t, track_pos), twin_doc, channels)


def micromotion_table(values: dict) -> dict:
    """A [micromotion] table (TOML units) from fitted values (``creep_forward_mps`` becomes the creep vector)."""
    table = {k: float(v) for k, v in values.items() if k != "creep_forward_mps"}
    if "creep_forward_mps" in values:
        table["creep_velocity_mps"] = [float(values["creep_forward_mps"]), 0.0, 0.0]
    return table


def twin_profiles(target: Target, table: dict, strides: int = FIT_STRIDES) -> Profiles:
    """Foot-flat profiles of the target's twin (``strides`` strides) with the stance model ``table``."""
    doc = copy.deepcopy(target.twin_doc)
    doc["micromotion"] = {**doc.get("micromotion", {}), **table}
    doc["path"]["length_m"] = strides * doc["gait"]["stride_length_m"]
    twin = simulate(doc)
    return foot_flat_profiles(twin, twin.truth.t, twin.truth.pos)


def profile_residuals(measured: Profiles, twin: Profiles, channels: tuple) -> np.ndarray:
    """Residuals of the twin's profiles against the measured ones (module docstring)."""
    inside = (measured.phase >= 0.0) & (measured.phase <= 1.0)
    rate = measured.median["rate_dps"][inside]
    weight = np.where(rate < GATE_DPS, 1.0, OUTSIDE_WEIGHT)
    parts = []
    for c in channels:
        have, want = twin.median[c][inside], measured.median[c][inside]
        if c == "rate_dps":
            parts.append(np.log((have + RATE_OFFSET_DPS) / (want + RATE_OFFSET_DPS)) / TOLERANCE[c])
        elif c == "sagittal_rate_dps":
            parts.append((have - want) / TOLERANCE[c])
        else:
            parts.append(weight * (have - want) / (TOLERANCE[c] + 0.1 * np.abs(want)))
    return np.concatenate(parts)


def _values(x: np.ndarray) -> dict:
    return {key: lo + xi * (hi - lo) for (key, lo, hi, _), xi in zip(FITTED, x)}


def _unit(values: dict) -> np.ndarray:
    return np.array([(values[key] - lo) / (hi - lo) for key, lo, hi, _ in FITTED])


@dataclass
class FitResult:
    """Fitted stance model: values (TOML units), the [micromotion] table, and per-target rms residuals (in
    units of the tolerance) at the start and at the optimum."""

    values: dict
    table: dict
    rms_start: dict
    rms_fit: dict
    evaluations: int

    def as_dict(self) -> dict:
        return {"values": self.values, "micromotion": self.table, "rms_residual_start": self.rms_start,
                "rms_residual_fit": self.rms_fit, "evaluations": self.evaluations,
                "tolerance": TOLERANCE, "fitted": [{"key": k, "low": lo, "high": hi} for k, lo, hi, _ in FITTED]}


def rms_by_target(targets: list[Target], table: dict) -> dict:
    """Per-target rms profile residual (in tolerances) of the stance model ``table``."""
    return {t.name: float(np.sqrt(np.mean(profile_residuals(t.measured, twin_profiles(t, table), t.channels) ** 2)))
            for t in targets}


def fit(targets: list[Target], start: dict | None = None, max_evaluations: int = MAX_EVALUATIONS) -> FitResult:
    """Fit the parameters of :data:`FITTED` jointly to ``targets`` (module docstring)."""
    start = start or {key: s for key, _, _, s in FITTED}
    count = [0]

    def cost(x):
        count[0] += 1
        table = micromotion_table(_values(np.clip(x, 0.0, 1.0)))
        parts = []
        for target in targets:
            try:
                parts.append(profile_residuals(target.measured, twin_profiles(target, table), target.channels))
            except ScenarioError:
                inside = np.sum((target.measured.phase >= 0) & (target.measured.phase <= 1)) * len(target.channels)
                parts.append(np.full(inside, 1e3))
        r = np.concatenate(parts)
        return np.where(np.isfinite(r), r, 1e3)

    x0 = _unit(start)
    found = least_squares(cost, x0, bounds=(0.0, 1.0), diff_step=0.02, max_nfev=max_evaluations, x_scale=1.0)
    values = _values(found.x)
    table = micromotion_table(values)
    return FitResult({k: float(v) for k, v in values.items()}, table, rms_by_target(targets, micromotion_table(start)),
                     rms_by_target(targets, table), count[0])


def cross_validate(targets: list[Target], folds: dict, start: dict | None = None) -> dict:
    """Fit on each fold's training targets and score every target: {fold: {"train": [...], "values": {...},
    "rms": {target: rms}}}. ``folds`` maps a fold name to the names of its training targets."""
    out = {}
    for fold, train in folds.items():
        result = fit([t for t in targets if t.name in train], start)
        out[fold] = {"train": list(train), "values": result.values,
                     "rms": rms_by_target(targets, result.table)}
    return out

