"""Deterministic IMU error equation, its exact inverse, and the calibration file the filter reads.

The deterministic part of the sensor model, in this order, with ``f`` the TRUE specific force (m/s^2) and
``w`` the TRUE angular rate (rad/s), both in the sensor frame, row vectors of (N, 3) arrays::

    f_m = M_a f + b_a
    w_m = M_g w + G_g f + G2_g (f * f) + b_g

``M_a``, ``M_g`` (3, 3, dimensionless) hold scale factor (diagonal) and cross-axis misalignment (off
diagonal); ``G_g`` (3, 3, rad/s per m/s^2) is the gyro g-sensitivity; ``G2_g`` (3, 3, rad/s per (m/s^2)^2)
is the optional g^2-sensitivity acting on the element-wise square ``f * f``. The exact inverse recovers the
specific force first, then uses it in the gyro equation::

    f = M_a^-1 (f_m - b_a)
    w = M_g^-1 (w_m - b_g - G_g f - G2_g (f * f))

The simulator (``gaitsim.imu.model``) distorts truth with :meth:`Calibration.distort`; the compensation
corrects readouts with :meth:`Calibration.correct`: one implementation of the equation serves both.

Terms are grouped for ablations: ``"bias"`` (b_a, b_g), ``"misalignment"`` (M_a, M_g) and
``"g_sensitivity"`` (G_g, G2_g). A group left out of ``terms`` is treated as absent (zero bias, identity
matrix, zero sensitivity).

This module is part of ``nav`` and imports only numpy, json, the standard library and nav.files.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .files import write_text_atomic

TERM_GROUPS = ("bias", "misalignment", "g_sensitivity")

FILE_FORMAT = "nav.calibration"
FILE_VERSION = 1

# field name -> (shape, SI unit written in the file)
_FIELD_UNITS = {
    "b_a": ((3,), "m/s^2"),
    "M_a": ((3, 3), "1"),
    "b_g": ((3,), "rad/s"),
    "M_g": ((3, 3), "1"),
    "G_g": ((3, 3), "rad/s/(m/s^2)"),
    "G2_g": ((3, 3), "rad/s/(m/s^2)^2"),
}
_OPTIONAL_FIELDS = ("G2_g",)


class CalibrationError(ValueError):
    """A calibration file or value that cannot be used; the message names the file and key."""


def _frozen_array(value, shape: tuple[int, ...], name: str) -> np.ndarray:
    array = np.array(value, dtype=float)
    if array.shape != shape:
        raise CalibrationError(f"{name}: expected shape {shape}, got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise CalibrationError(f"{name}: values must be finite, got {array.tolist()}")
    array.setflags(write=False)
    return array


def _check_terms(terms) -> frozenset[str]:
    chosen = frozenset(terms)
    unknown = chosen - set(TERM_GROUPS)
    if unknown:
        raise CalibrationError(f"terms: unknown {sorted(unknown)}; choose from {list(TERM_GROUPS)}")
    return chosen


@dataclass(frozen=True)
class Calibration:
    """Deterministic IMU error parameters in SI units (see the module docstring for the equation).

    Attributes
    ----------
    b_a : (3,) accelerometer bias, m/s^2.
    M_a : (3, 3) accelerometer scale factor and misalignment, dimensionless.
    b_g : (3,) gyro bias, rad/s.
    M_g : (3, 3) gyro scale factor and misalignment, dimensionless.
    G_g : (3, 3) gyro g-sensitivity, rad/s per m/s^2.
    G2_g : (3, 3) or None, gyro g^2-sensitivity on ``f * f``, rad/s per (m/s^2)^2.
    sigma : dict or None, 1-sigma uncertainties keyed by field name (same shapes and units); fields may be
        missing from it when unknown.
    source : what produced the values (e.g. "calibration lab, seed 3", "preset paper-vn200").
    """

    b_a: np.ndarray
    M_a: np.ndarray
    b_g: np.ndarray
    M_g: np.ndarray
    G_g: np.ndarray
    G2_g: np.ndarray | None = None
    sigma: dict | None = None
    source: str = ""

    def __post_init__(self):
        for name, (shape, _unit) in _FIELD_UNITS.items():
            value = getattr(self, name)
            if value is None and name in _OPTIONAL_FIELDS:
                continue
            object.__setattr__(self, name, _frozen_array(value, shape, name))
        for name in ("M_a", "M_g"):
            if abs(np.linalg.det(getattr(self, name))) < 1e-6:
                raise CalibrationError(f"{name}: matrix is singular, cannot be inverted: {getattr(self, name).tolist()}")
        if self.sigma is not None:
            frozen = {}
            for name, value in self.sigma.items():
                if name not in _FIELD_UNITS:
                    raise CalibrationError(f"sigma: unknown field {name!r}; choose from {list(_FIELD_UNITS)}")
                if value is not None:
                    frozen[name] = _frozen_array(value, _FIELD_UNITS[name][0], f"sigma.{name}")
            object.__setattr__(self, "sigma", frozen)

    @classmethod
    def identity(cls, source: str = "identity") -> "Calibration":
        """A calibration with no error: zero biases, identity matrices, zero g-sensitivity."""
        return cls(b_a=np.zeros(3), M_a=np.eye(3), b_g=np.zeros(3), M_g=np.eye(3), G_g=np.zeros((3, 3)),
                   source=source)

    def _parts(self, terms) -> tuple:
        chosen = _check_terms(terms)
        with_bias = "bias" in chosen
        with_matrix = "misalignment" in chosen
        with_g = "g_sensitivity" in chosen
        b_a = self.b_a if with_bias else np.zeros(3)
        b_g = self.b_g if with_bias else np.zeros(3)
        M_a = self.M_a if with_matrix else np.eye(3)
        M_g = self.M_g if with_matrix else np.eye(3)
        G_g = self.G_g if with_g else None
        G2_g = self.G2_g if with_g else None
        return b_a, M_a, b_g, M_g, G_g, G2_g

    @staticmethod
    def _g_terms(f: np.ndarray, G_g, G2_g) -> np.ndarray | float:
        """Gyro output caused by specific force ``f`` (N, 3): ``G_g f + G2_g (f*f)`` in rad/s."""
        out = 0.0
        if G_g is not None and np.any(G_g):
            out = f @ G_g.T
        if G2_g is not None and np.any(G2_g):
            out = out + (f * f) @ G2_g.T
        return out

    def distort(self, acc: np.ndarray, gyr: np.ndarray, terms=TERM_GROUPS) -> tuple[np.ndarray, np.ndarray]:
        """Apply the forward equation to true values.

        Parameters
        ----------
        acc : (N, 3) true specific force, m/s^2, sensor frame.
        gyr : (N, 3) true angular rate, rad/s, sensor frame.
        terms : groups to apply, subset of ``("bias", "misalignment", "g_sensitivity")``.

        Returns
        -------
        (acc_m, gyr_m) : (N, 3) arrays, m/s^2 and rad/s, new arrays (inputs untouched).
        """
        outputs = []
        for given, (product, addends) in zip((acc, gyr), self.distort_terms(acc, gyr, terms)):
            # the product may be the input's own memory (:func:`_product`; a memmap or a DataFrame's values too)
            output = product.copy() if np.may_share_memory(product, given) else product
            add_in_order(output, addends)
            outputs.append(output)
        return tuple(outputs)

    def distort_terms(self, acc: np.ndarray, gyr: np.ndarray, terms=TERM_GROUPS) -> tuple[tuple, tuple]:
        """The forward equation as :meth:`distort` evaluates it, its sums not yet done: per sensor the product
        (``M_a f``, ``M_g w``: a new (N, 3) array, or the input itself, not to be written, where :func:`_product`
        skips it) and the terms :func:`add_in_order` adds to it, in this order (``b_a``; ``G_g f + G2_g (f*f)``,
        an (N, 3) array or 0.0, then ``b_g``), for a caller that does the sums in a pass of its own (the
        simulator's noise pass: ``gaitsim.imu.kernels``) with the same roundings.

        Returns
        -------
        ((acc_product, acc_addends), (gyr_product, gyr_addends)) : m/s^2 and rad/s.
        """
        b_a, M_a, b_g, M_g, G_g, G2_g = self._parts(terms)
        acc = np.asarray(acc, float)
        gyr = np.asarray(gyr, float)
        # each bias is the last addend of its sum: _product's skip relies on it
        return (_product(acc, M_a, b_a), (b_a,)), (_product(gyr, M_g, b_g), (self._g_terms(acc, G_g, G2_g), b_g))

    def correct(self, acc: np.ndarray, gyr: np.ndarray, terms=TERM_GROUPS) -> tuple[np.ndarray, np.ndarray]:
        """Exact inverse of :meth:`distort` for the chosen ``terms``: readouts -> compensated values.

        Parameters
        ----------
        acc : (N, 3) measured specific force, m/s^2.
        gyr : (N, 3) measured angular rate, rad/s.
        terms : groups to correct, subset of ``("bias", "misalignment", "g_sensitivity")``; groups left out
            are not corrected.

        Returns
        -------
        (acc_c, gyr_c) : (N, 3) arrays, m/s^2 and rad/s.
        """
        b_a, M_a, b_g, M_g, G_g, G2_g = self._parts(terms)
        acc = np.asarray(acc, float)
        gyr = np.asarray(gyr, float)
        acc_c = np.linalg.solve(M_a, (acc - b_a).T).T
        gyr_c = np.linalg.solve(M_g, (gyr - b_g - self._g_terms(acc_c, G_g, G2_g)).T).T
        return acc_c, gyr_c


def _product(x: np.ndarray, matrix: np.ndarray, bias: np.ndarray) -> np.ndarray:
    """``x @ matrix.T`` (N, 3), or ``x`` itself where the product cannot change the bits of the sum it enters,
    ``x @ matrix.T (+ an (N, 3) term or 0.0) + bias``: ``matrix`` exactly the identity, every ``bias`` element
    nonzero and ``x`` finite (the BLAS product costs ~6 ns a row). Then each product element is
    x * 1 + y * 0 + z * 0, exactly x whatever the order of the sum or its fused multiply-adds, when x is nonzero;
    a zero x comes out as +0 or -0, the sums after it then differ at most in the sign of a zero (+0 + t and
    -0 + t are equal unless t is a zero), and the bias loses that sign: +-0 + b = b for b != 0. A non-finite
    element would spread NaN across its row (inf * 0); it is caught by the sum (an inf or NaN makes it
    non-finite; a sum that overflows only makes the product be taken)."""
    with np.errstate(over="ignore", invalid="ignore"):  # a huge finite input may overflow the sum: then no skip
        finite = np.isfinite(np.sum(x))
    if np.all(bias != 0.0) and np.array_equal(matrix, np.eye(3)) and finite:
        return x
    return x @ matrix.T


def add_in_order(x: np.ndarray, addends) -> None:
    """x (N, 3) += each of ``addends`` in turn, in place: an (N, 3) array, a number, or a (3,) vector per axis
    (added axis by axis: the sums of ``x + per_axis``, but numpy broadcasts a (3,) vector over (N, 3) rows one
    3-element inner loop per row, three times slower)."""
    for addend in addends:
        if np.ndim(addend) == 1:
            for c in range(3):
                x[..., c] += addend[c]
        else:
            x += addend


def _to_json(cal: Calibration) -> dict:
    terms = {}
    for name, (_shape, unit) in _FIELD_UNITS.items():
        value = getattr(cal, name)
        sigma = (cal.sigma or {}).get(name)
        terms[name] = {
            "unit": unit,
            "value": None if value is None else value.tolist(),
            "sigma_1": None if sigma is None else sigma.tolist(),
        }
    return {
        "format": FILE_FORMAT,
        "version": FILE_VERSION,
        "source": cal.source,
        "equation": "f_m = M_a f + b_a ; w_m = M_g w + G_g f + G2_g (f*f) + b_g ; "
                    "f, w true sensor-frame specific force and angular rate",
        "terms": terms,
    }


def save_calibration(cal: Calibration, path: str | Path) -> Path:
    """Write ``cal`` as JSON (SI values with their unit names) atomically (temporary file, then rename).

    Parameters
    ----------
    cal : the calibration to write.
    path : target file; its folder must exist.

    Returns
    -------
    The path written.
    """
    return write_text_atomic(path, json.dumps(_to_json(cal), indent=2) + "\n")


def load_calibration(path: str | Path) -> Calibration:
    """Read a calibration file written by :func:`save_calibration`.

    Raises
    ------
    CalibrationError
        naming the file and the key when the file is missing, not JSON, of another format, lacks a term,
        has a unit other than the SI unit written by :func:`save_calibration`, or a value of the wrong shape.
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except FileNotFoundError:
        raise CalibrationError(f"{path}: calibration file not found") from None
    except json.JSONDecodeError as exc:
        raise CalibrationError(f"{path}: not valid JSON ({exc})") from None
    if not isinstance(data, dict) or data.get("format") != FILE_FORMAT:
        raise CalibrationError(f"{path}: key 'format' must be {FILE_FORMAT!r}")
    if data.get("version") != FILE_VERSION:
        raise CalibrationError(f"{path}: key 'version' is {data.get('version')!r}; this reader knows {FILE_VERSION}")
    terms = data.get("terms")
    if not isinstance(terms, dict):
        raise CalibrationError(f"{path}: key 'terms' missing or not a table")
    values, sigma = {}, {}
    for name, (_shape, unit) in _FIELD_UNITS.items():
        entry = terms.get(name)
        if entry is None:
            if name in _OPTIONAL_FIELDS:
                continue
            raise CalibrationError(f"{path}: key 'terms.{name}' missing")
        if not isinstance(entry, dict) or entry.get("unit") != unit:
            raise CalibrationError(f"{path}: key 'terms.{name}.unit' must be {unit!r}, got "
                                   f"{entry.get('unit') if isinstance(entry, dict) else entry!r}")
        values[name] = entry.get("value")
        if values[name] is None and name not in _OPTIONAL_FIELDS:
            raise CalibrationError(f"{path}: key 'terms.{name}.value' missing")
        if entry.get("sigma_1") is not None:
            sigma[name] = entry["sigma_1"]
    try:
        return Calibration(**values, sigma=sigma or None, source=str(data.get("source", "")))
    except CalibrationError as exc:
        raise CalibrationError(f"{path}: key 'terms.{exc}") from None


def z_scores(estimate: Calibration, truth: Calibration) -> dict[str, np.ndarray]:
    """(estimate - truth) / sigma for every field of ``estimate`` that carries an uncertainty (dimensionless)."""
    out = {}
    for name, sig in (estimate.sigma or {}).items():
        true_value = getattr(truth, name)
        if true_value is None:
            true_value = np.zeros(_FIELD_UNITS[name][0])
        with np.errstate(divide="ignore", invalid="ignore"):
            out[name] = (getattr(estimate, name) - true_value) / sig
    return out


__all__ = ["Calibration", "CalibrationError", "TERM_GROUPS", "add_in_order", "load_calibration", "save_calibration",
           "z_scores"]
