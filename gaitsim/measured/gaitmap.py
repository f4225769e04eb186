"""Loader for gaitmap's healthy example walk: two NilsPod foot IMUs with Vicon foot markers.

Files (``gaitmap-healthy/``, MIT, (c) 2020 MaD-Lab Erlangen, from mad-lab-fau/gaitmap ``example_data/``):
``imu_sample.csv`` (204.8 Hz, m/s^2 and deg/s, already in gaitmap's foot sensor frame), ``mocap_sample.csv``
(100 Hz, mm, markers FCC/TOE/FM5 per foot) and ``stride_events_sample.csv`` (IMU sample indices).

Frames
------
The IMU data are in gaitmap's foot sensor frame, which is the project's body frame (the equivalence is stated,
and checked against gaitmap itself, in :mod:`gaitsim.interop.gaitmap`): the loader converts units only and
verifies the frame on the data with :func:`gaitsim.measured.quality.frame_checks`. The Vicon lab frame is z up and right-handed (checked: the
IMU's angular rate fits the marker body's rate by a proper rotation with correlation ~0.99); the reference is
given in it, converted to metres, with the lab's origin.

Alignment (:func:`align_foot`)
------------------------------
Both signals are low-passed by the same zero-phase filter (6 Hz), then

1. clock offset ``d`` (``t_mocap = t_imu + d``; ``d > 0``: the mocap clock is ahead) by cross-correlating the
   angular-rate norm of the IMU with that of the marker body (rigid-body rate: independent of the lever arm, and
   one derivative instead of two); the |specific force| correlation of the fitted IMU point is kept as a
   cross-check;
2. mount rotation IMU -> marker body by Kabsch on the paired angular rates;
3. lever arm: the marker-body point whose mocap specific force best matches the IMU's (least squares);
4. the reference is that point's raw (unfiltered) position, cubic-spline resampled onto the IMU clock.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.spatial.transform import Rotation, Slerp

from nav import quaternion as quat
from nav.constants import STANDARD_GRAVITY
from nav.recording import Recording, RecordingError, Reference

from . import mocap
from .quality import (
    frame_checks,
    nan_counts,
    saturation_counts,
    timestamp_report,
    warn_frame_problems,
    warn_quality,
)
from .table import read_csv

DATASET = "gaitmap-healthy"
IMU_RATE_HZ = 204.8
MOCAP_RATE_HZ = 100.0
ACC_FULL_SCALE = 16.0 * STANDARD_GRAVITY  # m/s^2, NilsPod accelerometer range used for this recording
GYR_FULL_SCALE = np.deg2rad(2000.0)  # rad/s, assumed gyroscope range (no sample comes near it)
SIDES = ("left", "right")
MARKERS = ("FCC", "TOE", "FM5")  # heel, toe, 5th metatarsal head (lateral)
ALIGN_CUTOFF_HZ = 6.0
DROPOUT_MARGIN_S = 0.1  # fit samples this close to a marker dropout are not used
EDGE_MARGIN_S = 0.3  # nor samples this close to the ends (filter transients)
CREDIT = ("gaitmap example data (mad-lab-fau/gaitmap, example_data/), MIT, (c) 2020 MaD-Lab Erlangen; "
          "Kuederle et al., gaitmap")


@dataclass
class FootPose:
    """Motion-capture pose of one foot and of its IMU, on the IMU clock, world = Vicon lab frame (m, z up).

    Attributes
    ----------
    t : (N,) s, IMU clock.
    sensor_pos : (N, 3) m, position of the IMU point (NaN during marker dropouts).
    sensor_quat : (N, 4) IMU frame -> world (w, x, y, z).
    marker_origin : (N, 3) m, centroid of the three markers.
    marker_quat : (N, 4) marker body frame -> world (x heel->toe, z up from the marker plane).
    lever_arm : (3,) m, IMU point from the marker centroid, marker body frame.
    mount_rotation : (3, 3) IMU frame -> marker body frame.
    clock_offset : s, ``t_mocap = t_imu + clock_offset``.
    """

    t: np.ndarray
    sensor_pos: np.ndarray
    sensor_quat: np.ndarray
    marker_origin: np.ndarray
    marker_quat: np.ndarray
    lever_arm: np.ndarray
    mount_rotation: np.ndarray
    clock_offset: float


@dataclass
class FootAlignment:
    """Result of :func:`align_foot` (units in the attribute names' docs of :class:`FootPose`)."""

    clock_offset: float
    rate_correlation: float
    clock_offset_from_specific_force: float
    specific_force_correlation: float
    mount_rotation: np.ndarray
    lever_arm: np.ndarray
    specific_force_residual_rms: float
    rate_residual_rms: float
    gravity_angle_deg: float

    def as_meta(self) -> dict:
        return {
            "clock_offset_s": self.clock_offset,
            "clock_offset_definition": "t_mocap = t_imu + offset (positive: mocap clock ahead of the IMU clock)",
            "clock_offset_method": f"max correlation of |angular rate| (IMU vs marker body), both low-passed "
                                   f"{ALIGN_CUTOFF_HZ} Hz zero-phase",
            "rate_correlation": self.rate_correlation,
            "clock_offset_from_specific_force_s": self.clock_offset_from_specific_force,
            "specific_force_correlation": self.specific_force_correlation,
            "mount_rotation_imu_to_marker": self.mount_rotation.tolist(),
            "mount_rotation_angle_deg": float(np.rad2deg(np.linalg.norm(quat.to_rotvec(
                quat.from_matrix(self.mount_rotation))))),
            "lever_arm_marker_frame_m": self.lever_arm.tolist(),
            "lever_arm_definition": "IMU point from the marker centroid in the marker body frame "
                                    "(x heel->toe, y left, z up)",
            "specific_force_residual_rms_m_s2": self.specific_force_residual_rms,
            "rate_residual_rms_rad_s": self.rate_residual_rms,
            "still_gravity_angle_deg": self.gravity_angle_deg,
        }


def _column_index(path: Path, header: tuple[list[str], list[str]], group: str, name: str) -> int:
    for k, key in enumerate(zip(*header)):
        if key == (group, name):
            return k + 1
    raise RecordingError(f"{path}: no column ({group!r}, {name!r}); header holds {sorted(set(zip(*header)))}")


def read_imu(root: Path) -> tuple[np.ndarray, dict[str, tuple[np.ndarray, np.ndarray]], dict]:
    """Read ``imu_sample.csv``.

    Parameters
    ----------
    root : the shared data folder (holding ``gaitmap-healthy/``).

    Returns
    -------
    t : (N,) s, sample index / 204.8 Hz.
    feet : {"left"/"right": (acc (N, 3) m/s^2, gyr (N, 3) rad/s)} in the FSF = project body frame.
    quality : per-file counts (rows, index steps, NaNs).
    """
    path = Path(root) / DATASET / "imu_sample.csv"
    rows, table = read_csv(path, header_rows=2)
    header = (rows[0][1:], rows[1][1:])  # (group, name) of every column after the index
    index = table[:, 0]
    quality = {"file": path.name, **timestamp_report(index),
               "index_steps_not_one": int(np.count_nonzero(np.diff(index) != 1))}
    feet, nans = {}, {}
    for side in SIDES:
        cols = [_column_index(path, header, f"{side}_sensor", f"{kind}_{axis}")
                for kind in ("acc", "gyr") for axis in "xyz"]
        acc, gyr = table[:, cols[:3]], np.deg2rad(table[:, cols[3:]])
        feet[side] = (acc, gyr)
        nans.update(nan_counts({f"{side}_acc": acc, f"{side}_gyr": gyr}))
    quality["nan_samples"] = nans
    if quality["index_steps_not_one"] or quality["non_increasing_rows"]:
        warn_quality(path.name, f"{quality['index_steps_not_one']} sample-index steps differ from 1")
    return (index - index[0]) / IMU_RATE_HZ, feet, quality


def read_markers(root: Path) -> tuple[np.ndarray, dict[str, dict[str, np.ndarray]], dict]:
    """Read ``mocap_sample.csv``: marker positions in m (Vicon lab frame), NaN kept where a marker dropped out.

    Returns
    -------
    t : (M,) s, mocap sample index / 100 Hz (mocap clock).
    markers : {"left"/"right": {"FCC"/"TOE"/"FM5": (M, 3) m}}.
    quality : per-marker NaN sample counts.
    """
    path = Path(root) / DATASET / "mocap_sample.csv"
    rows, table = read_csv(path, header_rows=2)
    header = (rows[0][1:], rows[1][1:])  # (group, name) of every column after the index
    markers = {}
    for side in SIDES:
        markers[side] = {
            name: table[:, [_column_index(path, header, f"{side[0].upper()}_{name}", axis) for axis in "xyz"]] / 1000.0
            for name in MARKERS
        }
    nans = nan_counts({f"{side}_{name}": markers[side][name] for side in SIDES for name in MARKERS})
    quality = {"file": path.name, "rows": int(len(table)), "nan_samples": nans,
               "nan_samples_total": int(sum(nans.values()))}
    if quality["nan_samples_total"]:
        warn_quality(path.name, f"{quality['nan_samples_total']} marker samples are NaN (dropouts): {nans}; "
                                "kept as NaN in the reference")
    return table[:, 0] / MOCAP_RATE_HZ, markers, quality


def _fill_dropouts(t: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Linear fill of NaN rows, for filtering only (the reference keeps its NaNs)."""
    good = ~np.isnan(values).any(axis=1)
    return np.column_stack([np.interp(t, t[good], values[good, k]) for k in range(values.shape[1])])


def _dropout_free(t: np.ndarray, marker_set: dict[str, np.ndarray]) -> np.ndarray:
    """Mocap samples farther than :data:`DROPOUT_MARGIN_S` from any marker dropout."""
    bad = np.zeros(len(t), dtype=bool)
    for values in marker_set.values():
        bad |= np.isnan(values).any(axis=1)
    if not bad.any():
        return np.ones(len(t), dtype=bool)
    near = np.abs(t[:, None] - t[bad][None, :]).min(axis=1) <= DROPOUT_MARGIN_S
    return ~near


def align_foot(t_imu: np.ndarray, acc: np.ndarray, gyr: np.ndarray, t_mocap: np.ndarray,
               marker_set: dict[str, np.ndarray], side: str) -> FootAlignment:
    """Clock offset, mount rotation and lever arm of one foot IMU against its three markers (module docstring).

    Parameters
    ----------
    t_imu : (N,) s; acc : (N, 3) m/s^2; gyr : (N, 3) rad/s -- the IMU in its own frame.
    t_mocap : (M,) s; marker_set : {"FCC", "TOE", "FM5": (M, 3) m}, may hold NaN rows.
    side : "left" or "right".
    """
    filled = {name: _fill_dropouts(t_mocap, values) for name, values in marker_set.items()}
    origin, rotation = mocap.marker_frame(filled["FCC"], filled["TOE"], filled["FM5"], side)
    kin = mocap.body_kinematics(origin, rotation, MOCAP_RATE_HZ, ALIGN_CUTOFF_HZ)
    gyr_lp = mocap.lowpass(gyr, ALIGN_CUTOFF_HZ, IMU_RATE_HZ)
    acc_lp = mocap.lowpass(acc, ALIGN_CUTOFF_HZ, IMU_RATE_HZ)
    offset, rate_corr = mocap.estimate_time_offset(
        t_mocap, np.linalg.norm(kin.rate_body, axis=1), t_imu, np.linalg.norm(gyr_lp, axis=1))

    t_on_imu = t_mocap - offset
    use = (_dropout_free(t_mocap, marker_set) & (t_on_imu > t_imu[0] + EDGE_MARGIN_S)
           & (t_on_imu < t_imu[-1] - EDGE_MARGIN_S) & (t_mocap > t_mocap[0] + EDGE_MARGIN_S)
           & (t_mocap < t_mocap[-1] - EDGE_MARGIN_S))
    gyr_at_mocap = CubicSpline(t_imu, gyr_lp)(t_on_imu[use])
    mount = mocap.rotation_between(gyr_at_mocap, kin.rate_body[use])
    rate_residual = kin.rate_body[use] - gyr_at_mocap @ mount.T

    force_world = np.full((len(t_mocap), 3), np.nan)
    force_world[use] = np.einsum("nij,jk,nk->ni", kin.rotation[use], mount, CubicSpline(t_imu, acc_lp)(t_on_imu[use]))
    lever_arm, force_residual = mocap.fit_lever_arm(kin, force_world, use)
    offset_force, force_corr = mocap.estimate_time_offset(
        t_mocap, np.linalg.norm(kin.point_specific_force(lever_arm), axis=1), t_imu, np.linalg.norm(acc_lp, axis=1))

    still = np.linalg.norm(kin.rate_body, axis=1) < 0.3
    still_force = force_world[use & still]
    cos_angle = still_force[:, 2] / np.linalg.norm(still_force, axis=1)
    return FootAlignment(
        clock_offset=offset, rate_correlation=rate_corr,
        clock_offset_from_specific_force=offset_force, specific_force_correlation=force_corr,
        mount_rotation=mount, lever_arm=lever_arm, specific_force_residual_rms=force_residual,
        rate_residual_rms=float(np.sqrt(np.mean(np.sum(rate_residual**2, axis=1)))),
        gravity_angle_deg=float(np.rad2deg(np.median(np.arccos(np.clip(cos_angle, -1.0, 1.0))))),
    )


def _resample_positions(t_mocap: np.ndarray, positions: np.ndarray, t_query: np.ndarray) -> np.ndarray:
    """Cubic-spline positions at ``t_query`` (mocap clock); NaN where a bracketing mocap sample is NaN."""
    good = ~np.isnan(positions).any(axis=1)
    out = CubicSpline(t_mocap[good], positions[good])(t_query)
    after = np.clip(np.searchsorted(t_mocap, t_query), 0, len(t_mocap) - 1)
    before = np.clip(after - 1, 0, len(t_mocap) - 1)
    out[~(good[after] & good[before])] = np.nan
    return out


def _resample_rotations(t_mocap: np.ndarray, rotation: np.ndarray, t_query: np.ndarray) -> np.ndarray:
    """Slerp body->world rotations at ``t_query``; returns (w, x, y, z) quaternions, NaN where undefined."""
    good = ~np.isnan(rotation).reshape(len(rotation), -1).any(axis=1)
    slerp = Slerp(t_mocap[good], Rotation.from_matrix(rotation[good]))
    out = slerp(np.clip(t_query, t_mocap[good][0], t_mocap[good][-1])).as_quat(scalar_first=True)
    after = np.clip(np.searchsorted(t_mocap, t_query), 0, len(t_mocap) - 1)
    out[~(good[after] & good[np.clip(after - 1, 0, None)])] = np.nan
    return out


def _foot_pose(t_imu: np.ndarray, t_mocap: np.ndarray, marker_set: dict[str, np.ndarray], side: str,
               alignment: FootAlignment) -> FootPose:
    origin, rotation = mocap.marker_frame(marker_set["FCC"], marker_set["TOE"], marker_set["FM5"], side)
    sensor_pos = origin + rotation @ alignment.lever_arm
    t_query = t_imu + alignment.clock_offset
    inside = (t_query >= t_mocap[0]) & (t_query <= t_mocap[-1])
    t_query = t_query[inside]
    marker_quat = _resample_rotations(t_mocap, rotation, t_query)
    return FootPose(
        t=t_imu[inside],
        sensor_pos=_resample_positions(t_mocap, sensor_pos, t_query),
        sensor_quat=quat.multiply(marker_quat, quat.from_matrix(alignment.mount_rotation)),
        marker_origin=_resample_positions(t_mocap, origin, t_query),
        marker_quat=marker_quat,
        lever_arm=alignment.lever_arm,
        mount_rotation=alignment.mount_rotation,
        clock_offset=alignment.clock_offset,
    )


def _load(root: Path) -> tuple[list[Recording], dict[str, FootPose]]:
    t_imu, feet, imu_quality = read_imu(root)
    t_mocap, markers, mocap_quality = read_markers(root)
    recordings, poses = [], {}
    for side in SIDES:
        acc, gyr = feet[side]
        label = f"{DATASET}/{side}"
        alignment = align_foot(t_imu, acc, gyr, t_mocap, markers[side], side)
        pose = _foot_pose(t_imu, t_mocap, markers[side], side, alignment)
        poses[side] = pose
        checks = frame_checks(t_imu, acc, gyr)
        warn_frame_problems(label, checks)
        acc_sat = saturation_counts(acc, ACC_FULL_SCALE)
        gyr_sat = saturation_counts(gyr, GYR_FULL_SCALE)
        if acc_sat["samples"] or gyr_sat["samples"]:
            warn_quality(label, f"{acc_sat['samples']} accelerometer samples at the +-16 g range limit "
                                f"(|a| >= {acc_sat['threshold']:.1f} m/s^2), {gyr_sat['samples']} gyroscope samples "
                                "at the range limit; kept unchanged")
        warn_quality(label, f"mocap-IMU clock offset estimated {1000 * alignment.clock_offset:+.1f} ms "
                            f"(t_mocap = t_imu + offset); reference resampled onto the IMU clock")
        meta = {
            "source": "mad-lab-fau/gaitmap, example_data/ (imu_sample.csv, mocap_sample.csv)",
            "license": "MIT",
            "credit": CREDIT,
            "dataset": DATASET,
            "recording": side,
            "sensor": "NilsPod on the lateral side of the shoe (heel)",
            "rate_hz": IMU_RATE_HZ,
            "frames": {
                "imu_source_frame": "gaitmap foot sensor frame (FSF): x to the shoe tip, y left, z up, right-handed",
                "imu_mapping": "identity (FSF == project body frame); gyr deg/s -> rad/s; acc already m/s^2",
                "imu_checks": checks,
                "world": "Vicon lab frame, mm -> m, z up, right-handed, lab origin (no shift)",
                "marker_frame": "origin: centroid of FCC, TOE, FM5; x: FCC->TOE; z: marker-plane normal, up; y = z x x",
            },
            "data_quality": {
                "imu": imu_quality,
                "mocap": mocap_quality,
                "acc_saturation": acc_sat,
                "gyr_saturation": gyr_sat,
                "acc_full_scale_m_s2": ACC_FULL_SCALE,
                "gyr_full_scale_rad_s": float(GYR_FULL_SCALE),
            },
            "reference": {
                "kind": "mocap",
                "point": "IMU point: marker centroid + mount lever arm (fitted)",
                "rate_hz": MOCAP_RATE_HZ,
                "resampling": "cubic spline of the raw marker-derived IMU point onto the IMU clock; NaN in dropouts",
                "samples": int(len(pose.t)),
                **alignment.as_meta(),
            },
        }
        recordings.append(Recording(t=t_imu, acc=acc, gyr=gyr, meta=meta,
                                    reference=Reference(t=pose.t, pos=pose.sensor_pos)))
    return recordings, poses


def load_gaitmap(root: str | Path) -> list[Recording]:
    """The two foot recordings (left, right) with their mocap reference of the IMU point on the IMU clock.

    Parameters
    ----------
    root : the shared data folder holding ``gaitmap-healthy/``.
    """
    return _load(Path(root))[0]


def gaitmap_foot_pose(side: str, root: str | Path) -> FootPose:
    """Full motion-capture pose of one foot and of its IMU on the IMU clock (see :class:`FootPose`).

    Parameters
    ----------
    side : "left" or "right".
    root : the shared data folder holding ``gaitmap-healthy/``.
    """
    if side not in SIDES:
        raise ValueError(f"gaitmap_foot_pose: side={side!r}; allowed: {SIDES}")
    return _load(Path(root))[1][side]


def gaitmap_stride_events(root: str | Path) -> dict[str, dict[str, np.ndarray]]:
    """Published stride events of ``stride_events_sample.csv`` converted from IMU samples to seconds.

    Parameters
    ----------
    root : the shared data folder holding ``gaitmap-healthy/``.

    Returns
    -------
    {"left"/"right": {"s_id": int array, "start", "end", "ic", "tc", "min_vel", "pre_ic": (S,) s on the IMU
    clock}}; ``ic`` initial contact, ``tc`` toe-off (terminal contact), ``min_vel`` the stride's minimum-velocity
    (mid-stance) instant, ``pre_ic`` the previous initial contact.
    """
    path = Path(root) / DATASET / "stride_events_sample.csv"
    if not path.exists():
        raise RecordingError(f"{path}: file not found")
    with open(path) as fh:
        header = fh.readline().strip().split(",")
    expected = ["s_id", "foot", "start", "end", "ic", "tc", "min_vel", "pre_ic"]
    if header != expected:
        raise RecordingError(f"{path}: header {header}, expected {expected}")
    rows = np.loadtxt(path, delimiter=",", skiprows=1, dtype=str, ndmin=2)
    events = {}
    for side in SIDES:
        mine = rows[rows[:, 1] == side]
        events[side] = {"s_id": mine[:, 0].astype(int)}
        events[side].update({name: mine[:, k].astype(float) / IMU_RATE_HZ for k, name in enumerate(expected) if k >= 2})
    return events
