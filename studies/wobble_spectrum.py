"""Step 1 of the wobble study: the stride-to-stride rate wobble of a real foot flat, as a model would need it.

Foot flats are the stance study's (:func:`studies.mount_rate.foot_flats`, FF to HO), mapped onto the phase u in
[0, 1]. The wobble of a stride is its gyro over the foot flat less the recording's median profile over strides at
the same phase (the part every stride shares, which a stance model describes), less the least-squares line of
what remains (its slow drift). Per axis, in the sensor frame and in the foot-flat frame (z along the foot-flat
specific force, y along the swing's principal rotation axis, x = y cross z: the twin's foot axes when its foot is
flat; the signs are immaterial here), reported:

- ``rms_dps``: rms over the foot-flat core (u 0.1..0.9, all strides pooled);
- ``envelope_dps``: rms in ten phase bins of 0.1 (loading tail u < 0.1, core, heel-off u > 0.9);
- ``psd``: the mean over strides of the Hann-tapered periodogram on a common grid (``NFFT`` points), normalised to
  unit sum; ``f50_hz`` / ``f90_hz``: the frequencies below which 50 / 90 % of that power lies.

On gaitmap, whose reference track is the sensor's own point, the same recipe gives the wobble of that point's
velocity (``site_velocity_rms_mmps``; at rest ``site_velocity_rest_rms_mmps``): a foot rotation w about a
contact r away would show there as w x r: ``contact`` regresses the one on the other (6 Hz). The
same recipe also runs on the Vicon body's rate in the sensor frame and on the IMU low-passed with it
(6 and 12 Hz): if the foot moved, the marker body would show the IMU's wobble (``vicon_rms_dps``) and correlate
with it (``correlation``, pooled over the core), and the IMU's wobble less the Vicon's (``difference_rms_dps``)
would be the sensor's own; the Vicon's noise at rest is ``vicon_rest_rms_dps``.

``python3 -m studies.wobble_spectrum > wobble.json`` from the repository root (reads ../shared/data).
"""

from __future__ import annotations

import json
import warnings

import numpy as np

from nav import quaternion as quat
from gaitsim.measured import mocap
from gaitsim.measured.gaitmap import IMU_RATE_HZ
from gaitsim.stance.command import load_recordings
from gaitsim.stance.profiles import site_velocity

from .mount_markers import still_noise
from .mount_rate import DATA, foot_flats, gaitmap_feet, vicon_rate_in_sensor_frame

NFFT = 256  # points of the common periodogram grid
PROFILE = np.linspace(0.0, 1.0, 101)  # foot-flat phases of the median profile
BINS = np.linspace(0.0, 1.0, 11)  # foot-flat phase bins of the envelope
CORE = (0.1, 0.9)
VICON_CUTOFFS_HZ = (6.0, 12.0)
REST_DPS = 2.0  # deg/s, abs(w) of a still stretch


def foot_flat_frame(rec, flats: np.ndarray) -> np.ndarray:
    """(3, 3) sensor -> foot-flat frame (module docstring), rows the foot axes in sensor coordinates."""
    t = np.asarray(rec.t, float)
    flat = np.zeros(len(t), bool)
    for t_ff, t_ho in flats:
        flat |= (t >= t_ff) & (t < t_ho)
    z = rec.acc[flat].mean(axis=0)
    z /= np.linalg.norm(z)
    swing = rec.gyr[~flat]
    y = np.linalg.eigh(swing.T @ swing)[1][:, -1]
    y -= np.dot(y, z) * z
    y /= np.linalg.norm(y)
    return np.stack([np.cross(y, z), y, z])


def residuals(t: np.ndarray, gyr: np.ndarray, flats: np.ndarray) -> list:
    """Per stride (u (n,), wobble (n, 3) rad/s) over its foot flat (module docstring); strides with a NaN
    sample are left out."""
    strides = []
    for t_ff, t_ho in flats:
        sel = (t >= t_ff) & (t <= t_ho)
        if np.isnan(gyr[sel]).any():
            continue
        strides.append(((t[sel] - t_ff) / (t_ho - t_ff), gyr[sel]))
    profile = np.median([np.stack([np.interp(PROFILE, u, g[:, i]) for i in range(3)], -1) for u, g in strides],
                        axis=0)
    out = []
    for u, g in strides:
        r = g - np.stack([np.interp(u, PROFILE, profile[:, i]) for i in range(3)], -1)
        line = np.polynomial.polynomial.polyfit(u, r, 1)
        out.append((u, r - np.polynomial.polynomial.polyval(u, line).T))
    return out


def psd(strides: list, rate_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """(frequencies (F,) Hz, PSD shape (F, 3) with unit sum per axis): mean Hann periodogram of the wobbles."""
    power = [np.abs(np.fft.rfft(r * np.hanning(len(r))[:, None], NFFT, axis=0)) ** 2 for _, r in strides]
    shape = np.mean(power, axis=0)
    return np.fft.rfftfreq(NFFT, 1.0 / rate_hz), shape / shape.sum(axis=0)


def band(freq: np.ndarray, shape: np.ndarray, share: float) -> list:
    """Hz per axis: the lowest frequency below which ``share`` of the PSD shape lies."""
    cumulative = np.cumsum(shape, axis=0)
    return [float(freq[np.searchsorted(cumulative[:, i], share)]) for i in range(shape.shape[1])]


def pooled_rms(strides: list, lo: float, hi: float) -> np.ndarray:
    """(3,) rad/s: rms of the wobbles over phases lo <= u < hi, all strides pooled."""
    r = np.concatenate([r[(u >= lo) & (u < hi)] for u, r in strides])
    return np.sqrt(np.mean(r**2, axis=0))


def describe(t: np.ndarray, gyr: np.ndarray, flats: np.ndarray, rate_hz: float) -> dict:
    """The wobble of ``gyr`` (N, 3) rad/s over the foot flats ``flats`` (K, 2) s (module docstring)."""
    strides = residuals(t, gyr, flats)
    freq, shape = psd(strides, rate_hz)
    return {"strides": len(strides), "rms_dps": np.degrees(pooled_rms(strides, *CORE)).round(2).tolist(),
            "envelope_dps": np.degrees([pooled_rms(strides, a, b)
                                        for a, b in zip(BINS[:-1], BINS[1:])]).round(2).tolist(),
            "f50_hz": band(freq, shape, 0.5), "f90_hz": band(freq, shape, 0.9),
            "psd_freq_hz": freq.tolist(), "psd": shape.tolist()}


def measure(rec, track_t: np.ndarray | None = None, track_pos: np.ndarray | None = None) -> dict:
    """The wobble of one recording in the sensor and the foot-flat frame (foot flats: the stance study's); with
    the sensor point's track (t (M,) s, pos (M, 3) m, world), also the rms of its velocity's wobble over the core
    (``site_velocity_rms_mmps``, world axes, :func:`gaitsim.stance.profiles.site_velocity`)."""
    t = np.asarray(rec.t, float)
    flats = foot_flats(rec)
    frame = foot_flat_frame(rec, flats)
    rate_hz = 1.0 / np.median(np.diff(t))
    out = {"foot_flat_s": float(np.median(flats[:, 1] - flats[:, 0])), "rate_hz": float(rate_hz),
           "foot_flat_frame": frame.round(3).tolist(),
           "sensor": describe(t, rec.gyr, flats, rate_hz), "foot": describe(t, rec.gyr @ frame.T, flats, rate_hz)}
    if track_t is not None:
        velocity = site_velocity(track_t, track_pos)
        on_imu = np.stack([np.interp(t, track_t, velocity[:, i], left=np.nan, right=np.nan) for i in range(3)], -1)
        inside = np.all(np.isfinite(on_imu), axis=1)
        flats = flats[(flats[:, 0] > t[inside][0]) & (flats[:, 1] < t[inside][-1])]
        out["site_velocity_rms_mmps"] = (1e3 * pooled_rms(residuals(t, on_imu, flats), *CORE)).round(2).tolist()
        out["site_velocity_rest_rms_mmps"] = site_velocity_at_rest(t, rec.gyr, track_t, track_pos)
    return out


def site_velocity_at_rest(t: np.ndarray, gyr: np.ndarray, track_t: np.ndarray, track_pos: np.ndarray) -> list:
    """mm/s per world axis: rms of the reference site velocity about its mean in the recording's (clock ``t``
    (N,) s, gyro ``gyr`` (N, 3) rad/s) longest stretch with abs(w) below ``REST_DPS`` (0.05 s trimmed at both
    ends): the track's noise floor."""
    velocity = site_velocity(track_t, track_pos)
    still = np.interp(track_t, t, np.degrees(np.linalg.norm(gyr, axis=1))) < REST_DPS
    edges = np.flatnonzero(np.diff(np.r_[0, still.astype(int), 0]))
    a, b = max(zip(edges[::2], edges[1::2]), key=lambda run: run[1] - run[0])
    trim = np.searchsorted(track_t, track_t[a] + 0.05) - a
    seg = velocity[a + trim:b - trim]
    return (1e3 * np.sqrt(np.mean((seg - seg.mean(axis=0)) ** 2, axis=0))).round(2).tolist()


def correlation(a: list, b: list) -> list:
    """Per axis, the correlation of two wobbles over the core, all strides pooled."""
    pick = [np.concatenate([r[(u >= CORE[0]) & (u < CORE[1])] for u, r in s]) for s in (a, b)]
    return [round(float(np.corrcoef(pick[0][:, i], pick[1][:, i])[0, 1]), 2) for i in range(3)]


def _skew(a: np.ndarray) -> np.ndarray:
    """(n, 3, 3): the cross-product matrices of ``a`` (n, 3)."""
    z = np.zeros(len(a))
    return np.stack([np.stack([z, -a[:, 2], a[:, 1]], -1), np.stack([a[:, 2], z, -a[:, 0]], -1),
                     np.stack([-a[:, 1], a[:, 0], z], -1)], 1)


def contact_lever(rec, pose, vicon: np.ndarray) -> dict:
    """Gaitmap: the lever r (m) from a fixed contact to the sensor point that best explains the wobble of the
    point's velocity as the Vicon body's rate wobble ``vicon`` (N, 3) rad/s (sensor frame) cross r, least
    squares over the core of every foot flat; r in the sensor and in the marker frame, and the velocity wobble's
    rms (mm/s, sensor frame) explained by it and left over."""
    n = len(pose.t)
    t = np.asarray(rec.t, float)[:n]
    ok = np.all(np.isfinite(vicon[:n]), axis=1) & np.all(np.isfinite(pose.sensor_quat), axis=1)
    velocity = np.full((n, 3), np.nan)
    velocity[ok] = np.einsum("nji,nj->ni", quat.to_matrix(pose.sensor_quat[ok]),
                             site_velocity(rec.reference.t, rec.reference.pos)[:n][ok])
    flats = foot_flats(rec)
    flats = flats[(flats[:, 0] > t[ok][0]) & (flats[:, 1] < t[ok][-1])]
    core = [np.concatenate([r[(u >= CORE[0]) & (u < CORE[1])] for u, r in residuals(t, x, flats)])
            for x in (vicon[:n], velocity)]
    lever = np.linalg.lstsq(_skew(core[0]).reshape(-1, 3), core[1].reshape(-1), rcond=None)[0]
    explained = np.einsum("nij,j->ni", _skew(core[0]), lever)
    return {"lever_sensor_m": lever.round(3).tolist(),
            "lever_marker_m": (pose.mount_rotation @ lever).round(3).tolist(),
            "site_velocity_rms_mmps": (1e3 * np.sqrt(np.mean(core[1] ** 2, 0))).round(1).tolist(),
            "explained_rms_mmps": (1e3 * np.sqrt(np.mean(explained ** 2, 0))).round(1).tolist(),
            "left_over_rms_mmps": (1e3 * np.sqrt(np.mean((core[1] - explained) ** 2, 0))).round(1).tolist()}


def vicon_check(side, rec, pose, t_mocap, marker_set) -> dict:
    """Gaitmap: the wobble of the IMU and of the Vicon body (sensor frame) at the same low-pass, their
    correlation, the Vicon's rms at rest, per cutoff (module docstring)."""
    t = np.asarray(rec.t, float)
    out = {}
    for cutoff in VICON_CUTOFFS_HZ:
        vicon = vicon_rate_in_sensor_frame(side, rec, pose, t_mocap, marker_set, cutoff)
        flats = foot_flats(rec)
        inside = np.all(np.isfinite(vicon), axis=1)
        flats = flats[(flats[:, 0] > t[inside][0]) & (flats[:, 1] < t[inside][-1])]
        imu = residuals(t, mocap.lowpass(rec.gyr, cutoff, IMU_RATE_HZ), flats)
        foot = residuals(t, vicon, flats)
        out[f"{cutoff:g}Hz"] = {
            "imu_rms_dps": np.degrees(pooled_rms(imu, *CORE)).round(2).tolist(),
            "vicon_rms_dps": np.degrees(pooled_rms(foot, *CORE)).round(2).tolist(),
            "correlation": correlation(imu, foot),
            "difference_rms_dps": np.degrees(pooled_rms([(u, a - b) for (u, a), (_, b) in zip(imu, foot)],
                                                        *CORE)).round(2).tolist(),
            "vicon_rest_rms_dps": still_noise(t_mocap, marker_set, side, cutoff).round(2).tolist()}
        if cutoff == VICON_CUTOFFS_HZ[0]:
            out["contact"] = contact_lever(rec, pose, vicon)
    return out


def main() -> dict:
    result = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for side, rec, pose, t_mocap, marker_set in gaitmap_feet():
            result[f"gaitmap-healthy/{side}"] = {**measure(rec, rec.reference.t, rec.reference.pos),
                                                 "vicon": vicon_check(side, rec, pose, t_mocap, marker_set)}
        for side, rec in load_recordings("ucr-fgo", DATA):
            result[f"ucr-fgo/{side}"] = measure(rec)
    return result


if __name__ == "__main__":
    print(json.dumps(main(), indent=1))
