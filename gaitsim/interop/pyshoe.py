"""MATLAB ``.mat`` files in pyshoe's layout (utiasSTARS/pyshoe, its processed VICON trials), in and out.

Layout: ``imu`` (N, 6) -- specific force (m/s^2) then angular rate (rad/s) in the sensor frame; ``ts`` (1, N) --
time (s); ``gt`` (N, 3) -- the reference position (m) at those times (the hallway and stair trials give it at the
rows ``gt_idx`` only; read as such when ``gt_idx`` is present).

Frame: pyshoe's IMU reads (0, 0, -g) at rest and its filter adds +g on the vertical: x forward, y right, z down
(the loaders of gaitmap-datasets rotate it to x forward, y left, z up by diag(1, -1, -1)). In the project's axis-map
syntax (:mod:`gaitsim.measured.axes`) that is :data:`PYSHOE_AXES` = ``x,-y,-z``; its inverse is itself. The
reference positions are kept in their own world frame (pyshoe compares after its own alignment).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.io import loadmat, savemat

from nav.recording import Recording, RecordingError, Reference

from ..measured.axes import apply_axis_map, parse_axis_map

PYSHOE_AXES = "x,-y,-z"  # project axes from pyshoe's sensor axes (a 180 deg turn about x: its own inverse)


def read_pyshoe(path: str | Path) -> Recording:
    """A recording from a pyshoe ``.mat`` file (module docstring): body frame, t from 0, ``gt`` as reference.

    Raises
    ------
    RecordingError
        naming the file and the variable that is missing or has the wrong shape.
    """
    path = Path(path)
    mat = loadmat(path)
    for key in ("imu", "ts"):
        if key not in mat:
            raise RecordingError(f"{path}: no variable {key!r}; a pyshoe file holds imu (N x 6), ts (1 x N), gt")
    imu, ts = np.asarray(mat["imu"], float), np.asarray(mat["ts"], float).ravel()
    if imu.ndim != 2 or imu.shape[1] != 6 or len(ts) != len(imu):
        raise RecordingError(f"{path}: imu has shape {imu.shape} and ts {len(ts)} values; expected (N, 6) and N")
    axes = parse_axis_map(PYSHOE_AXES)
    t = ts - ts[0]
    rec = Recording(t=t, acc=apply_axis_map(axes, imu[:, :3]), gyr=apply_axis_map(axes, imu[:, 3:]),
                    meta={"source": str(path), "frames": {"axis_map": PYSHOE_AXES, "body": "x toes, y left, z up"},
                          "clock": "ts minus its first value"})
    if "gt" in mat:
        gt = np.asarray(mat["gt"], float)
        rows = np.asarray(mat["gt_idx"]).ravel().astype(int) if "gt_idx" in mat else np.arange(len(gt))
        if gt.ndim != 2 or gt.shape[1] != 3 or len(rows) != len(gt):
            raise RecordingError(f"{path}: gt has shape {gt.shape}; expected (M, 3) positions at {len(rows)} rows")
        rec.reference = Reference(t=t[rows], pos=gt)
    return rec


def write_pyshoe(rec: Recording, path: str | Path) -> Path:
    """Write a recording as a pyshoe ``.mat`` file: imu in pyshoe's sensor frame, ts, and gt = the truth's
    positions (else the reference's, at the rows whose times it has; ``gt_idx`` then lists them)."""
    axes = parse_axis_map(PYSHOE_AXES)
    doc = {"imu": np.column_stack([apply_axis_map(axes.T, rec.acc), apply_axis_map(axes.T, rec.gyr)]),
           "ts": np.asarray(rec.t, float)[None, :]}
    if rec.truth is not None:
        doc["gt"] = rec.truth.pos
    elif rec.reference is not None:
        rows = np.searchsorted(rec.t, rec.reference.t)
        if np.any(rows >= len(rec.t)) or not np.array_equal(rec.t[np.minimum(rows, len(rec.t) - 1)], rec.reference.t):
            raise RecordingError("write_pyshoe: the reference's times are not sample times of the recording; "
                                 "pyshoe's gt needs rows of the IMU clock")
        doc["gt"], doc["gt_idx"] = rec.reference.pos, rows[None, :]
    savemat(Path(path), doc)
    return Path(path)
