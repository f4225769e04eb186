"""Physical ranges of every numeric scenario key, in the key's own unit, with where each range comes from.

One line per key: adding a scenario key means adding its :class:`Range` to :data:`RANGES` (a test refuses a
numeric field of a world dataclass without one). :func:`check_ranges` applies the table to a section;
:func:`ranges_markdown` renders it for the docs (``docs/scenario-ranges.md`` is generated from it and a test
keeps the two equal). Vector keys (``start_m``, ``creep_velocity_mps``, ...) apply the range to each component.

The ranges are deliberately wider than any gait the simulator is tuned for (slow walking at 60 steps/min to
running at 180 steps/min, stance fractions from ~0.3 for running, peaks of ~20 g and ~2000 deg/s): they refuse
what no foot does, not what is unusual.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from .errors import ScenarioError


@dataclass(frozen=True)
class Range:
    """Allowed values of one scenario key: a finite number between ``low`` and ``high`` (key's unit).

    Attributes
    ----------
    low, high : bounds, in the key's unit.
    unit : the key's unit as written in the docs.
    source : where the range comes from (anchors.md section, gait literature, a numerical limit).
    open_low, open_high : exclude the bound itself.
    """

    low: float
    high: float
    unit: str
    source: str
    open_low: bool = False
    open_high: bool = False

    def contains(self, value: float) -> bool:
        """True for a finite value inside the range."""
        if not math.isfinite(value):
            return False
        above = value > self.low if self.open_low else value >= self.low
        below = value < self.high if self.open_high else value <= self.high
        return above and below

    def describe(self, unit: bool = True) -> str:
        """The interval in the usual notation, with the unit unless ``unit`` is False, e.g. ``(0, 0.5] s``."""
        return (f"{'(' if self.open_low else '['}{self.low:g}, {self.high:g}{')' if self.open_high else ']'}"
                + (f" {self.unit}" if self.unit and unit else ""))


GAIT_LITERATURE = "gait literature (Perry & Burnfield, Gait Analysis) and anchors §7"
PEAKS = "anchors §7: measured peaks 600-1000 deg/s walking, 1800 deg/s on stairs; common gyro range 2000 deg/s"
MOTION_CAPTURE = "anchors §7 (Vicon-tracked stance: mm/s creep, core-stance |w| 4-25 deg/s), x10 margin"
NUMERIC = "numerical: keeps the sample count and the allocation bounded"

# section -> scenario key -> range, in the key's unit
RANGES: dict[str, dict[str, Range]] = {
    "scenario": {
        "seed": Range(0, 2**63 - 1, "", "numpy seeds are non-negative integers"),
        "runs": Range(1, 100_000, "", NUMERIC),
    },
    "path": {
        "length_m": Range(0, 100_000, "m", NUMERIC + "; also at least one stride", open_low=True),
        "yaw_deg": Range(-360, 360, "deg", "one turn either way"),
        "start_m": Range(-1e6, 1e6, "m", "float64 keeps sub-micrometre resolution within 1000 km"),
        "radius_m": Range(0, 10_000, "m", NUMERIC + "; also at least one step", open_low=True),
        "turn_deg": Range(-36_000, 36_000, "deg", "100 turns either way"),
        "waypoints_m": Range(-1e6, 1e6, "m", NUMERIC),
        "corner_radius_m": Range(0, 1_000, "m", NUMERIC + "; also at least one step", open_low=True),
        "duration_s": Range(0, 86_400, "s", "one day", open_low=True),
    },
    "gait": {
        "cadence_steps_per_min": Range(40, 200, "steps/min", GAIT_LITERATURE + ": slow walking ~60, running ~180"),
        "stride_length_m": Range(0.3, 4.0, "m", GAIT_LITERATURE + ": shuffling ~0.5, walking 1.4, running <= 3.5"),
        "heel_rocker_frac": Range(0.01, 0.6, "", GAIT_LITERATURE),
        "foot_flat_frac": Range(0.01, 0.7, "", GAIT_LITERATURE),
        "push_off_frac": Range(0.01, 0.6, "", GAIT_LITERATURE),
        "swing_frac": Range(0.2, 0.8, "", GAIT_LITERATURE + ": swing 38-40 % walking, ~70 % running (stance ~0.3)"),
        "pitch_heel_strike_deg": Range(-75, 45, "deg", GAIT_LITERATURE + ": -15..-30 deg toes up (heel strike); "
                                       "a few deg toes down (forefoot strike: Lieberman et al., Nature 2010)"),
        "pitch_rate_heel_strike_dps": Range(-2500, 2500, "deg/s", PEAKS),
        "pitch_accel_heel_strike_dps2": Range(-200_000, 200_000, "deg/s^2", "gaitmap: -8000 deg/s^2 after toe off, x25"),
        "pitch_toe_off_deg": Range(0, 90, "deg", GAIT_LITERATURE + ": 35-60 deg heel up", open_low=True),
        "pitch_rate_toe_off_dps": Range(-2500, 2500, "deg/s", PEAKS),
        "pitch_accel_toe_off_dps2": Range(-200_000, 200_000, "deg/s^2", "gaitmap: -8000 deg/s^2 after toe off, x25"),
        "pitch_accel_to_swing_max_dps2": Range(-200_000, 0, "deg/s^2", "gaitmap: -8000 deg/s^2 after toe off, x25; "
                                               "0: no swing maximum knot"),
        "swing_height_m": Range(0, 0.6, "m", GAIT_LITERATURE + ": heel clearance 0.05-0.3 m (running)"),
        "toe_release_accel_mps2": Range(0, 500, "m/s^2", "the foot's forward acceleration at toe off: ~50 m/s^2 "
                                        "walking on gaitmap's Vicon, a few g running"),
        "toe_release_s": Range(0, 0.2, "s", "the last part of a push-off of 0.1-0.3 s", open_low=True),
        "swing_lead": Range(-0.5, 0.5, "", "fractions of the swing's travel; beyond half the heel would run "
                                           "backward"),
        "swing_lateral_m": Range(-0.3, 0.3, "m", GAIT_LITERATURE + ": a few cm of circumduction"),
        "swing_roll_deg": Range(-45, 45, "deg", GAIT_LITERATURE),
        "toe_out_deg": Range(-45, 45, "deg", GAIT_LITERATURE + ": foot progression angle 5-15 deg"),
        "stride_length_sd_m": Range(0, 0.5, "m", GAIT_LITERATURE + ": stride variability 1-5 %"),
        "cycle_sd_frac": Range(0, 0.2, "", GAIT_LITERATURE + ": stride-time variability 1-5 %", open_high=True),
        "pitch_sd_deg": Range(0, 15, "deg", GAIT_LITERATURE),
        "stand_start_s": Range(0.5, 3_600, "s", "the filter aligns on >= 0.5 s of rest; one hour at most"),
        "stand_end_s": Range(0.5, 3_600, "s", "the filter aligns on >= 0.5 s of rest; one hour at most"),
        "stop_every_strides": Range(0, 10_000, "strides", "0 = no stops; " + NUMERIC),
        "stop_duration_s": Range(0, 3_600, "s", "a stop at a crossing or a door: seconds to minutes; one hour at most"),
    },
    "impact": {
        "heel_strike_velocity_mps": Range(-5, 5, "m/s", GAIT_LITERATURE + ": heel speed at contact < 1 m/s walking"),
        "heel_strike_duration_s": Range(0.001, 0.2, "s", "heel-pad compression takes ~10-50 ms"),
        "slap_rate_dps": Range(0, 2500, "deg/s", PEAKS),
        "slap_duration_s": Range(0.001, 0.2, "s", "forefoot slap takes ~10-50 ms"),
        "ringing_hz": Range(0, 2_000, "Hz", "anchors §7: shoe/mount resonances 60-140 Hz; 0 = off (and < Nyquist)"),
        "ringing_damping": Range(0, 1, "", "an underdamped oscillation", open_low=True, open_high=True),
        "ringing_accel_mps2": Range(-200, 200, "m/s^2", "anchors §7: impact peaks 5-19 g"),
    },
    "micromotion": {
        "heel_rise_rate_start_dps": Range(-60, 60, "deg/s", MOTION_CAPTURE + "; a slow heel rise, not a push-off"),
        "heel_rise_growth_dps3": Range(0, 1_000, "deg/s^3", MOTION_CAPTURE + "; 1000 deg/s^3 reaches 60 deg/s "
                                                                         "after a 0.25 s foot flat"),
        "contact_transfer_pitch_deg": Range(0.01, 20, "deg", "sole curvature: a 0.2 m foot rolls heel to toe over "
                                                             "1-20 deg (sole radius 11 to 0.6 m); > 0"),
        "contact_radius_m": Range(0, 0.05, "m", "heel pad and sole compression: a few mm to cm"),
        "loading_roll_rate_dps": Range(-100, 100, "deg/s", MOTION_CAPTURE + "; loading pronation peaks 20-50 deg/s"),
        "loading_duration_s": Range(0, 0.5, "s", "a fraction of a stance", open_low=True),
        "pronation_rate_dps": Range(-100, 100, "deg/s", MOTION_CAPTURE),
        "stance_rate_sd_frac": Range(0, 1, "", "stride-to-stride variation of the stance rates (measured 0.27-0.32)"),
        "creep_velocity_mps": Range(-0.2, 0.2, "m/s", MOTION_CAPTURE),
        "creep_ramp_s": Range(0, 0.5, "s", "a fraction of a stance", open_low=True),
        "stance_roll_rate_dps": Range(-100, 100, "deg/s", MOTION_CAPTURE),
        "stance_rotation_dps": Range(-100, 100, "deg/s", MOTION_CAPTURE),
        "stance_yaw_pivot_frac": Range(0, 1, "", "0 = heel contact, 1 = toe contact"),
    },
    "mount": {
        "offset_m": Range(-0.3, 0.3, "m", "stays on a shoe (foot length ~0.27 m)"),
        "rpy_deg": Range(-180, 180, "deg", "any orientation of the sensor on the foot"),
    },
    "sampling": {
        "rate_hz": Range(50, 5_000, "Hz", "foot IMUs sample at 60-1000 Hz; nav refuses measured rates above 5 kHz"),
        "gravity_mps2": Range(9.7, 9.9, "m/s^2", "Earth's surface gravity, 9.78 (equator) to 9.83 (poles)"),
    },
    "nav": {
        "threshold": Range(0, 1e12, "", "a detector threshold is positive", open_low=True),
        "sigma_a_mps2": Range(0, 10, "m/s^2", "anchors §2: OpenShoe 0.01", open_low=True),
        "sigma_g_dps": Range(0, 100, "deg/s", "anchors §2: OpenShoe 0.1", open_low=True),
        "window": Range(1, 1_000, "samples", "anchors §2: OpenShoe 3"),
        "states": Range(9, 24, "", "9, 15 or 24 EKF states"),
    },
    "experiment": {
        "lab_seed": Range(0, 2**63 - 1, "", "numpy seeds are non-negative integers"),
        "calibration_walk_seed": Range(0, 2**63 - 1, "", "numpy seeds are non-negative integers"),
        "calibration_walks": Range(1, 1_000, "", NUMERIC),
        "tracker_rate_hz": Range(1, 1_000, "Hz", "anchors §1: Polhemus 60 Hz"),
        "tracker_resolution_m": Range(0, 0.1, "m", "anchors §1: 1 mm"),
        "tracker_noise_m": Range(0, 0.1, "m", "anchors §1: 1 mm resolution"),
        "stance_profile_knots": Range(2, 1_000, "", NUMERIC),
        "threshold_sweep": Range(0, 1e12, "", "a detector threshold is positive", open_low=True),
        "threshold_sweep_runs": Range(1, 100_000, "", NUMERIC),
        "fig4_thresholds": Range(0, 1e12, "", "a detector threshold is positive", open_low=True),
        "cycle_count": Range(1, 100_000, "", NUMERIC),
        "heading_walk_length_m": Range(1, 100_000, "m", NUMERIC),
        "budget_runs": Range(1, 100_000, "", NUMERIC),
        "sensitivity_runs": Range(1, 100_000, "", NUMERIC),
        "sensitivity_cadences": Range(40, 200, "steps/min", GAIT_LITERATURE + ": slow walking ~60, running ~180"),
        "workers": Range(1, 1_024, "", "worker processes"),
    },
}


def _numbers(value) -> Iterable[float]:
    """The numbers of a scalar, a vector or a list of vectors (waypoints)."""
    if isinstance(value, (list, tuple)):
        for item in value:
            yield from _numbers(item)
    elif isinstance(value, (int, float)) and not isinstance(value, bool):
        yield float(value)


def check_value(section: str, key: str, value, where: str) -> None:
    """Raise :class:`ScenarioError` unless every number of ``value`` lies in the range of ``section``/``key``.

    Parameters
    ----------
    section, key : where the range is looked up in :data:`RANGES` (a key without a range is not checked).
    value : a number, or a (nested) list of numbers each checked alone, in the key's unit.
    where : how the message names the file and table, e.g. ``"walk.toml [gait]"``.
    """
    bounds = RANGES.get(section, {}).get(key)
    if bounds is None:
        return
    for number in _numbers(value):
        if not bounds.contains(number):
            shown = list(value) if isinstance(value, tuple) else value
            what = "a finite number" if not math.isfinite(number) else "a value"
            raise ScenarioError(f"{where}: {key} = {shown!r} is not allowed; {key} must be {what} in "
                                f"{bounds.describe()} ({bounds.source})")


def check_ranges(section: str, table: dict, where: str, keys: Iterable[str] | None = None) -> None:
    """Check the keys of a TOML-shaped ``table`` (values in the keys' units) against :data:`RANGES`.

    ``keys`` limits (and orders) the keys checked; default: all keys of the table.
    """
    for key in (table if keys is None else keys):
        if key in table:
            check_value(section, key, table[key], where)


def _shown(value) -> str:
    """A default as written in a scenario file (``required`` for a key without one)."""
    if value is None:
        return "required"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_shown(v) for v in value) + "]"
    if isinstance(value, bool):
        return str(value).lower()
    return f"{value:g}" if isinstance(value, (int, float)) else f'"{value}"'


def key_defaults() -> dict[str, dict[str, object]]:
    """section -> scenario key -> default in the key's unit (None: required), read from the objects that hold the
    defaults (the world's dataclasses, the path builder's, sampling's and the experiment settings'). Imported
    here, not at the top: those modules check their keys with this one."""
    from nav.constants import DEFAULT_GRAVITY

    from .experiments.setup import ExperimentSettings, NavSettings
    from .scenario import DEFAULT_CORNER_RADIUS_M, DEFAULT_RATE_HZ, WORLD_SECTIONS, Scenario, section_table

    defaults = {"scenario": {f.name: f.default for f in dataclasses.fields(Scenario) if f.name in ("seed", "runs")},
                "path": {"length_m": None, "yaw_deg": 0.0, "start_m": [0.0, 0.0], "radius_m": None,
                         "turn_deg": None, "waypoints_m": None, "corner_radius_m": DEFAULT_CORNER_RADIUS_M,
                         "duration_s": None},
                "sampling": {"rate_hz": DEFAULT_RATE_HZ, "gravity_mps2": DEFAULT_GRAVITY},
                "nav": dataclasses.asdict(NavSettings()), "experiment": dataclasses.asdict(ExperimentSettings())}
    defaults.update({section: section_table(cls()) for section, cls in WORLD_SECTIONS.items()})
    return defaults


def _sensor_markdown() -> list[str]:
    """The [sensor] keys: SI unit, default (the ideal sensor's) and accepted units (:mod:`gaitsim.imu.config`)."""
    from .imu.model import PARAMETERS
    from .imu.units import accepted_units, si_unit

    lines = ["## [sensor]", "",
             "Each term is written `[value, \"unit\"]` in any accepted unit and converted to SI once; `preset` "
             "(ideal, vn200, paper-vn200, bmi160, adis16497; default ideal) sets every term, the keys override "
             "single terms. The sensor's timing is checked against the sample rate (`gaitsim/scenario.py`); "
             "noise densities, repeatabilities, instabilities, random walks, resolutions and jitter must be >= 0, "
             "time constants, ranges and bandwidths > 0.", "",
             "| key | SI unit | default (ideal) | accepted units |", "|---|---|---|---|"]
    for key, (kind, _shape, default) in PARAMETERS.items():
        default = np.asarray(default).tolist()
        lines.append(f"| `{key}` | {si_unit(kind) or '1'} | {_shown(default)} | {', '.join(accepted_units(kind))} |")
    return lines + [""]


def ranges_markdown() -> str:
    """The reference of every scenario key (``docs/scenario-ranges.md``): unit, default and allowed range, generated
    from :data:`RANGES`, :func:`key_defaults` and the sensor's parameter table."""
    defaults = key_defaults()
    lines = ["# Scenario keys: units, defaults, allowed ranges",
             "",
             "Generated from `gaitsim/ranges.py` (`python3 -m gaitsim.ranges > docs/scenario-ranges.md`); a test "
             "keeps this file equal to the code. Units are in the key names and in the tables; every number must "
             "be finite and inside its range; vector keys apply the range to each component. Cross-key rules "
             "(phases add up to the cycle, the swing fits, ringing below Nyquist, sensor timing against the "
             "sample period, the sample count) are listed in `gaitsim/scenario.py`. `[path]` keys apply by kind "
             "(straight: length_m, yaw_deg, start_m; arc: radius_m, turn_deg, yaw_deg, start_m; polyline: "
             "waypoints_m, corner_radius_m, closed; static: duration_s).",
             ""]
    for section, table in RANGES.items():
        lines += [f"## [{section}]", "", "| key | unit | default | allowed | source |", "|---|---|---|---|---|"]
        lines += [f"| `{key}` | {bounds.unit or '1'} | {_shown(defaults[section].get(key))} | "
                  f"{bounds.describe(unit=False)} | {bounds.source} |" for key, bounds in table.items()]
        lines.append("")
    return "\n".join(lines + _sensor_markdown())


if __name__ == "__main__":
    print(ranges_markdown(), end="")
