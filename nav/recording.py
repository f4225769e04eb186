"""Recording folders: the interop contract between the simulator, measured data and the filter.

A recording is a folder anyone can read without this project:

``imu.csv``
    ``t, acc_x, acc_y, acc_z, gyr_x, gyr_y, gyr_z`` -- s, m/s^2 (specific force, body), rad/s (body).
``truth.csv`` (simulated recordings)
    ``t, pos_*, vel_*, q_w..q_z, gyr_*, acc_*, dv_*, dth_*, stance`` -- true IMU-site position (m, world
    ENU), velocity (m/s, world), attitude (body->world, w first), angular rate (rad/s, body), specific
    force (m/s^2, body), exact increments over [t_k, t_k+1] (see :class:`Truth`) and the stance label.
``events.csv`` (simulated recordings)
    one row per stride: ``stride, t_ic, t_ff, t_ho, t_to, disp_x, disp_y, disp_z`` -- times (s) of initial
    contact, foot flat, heel off and toe off, and the true IMU displacement (m, world) over the labelled
    stance, which ``meta.json``'s ``stance_label`` defines: the foot flat [t_ff, t_ho) of a simulated walk, the
    ground contact [t_ic, t_to) of a simulated run.
``reference.csv`` (measured recordings, optional)
    ``t, pos_x, pos_y, pos_z`` in the recording's world frame (m), on the IMU clock.
``meta.json``
    schema version, generator, frames and units of every column, gait/path/sensor parameters, seed, and how the
    tables are stored (``storage``: form, the resolution of rounded columns, SHA-256 of every table file).

Storage (:mod:`nav.storage`): each table is ``NAME.csv.gz`` (gzip-compressed CSV, the default) or ``NAME.csv``
(``form="csv"``). Every value is stored exactly (float64 round trip) except the truth's position, velocity and
attitude, stored to :data:`TRUTH_RESOLUTION` (1 nm, 1 nm/s, 1e-12): the increments ``dv``, ``dth``, the rates,
specific force and times stay exact. A table may have a Parquet twin ``NAME.parquet`` (optional, pyarrow) for
speed; the CSVs stay the reference: a twin holds the SHA-256 of the CSV file it was written with, and the reader
uses it only while that still matches the CSV. (The ``recording.npz`` twin of older folders is not read: their
CSVs are.)

This module belongs to ``nav`` so that the filter can read any recording without the simulator;
``gaitsim`` imports it to write them.
"""

from __future__ import annotations

import json
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import storage
from .constants import DEFAULT_GRAVITY
from .files import atomic_output_dir

SCHEMA_VERSION = 1

IMU_COLUMNS = ("t", "acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z")
TRUTH_COLUMNS = (
    "t", "pos_x", "pos_y", "pos_z", "vel_x", "vel_y", "vel_z", "q_w", "q_x", "q_y", "q_z",
    "gyr_x", "gyr_y", "gyr_z", "acc_x", "acc_y", "acc_z", "dv_x", "dv_y", "dv_z",
    "dth_x", "dth_y", "dth_z", "stance",
)
EVENT_COLUMNS = ("stride", "t_ic", "t_ff", "t_ho", "t_to", "disp_x", "disp_y", "disp_z")
REFERENCE_COLUMNS = ("t", "pos_x", "pos_y", "pos_z")
TABLE_COLUMNS = {"imu": IMU_COLUMNS, "truth": TRUTH_COLUMNS, "events": EVENT_COLUMNS, "reference": REFERENCE_COLUMNS}
# decimal places (of m, m/s, 1) to which the truth's position, velocity and attitude are stored; every other column
# is stored exactly. 1 nm is 65x below the strapdown-on-increments error of a 100 m walk (README).
TRUTH_RESOLUTION = {"pos": 9, "vel": 9, "q": 12}
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}  # unit of a file's time columns -> s per unit
MAX_TRUTH_CLOCK_SHARE = 0.01  # truth and IMU times on equal rows may differ by half a period + this share of
# the span (timestamp jitter and clock error of a simulated sensor)

COLUMN_UNITS = {
    "imu.csv": {"t": "s", "acc": "m/s^2, specific force, sensor frame", "gyr": "rad/s, sensor frame"},
    "truth.csv": {
        "t": "s", "pos": "m, world ENU", "vel": "m/s, world ENU", "q": "unit quaternion (w,x,y,z), body->world",
        "gyr": "rad/s, body", "acc": "m/s^2, specific force, body",
        "dv": "m/s, velocity increment over [t_k, t_k+1] expressed in the body frame at t_k (sculling-exact)",
        "dth": "rad, rotation vector of the attitude increment over [t_k, t_k+1] (coning-exact)",
        "stance": "1 inside the labelled stance (meta.json stance_label), else 0",
    },
    "events.csv": {"t_*": "s", "disp": "m, world ENU, true IMU displacement over the labelled stance "
                                       "(meta.json stance_label)"},
    "reference.csv": {"t": "s, IMU clock", "pos": "m, recording world frame"},
}


class RecordingError(ValueError):
    """A recording folder or array that cannot be used; the message names file, column and value."""


class RecordingWarning(UserWarning):
    """Something in a recording folder was flagged or ignored (a stale binary twin, reference dropouts)."""


@dataclass
class Truth:
    """Exact kinematics of the IMU site, sampled on the recording's time grid.

    Attributes
    ----------
    t : (N,) s
    pos, vel : (N, 3) m, m/s in the world frame (ENU).
    quat : (N, 4) attitude body->world (w, x, y, z).
    gyr : (N, 3) rad/s, body-frame angular rate.
    acc : (N, 3) m/s^2, body-frame specific force.
    dv : (N, 3) m/s, ``C_k^T (v_{k+1} - v_k - g dt)``: the velocity increment over [t_k, t_k+1] in the
        body frame at t_k. Last row is zero.
    dth : (N, 3) rad, rotation vector of ``q_k^* ⊗ q_{k+1}``. Last row is zero.
    stance : (N,) bool, the labelled stance (foot flat).
    """

    t: np.ndarray
    pos: np.ndarray
    vel: np.ndarray
    quat: np.ndarray
    gyr: np.ndarray
    acc: np.ndarray
    dv: np.ndarray
    dth: np.ndarray
    stance: np.ndarray

    def as_table(self) -> np.ndarray:
        return np.column_stack(
            [self.t, self.pos, self.vel, self.quat, self.gyr, self.acc, self.dv, self.dth, self.stance.astype(float)]
        )

    @classmethod
    def from_table(cls, a: np.ndarray) -> "Truth":
        return cls(
            t=a[:, 0], pos=a[:, 1:4], vel=a[:, 4:7], quat=a[:, 7:11], gyr=a[:, 11:14], acc=a[:, 14:17],
            dv=a[:, 17:20], dth=a[:, 20:23], stance=a[:, 23] > 0.5,
        )


@dataclass
class Events:
    """Per-stride gait events (s) and the true IMU displacement over the labelled stance (m, world)."""

    t_ic: np.ndarray
    t_ff: np.ndarray
    t_ho: np.ndarray
    t_to: np.ndarray
    stance_displacement: np.ndarray

    def as_table(self) -> np.ndarray:
        n = len(self.t_ic)
        return np.column_stack([np.arange(n), self.t_ic, self.t_ff, self.t_ho, self.t_to, self.stance_displacement])

    @classmethod
    def from_table(cls, a: np.ndarray) -> "Events":
        a = np.atleast_2d(a)
        return cls(t_ic=a[:, 1], t_ff=a[:, 2], t_ho=a[:, 3], t_to=a[:, 4], stance_displacement=a[:, 5:8])


@dataclass
class Reference:
    """A measured position reference on the IMU clock (m, recording world frame)."""

    t: np.ndarray
    pos: np.ndarray


@dataclass
class Recording:
    """What a sensor output, with whatever truth or reference is known.

    Attributes
    ----------
    t : (N,) s from the start of the recording.
    acc : (N, 3) m/s^2 measured specific force, sensor frame.
    gyr : (N, 3) rad/s measured angular rate, sensor frame.
    meta : dict, the content of ``meta.json``.
    truth, events, reference : optional.
    flags : counts of what the reader flagged and left as it is (e.g. ``reference_nan_rows``).
    """

    t: np.ndarray
    acc: np.ndarray
    gyr: np.ndarray
    meta: dict = field(default_factory=dict)
    truth: Truth | None = None
    events: Events | None = None
    reference: Reference | None = None
    flags: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        return len(self.t)

    @property
    def gravity(self) -> float:
        """m/s^2, the world's gravity magnitude: ``meta["sampling"]["gravity_mps2"]``, else DEFAULT_GRAVITY."""
        return float(self.meta.get("sampling", {}).get("gravity_mps2", DEFAULT_GRAVITY))


def write_csv(path: Path, header: tuple[str, ...], table: np.ndarray, resolution: dict[str, int] | None = None) -> None:
    """Write a table with a header row of column names, gzip-compressed when ``path`` ends in ``.gz``.

    Values round-trip float64 exactly (``%.17g``) except in columns whose name before ``_`` is a key of
    ``resolution`` (decimal places; see :func:`nav.storage.column_formats`).
    """
    storage.write_table(path, header, table, resolution)


def read_csv(path: Path, header: tuple[str, ...]) -> np.ndarray:
    """The (M, len(header)) table of a CSV (plain or ``.gz``) written by :func:`write_csv` (NaN cells allowed: the
    caller decides).

    Raises
    ------
    RecordingError
        naming the file, and the line and column where a cell is not a number or a line has the wrong number
        of cells; for a missing or non-text file, a header that is not ``header``, or no data rows.
    """
    path = Path(path)
    try:
        with storage.open_text(path) as fh:
            first = fh.readline().strip().split(",")
            if tuple(first) != header:
                raise RecordingError(f"{path}: line 1: header {first} does not match the expected columns "
                                     f"{list(header)}")
            table = np.loadtxt(fh, delimiter=",", ndmin=2, dtype=float)
    except FileNotFoundError:
        raise RecordingError(f"{path}: file not found") from None
    except UnicodeDecodeError as exc:
        raise RecordingError(f"{path}: not a text CSV file ({exc.reason} at byte {exc.start})") from None
    except (OSError, EOFError) as exc:  # gzip.BadGzipFile, a truncated .gz
        raise RecordingError(f"{path}: not a readable gzip file ({type(exc).__name__}: {exc})") from None
    except ValueError as exc:
        _raise_bad_cell(path, header)
        raise RecordingError(f"{path}: not a table of numbers ({exc})") from None
    if table.shape[0] == 0:
        raise RecordingError(f"{path}: no data rows below the header")
    if table.shape[1] != len(header):
        raise RecordingError(f"{path}: {table.shape[1]} columns, expected {len(header)} ({', '.join(header)})")
    return table


def _raise_bad_cell(path: Path, header: tuple[str, ...]) -> None:
    """Find the first line of ``path`` that numpy could not parse and raise naming its line and column."""
    with storage.open_text(path) as fh:
        fh.readline()
        for line_number, line in enumerate(fh, start=2):
            if not line.strip():
                continue
            cells = line.rstrip("\r\n").split(",")
            if len(cells) != len(header):
                raise RecordingError(f"{path}: line {line_number}: {len(cells)} cells, expected {len(header)} "
                                     f"({', '.join(header)}); truncated or extra cells")
            for column, cell in zip(header, cells):
                try:
                    float(cell)
                except ValueError:
                    raise RecordingError(f"{path}: line {line_number}, column {column}: {cell.strip()!r} is not a "
                                         "number") from None


def nonfinite_cells(table: np.ndarray, header: tuple[str, ...]) -> tuple[dict[str, int], int]:
    """NaN/inf cells of a table: (count per column that has any, first data row holding one, 1-based; 0 if none)."""
    bad = ~np.isfinite(table)
    if not bad.any():
        return {}, 0
    per_column = {column: int(n) for column, n in zip(header, bad.sum(axis=0)) if n}
    return per_column, int(np.flatnonzero(bad.any(axis=1))[0]) + 1


def require_finite(table: np.ndarray, header: tuple[str, ...], name: str) -> None:
    """Raise :class:`RecordingError` naming ``name``, the columns and the first data row with NaN/inf cells."""
    per_column, first = nonfinite_cells(table, header)
    if per_column:
        raise RecordingError(f"{name}: {sum(per_column.values())} NaN/inf cells (per column {per_column}; first in "
                             f"data row {first}, line {first + 1}); every value must be finite")


def table_file(folder: Path, name: str) -> Path | None:
    """The file holding table ``name`` ("imu", "truth", ...) in ``folder``: ``name.csv.gz`` or ``name.csv``; None
    if neither exists; RecordingError naming both if both do (which one is meant is unknown)."""
    found = [Path(folder) / f"{name}.{form}" for form in storage.FORMS if (Path(folder) / f"{name}.{form}").exists()]
    if len(found) > 1:
        raise RecordingError(f"{folder}: both {found[0].name} and {found[1].name}; keep one of them")
    return found[0] if found else None


def _tables(rec: Recording) -> dict[str, np.ndarray]:
    tables = {"imu": np.column_stack([rec.t, rec.acc, rec.gyr])}
    if rec.truth is not None:
        tables["truth"] = rec.truth.as_table()
    if rec.events is not None:
        tables["events"] = rec.events.as_table()
    if rec.reference is not None:
        tables["reference"] = np.column_stack([rec.reference.t, rec.reference.pos])
    return tables


def write_recording_into(rec: Recording, folder: Path, form: str = storage.DEFAULT_FORM, parquet: bool = False,
                         workers: int = 1) -> None:
    """Write ``rec`` into an existing (temporary) folder, its tables' text formatted by ``workers`` processes
    (:func:`nav.storage.write_tables`; the same bytes with any number). Prefer :func:`write_recording`."""
    folder = Path(folder)
    storage.check_form(form)
    tables = {name: (folder / f"{name}.{form}", TABLE_COLUMNS[name], table,
                     TRUTH_RESOLUTION if name == "truth" else None) for name, table in _tables(rec).items()}
    digests = storage.write_tables(list(tables.values()), workers)
    files = {}
    for (name, (path, _header, table, resolution)), digest in zip(tables.items(), digests):
        files[path.name] = digest
        if parquet:
            twin = storage.write_twin(path, TABLE_COLUMNS[name],
                                      table if resolution is None else read_csv(path, TABLE_COLUMNS[name]))
            files[twin.name] = storage.sha256(twin)
    meta = dict(rec.meta)
    meta.setdefault("schema_version", SCHEMA_VERSION)
    meta.setdefault("columns", {k: v for k, v in COLUMN_UNITS.items() if k.split(".")[0] in tables})
    meta["storage"] = {
        "form": form,
        "exact": "every column is stored as float64 round trip (%.17g) except those in 'resolution'",
        "resolution": ({"truth": {f"{k}_*": 10.0 ** -v for k, v in TRUTH_RESOLUTION.items()}}
                       if rec.truth is not None else {}),
        "sha256": files,
    }
    with open(folder / "meta.json", "w") as fh:
        json.dump(meta, fh, indent=2, sort_keys=True, default=_json_default)


def _json_default(o):
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, (np.floating, np.integer, np.bool_)):
        return o.item()
    raise TypeError(f"meta.json: cannot serialise {type(o).__name__}")


def write_recording(rec: Recording, folder: str | Path, overwrite: bool = False, form: str = storage.DEFAULT_FORM,
                    parquet: bool = False) -> Path:
    """Write a recording folder atomically: an interrupted write leaves nothing at ``folder``.

    Parameters
    ----------
    rec : the recording.
    folder : the output folder.
    overwrite : replace an existing non-empty folder.
    form : "csv.gz" (default) or "csv": how every table is stored (:mod:`nav.storage`).
    parquet : also write a Parquet twin of every table (needs pyarrow).
    """
    with atomic_output_dir(folder, overwrite) as tmp:
        write_recording_into(rec, tmp, form=form, parquet=parquet)
    return Path(folder)


def _read_meta(folder: Path) -> dict:
    path = folder / "meta.json"
    if not path.exists():
        return {}
    try:
        meta = json.loads(path.read_text(encoding="utf-8"))
    except (ValueError, UnicodeDecodeError) as exc:
        raise RecordingError(f"{path}: not valid JSON ({exc})") from None
    if not isinstance(meta, dict):
        raise RecordingError(f"{path}: must hold a JSON object ({{...}}), holds a {type(meta).__name__}")
    return meta


def _read_table(path: Path, columns: tuple[str, ...], prefer_binary: bool) -> np.ndarray:
    """The table of the CSV ``path``, from its Parquet twin when ``prefer_binary`` and the twin carries the CSV's
    SHA-256 (else a :class:`RecordingWarning` says why the twin is ignored)."""
    twin = storage.read_twin(path, columns, RecordingWarning) if prefer_binary else None
    return twin if twin is not None else read_csv(path, columns)


def _time_columns(key: str) -> list[int]:
    """Indices of the columns holding times in the table ``key``."""
    return [1, 2, 3, 4] if key == "events" else [0]


def read_recording(folder: str | Path, prefer_binary: bool = True, time_unit: str = "s") -> Recording:
    """Read a recording folder written by :func:`write_recording` (or by hand in the same format).

    Parameters
    ----------
    folder : the recording folder (``imu.csv.gz`` or ``imu.csv`` required).
    prefer_binary : read a table's Parquet twin instead of parsing its CSV when the twin carries the SHA-256 of
        the CSV beside it; a twin without it, with another, or unreadable is ignored with a
        :class:`RecordingWarning`. The CSVs are the reference.
    time_unit : unit of every time column in the files (one of :data:`TIME_UNITS`); converted to s here.

    Raises
    ------
    RecordingError
        naming the file, line and column of a cell that is not a number, NaN/inf in imu, truth or events,
        timestamps that do not increase, files whose time spans do not match, or a meta.json that is not a
        JSON object. NaN rows in reference.csv (tracking dropouts) are not an error: they are counted in
        ``Recording.flags`` and left out of scoring.
    """
    folder = Path(folder)
    if time_unit not in TIME_UNITS:
        raise RecordingError(f"time_unit = {time_unit!r}; allowed: {', '.join(TIME_UNITS)}")
    files = {key: table_file(folder, key) for key in TABLE_COLUMNS}
    files = {key: path for key, path in files.items() if path is not None}
    if "imu" not in files:
        raise RecordingError(f"{folder}: not a recording folder (no imu.csv.gz or imu.csv)")
    meta = _read_meta(folder)
    tables = {}
    for key, path in files.items():
        table = _read_table(path, TABLE_COLUMNS[key], prefer_binary).copy()
        if table.shape[0] == 0:
            raise RecordingError(f"{path}: no data rows")
        table[:, _time_columns(key)] *= TIME_UNITS[time_unit]
        tables[key] = table
    flags = _check_tables({key: str(path) for key, path in files.items()}, tables)
    imu = tables["imu"]
    rec = Recording(t=imu[:, 0].copy(), acc=imu[:, 1:4].copy(), gyr=imu[:, 4:7].copy(), meta=meta, flags=flags)
    if "truth" in tables:
        rec.truth = Truth.from_table(tables["truth"])
    if "events" in tables:
        rec.events = Events.from_table(tables["events"])
    if "reference" in tables:
        ref = tables["reference"]
        rec.reference = Reference(t=ref[:, 0].copy(), pos=ref[:, 1:4].copy())
    return rec


def _increasing(t: np.ndarray, name: str) -> None:
    """Raise naming ``name`` and the first data row where the time column ``t`` does not increase."""
    steps = np.diff(t)
    if np.any(steps <= 0):
        row = int(np.flatnonzero(steps <= 0)[0]) + 2
        raise RecordingError(f"{name}: column t: {int(np.sum(steps == 0))} repeated and {int(np.sum(steps < 0))} "
                             f"decreasing timestamps (first at data row {row}, line {row + 1}: t = {t[row - 1]!r} "
                             f"after {t[row - 2]!r}); time must increase")


def _check_tables(names: dict[str, str], tables: dict) -> dict:
    """Finite values, increasing time and matching time spans across the files (``names``: table key -> file
    name for messages); returns the reader's flags."""
    imu = tables["imu"]
    require_finite(imu, IMU_COLUMNS, names["imu"])
    t = imu[:, 0]
    period = float(np.median(np.diff(t))) if len(t) > 1 else 0.0
    span = (t[0], t[-1])
    slack = 2 * period + 0.02 * (span[1] - span[0])  # clock error and skew move a simulated IMU clock this much
    flags = {}
    if "truth" in tables:
        truth = tables["truth"]
        name = names["truth"]
        require_finite(truth, TRUTH_COLUMNS, name)
        _increasing(truth[:, 0], name)
        if len(truth) == len(imu):
            offset = float(np.max(np.abs(truth[:, 0] - t)))
            if offset > 0.5 * period + MAX_TRUTH_CLOCK_SHARE * (span[1] - span[0]):
                raise RecordingError(f"{name}: column t differs from the IMU file's by up to {offset:.6g} s with the same "
                                     "number of rows; the two files are not on one clock")
        elif truth[0, 0] > span[0] + slack or truth[-1, 0] < span[1] - slack:
            raise RecordingError(f"{name}: {len(truth)} rows over t = {truth[0, 0]:.6g}..{truth[-1, 0]:.6g} s do not "
                                 f"cover the IMU file's {len(imu)} rows over t = {span[0]:.6g}..{span[1]:.6g} s")
    if "events" in tables:
        events = tables["events"]
        name = names["events"]
        require_finite(events, EVENT_COLUMNS, name)
        times = events[:, 1:5]
        order = np.diff(times, axis=1)
        if np.any(order < 0):
            row = int(np.flatnonzero((order < 0).any(axis=1))[0]) + 1
            raise RecordingError(f"{name}: data row {row}: events out of order (t_ic <= t_ff <= t_ho <= t_to "
                                 f"required): {times[row - 1].tolist()}")
        if times.min() < span[0] - slack or times.max() > span[1] + slack:
            raise RecordingError(f"{name}: event times {times.min():.6g}..{times.max():.6g} s fall outside the IMU file's "
                                 f"{span[0]:.6g}..{span[1]:.6g} s")
    if "reference" in tables:
        ref = tables["reference"]
        name = names["reference"]
        require_finite(ref[:, :1], REFERENCE_COLUMNS[:1], name)
        _increasing(ref[:, 0], name)
        gaps, first = nonfinite_cells(ref[:, 1:], REFERENCE_COLUMNS[1:])
        if gaps:
            rows = int(np.sum(~np.isfinite(ref[:, 1:]).all(axis=1)))
            flags["reference_nan_rows"] = rows
            warnings.warn(f"{name}: {rows} of {len(ref)} rows hold NaN positions (per column {gaps}; first in data "
                          f"row {first}): tracking dropouts, left out of scoring", RecordingWarning, stacklevel=3)
        if ref[-1, 0] < span[0] or ref[0, 0] > span[1]:
            raise RecordingError(f"{name}: t = {ref[0, 0]:.6g}..{ref[-1, 0]:.6g} s does not overlap the IMU file's "
                                 f"{span[0]:.6g}..{span[1]:.6g} s")
    return flags


def list_runs(folder: str | Path) -> list[Path]:
    """The recordings in ``folder``: itself if it is one, else its ``run-NNN`` subfolders in order."""
    folder = Path(folder)
    if table_file(folder, "imu") is not None:
        return [folder]
    runs = sorted(p for p in folder.glob("run-*") if table_file(p, "imu") is not None)
    if not runs:
        raise RecordingError(f"{folder}: neither a recording (imu.csv.gz or imu.csv) nor a folder of run-NNN "
                             "recordings")
    return runs
