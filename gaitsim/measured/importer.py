"""Bring your own data: a logger's CSV file turned into a recording folder (``gaitsim import``).

What is converted, each stated by the user and reported back (``meta.json`` ``import`` and ``import-report.md``):

- columns: which column holds the time and which three hold specific force and angular rate (by header name);
- units: time (s, ms, us, ns), specific force (m/s^2, g, mg, ...) and angular rate (rad/s, deg/s, ...), converted
  once with the factors of :mod:`gaitsim.imu.units` (g = 9.80665 m/s^2, the datasheet convention);
- axes: an axis map (:mod:`gaitsim.measured.axes`, e.g. ``y,-x,z``) from the logger's axes to the body frame;
- time origin: the first kept sample becomes t = 0 (its original value is reported);
- rows whose time does not increase (repeated packets) are refused, or dropped and counted with ``drop_repeated``.

Checked before anything is written; a failed check is an error that names the file, the column or option, the
value found and what would fit (another time unit, another acceleration unit, an axis map that passes):

- sample rate: the median interval must give 20 Hz to 10 kHz (a foot IMU); jitter is reported;
- gravity: the quietest 0.5 s must read |f| within 10 % of gravity (:mod:`nav.checks`' bound);
- angular rate: the peak must stay below 35 rad/s (2000 deg/s);
- frame: :func:`gaitsim.measured.quality.frame_checks` (gravity on +z at rest; with walking, pitch about y and
  toes along +x), unless ``frame_check`` is off (the failures are then reported as warnings).

NaN samples are refused with their counts per column (never filled in).
"""

from __future__ import annotations

import csv
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from nav import storage
from nav.checks import GRAVITY_TOLERANCE, MAX_WALKING_RATE, STATIC_WINDOW_S, quietest_window
from nav.constants import DEFAULT_GRAVITY
from nav.files import atomic_output_dir
from nav.recording import Recording, RecordingError, Reference, write_recording_into

from .. import __version__
from ..imu.units import UNIT_KINDS, factor_to_si
from .axes import AXES, IDENTITY, apply_axis_map, axis_map_text, is_mirror, parse_axis_map
from .quality import frame_checks, frame_problems, jitter_stats, non_increasing_time_mask, timestamp_report

RATE_RANGE_HZ = (20.0, 10000.0)  # sample rates a foot-mounted IMU logger plausibly has
REPORT_FILE = "import-report.md"


class LoggerFileError(RecordingError):
    """A file or setting that cannot be imported; the message names the file, column or option and the value."""


@dataclass(frozen=True)
class ImportSpec:
    """How to read a logger's CSV file. Column names are the file's header names; units are accepted unit strings
    of :mod:`gaitsim.imu.units` (kinds "time", "acceleration", "angular_rate").

    Attributes
    ----------
    time_column : the time column, or None to use ``rate_hz`` (sample k at k / rate_hz).
    acc_columns, gyr_columns : the three specific-force and angular-rate columns, in the file's x, y, z order.
    time_unit, acc_unit, gyr_unit : the units of those columns.
    axes : axis map from the file's axes to the body frame (x toes, y left, z up).
    rate_hz : Hz, the sample rate when there is no time column.
    drop_repeated : drop rows whose time does not increase past every earlier row (counted), instead of refusing.
    loop_closure : the walk ends where it started: add a loop-closure reference (scored as the end-point error).
    delimiter : the column separator.
    skip_rows : lines before the header row.
    gravity : m/s^2, the local gravity (written to meta.json for the filter).
    frame_check : refuse a recording whose frame checks fail (False: report them as warnings).
    """

    time_column: str | None = "t"
    acc_columns: tuple[str, str, str] = ("acc_x", "acc_y", "acc_z")
    gyr_columns: tuple[str, str, str] = ("gyr_x", "gyr_y", "gyr_z")
    time_unit: str = "s"
    acc_unit: str = "m/s^2"
    gyr_unit: str = "rad/s"
    axes: str = IDENTITY
    rate_hz: float | None = None
    drop_repeated: bool = False
    loop_closure: bool = False
    delimiter: str = ","
    skip_rows: int = 0
    gravity: float = DEFAULT_GRAVITY
    frame_check: bool = True


@dataclass
class ImportReport:
    """What an import converted and found (every number in the unit its name says)."""

    source: str
    source_sha256: str
    spec: dict
    factors_to_si: dict
    axis_matrix: list
    rows_in_file: int
    rows_dropped: int
    time_origin_in_file_unit: float
    samples: int
    duration_s: float
    timing: dict
    static_specific_force_mps2: float
    peak_rate_rad_s: float
    frame_checks: dict
    warnings: list = field(default_factory=list)

    def as_dict(self) -> dict:
        return asdict(self)

    def markdown(self) -> str:
        """The short human report written beside the recording."""
        s = self.spec
        time_source = f"{s['time_column']} ({s['time_unit']})" if s["time_column"] else f"none: {s['rate_hz']} Hz"
        lines = [f"# Imported from {self.source}", "",
                 f"SHA-256 of the file: `{self.source_sha256}`", "",
                 "| quantity | file | converted |", "|---|---|---|",
                 f"| time | {time_source} | s, x {self.factors_to_si['time']:g}, origin "
                 f"{self.time_origin_in_file_unit!r} moved to 0 |",
                 f"| specific force | {', '.join(s['acc_columns'])} ({s['acc_unit']}) | m/s^2, "
                 f"x {self.factors_to_si['acceleration']:.10g} |",
                 f"| angular rate | {', '.join(s['gyr_columns'])} ({s['gyr_unit']}) | rad/s, "
                 f"x {self.factors_to_si['angular_rate']:.10g} |",
                 f"| axes | {s['axes']} | body frame x toes, y left, z up (matrix {self.axis_matrix}) |", "",
                 f"Rows: {self.rows_in_file} in the file, {self.rows_dropped} dropped (time not increasing), "
                 f"{self.samples} samples over {self.duration_s:.3f} s.",
                 f"Sample rate {self.timing['rate_hz']:.4g} Hz (median interval), jitter "
                 f"{100 * self.timing['jitter_rel']:.1f} %, {self.timing['gaps']} gaps > 1.5 intervals.",
                 f"At rest |f| = {self.static_specific_force_mps2:.4f} m/s^2 (gravity {s['gravity']}); peak rate "
                 f"{self.peak_rate_rad_s:.3g} rad/s.",
                 f"Frame checks: still specific force "
                 f"{np.round(self.frame_checks['still_acc_mean'], 3).tolist()} m/s^2, "
                 f"dominant rate axis {AXES[self.frame_checks['dominant_gyro_axis']]}, swing pitch excursion "
                 f"{self.frame_checks['pitch_excursion_deg']:.1f} deg over {self.frame_checks['swings']} swings."]
        lines += ["", "Warnings:"] + [f"- {w}" for w in self.warnings] if self.warnings else ["", "No warnings."]
        return "\n".join(lines) + "\n"


def _columns(path: Path, spec: ImportSpec) -> tuple[list[str], list[int]]:
    """Header names of the file and the indices of the time (if any), acc and gyr columns."""
    with storage.open_text(path) as fh:
        for _ in range(spec.skip_rows):
            fh.readline()
        header = [h.strip() for h in next(csv.reader(fh, delimiter=spec.delimiter), [])]
    wanted = ([spec.time_column] if spec.time_column else []) + list(spec.acc_columns) + list(spec.gyr_columns)
    missing = [c for c in wanted if c not in header]
    if missing:
        raise LoggerFileError(f"{path}: no column(s) {missing} in the header row (line {spec.skip_rows + 1}); "
                              f"the file has {header}")
    return header, [header.index(c) for c in wanted]


def _read(path: Path, spec: ImportSpec) -> np.ndarray:
    """The wanted columns as floats, (rows, 6 or 7), in the file's units; NaNs and text refused with counts."""
    header, usecols = _columns(path, spec)
    try:
        table = np.loadtxt(path, delimiter=spec.delimiter, skiprows=spec.skip_rows + 1, usecols=usecols, ndmin=2)
    except ValueError as exc:
        raise LoggerFileError(f"{path}: a value in columns {[header[i] for i in usecols]} is not a number: "
                              f"{exc}") from None
    bad = np.isnan(table).sum(axis=0)
    if bad.any():
        counts = {header[i]: int(n) for i, n in zip(usecols, bad) if n}
        raise LoggerFileError(f"{path}: NaN samples per column {counts}; drop or fill them in the file first "
                              "(they are never filled in here)")
    if len(table) < 2:
        raise LoggerFileError(f"{path}: {len(table)} data rows; at least 2 are needed")
    return table


def _units(spec: ImportSpec) -> dict:
    """SI factor per kind, the options named in errors."""
    return {"time": factor_to_si(spec.time_unit, "time", "--time-unit"),
            "acceleration": factor_to_si(spec.acc_unit, "acceleration", "--acc-unit"),
            "angular_rate": factor_to_si(spec.gyr_unit, "angular_rate", "--gyr-unit")}


def _fits(kind: str, given_factor: float, value_si: float, bounds: tuple[float, float], shown: str,
          inverse: bool = False) -> str:
    """The units of ``kind`` in which the file's values would put ``value_si`` (computed with ``given_factor``)
    inside ``bounds``, each with the value it gives (in ``shown``); ``inverse`` for a rate (1/time). Empty when
    none does."""
    out = []
    for unit, factor in UNIT_KINDS[kind][1].items():
        value = value_si * (given_factor / factor if inverse else factor / given_factor)
        if bounds[0] <= value <= bounds[1]:
            out.append(f"{unit} (giving {value:.4g} {shown})")
    return " or ".join(out)


def _time(path: Path, spec: ImportSpec, raw: np.ndarray, factor: float) -> tuple[np.ndarray, dict]:
    """Times (s) of the kept rows from the time column or the rate, and the rows kept (bool mask) with counts."""
    if spec.time_column is None:
        if not spec.rate_hz or spec.rate_hz <= 0:
            raise LoggerFileError(f"{path}: no time column given and --rate-hz = {spec.rate_hz!r}; give one of them")
        return np.arange(len(raw)) / float(spec.rate_hz), {"keep": np.ones(len(raw), bool), "origin": 0.0,
                                                           **timestamp_report(np.arange(len(raw)))}
    t_file = raw[:, 0]
    counts = timestamp_report(t_file)
    drop = non_increasing_time_mask(t_file)
    if drop.any() and not spec.drop_repeated:
        first = int(np.flatnonzero(drop)[0])
        raise LoggerFileError(
            f"{path}: column {spec.time_column!r}: {counts['non_increasing_rows']} rows whose time does not increase "
            f"({counts['repeated_time_rows']} repeat the previous time, {counts['backward_time_rows']} go back; "
            f"first at data row {first}, t = {float(t_file[first])!r}); pass --drop-repeated to drop and count them")
    keep = ~drop
    origin = float(t_file[keep][0])
    return (t_file[keep] - origin) * factor, {"keep": keep, "origin": origin, **counts}


def _check_rate(path: Path, spec: ImportSpec, t: np.ndarray, factor: float) -> dict:
    timing = jitter_stats(t)
    if not RATE_RANGE_HZ[0] <= timing["rate_hz"] <= RATE_RANGE_HZ[1]:
        fits = _fits("time", factor, timing["rate_hz"], RATE_RANGE_HZ, "Hz", inverse=True)
        raise LoggerFileError(
            f"{path}: column {spec.time_column!r} in {spec.time_unit}: median interval {timing['dt_median']:.6g} s "
            f"gives {timing['rate_hz']:.4g} Hz, outside {RATE_RANGE_HZ[0]:g}-{RATE_RANGE_HZ[1]:g} Hz; "
            + (f"--time-unit {fits} would fit" if fits else "check the time column"))
    return timing


def _check_gravity(path: Path, spec: ImportSpec, acc: np.ndarray, rate_hz: float, factor: float) -> float:
    start, end = quietest_window(acc, int(round(STATIC_WINDOW_S * rate_hz)))
    static = float(np.linalg.norm(acc[start:end].mean(axis=0)))
    bounds = ((1 - GRAVITY_TOLERANCE) * spec.gravity, (1 + GRAVITY_TOLERANCE) * spec.gravity)
    if not bounds[0] <= static <= bounds[1]:
        fits = _fits("acceleration", factor, static, bounds, "m/s^2")
        raise LoggerFileError(
            f"{path}: columns {list(spec.acc_columns)} in {spec.acc_unit}: |specific force| in the quietest "
            f"{STATIC_WINDOW_S} s (rows {start}..{end - 1}) is {static:.4g} m/s^2, not {spec.gravity} within "
            f"{GRAVITY_TOLERANCE:.0%}; "
            + (f"--acc-unit {fits} would fit" if fits else "no unit fits: is there a rest in the recording?"))
    return static


def _check_rate_unit(path: Path, spec: ImportSpec, gyr: np.ndarray, factor: float) -> float:
    peak = float(np.max(np.linalg.norm(gyr, axis=1)))
    if peak > MAX_WALKING_RATE:
        fits = _fits("angular_rate", factor, peak, (1.0, MAX_WALKING_RATE), "rad/s")  # walking: 10-31 rad/s
        raise LoggerFileError(
            f"{path}: columns {list(spec.gyr_columns)} in {spec.gyr_unit}: peak angular rate {peak:.4g} rad/s "
            f"exceeds {MAX_WALKING_RATE} rad/s ({math.degrees(MAX_WALKING_RATE):.0f} deg/s); "
            + (f"--gyr-unit {fits} would fit" if fits else "check the columns"))
    return peak


def suggest_axis_map(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, gravity: float = DEFAULT_GRAVITY) -> str | None:
    """An axis map (file -> body frame) under which the frame checks pass, or None when none does.

    z is the file axis along which the specific force points at rest, y the remaining axis with the most angular
    rate (the pitch axis), with the sign that makes the swings pitch toes-down; x completes the rotation.
    """
    still = frame_checks(t, acc, gyr)
    mean = np.asarray(still["still_acc_mean"], float)
    if not np.all(np.isfinite(mean)):
        return None
    z = int(np.argmax(np.abs(mean)))
    rms = np.asarray(still["gyro_rms"], float)
    y = max((a for a in range(3) if a != z), key=lambda a: rms[a])
    for sign in (1.0, -1.0):
        matrix = np.zeros((3, 3))
        matrix[2, z] = math.copysign(1.0, mean[z])
        matrix[1, y] = sign
        matrix[0] = np.cross(matrix[1], matrix[2])
        checks = frame_checks(t, apply_axis_map(matrix, acc), apply_axis_map(matrix, gyr))
        if not frame_problems(checks, gravity=gravity):
            return axis_map_text(matrix)
    return None


def import_csv(path: str | Path, spec: ImportSpec = ImportSpec()) -> tuple[Recording, ImportReport]:
    """Read a logger's CSV file into a :class:`nav.recording.Recording` in SI units and the body frame.

    Parameters
    ----------
    path : the CSV file (one header row after ``spec.skip_rows`` lines).
    spec : columns, units, axis map and options (:class:`ImportSpec`).

    Returns
    -------
    (recording, report): the recording's meta holds the report (``meta["import"]``).

    Raises
    ------
    LoggerFileError (a RecordingError)
        naming the file, column or option, the value found and what would fit (module docstring).
    ScenarioError
        for a unit string that is not accepted (listing the accepted ones).
    """
    path = Path(path)
    if not path.is_file():
        raise LoggerFileError(f"{path}: file not found")
    factors = _units(spec)
    axis_matrix = parse_axis_map(spec.axes)
    raw = _read(path, spec)
    t, timing_rows = _time(path, spec, raw, factors["time"])
    values = raw[timing_rows["keep"], 1 if spec.time_column else 0:]
    acc_file = values[:, 0:3] * factors["acceleration"]
    gyr_file = values[:, 3:6] * factors["angular_rate"]
    timing = _check_rate(path, spec, t, factors["time"]) if spec.time_column else jitter_stats(t)
    static = _check_gravity(path, spec, acc_file, timing["rate_hz"], factors["acceleration"])
    peak = _check_rate_unit(path, spec, gyr_file, factors["angular_rate"])
    acc = apply_axis_map(axis_matrix, acc_file)
    gyr = apply_axis_map(axis_matrix, gyr_file)
    checks = frame_checks(t, acc, gyr)
    problems = frame_problems(checks, gravity=spec.gravity)
    if problems and spec.frame_check:
        suggestion = suggest_axis_map(t, acc_file, gyr_file, spec.gravity)
        raise LoggerFileError(f"{path}: with --axes {spec.axes} the frame checks fail: {'; '.join(problems)}. "
                              + (f"--axes {suggestion} passes them" if suggestion else "no axis map passes them")
                              + " (or pass --no-frame-check to import as it is)")
    dropped = int((~timing_rows["keep"]).sum())
    report = ImportReport(
        source=str(path), source_sha256=storage.sha256(path), spec=asdict(spec), factors_to_si=factors,
        axis_matrix=axis_matrix.astype(int).tolist(), rows_in_file=len(raw), rows_dropped=dropped,
        time_origin_in_file_unit=timing_rows["origin"], samples=len(t), duration_s=float(t[-1]), timing=timing,
        static_specific_force_mps2=static, peak_rate_rad_s=peak, frame_checks=checks,
        warnings=[f"frame check (not enforced): {p}" for p in problems]
        + ([f"axis map {spec.axes} is a mirror (determinant -1): right only if the file's data were mirrored in "
             "both sensors alike"] if is_mirror(axis_matrix) else [])
        + ([f"dropped {dropped} of {len(raw)} rows whose time does not increase "
            f"({timing_rows['repeated_time_rows']} repeat the previous time)"] if dropped else []),
    )
    meta = {
        "generator": f"gaitsim {__version__} import",
        "source": str(path),
        "sampling": {"rate_hz": timing["rate_hz"], "gravity_mps2": spec.gravity},
        "frames": {"body": "x toward the toes, y left, z up with the foot flat (axis map applied)",
                   "axis_map": spec.axes, "imu_checks": checks},
        "clock": "file timestamps converted to s, minus the first kept one" if spec.time_column
                 else f"sample index / {spec.rate_hz} Hz",
        "import": report.as_dict(),
    }
    rec = Recording(t=t, acc=acc, gyr=gyr, meta=meta)
    if spec.loop_closure:
        rec.reference = Reference(t=np.array([t[0], t[-1]]), pos=np.zeros((2, 3)))
        meta["reference"] = {"kind": "loop_closure",
                             "description": "the walk ends where it started: the start-to-end distance is the error"}
    return rec, report


def write_import(rec: Recording, report: ImportReport, out: str | Path, overwrite: bool = False,
                 form: str = storage.DEFAULT_FORM, parquet: bool = False) -> Path:
    """Write the imported recording and ``import-report.md`` into ``out`` atomically."""
    with atomic_output_dir(out, overwrite) as tmp:
        write_recording_into(rec, tmp, form=form, parquet=parquet)
        (tmp / REPORT_FILE).write_text(report.markdown())
    return Path(out)

