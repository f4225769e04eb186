"""Datasheet units: named unit strings converted once to SI at the configuration boundary.

Every configurable sensor quantity has a *kind* (a physical dimension). Each kind has one SI unit (the unit
used inside the simulator) and a table of accepted unit strings with their factor to SI. A value given in a
unit of another kind, or in an unknown unit, is refused with a message naming the key, the value and the
accepted units.

Unit strings are compared after removing spaces and mapping the usual datasheet glyphs: ``µ``/``μ`` -> ``u``,
``°`` -> ``deg``, ``√x`` -> ``sqrt(x)``, ``²`` -> ``^2``. The ``g`` in ``mg``, ``ug``, ``deg/s/g``, ... is
standard gravity 9.80665 m/s^2 (the datasheet convention), not the simulator's local gravity.
Temperatures are kept in degrees Celsius inside (they are only ever used as differences from a reference).
"""

from __future__ import annotations

import math
import re

import numpy as np

from nav.constants import STANDARD_GRAVITY

from gaitsim.errors import ScenarioError

_DEG = math.pi / 180.0
_HOUR = 3600.0
_SQRT_HOUR = 60.0  # sqrt(3600 s)
_G = STANDARD_GRAVITY

# kind -> (SI unit name, {accepted unit string: factor to SI})
UNIT_KINDS: dict[str, tuple[str, dict[str, float]]] = {
    "acceleration": ("m/s^2", {
        "m/s^2": 1.0, "mm/s^2": 1e-3, "g": _G, "mg": 1e-3 * _G, "ug": 1e-6 * _G,
    }),
    "angular_rate": ("rad/s", {
        "rad/s": 1.0, "mrad/s": 1e-3, "deg/s": _DEG, "deg/h": _DEG / _HOUR,
    }),
    "accel_noise_density": ("m/s^2/sqrt(Hz)", {
        "m/s^2/sqrt(Hz)": 1.0, "m/s/sqrt(s)": 1.0, "m/s/sqrt(h)": 1.0 / _SQRT_HOUR,
        "mg/sqrt(Hz)": 1e-3 * _G, "ug/sqrt(Hz)": 1e-6 * _G,
    }),
    "gyro_noise_density": ("rad/s/sqrt(Hz)", {
        "rad/s/sqrt(Hz)": 1.0, "rad/sqrt(s)": 1.0, "deg/s/sqrt(Hz)": _DEG, "deg/h/sqrt(Hz)": _DEG / _HOUR,
        "deg/sqrt(h)": _DEG / _SQRT_HOUR, "deg/sqrt(s)": _DEG,
    }),
    "accel_random_walk": ("m/s^2/sqrt(s)", {
        "m/s^2/sqrt(s)": 1.0, "m/s^2*sqrt(Hz)": 1.0, "mg/sqrt(s)": 1e-3 * _G, "ug/sqrt(s)": 1e-6 * _G,
        "mg/sqrt(h)": 1e-3 * _G / _SQRT_HOUR, "ug/sqrt(h)": 1e-6 * _G / _SQRT_HOUR,
        "m/s/h/sqrt(h)": 1.0 / _HOUR / _SQRT_HOUR,
    }),
    "gyro_random_walk": ("rad/s/sqrt(s)", {
        "rad/s/sqrt(s)": 1.0, "rad/s*sqrt(Hz)": 1.0, "deg/s/sqrt(s)": _DEG, "deg/s/sqrt(h)": _DEG / _SQRT_HOUR,
        "deg/h/sqrt(h)": _DEG / _HOUR / _SQRT_HOUR, "deg/h/sqrt(s)": _DEG / _HOUR,
    }),
    "time": ("s", {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9, "min": 60.0, "h": _HOUR}),
    "frequency": ("Hz", {"Hz": 1.0, "kHz": 1e3}),
    "ratio": ("1", {"1": 1.0, "ppm": 1e-6, "ppb": 1e-9, "%": 1e-2}),
    "matrix": ("1", {"1": 1.0}),
    "angle": ("rad", {"rad": 1.0, "mrad": 1e-3, "deg": _DEG, "arcmin": _DEG / 60.0}),
    "g_sensitivity": ("rad/s/(m/s^2)", {
        "rad/s/(m/s^2)": 1.0, "deg/s/(m/s^2)": _DEG, "rad/s/g": 1.0 / _G, "deg/s/g": _DEG / _G,
        "deg/h/g": _DEG / _HOUR / _G,
    }),
    "g2_sensitivity": ("rad/s/(m/s^2)^2", {
        "rad/s/(m/s^2)^2": 1.0, "deg/s/(m/s^2)^2": _DEG, "rad/s/g^2": 1.0 / _G**2, "deg/s/g^2": _DEG / _G**2,
        "deg/h/g^2": _DEG / _HOUR / _G**2,
    }),
    "accel_temperature_coefficient": ("m/s^2/K", {
        "m/s^2/K": 1.0, "m/s^2/degC": 1.0, "mg/K": 1e-3 * _G, "mg/degC": 1e-3 * _G,
        "ug/K": 1e-6 * _G, "ug/degC": 1e-6 * _G,
    }),
    "gyro_temperature_coefficient": ("rad/s/K", {
        "rad/s/K": 1.0, "rad/s/degC": 1.0, "deg/s/K": _DEG, "deg/s/degC": _DEG,
        "deg/h/K": _DEG / _HOUR, "deg/h/degC": _DEG / _HOUR,
    }),
    "scale_temperature_coefficient": ("1/K", {
        "1/K": 1.0, "1/degC": 1.0, "ppm/K": 1e-6, "ppm/degC": 1e-6, "%/K": 1e-2, "%/degC": 1e-2,
    }),
    "temperature": ("degC", {"degC": 1.0}),
}

_GLYPHS = (("µ", "u"), ("μ", "u"), ("°", "deg"), ("²", "^2"), ("³", "^3"), ("℃", "degC"))
_SQRT_GLYPH = re.compile(r"√\(?([A-Za-z]+)\)?")


def normalise_unit(unit: str) -> str:
    """Canonical spelling of a unit string (spaces removed, datasheet glyphs mapped to ASCII)."""
    text = unit.replace(" ", "")
    for glyph, ascii_text in _GLYPHS:
        text = text.replace(glyph, ascii_text)
    return _SQRT_GLYPH.sub(r"sqrt(\1)", text)


_LOOKUP = {kind: {normalise_unit(u): f for u, f in table.items()} for kind, (_si, table) in UNIT_KINDS.items()}


def si_unit(kind: str) -> str:
    """The SI unit name used inside the simulator for a quantity ``kind``."""
    return UNIT_KINDS[kind][0]


def accepted_units(kind: str) -> list[str]:
    """Unit strings accepted for a quantity ``kind``."""
    return list(UNIT_KINDS[kind][1])


def factor_to_si(unit, kind: str, where: str) -> float:
    """Factor converting a value in ``unit`` to the SI unit of ``kind``.

    Parameters
    ----------
    unit : the unit string as written by the user.
    kind : one of :data:`UNIT_KINDS`.
    where : the key path for error messages (e.g. ``"[sensor] gyro_noise_density"``).

    Raises
    ------
    ScenarioError
        naming ``where``, the unit, its dimension when it belongs to another kind, and the accepted units.
    """
    if not isinstance(unit, str):
        raise ScenarioError(f"{where}: unit must be a string, got {unit!r}; accepted units: {accepted_units(kind)}")
    key = normalise_unit(unit)
    table = _LOOKUP[kind]
    if key in table:
        return table[key]
    other_kinds = [k for k, t in _LOOKUP.items() if key in t]
    reason = (f"has the dimension of {other_kinds[0].replace('_', ' ')}, not {kind.replace('_', ' ')}"
              if other_kinds else "is not a known unit")
    raise ScenarioError(f"{where}: unit {unit!r} {reason}; accepted units: {accepted_units(kind)}")


def to_si(value, unit, kind: str, where: str) -> np.ndarray:
    """Convert a number or nested list ``value`` given in ``unit`` to a float SI array of the same shape.

    Raises
    ------
    ScenarioError
        when the unit is refused (see :func:`factor_to_si`) or the value is not numeric or is NaN
        (infinity passes: it switches a range or bandwidth off; the model refuses it elsewhere).
    """
    factor = factor_to_si(unit, kind, where)
    if not _is_numeric(value):
        raise ScenarioError(f"{where}: value {value!r} is not a number or a (nested) list of numbers")
    array = np.array(value, dtype=float)
    if np.any(np.isnan(array)):
        raise ScenarioError(f"{where}: value {value!r} must not be NaN")
    return array * factor


def _is_numeric(value) -> bool:
    """True for an int/float (not bool) or a (nested) list/tuple of them."""
    if isinstance(value, (list, tuple)):
        return len(value) > 0 and all(_is_numeric(item) for item in value)
    return isinstance(value, (int, float)) and not isinstance(value, bool)
