"""Loader for the UCR constrained-ZUPT FGO recordings: two foot IMUs at 60 Hz with foot positions.

Files (``ucr-fgo/``, MIT, (c) 2025 UC Regents, from Azurehappen/Constrained-ZUPT-FGO ``measData/``):
``imuMeasLeft.csv``, ``imuMeasRight.csv`` (time_index, acc m/s^2, gyro rad/s, is_zero_vel) and ``positionGt.csv``
(time_index, left and right foot positions in m).

Clock: the files carry only a sample counter; no timestamps are documented, so ``t = time_index / 60 Hz`` for the
IMU and the reference alike (they share the counter, one row each).

Frames
------
IMU: used as stored (identity). Verified with :func:`gaitsim.measured.quality.frame_checks`: gravity on +z at
rest, pitch about y, x forward.
Reference: ``positionGt.csv`` is right-handed with z DOWN (x, y, z_down): the walk turns counter-clockwise about
the IMU's up axis (integrated gyro z ~ +6 laps) while the stored (x, y) path turns clockwise seen with z up. A
proper rotation by 180 deg about x, ``(x, y, z) -> (x, -y, -z)``, makes it right-handed z-up; negating z alone would
leave it mirrored. The loader applies that rotation and re-verifies the turning direction (stored in meta).
The reference's origin is not documented and is kept.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from nav.recording import Recording, RecordingError, Reference

from .quality import frame_checks, nan_counts, timestamp_report, warn_frame_problems, warn_quality
from .table import read_csv

DATASET = "ucr-fgo"
RATE_HZ = 60.0
SIDES = {"left": "imuMeasLeft.csv", "right": "imuMeasRight.csv"}
IMU_HEADER = ["time_index", "acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z", "is_zero_vel"]
REFERENCE_HEADER = ["time_index", "pos_left_x", "pos_left_y", "pos_left_z", "pos_right_x", "pos_right_y",
                    "pos_right_z"]
Z_DOWN_TO_Z_UP = np.diag([1.0, -1.0, -1.0])  # rotation by 180 deg about x
CREDIT = ("Azurehappen/Constrained-ZUPT-FGO measData/, MIT, (c) 2025 UC Regents; Hu & Hu, 'Constrained Factor Graph "
          "Optimization for Robust Networked Pedestrian Inertial Navigation', IEEE/ION PLANS 2025")


def _heading_change(xy: np.ndarray, rate_hz: float, min_speed: float = 0.2) -> float:
    """rad, unwrapped change of the direction of travel (counter-clockwise positive) over a planar path."""
    step = np.diff(xy, axis=0)
    moving = np.linalg.norm(step, axis=1) * rate_hz > min_speed
    heading = np.unwrap(np.arctan2(step[moving, 1], step[moving, 0]))
    return float(heading[-1] - heading[0])


def ucr_zero_velocity_labels(side: str, root: str | Path) -> np.ndarray:
    """The authors' ``is_zero_vel`` label of one foot, (N,) bool on the loader's IMU samples.

    Parameters
    ----------
    side : "left" or "right".
    root : the shared data folder holding ``ucr-fgo/``.
    """
    if side not in SIDES:
        raise ValueError(f"ucr_zero_velocity_labels: side={side!r}; allowed: {sorted(SIDES)}")
    table = read_csv(Path(root) / DATASET / SIDES[side], 1, IMU_HEADER)[1]
    return table[:, 7] > 0.5


def load_ucr(root: str | Path) -> list[Recording]:
    """The two foot recordings (left, right) with the foot position reference converted to right-handed z-up.

    Parameters
    ----------
    root : the shared data folder holding ``ucr-fgo/``.
    """
    root = Path(root)
    ref_path = root / DATASET / "positionGt.csv"
    ref_table = read_csv(ref_path, 1, REFERENCE_HEADER)[1]
    ref_quality = {"file": ref_path.name, **timestamp_report(ref_table[:, 0]),
                   "nan_samples": nan_counts({"left": ref_table[:, 1:4], "right": ref_table[:, 4:7]})}
    recordings = []
    for k, (side, name) in enumerate(SIDES.items()):
        path = root / DATASET / name
        table = read_csv(path, 1, IMU_HEADER)[1]
        index = table[:, 0]
        stamps = timestamp_report(index)
        stamps["index_steps_not_one"] = int(np.count_nonzero(np.diff(index) != 1))
        if stamps["index_steps_not_one"]:
            warn_quality(path.name, f"{stamps['index_steps_not_one']} time_index steps differ from 1")
        if not np.array_equal(index, ref_table[:, 0]):
            raise RecordingError(f"{path}: time_index does not match {ref_path.name} row by row "
                                 f"({len(index)} vs {len(ref_table)} rows)")
        t = (index - index[0]) / RATE_HZ
        acc, gyr = table[:, 1:4], table[:, 4:7]
        zero_velocity = table[:, 7] > 0.5
        nans = nan_counts({"acc": acc, "gyr": gyr})
        if sum(nans.values()) or sum(ref_quality["nan_samples"].values()):
            warn_quality(path.name, f"NaN samples: imu {nans}, reference {ref_quality['nan_samples']}")
        label = f"{DATASET}/{side}"
        checks = frame_checks(t, acc, gyr)
        warn_frame_problems(label, checks)

        stored = ref_table[:, 1 + 3 * k: 4 + 3 * k]
        pos = stored @ Z_DOWN_TO_Z_UP.T
        imu_turn = float(np.sum(gyr[:-1, 2] * np.diff(t)))
        ref_turn = _heading_change(pos[:, :2], RATE_HZ)
        warn_quality(ref_path.name, f"{side} reference z points down: converted (x, y, z) -> (x, -y, -z) to a "
                                    "right-handed z-up frame")
        meta = {
            "source": f"Azurehappen/Constrained-ZUPT-FGO, measData/ ({name}, positionGt.csv)",
            "license": "MIT",
            "credit": CREDIT,
            "dataset": DATASET,
            "recording": side,
            "rate_hz": RATE_HZ,
            "clock": "t = time_index / 60 Hz (no timestamps in the files; IMU and reference share time_index)",
            "frames": {
                "imu_mapping": "identity (stored axes already x forward, y left, z up; verified by imu_checks)",
                "imu_checks": checks,
                "reference_source_frame": "positionGt.csv: right-handed, z down, origin undocumented",
                "reference_mapping": "(x, y, z) -> (x, -y, -z): rotation by 180 deg about x to right-handed z up",
                "turn_check_rad": {"imu_integrated_gyro_z": imu_turn, "reference_heading_change": ref_turn},
            },
            "data_quality": {
                "imu": {"file": name, **stamps, "nan_samples": nans,
                        "max_abs_acc_m_s2": np.abs(acc).max(axis=0).tolist(),
                        "max_abs_gyr_rad_s": np.abs(gyr).max(axis=0).tolist(),
                        "saturation": "not counted: sensor range undocumented"},
                "reference": ref_quality,
                "zero_velocity_label": {"samples": int(zero_velocity.sum()),
                                        "fraction": float(zero_velocity.mean()),
                                        "access": "gaitsim.measured.ucr_zero_velocity_labels(side, root)"},
            },
            "reference": {"kind": "position", "point": "foot (authors' ground truth)", "rate_hz": RATE_HZ,
                          "z_down_converted": True, "origin": "undocumented (kept)"},
        }
        recordings.append(Recording(t=t, acc=acc, gyr=gyr, meta=meta, reference=Reference(t=t.copy(), pos=pos)))
    return recordings
