"""Is gaitmap's Vicon foot-flat roll motion, and is the sensor's z rate a twist of the marker triangle?

``python3 -m studies.mount_markers``: per foot, the marker body's angular rate (rms per axis, deg/s, low-passed
6 and 12 Hz) in the longest still stretch of the walk (its noise floor), and over the core of every foot flat
(phases 0.2 to 0.8, the stance study's events on the mocap clock) the change of the three side lengths and the
rise of FM5 against the heel-toe line (mm), median and median absolute deviation over strides.
"""

from __future__ import annotations

import numpy as np

from gaitsim.measured import mocap
from gaitsim.measured.gaitmap import MOCAP_RATE_HZ

from .mount_rate import filled_markers, foot_flats, gaitmap_feet

STILL_DPS = 3.0  # deg/s, a still stretch's marker-body rate
SIDES = {"FCC-TOE": ("FCC", "TOE"), "FCC-FM5": ("FCC", "FM5"), "TOE-FM5": ("TOE", "FM5")}


def still_noise(t: np.ndarray, marker_set: dict, side: str, cutoff_hz: float) -> np.ndarray:
    """(3,) deg/s rms of the marker body's rate in its longest still stretch (0.2 s trimmed at both ends)."""
    filled = {k: filled_markers(v, t) for k, v in marker_set.items()}
    _, rotation = mocap.marker_frame(filled["FCC"], filled["TOE"], filled["FM5"], side)
    rate = mocap.body_kinematics(np.zeros((len(t), 3)), rotation, MOCAP_RATE_HZ, cutoff_hz).rate_body
    still = np.degrees(np.linalg.norm(rate, axis=1)) < STILL_DPS
    edges = np.flatnonzero(np.diff(np.r_[0, still.astype(int), 0]))
    a, b = max(zip(edges[::2], edges[1::2]), key=lambda run: run[1] - run[0])
    trim = int(0.2 * MOCAP_RATE_HZ)
    return np.degrees(np.sqrt(np.mean(rate[a + trim:b - trim] ** 2, axis=0)))


def core_changes(t: np.ndarray, marker_set: dict, flats: np.ndarray, clock_offset: float) -> dict:
    """mm: per stride, side-length changes and FM5's rise against the heel-toe line over the core."""
    out = {name: [] for name in [*SIDES, "FM5_rise"]}

    def fm5_off_line(k):
        heel, toe, fm5 = (marker_set[name][k] for name in ("FCC", "TOE", "FM5"))
        along = np.dot(fm5 - heel, toe - heel) / np.dot(toe - heel, toe - heel)
        return (fm5 - heel - along * (toe - heel))[2]

    for t_ff, t_ho in flats:
        d = t_ho - t_ff
        i, j = np.searchsorted(t, [t_ff + 0.2 * d + clock_offset, t_ff + 0.8 * d + clock_offset])
        if j >= len(t) or np.isnan([marker_set[name][[i, j]] for name in marker_set]).any():
            continue
        for name, (p, q) in SIDES.items():
            length = np.linalg.norm(marker_set[p][[i, j]] - marker_set[q][[i, j]], axis=1)
            out[name].append(1000 * (length[1] - length[0]))
        out["FM5_rise"].append(1000 * (fm5_off_line(j) - fm5_off_line(i)))
    return {name: (round(float(np.median(v)), 2), round(float(np.median(np.abs(np.subtract(v, np.median(v))))), 2),
                   len(v)) for name, v in out.items()}


if __name__ == "__main__":
    for side, rec, pose, t_mocap, marker_set in gaitmap_feet():
        for cutoff in (6.0, 12.0):
            print(side, f"still marker-body rate rms at {cutoff:g} Hz (deg/s)",
                  still_noise(t_mocap, marker_set, side, cutoff).round(2).tolist())
        print(side, "core changes (median mm, MAD mm, strides)",
              core_changes(t_mocap, marker_set, foot_flats(rec), pose.clock_offset))
