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
    stance [t_ff, t_ho).
``reference.csv`` (measured recordings, optional)
    ``t, pos_x, pos_y, pos_z`` in the recording's world frame (m), on the IMU clock.
``meta.json``
    schema version, generator, frames and units of every column, gait/path/sensor parameters, seed, and how the
    tables are stored (``storage``: form, the resolution of rounded columns, SHA-256 of every table file).

Storage (:mod:`nav.storage`): each table is ``NAME.csv.gz`` (gzip-compressed CSV, the default) or ``NAME.csv``
(``form="csv"``); either may have a Parquet twin ``NAME.parquet`` (optional, pyarrow) for speed. Every value is
stored exactly (float64 round trip) except the truth's position, velocity and attitude, stored to
:data:`TRUTH_RESOLUTION` (1 nm, 1 nm/s, 1e-12): the increments ``dv``, ``dth``, the rates, specific force and
times stay exact. Folders written before this form (plain CSVs with a ``recording.npz`` twin) are read as well.

This module belongs to ``nav`` so that the filter can read any recording without the simulator;
``gaitsim`` imports it to write them.
"""

from __future__ import annotations

import json
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

COLUMN_UNITS = {
    "imu.csv": {"t": "s", "acc": "m/s^2, specific force, sensor frame", "gyr": "rad/s, sensor frame"},
    "truth.csv": {
        "t": "s", "pos": "m, world ENU", "vel": "m/s, world ENU", "q": "unit quaternion (w,x,y,z), body->world",
        "gyr": "rad/s, body", "acc": "m/s^2, specific force, body",
        "dv": "m/s, velocity increment over [t_k, t_k+1] expressed in the body frame at t_k (sculling-exact)",
        "dth": "rad, rotation vector of the attitude increment over [t_k, t_k+1] (coning-exact)",
        "stance": "1 inside the labelled stance (foot flat, t_ff <= t < t_ho), else 0",
    },
    "events.csv": {"t_*": "s", "disp": "m, world ENU, true IMU displacement over [t_ff, t_ho)"},
    "reference.csv": {"t": "s, IMU clock", "pos": "m, recording world frame"},
}


class RecordingError(ValueError):
    """A recording folder or array that cannot be used; the message names file, column and value."""


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
    """

    t: np.ndarray
    acc: np.ndarray
    gyr: np.ndarray
    meta: dict = field(default_factory=dict)
    truth: Truth | None = None
    events: Events | None = None
    reference: Reference | None = None

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
    storage.write_text(path, storage.table_text(header, table, resolution))


def read_csv(path: Path, header: tuple[str, ...]) -> np.ndarray:
    """The (M, len(header)) table of a CSV (plain or ``.gz``) written by :func:`write_csv`; raises RecordingError
    naming the file when its header or column count is not ``header``'s."""
    with storage.open_text(path) as fh:
        first = fh.readline().strip().split(",")
    if tuple(first) != header:
        raise RecordingError(f"{path}: header {first} does not match the expected columns {list(header)}")
    table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    if table.shape[1] != len(header):
        raise RecordingError(f"{path}: {table.shape[1]} columns, expected {len(header)}")
    return table


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


def write_recording_into(rec: Recording, folder: Path, form: str = storage.DEFAULT_FORM, parquet: bool = False) -> None:
    """Write ``rec`` into an existing (temporary) folder. Prefer :func:`write_recording`."""
    folder = Path(folder)
    storage.check_form(form)
    files = {}
    for name, table in _tables(rec).items():
        path = folder / f"{name}.{form}"
        resolution = TRUTH_RESOLUTION if name == "truth" else None
        write_csv(path, TABLE_COLUMNS[name], table, resolution)
        files[path.name] = storage.sha256(path)
        if parquet:
            twin = storage.write_twin(path, TABLE_COLUMNS[name],
                                      table if resolution is None else read_csv(path, TABLE_COLUMNS[name]))
            files[twin.name] = storage.sha256(twin)
    meta = dict(rec.meta)
    meta.setdefault("schema_version", SCHEMA_VERSION)
    meta.setdefault("columns", {k: v for k, v in COLUMN_UNITS.items() if k.split(".")[0] in _tables(rec)})
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


def _read_table(path: Path, columns: tuple[str, ...], prefer_binary: bool) -> np.ndarray:
    twin = storage.read_twin(path, columns) if prefer_binary else None
    return twin if twin is not None else read_csv(path, columns)


def read_recording(folder: str | Path, prefer_binary: bool = True) -> Recording:
    """Read a recording folder written by :func:`write_recording` (or by hand in the same format).

    ``prefer_binary``: read a table's Parquet twin (or an older folder's ``recording.npz``) instead of its CSV
    when there is one that matches it.
    """
    folder = Path(folder)
    imu_file = table_file(folder, "imu")
    if imu_file is None:
        raise RecordingError(f"{folder}: not a recording folder (no imu.csv or imu.csv.gz)")
    meta = {}
    if (folder / "meta.json").exists():
        with open(folder / "meta.json") as fh:
            meta = json.load(fh)
    npz_path = folder / "recording.npz"
    if prefer_binary and npz_path.exists():
        with np.load(npz_path) as z:
            tables = {k: z[k] for k in z.files}
    else:
        tables = {}
        for name, columns in TABLE_COLUMNS.items():
            path = table_file(folder, name)
            if path is not None:
                tables[name] = _read_table(path, columns, prefer_binary)
    imu = tables["imu"]
    rec = Recording(t=imu[:, 0].copy(), acc=imu[:, 1:4].copy(), gyr=imu[:, 4:7].copy(), meta=meta)
    if "truth" in tables:
        rec.truth = Truth.from_table(tables["truth"])
    if "events" in tables:
        rec.events = Events.from_table(tables["events"])
    if "reference" in tables:
        ref = tables["reference"]
        rec.reference = Reference(t=ref[:, 0].copy(), pos=ref[:, 1:4].copy())
    return rec


def list_runs(folder: str | Path) -> list[Path]:
    """The recordings in ``folder``: itself if it is one, else its ``run-NNN`` subfolders in order."""
    folder = Path(folder)
    if table_file(folder, "imu") is not None:
        return [folder]
    runs = sorted(p for p in folder.glob("run-*") if table_file(p, "imu") is not None)
    if not runs:
        raise RecordingError(f"{folder}: neither a recording (imu.csv or imu.csv.gz) nor a folder of run-NNN "
                             "recordings")
    return runs
