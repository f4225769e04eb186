"""Scenario files (TOML): load, validate, and turn into a :class:`Scenario`; and back into TOML-shaped documents.

This module is the world's unit boundary: scenario keys carry their unit in the name (``pitch_toe_off_deg``,
``slap_rate_dps``, ...), the objects hold SI values under unit-free names (``GaitParams.pitch_toe_off`` in rad),
converted here once (:data:`IN_DEGREES`); :func:`scenario_document` writes the keys and units back.

Sections and keys (every key optional unless marked; units in the key names):

``[scenario]``  name (str), description (str), seed (int >= 0, default 0), runs (int >= 1, default 1)
``[path]``      kind = "straight" | "arc" | "polyline" | "static" (required)
                straight: length_m (>0), yaw_deg (walking direction, CCW from east; north = 90), start_m [x, y]
                arc:      radius_m (>= one step), turn_deg (signed, left positive), yaw_deg, start_m
                polyline: waypoints_m [[x, y], ...] (>= 2), corner_radius_m (>= one step), closed (bool)
                static:   duration_s (>0)
``[gait]``      kind = "custom" | "walk" | "run-rearfoot" | "run-forefoot" (default "custom"): the gait whose
                speed-dependent defaults (:mod:`gaitsim.world.gaits`, at the file's cadence) fill [gait],
                [impact] and [micromotion] under the keys the file writes; then the fields of
                :class:`gaitsim.world.gait.GaitParams`, angles in deg (``_deg``, ``_dps``, ``_dps2``). The
                resolved values are what a scenario holds: :func:`scenario_document` writes them all and no kind,
                and :func:`with_changes` changes them one by one (a changed cadence does not move the others).
``[impact]``    fields of :class:`gaitsim.world.gait.ImpactParams`, likewise
``[micromotion]`` fields of :class:`gaitsim.world.gait.MicroMotionParams`, likewise
``[mount]``     fields of :class:`gaitsim.world.foot.Mount`, likewise
``[sampling]``  rate_hz (>0, default 800), gravity_mps2 (>0, default nav's 9.81)
``[sensor]``    handed to :func:`gaitsim.imu.config.sensor_from_table` (absent: the ideal sensor)
``[nav]``, ``[experiment]``, ``[targets]``  kept as tables for the filter and the experiment runner (which
                validates them; ``[targets]`` holds the numbers a reproduction is measured against).

Every number must be finite and inside its physical range (:mod:`gaitsim.ranges`, tabulated in
``docs/scenario-ranges.md``); then the rules between keys hold: the phase fractions add up to 1, the swing
fits (mean foot speed <= MAX_SWING_SPEED) with its pitch maximum in its first half, the toe release fits the
push-off, the slap, heel strike and stance pulses fit their phases, ringing lies below the Nyquist frequency, the
sensor's jitter, skew, clock error and bandwidths suit the sample rate, and one run stays below MAX_SAMPLES
samples (estimated before anything is allocated). Rules over several keys are named after the key the user wrote.

Any unknown section or key, wrong type or impossible value raises :class:`ScenarioError` naming the file, the
key, the value and what is allowed; nothing is written.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from nav.constants import DEFAULT_GRAVITY

from .errors import ScenarioError
from .ranges import check_ranges, check_value
from .imu.config import changed_sensor, sensor_from_table, sensor_table
from .imu.model import SensorSpec
from .world import path as paths
from .world.foot import MOUNTS, Mount
from .world.gait import LABELLED_STANCES, GaitParams, ImpactParams, MicroMotionParams, Walk
from .world.gaits import kind_tables

DEG = math.pi / 180.0  # rad per deg (deg/s and deg/s^2 convert alike)
# scenario key (unit in its name) -> field of the world's dataclass that holds the quantity in SI (rad, rad/s, rad/s^2)
IN_DEGREES = {
    GaitParams: {"pitch_heel_strike_deg": "pitch_heel_strike", "pitch_rate_heel_strike_dps": "pitch_rate_heel_strike",
                 "pitch_accel_heel_strike_dps2": "pitch_accel_heel_strike", "pitch_toe_off_deg": "pitch_toe_off",
                 "pitch_rate_toe_off_dps": "pitch_rate_toe_off", "pitch_accel_toe_off_dps2": "pitch_accel_toe_off",
                 "pitch_accel_to_swing_max_dps2": "pitch_accel_to_swing_max",
                 "swing_roll_deg": "swing_roll", "toe_out_deg": "toe_out", "pitch_sd_deg": "pitch_sd"},
    ImpactParams: {"slap_rate_dps": "slap_rate"},
    MicroMotionParams: {"heel_rise_rate_start_dps": "heel_rise_rate_start", "heel_rise_growth_dps3": "heel_rise_growth",
                        "contact_transfer_pitch_deg": "contact_transfer_pitch", "loading_roll_rate_dps": "loading_roll_rate",
                        "pronation_rate_dps": "pronation_rate", "stance_roll_rate_dps": "stance_roll_rate",
                        "stance_rotation_dps": "stance_rotation_rate"},
    Mount: {"rpy_deg": "rpy"},
}
WORLD_SECTIONS = {"gait": GaitParams, "impact": ImpactParams, "micromotion": MicroMotionParams, "mount": Mount}
WRITTEN_DIGITS = 15  # significant digits of a converted value written back (the deg -> rad -> deg round trip is
# exact to them)

MAX_SWING_SPEED = 10.0  # m/s, mean foot speed over the swing (stride / swing time); sprinting feet reach ~2x this at peak
MAX_SWING_MAX_SHARE = 0.5  # the swing's pitch maximum comes in its first half (the foot turns back to land)
MAX_STRIDE_SD_SHARE = 0.25  # stride-to-stride spread of the stride length, share of the stride (4 sd stay > 0)
RADIUS_ROUNDING = 1e-9  # relative: a radius of exactly one step survives the rounding of a path's geometry
DEFAULT_RATE_HZ = 800.0  # [sampling] rate_hz when not given
DEFAULT_CORNER_RADIUS_M = 1.0  # [path] corner_radius_m of a polyline when not given
MAX_SAMPLES = 5_000_000  # samples of one run (~1.7 h at 800 Hz; ~0.7 kB of memory per sample while simulating)
MAX_JITTER_SHARE = 0.1  # timestamp jitter std, share of the sample period (10 sd apart: timestamps never reorder)
MAX_SKEW_S = 0.05  # s, accelerometer-gyro skew (the skewed channel loses this much data at each end)
MAX_CLOCK_ERROR = 0.01  # relative clock error (10,000 ppm; crystals are off by < 100 ppm)

PATH_KEYS = {
    "straight": {"kind", "length_m", "yaw_deg", "start_m"},
    "arc": {"kind", "radius_m", "turn_deg", "yaw_deg", "start_m"},
    "polyline": {"kind", "waypoints_m", "corner_radius_m", "closed"},
    "static": {"kind", "duration_s"},
}
SECTIONS = {"scenario", "path", "gait", "impact", "micromotion", "mount", "sampling", "sensor", "nav", "experiment",
            "targets"}


@dataclass(frozen=True)
class Scenario:
    """A validated scenario in SI: the walk, the mount, sampling (Hz, m/s^2), the sensor (None: ideal), and the
    [path] table as given (for the metadata) and the [nav], [experiment], [targets] tables (validated by their
    users)."""

    name: str
    walk: Walk
    mount: Mount = field(default_factory=Mount)
    rate_hz: float = DEFAULT_RATE_HZ
    gravity: float = DEFAULT_GRAVITY
    seed: int = 0
    runs: int = 1
    description: str = ""
    path_table: dict = field(default_factory=dict)
    sensor: SensorSpec | None = None
    nav: dict = field(default_factory=dict)
    experiment: dict = field(default_factory=dict)
    targets: dict = field(default_factory=dict)
    source: str = ""


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _check_type(where: str, key: str, value, default):
    """Coerce a TOML value to the type of ``default`` or raise naming key, value and the expected type."""
    if isinstance(default, bool):
        if not isinstance(value, bool):
            raise ScenarioError(f"{where}: {key} = {value!r} must be true or false")
        return value
    if isinstance(default, int) and not isinstance(default, bool):
        if not isinstance(value, int) or isinstance(value, bool):
            raise ScenarioError(f"{where}: {key} = {value!r} must be an integer")
        return value
    if isinstance(default, float):
        if not _is_number(value):
            raise ScenarioError(f"{where}: {key} = {value!r} must be a number")
        return float(value)
    if isinstance(default, str):
        if not isinstance(value, str):
            raise ScenarioError(f"{where}: {key} = {value!r} must be a string")
        return value
    if isinstance(default, tuple):
        if not (isinstance(value, list) and len(value) == len(default) and all(_is_number(x) for x in value)):
            raise ScenarioError(f"{where}: {key} = {value!r} must be a list of {len(default)} numbers")
        return tuple(float(x) for x in value)
    raise TypeError(f"no type rule for {key}")


def scenario_keys(cls) -> dict[str, str]:
    """Scenario key -> field name of the dataclass ``cls`` (keys in degrees name their SI field, others are equal)."""
    field_key = {name: key for key, name in IN_DEGREES.get(cls, {}).items()}
    return {field_key.get(f.name, f.name): f.name for f in dataclasses.fields(cls)}


def _scaled(value, factor: float):
    return tuple(x * factor for x in value) if isinstance(value, tuple) else value * factor


def fill(cls, table: dict, where: str, base=None):
    """Dataclass ``cls`` from a TOML table (keys in the table's units, converted to SI), on top of ``base``
    (default ``cls()``); unknown keys and wrong types are refused."""
    base = cls() if base is None else base
    keys = scenario_keys(cls)
    values = {}
    for key, value in table.items():
        if key not in keys:
            raise ScenarioError(f"{where}: unknown key {key!r}; allowed: {', '.join(sorted(keys))}")
        name = keys[key]
        checked = _check_type(where, key, value, getattr(base, name))
        values[name] = _scaled(checked, DEG) if name != key else checked
    return dataclasses.replace(base, **values)


def _from_degrees(value, digits: int | None):
    """A value in rad (or a tuple of them) in deg, rounded to ``digits`` significant digits (None: not rounded)."""
    if isinstance(value, tuple):
        return tuple(_from_degrees(x, digits) for x in value)
    value = value / DEG
    return value if digits is None else float(f"{value:.{digits}g}")


def section_table(obj, digits: int | None = WRITTEN_DIGITS) -> dict:
    """The TOML table of a world dataclass: every field under its scenario key, in that key's unit; converted
    values rounded to ``digits`` significant digits (None: full precision, for computing with them)."""
    out = {}
    for key, name in scenario_keys(type(obj)).items():
        value = getattr(obj, name)
        if name != key:
            value = _from_degrees(value, digits)
        out[key] = list(value) if isinstance(value, tuple) else value
    return out


def _checked(where: str, section: str, key: str, value, default):
    """``value`` coerced to the type of ``default`` (:func:`_check_type`) and checked against its range."""
    value = _check_type(where, key, value, default)
    check_value(section, key, value, where)
    return value


def _require(cond: bool, where: str, key: str, value, allowed: str):
    if not cond:
        raise ScenarioError(f"{where}: {key} = {value!r} is not allowed; {allowed}")


def _blamed(where: str, keys: dict, written: frozenset, allowed: str) -> ScenarioError:
    """The error of a rule over several keys (``{key: value in its unit}``), named after the first key of them
    the user wrote (``written``: keys as given in the file), the others shown as context."""
    first = next((k for k in keys if k in written), next(iter(keys)))
    others = ", ".join(f"{k} = {v!r}" for k, v in keys.items() if k != first)
    return ScenarioError(f"{where}: {first} = {keys[first]!r}{f' (with {others})' if others else ''} is not "
                         f"allowed; {allowed}")


def validate_gait(g: GaitParams, imp: ImpactParams, mm: MicroMotionParams, where: str,
                  written: frozenset = frozenset()) -> None:
    """Physical plausibility of the gait, impact and micro-motion parameters (SI objects; errors name the
    scenario keys and their values in the keys' units).

    Every value is first checked alone against its range (:mod:`gaitsim.ranges`), so a rule over several keys
    only ever sees finite, plausible values; ``written`` (scenario keys the user gave) decides which key a rule
    over several keys is named after.
    """
    tables = {"gait": section_table(g), "impact": section_table(imp), "micromotion": section_table(mm)}
    for section, table in tables.items():
        check_ranges(section, table, f"{where} [{section}]")
    gait, impact, micro = tables["gait"], tables["impact"], tables["micromotion"]
    fracs = ("heel_rocker_frac", "foot_flat_frac", "push_off_frac", "swing_frac")
    total = sum(getattr(g, k) for k in fracs)
    if abs(total - 1) > 1e-9:
        raise _blamed(f"{where} [gait]", {k: gait[k] for k in fracs}, written,
                      f"the phase fractions must add up to 1 (they add up to {total:.6g})")
    _require(g.labelled_stance in LABELLED_STANCES, f"{where} [gait]", "labelled_stance", g.labelled_stance,
             f"allowed: {', '.join(repr(k) for k in LABELLED_STANCES)}")
    strike = "forefoot strike" if g.forefoot_strike else "heel strike"
    if (g.pitch_heel_strike > 0) != g.forefoot_strike or g.pitch_heel_strike == 0:
        raise _blamed(f"{where} [gait]", {"pitch_heel_strike_deg": gait["pitch_heel_strike_deg"],
                                          "forefoot_strike": g.forefoot_strike}, written,
                      f"a {strike} lands {'toes down (pitch > 0)' if g.forefoot_strike else 'toes up (pitch < 0)'}")
    swing_s = g.swing_frac * g.cycle_s
    swing_speed = g.stride_length_m / swing_s
    if swing_speed > MAX_SWING_SPEED:
        raise _blamed(f"{where} [gait]", {k: gait[k] for k in ("swing_frac", "stride_length_m", "cadence_steps_per_min")},
                      written, f"the foot would cover the stride in {swing_s:.3g} s of swing at a mean "
                               f"{swing_speed:.3g} m/s; at most {MAX_SWING_SPEED} m/s (a sprinting foot)")
    if g.pitch_accel_to_swing_max < 0:
        stop_s = g.pitch_rate_toe_off / -g.pitch_accel_to_swing_max
        if not 0 < stop_s < MAX_SWING_MAX_SHARE * swing_s:
            raise _blamed(f"{where} [gait]", {k: gait[k] for k in ("pitch_accel_to_swing_max_dps2",
                                                                    "pitch_rate_toe_off_dps", "swing_frac",
                                                                    "cadence_steps_per_min")}, written,
                          f"the swing's pitch maximum comes pitch_rate_toe_off / |pitch_accel_to_swing_max| = "
                          f"{stop_s:.3g} s after toe off; it needs a toe-off rate turning the toes down (> 0) and "
                          f"must come in the first {MAX_SWING_MAX_SHARE:.0%} of the swing ({swing_s:.3g} s)")
    push_off_s = g.push_off_frac * g.cycle_s
    if g.toe_release_accel_mps2 and g.toe_release_s > push_off_s:
        raise _blamed(f"{where} [gait]", {k: gait[k] for k in ("toe_release_s", "push_off_frac",
                                                                "cadence_steps_per_min")}, written,
                      f"the toe release must fit in the push-off ({push_off_s:.3g} s)")
    if g.stride_length_sd_m > MAX_STRIDE_SD_SHARE * g.stride_length_m:
        raise _blamed(f"{where} [gait]", {k: gait[k] for k in ("stride_length_sd_m", "stride_length_m")}, written,
                      f"the stride-to-stride spread must be at most {MAX_STRIDE_SD_SHARE:.0%} of the stride")
    rocker = g.heel_rocker_frac * g.cycle_s
    if not imp.slap_duration_s < 0.8 * rocker:
        raise _blamed(f"{where} [impact]", {"slap_duration_s": impact["slap_duration_s"],
                                            "heel_rocker_frac": gait["heel_rocker_frac"],
                                            "cadence_steps_per_min": gait["cadence_steps_per_min"]}, written,
                      f"the slap must be shorter than 80% of the heel rocker ({rocker:.3f} s)")
    if not imp.heel_strike_duration_s < rocker - imp.slap_duration_s:
        raise _blamed(f"{where} [impact]", {"heel_strike_duration_s": impact["heel_strike_duration_s"],
                                            "slap_duration_s": impact["slap_duration_s"],
                                            "heel_rocker_frac": gait["heel_rocker_frac"]}, written,
                      "the heel strike must end before the forefoot slap")
    if imp.ringing_hz > 0:
        _require(imp.ringing_hz >= 5, f"{where} [impact]", "ringing_hz", imp.ringing_hz,
                 "must be 0 (off) or >= 5 Hz (the ringing must die out within the stance)")
    push = g.push_off_frac * g.cycle_s
    if not mm.creep_ramp_s < min(rocker, push):
        raise _blamed(f"{where} [micromotion]", {"creep_ramp_s": micro["creep_ramp_s"],
                                                 "heel_rocker_frac": gait["heel_rocker_frac"],
                                                 "push_off_frac": gait["push_off_frac"]}, written,
                      f"the creep ramp must be shorter than the heel rocker and push-off ({min(rocker, push):.3f} s)")
    transfer_limit = 2.0 * min(abs(g.pitch_heel_strike), g.pitch_toe_off)
    if not mm.contact_transfer_pitch <= transfer_limit:
        raise _blamed(f"{where} [micromotion]", {"contact_transfer_pitch_deg": micro["contact_transfer_pitch_deg"],
                                                 "pitch_heel_strike_deg": gait["pitch_heel_strike_deg"],
                                                 "pitch_toe_off_deg": gait["pitch_toe_off_deg"]}, written,
                      f"the foot must strike on its heel (or, striking with the forefoot, on its toes) and leave the "
                      f"ground from its toes, outside the pitch range +-half the transfer pitch over which the "
                      f"contact rolls along the sole: at most {math.degrees(transfer_limit):.3g} deg (twice the "
                      f"smaller of the strike and toe-off pitch)")
    _require(mm.foot in ("left", "right"), f"{where} [micromotion]", "foot", mm.foot, "allowed: left, right")
    flat = g.foot_flat_frac * g.cycle_s
    if not mm.loading_duration_s < flat:
        raise _blamed(f"{where} [micromotion]", {"loading_duration_s": micro["loading_duration_s"],
                                                 "foot_flat_frac": gait["foot_flat_frac"]}, written,
                      f"the loading pronation pulse must be shorter than the foot flat ({flat:.3f} s)")
    held = {k: micro[k] for k in ("stance_rotation_dps", "pronation_rate_dps") if np.any(micro[k])}
    if held and not 2 * mm.creep_ramp_s < flat:
        raise _blamed(f"{where} [micromotion]", {**held, "creep_ramp_s": micro["creep_ramp_s"],
                                                 "foot_flat_frac": gait["foot_flat_frac"]}, written,
                      f"a rate held through the foot flat needs a foot flat ({flat:.3f} s) longer than two creep "
                      f"ramps")


def build_path(table: dict, gait: GaitParams, where: str):
    """The :class:`gaitsim.world.path.Path` of a [path] table (None for ``static``) and the static duration (s)."""
    kind = table.get("kind")
    _require(kind in PATH_KEYS, where, "kind", kind, f"allowed: {', '.join(PATH_KEYS)}")
    for key in table:
        if key not in PATH_KEYS[kind]:
            raise ScenarioError(f"{where}: unknown key {key!r} for kind {kind!r}; allowed: {', '.join(sorted(PATH_KEYS[kind]))}")
    num = lambda key, default=None: _checked(where, "path", key, table.get(key, default), 0.0)  # noqa: E731
    step = gait.stride_length_m / 2 * (1 - RADIUS_ROUNDING)
    if kind == "static":
        _require("duration_s" in table, where, "duration_s", None, "required for kind 'static'")
        d = num("duration_s")
        _require(d > 0, where, "duration_s", d, "must be > 0")
        return None, d
    if kind in ("straight", "arc"):
        start = _checked(where, "path", "start_m", table.get("start_m", [0.0, 0.0]), (0.0, 0.0))
        yaw = np.deg2rad(num("yaw_deg", 0.0))
    if kind == "straight":
        _require("length_m" in table, where, "length_m", None, "required for kind 'straight'")
        length = num("length_m")
        _require(length >= gait.stride_length_m, where, "length_m", length,
                 f"must be at least one stride ({gait.stride_length_m} m)")
        return paths.straight(length, yaw, start), 0.0
    if kind == "arc":
        for key in ("radius_m", "turn_deg"):
            _require(key in table, where, key, None, "required for kind 'arc'")
        radius, turn = num("radius_m"), num("turn_deg")
        _require(radius >= step, where, "radius_m", radius, f"a turn radius must be at least one step ({step} m)")
        _require(abs(turn) * np.pi / 180 * radius >= gait.stride_length_m, where, "turn_deg", turn,
                 "the arc must be at least one stride long")
        return paths.arc(radius, np.deg2rad(turn), yaw, start), 0.0
    pts = table.get("waypoints_m")
    ok = isinstance(pts, list) and len(pts) >= 2 and all(
        isinstance(p, list) and len(p) == 2 and all(_is_number(x) for x in p) for p in pts)
    _require(ok, where, "waypoints_m", pts, "must be a list of at least two [x, y] points (m)")
    check_value("path", "waypoints_m", pts, where)
    radius = num("corner_radius_m", DEFAULT_CORNER_RADIUS_M)
    _require(radius >= step, where, "corner_radius_m", radius, f"a turn radius must be at least one step ({step} m)")
    w = np.array(pts, float)
    if _check_type(where, "closed", table.get("closed", False), False):
        w = np.vstack([w, w[:1]])
    _require(bool(np.all(np.linalg.norm(np.diff(w, axis=0), axis=1) > 0)), where, "waypoints_m", pts,
             "consecutive waypoints must differ")
    try:
        path = paths.polyline(w, radius)
    except ValueError as exc:
        raise ScenarioError(f"{where}: corner_radius_m = {radius}: {exc}") from None
    _require(path.length >= gait.stride_length_m, where, "waypoints_m", pts, "the path must be at least one stride long")
    return path, 0.0


def scenario_from_dict(doc: dict, source: str = "<scenario>") -> Scenario:
    """Validate a parsed TOML document (see the module docstring) into a :class:`Scenario`."""
    for section in doc:
        if section not in SECTIONS:
            raise ScenarioError(f"{source}: unknown section [{section}]; allowed: {', '.join(sorted(SECTIONS))}")
        if not isinstance(doc[section], dict):
            raise ScenarioError(f"{source}: {section} must be a table [{section}]")
    head = doc.get("scenario", {})
    allowed = {"name", "description", "seed", "runs"}
    for key in head:
        _require(key in allowed, f"{source} [scenario]", key, head[key], f"unknown key; allowed: {', '.join(sorted(allowed))}")
    name = _check_type(f"{source} [scenario]", "name", head.get("name", Path(source).stem), "")
    seed = _checked(f"{source} [scenario]", "scenario", "seed", head.get("seed", 0), 0)
    runs = _checked(f"{source} [scenario]", "scenario", "runs", head.get("runs", 1), 0)
    written = frozenset(key for section in doc.values() for key in section)

    tables = _world_tables(doc, source)
    gait = fill(GaitParams, tables["gait"], f"{source} [gait]")
    impact = fill(ImpactParams, tables["impact"], f"{source} [impact]")
    micro = fill(MicroMotionParams, tables["micromotion"], f"{source} [micromotion]")
    validate_gait(gait, impact, micro, source, written)
    mount = _mount(doc.get("mount", {}), Mount(), source)
    rate, gravity = _sampling(doc.get("sampling", {}), DEFAULT_RATE_HZ, DEFAULT_GRAVITY, source)

    if "path" not in doc:
        raise ScenarioError(f"{source}: missing section [path] (kind = straight | arc | polyline | static)")
    path, duration = build_path(doc["path"], gait, f"{source} [path]")
    sensor = sensor_from_table(doc["sensor"], where=f"{source} [sensor]") if "sensor" in doc else None
    walk = Walk(path=path, gait=gait, impact=impact, micro=micro, duration_s=duration)
    validate_sampling(walk, rate, sensor, source, written)
    return Scenario(
        name=name, walk=walk, mount=mount, rate_hz=rate, gravity=gravity, seed=seed, runs=runs,
        description=_check_type(f"{source} [scenario]", "description", head.get("description", ""), ""),
        path_table=dict(doc["path"]), sensor=sensor, nav=dict(doc.get("nav", {})),
        experiment=dict(doc.get("experiment", {})), targets=dict(doc.get("targets", {})), source=source,
    )


def _world_tables(doc: dict, source: str) -> dict[str, dict]:
    """The [gait], [impact] and [micromotion] tables of ``doc``, on top of the defaults of its gait kind."""
    gait = dict(doc.get("gait", {}))
    kind = _check_type(f"{source} [gait]", "kind", gait.pop("kind", "custom"), "")
    cadence = gait.get("cadence_steps_per_min")
    if cadence is not None:
        cadence = _checked(f"{source} [gait]", "gait", "cadence_steps_per_min", cadence, 0.0)
    try:
        defaults = kind_tables(kind, cadence)
    except ValueError as exc:
        raise ScenarioError(f"{source} [gait]: {exc}") from None
    return {"gait": {**defaults["gait"], **gait},
            **{s: {**defaults[s], **doc.get(s, {})} for s in ("impact", "micromotion")}}


def expected_samples(walk: Walk, rate_hz: float) -> int:
    """Samples of one run of ``walk`` at ``rate_hz``, estimated from the path and the gait before anything is
    allocated (an upper bound: every cycle 4 sd long, one extra stride, one extra stop)."""
    g = walk.gait
    if walk.path is None:
        return int(math.ceil(walk.duration_s * rate_hz)) + 1
    strides = max(1, round(walk.path.length / g.stride_length_m)) + 1
    stops = strides // g.stop_every_strides if g.stop_every_strides > 0 else 0
    duration = (g.stand_start_s + g.stand_end_s + strides * g.cycle_s * (1 + 4 * g.cycle_sd_frac)
                + stops * g.stop_duration_s)
    return int(math.ceil(duration * rate_hz)) + 1


def validate_sampling(walk: Walk, rate_hz: float, sensor: SensorSpec | None, source: str,
                      written: frozenset = frozenset()) -> None:
    """Rules between the walk, the sample rate and the sensor: the size of a run, ringing below the Nyquist
    frequency, and the sensor's timing terms and bandwidths against the sample period."""
    samples = expected_samples(walk, rate_hz)
    if samples > MAX_SAMPLES:
        size = ({"duration_s": walk.duration_s} if walk.path is None else
                {"length_m": round(walk.path.length, 6), "stride_length_m": walk.gait.stride_length_m})
        raise _blamed(f"{source} [path]", {**size, "rate_hz": rate_hz}, written,
                      f"one run would hold about {samples:.3g} samples (~{samples * 0.7e-6:.3g} GB while simulated); "
                      f"at most {MAX_SAMPLES:.3g}: shorten the walk or lower the rate")
    nyquist = rate_hz / 2
    if walk.impact.ringing_hz >= nyquist:
        raise _blamed(f"{source} [impact]", {"ringing_hz": walk.impact.ringing_hz, "rate_hz": rate_hz}, written,
                      f"the ringing must lie below the Nyquist frequency ({nyquist:g} Hz) to be sampled at all")
    if sensor is None:
        return
    where = f"{source} [sensor]"
    period = 1.0 / rate_hz
    jitter = float(sensor["timestamp_jitter"])
    _require(jitter <= MAX_JITTER_SHARE * period, where, "timestamp_jitter", f"{jitter:g} s",
             f"must be at most {MAX_JITTER_SHARE:g} of the sample period ({MAX_JITTER_SHARE * period:g} s at "
             f"{rate_hz:g} Hz): larger jitter reorders the timestamps")
    skew = float(sensor["accel_gyro_skew"])
    _require(abs(skew) <= MAX_SKEW_S, where, "accel_gyro_skew", f"{skew:g} s",
             f"must lie within +-{MAX_SKEW_S:g} s (the skewed channel loses |skew| of data at each end)")
    clock = float(sensor["clock_error"])
    _require(abs(clock) <= MAX_CLOCK_ERROR, where, "clock_error", f"{clock:g}",
             f"must lie within +-{MAX_CLOCK_ERROR:g} ({MAX_CLOCK_ERROR * 1e6:g} ppm)")
    for key in ("accel_bandwidth", "gyro_bandwidth"):
        bandwidth = float(sensor[key])
        _require(not math.isfinite(bandwidth) or bandwidth < nyquist, where, key, f"{bandwidth:g} Hz",
                 f"must lie below the Nyquist frequency ({nyquist:g} Hz at {rate_hz:g} Hz), or inf (off)")


def _mount(table: dict, base: Mount, source: str) -> Mount:
    mount = fill(Mount, table, f"{source} [mount]", base)
    check_ranges("mount", section_table(mount), f"{source} [mount]")
    _require(mount.site in MOUNTS, f"{source} [mount]", "site", mount.site, f"allowed: {', '.join(MOUNTS)}")
    return mount


def _sampling(table: dict, rate: float, gravity: float, source: str) -> tuple[float, float]:
    """(rate_hz, gravity m/s^2) of a [sampling] table on top of the given values."""
    for key in table:
        _require(key in ("rate_hz", "gravity_mps2"), f"{source} [sampling]", key, table[key],
                 "unknown key; allowed: gravity_mps2, rate_hz")
    rate = _checked(f"{source} [sampling]", "sampling", "rate_hz", table.get("rate_hz", rate), 0.0)
    gravity = _checked(f"{source} [sampling]", "sampling", "gravity_mps2", table.get("gravity_mps2", gravity), 0.0)
    _require(rate >= 50, f"{source} [sampling]", "rate_hz", rate, "must be >= 50 Hz")
    _require(gravity > 0, f"{source} [sampling]", "gravity_mps2", gravity, "must be > 0")
    return rate, gravity


def with_changes(scenario: Scenario, changes: dict, source: str = "<changes>") -> Scenario:
    """``scenario`` with TOML-shaped ``changes`` ``{section: {key: value}}`` (keys and units as in a scenario
    file) to its [gait], [impact], [micromotion], [mount], [sampling] or [sensor] keys, validated like a file.

    Raises
    ------
    ScenarioError
        naming the section, key and value that cannot be used.
    """
    unknown = set(changes) - set(WORLD_SECTIONS) - {"sampling", "sensor"}
    if unknown:
        raise ScenarioError(f"{source}: sections {sorted(unknown)} cannot be changed; allowed: "
                            f"{', '.join(sorted(WORLD_SECTIONS))}, sampling, sensor")
    walk = scenario.walk
    gait = fill(GaitParams, changes.get("gait", {}), f"{source} [gait]", walk.gait)
    impact = fill(ImpactParams, changes.get("impact", {}), f"{source} [impact]", walk.impact)
    micro = fill(MicroMotionParams, changes.get("micromotion", {}), f"{source} [micromotion]", walk.micro)
    written = frozenset(key for section in changes.values() if isinstance(section, dict) for key in section)
    validate_gait(gait, impact, micro, source, written)
    if walk.path is not None:
        step = gait.stride_length_m / 2 * (1 - RADIUS_ROUNDING)
        _require(walk.path.min_radius >= step, f"{source} [path]", "turn radius", walk.path.min_radius,
                 f"a turn radius must be at least one step ({step} m)")
        _require(walk.path.length >= gait.stride_length_m, f"{source} [path]", "length", walk.path.length,
                 f"must be at least one stride ({gait.stride_length_m} m)")
    mount = _mount(changes.get("mount", {}), scenario.mount, source)
    rate, gravity = _sampling(changes.get("sampling", {}), scenario.rate_hz, scenario.gravity, source)
    sensor = scenario.sensor
    if "sensor" in changes:
        sensor = changed_sensor(sensor, changes["sensor"], f"{source} [sensor]")
    walk = dataclasses.replace(walk, gait=gait, impact=impact, micro=micro)
    validate_sampling(walk, rate, sensor, source, written)
    return dataclasses.replace(scenario, walk=walk, mount=mount, rate_hz=rate, gravity=gravity, sensor=sensor)


def scenario_document(scenario: Scenario) -> dict:
    """The TOML-shaped document of ``scenario`` (keys with their units; :func:`scenario_from_dict` reads it back
    to the same scenario, its converted values to ``WRITTEN_DIGITS`` significant digits)."""
    walk = scenario.walk
    doc = {"scenario": {"name": scenario.name, "description": scenario.description, "seed": scenario.seed,
                        "runs": scenario.runs},
           "path": dict(scenario.path_table),
           **{section: section_table(obj) for section, obj in
              (("gait", walk.gait), ("impact", walk.impact), ("micromotion", walk.micro), ("mount", scenario.mount))},
           "sampling": {"rate_hz": scenario.rate_hz, "gravity_mps2": scenario.gravity}}
    if scenario.sensor is not None:
        doc["sensor"] = sensor_table(scenario.sensor)
    for section in ("nav", "experiment", "targets"):
        if getattr(scenario, section):
            doc[section] = dict(getattr(scenario, section))
    return doc


def read_toml(path: str | Path, what: str = "scenario") -> dict:
    """The document of a TOML file; ScenarioError naming the file (a ``what`` file) when it is missing or not
    valid TOML."""
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise ScenarioError(f"{path}: {what} file not found") from None
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"{path}: not valid TOML: {exc}") from None


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario TOML file."""
    return scenario_from_dict(read_toml(path), str(path))
