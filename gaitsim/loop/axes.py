"""The sensor-axis map of ``--axes``: which sensor axis, with which sign, becomes each body axis.

``"y,-x,z"`` reads: body x = sensor y, body y = -sensor x, body z = sensor z. The map is a signed permutation
``M`` with ``body = M @ sensor``; it may be a mirror (determinant -1), which is how a left-handed logger frame is
put right. Accelerometer and gyro are mapped alike.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from nav.recording import Recording

AXES = "xyz"
IDENTITY = "x,y,z"


def parse_axes(text: str) -> np.ndarray:
    """The (3, 3) signed permutation of an axis map such as ``"y,-x,z"`` (module docstring).

    Raises
    ------
    ValueError
        naming the text and what is allowed, unless it names each of x, y, z exactly once, each optionally
        preceded by a sign.
    """
    items = [item.strip().lower() for item in str(text).split(",")]
    names = [item.lstrip("+-") for item in items]
    if len(items) != 3 or sorted(names) != list(AXES) or any(len(item) - len(name) > 1 for item, name in
                                                             zip(items, names)):
        raise ValueError(f"--axes {text!r}: give three comma-separated sensor axes, each of x, y, z once with an "
                         f"optional sign, e.g. 'y,-x,z' (body x = sensor y, body y = -sensor x, body z = sensor z)")
    matrix = np.zeros((3, 3))
    for row, (item, name) in enumerate(zip(items, names)):
        matrix[row, AXES.index(name)] = -1.0 if item.startswith("-") else 1.0
    return matrix


def format_axes(matrix: np.ndarray) -> str:
    """The ``--axes`` text of a signed permutation (inverse of :func:`parse_axes`)."""
    out = []
    for row in np.asarray(matrix):
        column = int(np.argmax(np.abs(row)))
        out.append(("-" if row[column] < 0 else "") + AXES[column])
    return ",".join(out)


def remapped(rec: Recording, matrix: np.ndarray) -> Recording:
    """``rec`` with its accelerometer and gyro samples in the body frame ``matrix @ sensor``; the map is noted in
    ``meta["axes"]``."""
    matrix = np.asarray(matrix, float)
    meta = {**rec.meta, "axes": format_axes(matrix)}
    return dataclasses.replace(rec, acc=rec.acc @ matrix.T, gyr=rec.gyr @ matrix.T, meta=meta)
