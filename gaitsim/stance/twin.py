"""The simulated twin of a recording for the stance study: a straight walk at the recording's gait and rate, a
sensor (ideal or of the recording's class) and the simulator's default stance model.

"The same gait" is what a gait lab reports for a walk, measured from the recording alone
(:func:`measure_gait`):

- cadence from the median stride period (time between consecutive initial contacts);
- stride length from the median distance between consecutive stance middles in the position track;
- the foot flat's duration from the IMU's gait events (:func:`gaitsim.stance.events.gait_events`): median
  time from forefoot contact to heel off, both read at a sagittal rate of 50 deg/s. The model's slap and
  push-off cross that rate a little inside its phase boundaries, so the twin's foot-flat fraction is matched
  by simulation (``TIMING_ROUNDS`` rounds: simulate, read the twin's events the same way, correct by the
  difference). The heel rocker and push-off keep the default gait's fractions of the cycle and its pitch
  profile; the swing takes the rest (:func:`timing_report` gives measured and twin phase durations);
- the sample rate, and the number of strides (a straight walk of that many strides).

The IMU site on the foot is an input (:class:`TwinSpec`), not fitted here: one of the simulator's named
mounts, or a measured offset (gaitmap: from the Vicon pose, :data:`gaitsim.stance.command.SITES`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from nav.recording import Recording
from nav.series import resample

from ..world.gait import GaitParams
from ..ranges import RANGES
from ..scenario import scenario_from_dict
from ..simulate import sense, simulate_walk, simulate_world
from .profiles import detected_gait

TWIN_SEED = 5
MIN_STRIDES = 8
TIMING_ROUNDS = 2
MIN_SWING_FRAC = RANGES["gait"]["swing_frac"].low  # the foot flat is shortened where the swing would be shorter
PHASES = ("heel_rocker", "foot_flat", "push_off")


@dataclass(frozen=True)
class GaitSummary:
    """The measured gait of a recording (module docstring).

    Attributes
    ----------
    stride_period_s : s.   stride_length_m : m.
    heel_rocker_s, foot_flat_s, push_off_s : s, median event-to-event durations.
    strides : number of steady strides the stride-period median came from (the phase medians use every
        complete stance, the stride length every walking step).   rate_hz : Hz, median sample rate.
    """

    stride_period_s: float
    stride_length_m: float
    heel_rocker_s: float
    foot_flat_s: float
    push_off_s: float
    strides: int
    rate_hz: float

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


def _phase_durations(rec: Recording) -> tuple[dict, np.ndarray, object]:
    """Median durations (s) of the stance phases, the stride periods (s) and the detected stances of ``rec``."""
    t = np.asarray(rec.t, float)
    _, stances, ev = detected_gait(rec)
    ok = ev.complete()
    durations = {"heel_rocker": float(np.median(t[ev.ff[ok]] - t[ev.ic[ok]])),
                 "foot_flat": float(np.median(t[ev.ho[ok]] - t[ev.ff[ok]])),
                 "push_off": float(np.median(t[ev.to[ok]] - t[ev.ho[ok]]))}
    return durations, np.diff(t[ev.ic[ev.ic >= 0]]), stances


def measure_gait(rec: Recording, track_t: np.ndarray, track_pos: np.ndarray) -> GaitSummary:
    """The gait of ``rec`` from its IMU (events, at the largest threshold of the sweep) and its position track
    (t (N,) s, pos (N, 3) m)."""
    t = np.asarray(rec.t, float)
    durations, periods, stances = _phase_durations(rec)
    period = float(np.median(periods))
    steady = (periods > 0.6 * period) & (periods < 1.5 * period)
    finite = np.all(np.isfinite(track_pos), axis=1)
    middles = t[stances.middles()]
    xy = resample(middles, track_t[finite], track_pos[finite, :2])
    steps = np.linalg.norm(np.diff(xy, axis=0), axis=1)
    walking = steps > 0.25 * np.median(steps)
    return GaitSummary(stride_period_s=float(np.median(periods[steady])),
                       stride_length_m=float(np.median(steps[walking])),
                       **{f"{name}_s": durations[name] for name in PHASES},
                       strides=int(np.sum(steady)), rate_hz=round(float(1.0 / np.median(np.diff(t))), 1))


@dataclass(frozen=True)
class TwinSpec:
    """What the twin is given besides the gait: the IMU site ([mount] table), the stance model ([micromotion]
    table, TOML units; empty = the simulator's defaults) and the sensor ([sensor] table; empty = ideal)."""

    mount: dict = field(default_factory=dict)
    micromotion: dict = field(default_factory=dict)
    sensor: dict = field(default_factory=dict)


def twin_document(gait: GaitSummary, foot_flat_frac: float, spec: TwinSpec = TwinSpec()) -> dict:
    """Scenario document of the twin with the given foot-flat fraction of the cycle (module docstring)."""
    strides = max(gait.strides, MIN_STRIDES)
    base = GaitParams()
    flat = min(foot_flat_frac, 1.0 - MIN_SWING_FRAC - base.heel_rocker_frac - base.push_off_frac)
    doc = {
        "scenario": {"name": "stance-twin", "seed": TWIN_SEED},
        "path": {"kind": "straight", "length_m": strides * gait.stride_length_m, "yaw_deg": 0.0},
        "gait": {"cadence_steps_per_min": 120.0 / gait.stride_period_s, "stride_length_m": gait.stride_length_m,
                 "foot_flat_frac": float(flat),
                 "swing_frac": max(MIN_SWING_FRAC, float(1.0 - base.heel_rocker_frac - base.push_off_frac - flat))},
        "sampling": {"rate_hz": gait.rate_hz},
    }
    if spec.mount:
        doc["mount"] = dict(spec.mount)
    if spec.micromotion:
        doc["micromotion"] = dict(spec.micromotion)
    if spec.sensor:
        doc["sensor"] = dict(spec.sensor)
    return doc


def simulate(doc: dict) -> Recording:
    """Simulate a twin document (its truth is the site track)."""
    return simulate_walk(scenario_from_dict(doc, "<stance twin>"), seed=TWIN_SEED)


def simulate_sensed_and_ideal(doc: dict) -> tuple[Recording, Recording]:
    """The twin document's walk simulated once and read by its [sensor] and by the ideal sensor: the recordings
    :func:`simulate` gives for the document with and without its [sensor] table."""
    scenario = scenario_from_dict(doc, "<stance twin>")
    world = simulate_world(scenario, TWIN_SEED)
    return sense(*world, scenario.sensor, TWIN_SEED), sense(*world, None, TWIN_SEED)


def match_timing(gait: GaitSummary, spec: TwinSpec = TwinSpec()) -> dict:
    """Twin document whose simulated gait events give the measured phase durations (module docstring)."""
    flat = gait.foot_flat_s / gait.stride_period_s
    for _ in range(TIMING_ROUNDS):
        doc = twin_document(gait, flat, spec)
        twin_durations, _, _ = _phase_durations(simulate(doc))
        flat = doc["gait"]["foot_flat_frac"] + (gait.foot_flat_s - twin_durations["foot_flat"]) / gait.stride_period_s
    return twin_document(gait, flat, spec)


def timing_report(gait: GaitSummary, twin: Recording) -> dict:
    """Measured and twin phase durations (s), read from the IMU the same way."""
    twin_durations, _, _ = _phase_durations(twin)
    return {name: {"measured_s": getattr(gait, f"{name}_s"), "twin_s": twin_durations[name]} for name in PHASES}
