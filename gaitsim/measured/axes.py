"""Axis maps: which axis of a sensor's (a logger's, a file's) frame becomes each axis of the project's body frame.

The project's body frame with the foot flat: x toward the toes, y to the left, z up. An axis map is written as
three comma-separated entries, one for the project's x, y and z in that order; each entry names the file axis
that becomes it, with an optional sign::

    y,-x,z     project x = file y,  project y = -file x,  project z = file z   (a 90 deg turn about z)
    x,-y,-z    a frame with x forward, y right, z down (pyshoe's, many NED-minded loggers)
    x,y,z      the identity

Every file axis appears once. The same map applies to specific force and angular rate. A map is usually a
rotation (determinant +1); a mirror (determinant -1, e.g. ``x,-y,z``) is allowed because it undoes data that were
mirrored alike in both sensors (a left-foot recording mirrored into a right-foot convention, a left-handed
export): :func:`is_mirror` says which it is, the import report and the loop's frame check state it, and the frame
checks (gravity up, toes-down swing pitch, stride closure) tell a wrong guess. :func:`parse_axis_map` is the one
parser; the command line (``gaitsim import --axes``, ``gaitsim loop --axes``), the interop adapters and the loop's
frame check use it.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from nav.recording import Recording

AXES = "xyz"
IDENTITY = "x,y,z"


class AxisMapError(ValueError):
    """An axis map that is not three signed, distinct axes; the message shows the map."""


def parse_axis_map(text: str) -> np.ndarray:
    """The rotation matrix R of an axis map (module docstring): ``v_project = R @ v_file``.

    Raises
    ------
    AxisMapError
        naming the map and what is wrong (a wrong number of entries, an unknown entry, a repeated axis).
    """
    entries = [e.strip().lower() for e in str(text).split(",")]
    if len(entries) != 3:
        raise AxisMapError(f"axis map {text!r}: {len(entries)} entries; expected three (project x, y, z), "
                           "e.g. 'y,-x,z'")
    matrix = np.zeros((3, 3))
    for row, entry in enumerate(entries):
        sign = -1.0 if entry.startswith("-") else 1.0
        axis = entry.lstrip("+-")
        if len(axis) != 1 or axis not in AXES or len(entry) - len(axis) > 1:
            raise AxisMapError(f"axis map {text!r}: entry {entry!r} for project {AXES[row]} is not one of "
                               "x, y, z with an optional sign")
        matrix[row, AXES.index(axis)] = sign
    if sorted(e.lstrip("+-") for e in entries) != list(AXES):
        raise AxisMapError(f"axis map {text!r}: every file axis x, y, z must appear exactly once")
    return matrix


def is_mirror(matrix: np.ndarray) -> bool:
    """True when the axis map ``matrix`` is a mirror (determinant -1), False for a rotation."""
    return bool(np.linalg.det(np.asarray(matrix, float)) < 0)


def axis_map_text(matrix: np.ndarray) -> str:
    """The axis map text of a signed permutation matrix R (``v_project = R @ v_file``); inverse of
    :func:`parse_axis_map`."""
    matrix = np.asarray(matrix, float)
    entries = []
    for row in matrix:
        col = int(np.argmax(np.abs(row)))
        entries.append(("-" if row[col] < 0 else "") + AXES[col])
    text = ",".join(entries)
    if not np.array_equal(parse_axis_map(text), matrix):
        raise AxisMapError(f"matrix {matrix.tolist()} is not a signed permutation (an axis map)")
    return text


def apply_axis_map(matrix: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """(N, 3) file-frame vectors expressed in the project frame (exact: a signed permutation of columns)."""
    return np.asarray(vectors, float) @ np.asarray(matrix, float).T


def remapped(rec: Recording, matrix: np.ndarray) -> Recording:
    """``rec`` with its specific force and angular rate mapped by ``matrix`` (:func:`apply_axis_map`); the map's
    text is noted in ``meta["axes"]``."""
    meta = {**rec.meta, "axes": axis_map_text(matrix)}
    return dataclasses.replace(rec, acc=apply_axis_map(matrix, rec.acc), gyr=apply_axis_map(matrix, rec.gyr), meta=meta)
