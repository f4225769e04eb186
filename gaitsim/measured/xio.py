"""Loader for x-io's Gait-Tracking walks: one NGIMU on the shoe, closed loops at ~400 Hz.

Files (``xio-ngimu/``, MIT, (c) x-io Technologies, from xioTechnologies/Gait-Tracking): ``short_walk.csv`` and
``long_walk.csv`` with Time (s), Gyroscope X/Y/Z (deg/s), Accelerometer X/Y/Z (g).

Traps: repeated packets (rows whose time does not increase past the previous rows) are dropped and counted; the
timestamps jitter (~15 % of the interval, with lost-packet gaps) and are kept as stored, with their statistics
reported. Units: deg/s -> rad/s, g -> m/s^2 with the standard gravity 9.80665 m/s^2 per g.

Frames: the NGIMU's axes are used as stored (identity) and verified on the data with
:func:`gaitsim.measured.quality.frame_checks` (gravity on +z at rest, pitch about y, x forward). The sensor sits on
the shoe tilted ~30 deg toes-down (still specific force has x ~ -0.45 g): a mount misalignment that is reported
(``meta["frames"]["mount_tilt_deg"]``), not rotated away.

Reference: only loop closure -- the foot ends where it started. It is represented as
``Reference(t=[t_start, t_end], pos=zeros((2, 3)))`` in a world frame whose origin is the start position (the
horizontal axes are arbitrary), and ``meta["reference"] = {"kind": "loop_closure", ...}``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from nav.constants import STANDARD_GRAVITY
from nav.recording import Recording, Reference

from .quality import (
    frame_checks,
    jitter_stats,
    nan_counts,
    non_increasing_time_mask,
    saturation_counts,
    timestamp_report,
    warn_frame_problems,
    warn_quality,
)
from .table import read_csv

DATASET = "xio-ngimu"
WALKS = ("short_walk", "long_walk")
HEADER = ["Time (s)", "Gyroscope X (deg/s)", "Gyroscope Y (deg/s)", "Gyroscope Z (deg/s)",
          "Accelerometer X (g)", "Accelerometer Y (g)", "Accelerometer Z (g)"]
ACC_FULL_SCALE = 16.0 * STANDARD_GRAVITY  # m/s^2, NGIMU accelerometer range
GYR_FULL_SCALE = np.deg2rad(2000.0)  # rad/s, NGIMU gyroscope range
NOMINAL_RATE_HZ = 400.0
PUBLISHED_LOOP_ERROR_M = {"short_walk": 0.082, "long_walk": 0.421}  # x-io's own tracker (README)
CREDIT = "xioTechnologies/Gait-Tracking, MIT, (c) x-io Technologies"


def read_walk(path: Path) -> tuple[np.ndarray, dict]:
    """Read one walk file and drop the rows whose time does not increase.

    Parameters
    ----------
    path : the CSV file.

    Returns
    -------
    table : (N, 7) the kept rows in the file's units (s, deg/s, g).
    quality : counts (rows, repeated, dropped, of which identical to the previous row, NaNs) and jitter statistics
        of the kept timestamps.
    """
    _, raw = read_csv(path, 1, HEADER)
    drop = non_increasing_time_mask(raw[:, 0])
    identical = np.zeros(len(raw), dtype=bool)
    identical[1:] = np.all(raw[1:] == raw[:-1], axis=1)
    table = raw[~drop]
    quality = {
        "file": path.name,
        **timestamp_report(raw[:, 0]),
        "dropped_rows": int(drop.sum()),
        "dropped_fraction": float(drop.mean()),
        "dropped_identical_to_previous_row": int(np.count_nonzero(drop & identical)),
        "nan_samples": nan_counts({"time": raw[:, 0], "gyr": raw[:, 1:4], "acc": raw[:, 4:7]}),
        "jitter": jitter_stats(table[:, 0]),
    }
    warn_quality(path.name, f"dropped {quality['dropped_rows']} of {quality['rows']} rows whose time does not "
                            f"increase ({quality['dropped_identical_to_previous_row']} exact repeats)")
    jitter = quality["jitter"]
    warn_quality(path.name, f"timestamp jitter {100 * jitter['jitter_rel']:.1f} % of the median interval "
                            f"{1000 * jitter['dt_median']:.3f} ms, {jitter['gaps']} gaps > 1.5 intervals; "
                            "timestamps kept as stored")
    if sum(quality["nan_samples"].values()):
        warn_quality(path.name, f"NaN samples {quality['nan_samples']}")
    return table, quality


def load_xio(root: str | Path) -> list[Recording]:
    """The two closed-loop walks (short_walk, long_walk) with a loop-closure reference.

    Parameters
    ----------
    root : the shared data folder holding ``xio-ngimu/``.
    """
    recordings = []
    for walk in WALKS:
        path = Path(root) / DATASET / f"{walk}.csv"
        table, quality = read_walk(path)
        t = table[:, 0] - table[0, 0]
        gyr = np.deg2rad(table[:, 1:4])
        acc = table[:, 4:7] * STANDARD_GRAVITY
        label = f"{DATASET}/{walk}"
        checks = frame_checks(t, acc, gyr)
        warn_frame_problems(label, checks)
        still = np.asarray(checks["still_acc_mean"])
        tilt = float(np.rad2deg(np.arcsin(np.clip(-still[0] / np.linalg.norm(still), -1.0, 1.0))))
        quality["acc_saturation"] = saturation_counts(acc, ACC_FULL_SCALE)
        quality["gyr_saturation"] = saturation_counts(gyr, GYR_FULL_SCALE)
        if quality["acc_saturation"]["samples"] or quality["gyr_saturation"]["samples"]:
            warn_quality(label, f"samples at the range limit: acc {quality['acc_saturation']['samples']}, "
                                f"gyr {quality['gyr_saturation']['samples']}; kept unchanged")
        meta = {
            "source": f"xioTechnologies/Gait-Tracking ({walk}.csv)",
            "license": "MIT",
            "credit": CREDIT,
            "dataset": DATASET,
            "recording": walk,
            "sensor": "x-io NGIMU on the shoe",
            "rate_hz": NOMINAL_RATE_HZ,
            "clock": "file timestamps (s) minus the first kept one; not a nominal rate",
            "frames": {
                "imu_mapping": "identity (NGIMU axes as stored: x forward, y left, z up; verified by imu_checks); "
                               "gyr deg/s -> rad/s, acc g -> m/s^2 (x 9.80665)",
                "imu_checks": checks,
                "mount_tilt_deg": tilt,
                "mount_tilt_definition": "toes-down pitch of the sensor x axis at rest, from the still specific force",
            },
            "data_quality": quality,
            "reference": {
                "kind": "loop_closure",
                "description": "the foot ends where it started: the start-to-end distance is the error; "
                               "Reference holds t = [t_start, t_end] and pos = zeros((2, 3)) (origin at the start)",
                "published_loop_error_m": PUBLISHED_LOOP_ERROR_M[walk],
            },
        }
        reference = Reference(t=np.array([t[0], t[-1]]), pos=np.zeros((2, 3)))
        recordings.append(Recording(t=t, acc=acc, gyr=gyr, meta=meta, reference=reference))
    return recordings
