"""Parse a scenario's ``[sensor]`` TOML table into a :class:`~gaitsim.imu.model.SensorSpec`.

A table selects a preset and overrides single terms, each written as ``[value, "unit"]`` in datasheet units::

    [sensor]
    preset = "vn200"
    gyro_noise_density = [0.0035, "deg/s/sqrt(Hz)"]
    accel_bias = [[1, 2, 3], "mg"]
    gyro_g_sensitivity = [[[0.0041, 0.0002, -0.0005], [0.0002, 0.0025, 0.0002], [-0.0005, -0.0006, -0.0022]],
                          "deg/s/(m/s^2)"]
    withhold = true      # meta.json then says only that the sensor parameters were withheld

A per-axis value may be one number (all three axes) or a list of three. ``inf`` switches a range or a
bandwidth off. Values are converted once to SI (:mod:`gaitsim.imu.units`).

| key | value | accepted units (first = SI) |
|---|---|---|
| preset | string | ideal, vn200, paper-vn200, bmi160, adis16497 (default ideal) |
| withhold | bool | - |
| filter_order | int 1..8 | Butterworth order of the bandwidth low-pass (default 2) |
| filter_kind | "digital" or "analogue" | the low-pass is the sensor's digital filter or an analogue front end (default digital) |
| accel_noise_density | axes | m/s^2/sqrt(Hz), m/s/sqrt(s), m/s/sqrt(h), mg/sqrt(Hz), ug/sqrt(Hz) |
| gyro_noise_density | axes | rad/s/sqrt(Hz), rad/sqrt(s), deg/s/sqrt(Hz), deg/h/sqrt(Hz), deg/sqrt(h), deg/sqrt(s) |
| accel_bias, accel_bias_repeatability, accel_bias_instability | axes | m/s^2, mm/s^2, g, mg, ug |
| gyro_bias, gyro_bias_repeatability, gyro_bias_instability | axes | rad/s, mrad/s, deg/s, deg/h |
| accel_bias_instability_tau, gyro_bias_instability_tau | number | s, ms, us, ns, min, h (default 100 s) |
| accel_random_walk | axes | m/s^2/sqrt(s), m/s^2*sqrt(Hz), mg/sqrt(s), ug/sqrt(s), mg/sqrt(h), ug/sqrt(h), m/s/h/sqrt(h) |
| gyro_random_walk | axes | rad/s/sqrt(s), rad/s*sqrt(Hz), deg/s/sqrt(s), deg/s/sqrt(h), deg/h/sqrt(h), deg/h/sqrt(s) |
| accel_misalignment, gyro_misalignment | 3x3 | 1 (the full matrix M: scale factor on the diagonal) |
| gyro_g_sensitivity | 3x3 | rad/s/(m/s^2), deg/s/(m/s^2), rad/s/g, deg/s/g, deg/h/g |
| gyro_g2_sensitivity | 3x3 | rad/s/(m/s^2)^2, deg/s/(m/s^2)^2, rad/s/g^2, deg/s/g^2, deg/h/g^2 |
| accel_resolution, accel_range | number | acceleration units as accel_bias |
| gyro_resolution, gyro_range | number | angular-rate units as gyro_bias |
| accel_bandwidth, gyro_bandwidth | number | Hz, kHz |
| accel_temp_bias | axes | m/s^2/K, m/s^2/degC, mg/K, mg/degC, ug/K, ug/degC |
| gyro_temp_bias | axes | rad/s/K, rad/s/degC, deg/s/K, deg/s/degC, deg/h/K, deg/h/degC |
| accel_temp_scale, gyro_temp_scale | axes | 1/K, 1/degC, ppm/K, ppm/degC, %/K, %/degC |
| temperature | number or [start, end] | degC (a constant, or a linear ramp over the run; default 25) |
| temperature_ref | number | degC (default 25) |
| clock_error | number | 1, ppm, ppb, % (positive: the sensor clock runs fast) |
| timestamp_jitter, accel_gyro_skew | number | s, ms, us, ns, min, h (skew > 0: gyro sampled later) |
| mounting_misalignment | axes | rad, mrad, deg, arcmin (roll, pitch, yaw of the sensor on the foot) |

Unicode datasheet spellings (``°/√h``, ``µg/√Hz``) are accepted as well.
"""

from __future__ import annotations

import numpy as np

from gaitsim.errors import ScenarioError
from gaitsim.imu.model import FILTER_KINDS, PARAMETERS, SensorSpec
from gaitsim.imu.presets import PRESET_NAMES, get_preset
from gaitsim.imu.units import accepted_units, si_unit, to_si

PLAIN_KEYS = ("preset", "withhold", "filter_order", "filter_kind")
FILTER_KEYS = ("filter_order", "filter_kind")  # plain keys a sensor change may set
ACCEPTED_KEYS = PLAIN_KEYS + tuple(PARAMETERS)


def _parse_quantity(key: str, raw, where: str):
    """SI value of one ``[value, "unit"]`` entry."""
    kind = PARAMETERS[key][0]
    if not (isinstance(raw, (list, tuple)) and len(raw) == 2 and isinstance(raw[1], str)):
        raise ScenarioError(f"{where} {key}: expected [value, \"unit\"], got {raw!r}; "
                            f"accepted units: {accepted_units(kind)}")
    value, unit = raw
    return to_si(value, unit, kind, f"{where} {key}")


def sensor_from_table(table: dict, where: str = "[sensor]") -> SensorSpec:
    """Build the sensor of a scenario from its ``[sensor]`` table (keys and units in the module docstring).

    Parameters
    ----------
    table : the parsed TOML table.
    where : how error messages name the table (e.g. ``"scenarios/walk.toml [sensor]"``).

    Raises
    ------
    ScenarioError
        naming the key, the value and the accepted keys, units or choices.
    """
    if not isinstance(table, dict):
        raise ScenarioError(f"{where}: expected a table, got {table!r}")
    unknown = [key for key in table if key not in ACCEPTED_KEYS]
    if unknown:
        raise ScenarioError(f"{where}: unknown key(s) {unknown}; accepted keys: {list(ACCEPTED_KEYS)}")
    preset = table.get("preset", "ideal")
    if not isinstance(preset, str) or preset not in PRESET_NAMES:
        raise ScenarioError(f"{where} preset: {preset!r} is not a preset; choose from {list(PRESET_NAMES)}")
    withhold = table.get("withhold", False)
    if not isinstance(withhold, bool):
        raise ScenarioError(f"{where} withhold: expected true or false, got {withhold!r}")
    base = get_preset(preset)
    filter_order = _filter_order(table.get("filter_order", base.filter_order), where)
    filter_kind = _filter_kind(table.get("filter_kind", base.filter_kind), where)
    overrides = {key: _parse_quantity(key, raw, where) for key, raw in table.items() if key in PARAMETERS}
    try:
        return base.replace(
            name=preset if not overrides else f"{preset} (customised: {', '.join(overrides)})",
            filter_order=filter_order, filter_kind=filter_kind, withheld=withhold, **overrides,
        )
    except ScenarioError as exc:
        raise ScenarioError(f"{where} {exc}") from None


def _filter_order(value, where: str) -> int:
    """The ``filter_order`` key, checked (an integer 1..8)."""
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 8:
        raise ScenarioError(f"{where} filter_order: expected an integer in 1..8, got {value!r}")
    return value


def _filter_kind(value, where: str) -> str:
    """The ``filter_kind`` key, checked (one of :data:`gaitsim.imu.model.FILTER_KINDS`)."""
    if value not in FILTER_KINDS:
        raise ScenarioError(f"{where} filter_kind: expected one of {list(FILTER_KINDS)}, got {value!r}")
    return value


def changed_sensor(spec: SensorSpec | None, table: dict, where: str = "[sensor]") -> SensorSpec:
    """``spec`` (None: the ideal sensor) with the quantities of a ``[sensor]``-style table (``[value, "unit"]``
    entries, converted to SI) and its ``filter_order`` / ``filter_kind`` replaced; the other keys of a [sensor]
    table (preset, withhold) cannot change an existing sensor."""
    spec = get_preset("ideal") if spec is None else spec
    refused = [key for key in table if key not in PARAMETERS and key not in FILTER_KEYS]
    if refused:
        raise ScenarioError(f"{where}: key(s) {refused} cannot change a sensor; accepted keys: "
                            f"{list(PARAMETERS) + list(FILTER_KEYS)}")
    changes = {key: _parse_quantity(key, raw, where) for key, raw in table.items() if key not in FILTER_KEYS}
    if "filter_order" in table:
        changes["filter_order"] = _filter_order(table["filter_order"], where)
    if "filter_kind" in table:
        changes["filter_kind"] = _filter_kind(table["filter_kind"], where)
    try:
        return spec.replace(**changes)
    except ScenarioError as exc:
        raise ScenarioError(f"{where} {exc}") from None


def sensor_table(spec: SensorSpec) -> dict:
    """A ``[sensor]`` table that rebuilds ``spec``: the ideal preset, its filter order (and kind, when not the
    ideal sensor's), whether it is withheld, and every parameter that differs from the ideal sensor's, in SI with
    the unit's name."""
    ideal = get_preset("ideal")
    table = {"preset": "ideal", "filter_order": spec.filter_order, "withhold": spec.withheld}
    if spec.filter_kind != ideal.filter_kind:
        table["filter_kind"] = spec.filter_kind
    for key, (kind, _shape, _default) in PARAMETERS.items():
        if not np.array_equal(spec[key], ideal[key]):
            table[key] = [spec[key].tolist(), si_unit(kind)]
    return table
