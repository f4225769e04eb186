"""Step 1 of the mount-yaw study: the sensor-frame angular rate in foot flat that the foot's reference pose does
not show (gaitmap: IMU gyro minus the Vicon three-marker body's rate in the sensor frame).

Foot flats: the stance study's events (:func:`gaitsim.stance.profiles.detected_gait`, FF to HO). Per stride the
rates are read at foot-flat phases u and their core mean over u in [0.2, 0.8]; reported: median over strides,
the median absolute deviation over strides ("scatter"), the profile at u = 0.1..0.9 and the per-stride trend.
Both the IMU gyro and the marker body are low-passed by the same zero-phase filter (``CUTOFF_HZ``).

Run from the repository root: ``python3 -m studies.mount_rate [CUTOFF_HZ ...]`` (default 6 and 12 Hz).
"""

from __future__ import annotations

import json
import sys
import warnings

import numpy as np
from scipy.interpolate import CubicSpline

from gaitsim.measured import mocap
from gaitsim.measured.gaitmap import IMU_RATE_HZ, MOCAP_RATE_HZ, gaitmap_foot_pose, read_markers
from gaitsim.stance.command import load_recordings
from gaitsim.stance.profiles import detected_gait

DATA = "../shared/data"
CUTOFF_HZ = 6.0  # the gaitmap loader's alignment band
CORE = np.linspace(0.2, 0.8, 13)  # foot-flat phases of the core
FINE = np.round(np.arange(0.1, 0.95, 0.1), 2)  # foot-flat phases of the profiles


def foot_flats(rec):
    """(K, 2) s: FF and HO times of the complete interior strides (the stance study's recipe)."""
    t = np.asarray(rec.t, float)
    _, stances, ev = detected_gait(rec)
    ok = np.flatnonzero(ev.complete())
    ok = ok[(ok > 0) & (ok < len(stances) - 1)]
    return np.column_stack([t[ev.ff[ok]], t[ev.ho[ok]]])


def per_stride(t, values, flats, phases):
    """(K, P, 3): ``values`` (N, 3) interpolated at foot-flat phases of every stride."""
    out = []
    for t_ff, t_ho in flats:
        at = t_ff + np.asarray(phases) * (t_ho - t_ff)
        out.append(np.stack([np.interp(at, t, values[:, i]) for i in range(3)], -1))
    return np.array(out)


def summary(t, values, flats) -> dict:
    """Rates ``values`` (N, 3) rad/s on the clock ``t`` over the foot flats ``flats`` (K, 2) s: each stride's core
    mean, its median and median absolute deviation over strides (deg/s); the median profile at the phases FINE;
    the median over strides of each stride's least-squares trend over the core (deg/s per s)."""
    core_values = per_stride(t, values, flats, CORE)
    core = core_values.mean(axis=1)
    span = (flats[:, 1] - flats[:, 0])[:, None] * (CORE - CORE.mean())[None, :]
    trend = np.einsum("kp,kpi->ki", span, core_values - core[:, None, :]) / np.sum(span**2, axis=1)[:, None]
    med = np.median(core, axis=0)
    return {"core_median_dps": np.degrees(med).round(2).tolist(),
            "core_mad_dps": np.degrees(np.median(np.abs(core - med), axis=0)).round(2).tolist(),
            "strides": int(len(core)),
            "fine_profile_dps": {f"{u:.1f}": np.degrees(p).round(2).tolist()
                                 for u, p in zip(FINE, np.median(per_stride(t, values, flats, FINE), axis=0))},
            "core_trend_dps2": np.degrees(np.median(trend, axis=0)).round(1).tolist(),
            "core_trend_mad_dps2": np.degrees(np.median(np.abs(trend - np.median(trend, 0)), axis=0)).round(1).tolist()}


def filled_markers(values: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(M, 3) m: a marker track with its dropouts (NaN rows) filled linearly, for filtering only."""
    ok = ~np.isnan(values).any(axis=1)
    return np.column_stack([np.interp(t, t[ok], values[ok, i]) for i in range(3)])


def gaitmap_feet():
    """Per gaitmap foot: (side, recording, Vicon pose on the IMU clock, mocap clock (M,) s, its three markers)."""
    t_mocap, markers, _ = read_markers(DATA)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        recs = dict(load_recordings("gaitmap-healthy", DATA))
        poses = {side: gaitmap_foot_pose(side, DATA) for side in recs}
    for side, rec in recs.items():
        yield side, rec, poses[side], t_mocap, markers[side]


def vicon_rate_in_sensor_frame(side, rec, pose, t_mocap, marker_set, cutoff_hz: float) -> np.ndarray:
    """(N, 3) rad/s: the Vicon three-marker body's angular rate (markers low-passed at ``cutoff_hz``) on the IMU
    clock of ``rec``, in the sensor frame (``pose.mount_rotation``); NaN outside the mocap take."""
    filled = {k: filled_markers(v, t_mocap) for k, v in marker_set.items()}
    _, rotation = mocap.marker_frame(filled["FCC"], filled["TOE"], filled["FM5"], side)
    kin = mocap.body_kinematics(np.zeros((len(t_mocap), 3)), rotation, MOCAP_RATE_HZ, cutoff_hz)
    t = np.asarray(rec.t, float)
    inside = (t + pose.clock_offset > t_mocap[0]) & (t + pose.clock_offset < t_mocap[-1])
    foot_in_sensor = np.full((len(t), 3), np.nan)
    foot_in_sensor[inside] = CubicSpline(t_mocap, kin.rate_body)(t[inside] + pose.clock_offset) @ pose.mount_rotation
    return foot_in_sensor


def gaitmap_rates(cutoff_hz: float = CUTOFF_HZ) -> dict:
    """Per gaitmap foot: :func:`summary` of the raw and the low-passed gyro, of the Vicon body's rate in the
    sensor frame and of their difference (out of foot), both low-passed at ``cutoff_hz``; and each stride's core
    mean of the Vicon rate and of the difference ("strides": (K, 3) rad/s each, in stride order)."""
    out = {}
    for side, rec, pose, t_mocap, marker_set in gaitmap_feet():
        t = np.asarray(rec.t, float)
        foot_in_sensor = vicon_rate_in_sensor_frame(side, rec, pose, t_mocap, marker_set, cutoff_hz)
        inside = np.all(np.isfinite(foot_in_sensor), axis=1)
        gyr = mocap.lowpass(rec.gyr, cutoff_hz, IMU_RATE_HZ)
        flats = foot_flats(rec)
        flats = flats[(flats[:, 0] > t[inside][0]) & (flats[:, 1] < t[inside][-1])]
        ok = np.all(np.isfinite(foot_in_sensor), 1)
        tt = t[ok]
        out[side] = {
            "imu_raw": summary(t, rec.gyr, flats),
            "imu_lowpassed": summary(tt, gyr[ok], flats),
            "vicon_foot_in_sensor_frame": summary(tt, foot_in_sensor[ok], flats),
            "out_of_foot": summary(tt, gyr[ok] - foot_in_sensor[ok], flats),
            "foot_flat_s": float(np.median(flats[:, 1] - flats[:, 0])),
            "strides": {"out_of_foot": per_stride(tt, gyr[ok] - foot_in_sensor[ok], flats, CORE).mean(axis=1),
                        "vicon_foot": per_stride(tt, foot_in_sensor[ok], flats, CORE).mean(axis=1)},
        }
    return out


def ucr_rates() -> dict:
    """Per ucr-fgo foot: :func:`summary` of the gyro (no pose to compare with)."""
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        recs = dict(load_recordings("ucr-fgo", DATA))
    for side, rec in recs.items():
        t = np.asarray(rec.t, float)
        flats = foot_flats(rec)
        out[side] = {"imu_raw": summary(t, rec.gyr, flats), "foot_flat_s": float(np.median(flats[:, 1] - flats[:, 0]))}
    return out


if __name__ == "__main__":
    cutoffs = [float(c) for c in sys.argv[1:]] or [CUTOFF_HZ, 12.0]
    result = {f"gaitmap_cutoff_{c:g}Hz": {side: {k: v for k, v in foot.items() if k != "strides"}
                                          for side, foot in gaitmap_rates(c).items()} for c in cutoffs}
    result["ucr"] = ucr_rates()
    print(json.dumps(result, indent=1))
