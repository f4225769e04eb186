"""Measured foot-IMU datasets loaded into the project's recording form.

``load_dataset(name)`` returns :class:`nav.recording.Recording` objects in SI units and the project's body frame
(x toes, y left, z up when the foot is flat) with their reference on the IMU clock in a right-handed z-up world
frame. Documented traps (repeated rows, timestamp jitter, NaN dropouts, saturation, a z-down reference, the
reference-IMU clock offset, the sensor's lever arm) are handled and reported: counts in ``meta["data_quality"]``
and a :class:`gaitsim.measured.quality.DataQualityWarning` each, never silently repaired.

The data live outside the repository: ``$GAITSIM_DATA`` if set, else ``../shared/data`` next to the repository.
"""

from __future__ import annotations

import os
from pathlib import Path

from nav.recording import Recording, RecordingError

from .gaitmap import gaitmap_foot_pose, gaitmap_stride_events, load_gaitmap
from .quality import DataQualityWarning
from .ucr import load_ucr, ucr_zero_velocity_labels
from .xio import load_xio

LOADERS = {"gaitmap-healthy": load_gaitmap, "ucr-fgo": load_ucr, "xio-ngimu": load_xio}
REPOSITORY_ROOT = Path(__file__).resolve().parents[2]

__all__ = [
    "DataQualityWarning", "LOADERS", "data_root", "gaitmap_foot_pose", "gaitmap_stride_events", "load_dataset",
    "ucr_zero_velocity_labels",
]


def data_root(root: str | Path | None = None) -> Path:
    """The shared data folder: ``root`` if given, else ``$GAITSIM_DATA``, else ``<repository>/../shared/data``.

    Raises
    ------
    RecordingError
        naming the path when the folder does not exist.
    """
    if root is None:
        root = os.environ.get("GAITSIM_DATA") or REPOSITORY_ROOT.parent / "shared" / "data"
    root = Path(root)
    if not root.is_dir():
        raise RecordingError(f"{root}: measured-data folder not found (pass root=... or set GAITSIM_DATA)")
    return root


def load_dataset(name: str, root: str | Path | None = None) -> list[Recording]:
    """Load a shared measured dataset.

    Parameters
    ----------
    name : "gaitmap-healthy" (left, right), "ucr-fgo" (left, right) or "xio-ngimu" (short_walk, long_walk).
    root : folder holding the dataset folders; default :func:`data_root`.

    Returns
    -------
    list of recordings: t (s), acc (m/s^2, specific force), gyr (rad/s), body frame x toes / y left / z up, meta
    (source, license, credit, dataset, recording, frames, data_quality, reference) and reference (m, IMU clock).
    """
    if name not in LOADERS:
        raise RecordingError(f"load_dataset: unknown dataset {name!r}; allowed: {sorted(LOADERS)}")
    folder = data_root(root)
    if not (folder / name).is_dir():
        raise RecordingError(f"{folder / name}: dataset folder not found")
    return LOADERS[name](folder)
