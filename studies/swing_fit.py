"""The walking swing's translation fitted to tracked feet: results/stance/findings.md, "The swing".

gaitmap-healthy's Vicon gives the IMU site's track at 100 Hz (both feet, 109-110 steps/min). Each foot's twin is
the one `gaitsim loop` fitted (results/loop/gaitmap-healthy/<foot>/twin.toml: the recording's gait, pitch fitted
to the gyro, mount) without its sensor. Per stride, the IMU site's horizontal speed, its specific force along x
and z and its rate about y are taken around the gyro's reversal after the push-off (the rate about y falling
through zero within 0.1 s of exceeding 200 deg/s: the toes leaving, a sharp event that the swing's translation
does not move), and their medians over strides are compared on a 10 ms grid from 0.25 s before to 0.45 s after.

Fitted: the toe release's acceleration at toe off (``toe_release_accel_mps2``, over ``toe_release_s`` fixed at
:data:`RELEASE_S`) alone, then with the swing lead (``swing_lead``, three values), by least squares on the twin's
minus the recording's median profiles of the feet fitted on: the speed (m/s, the Vicon's) and the specific force
along x and z (the IMU's, in units of :data:`ACC_UNIT`: 1 m/s gained in 0.1 s), which the rate about y does not
see. Printed: the fit on each foot and on both, and the rms misfit of speed (m/s), acc x and z (m/s^2) and gyro y
(deg/s, which the translation leaves alone) of the twin without and with each fit on each foot (a foot not
fitted on is held out). The walking kind's release (:data:`gaitsim.world.gaits.SWING_TOE_RELEASE`) is the
both-feet fit of the release alone.

Run from the repository root (it reads ../shared/data and results/loop; ~1 min)::

    python3 -m studies.swing_fit
"""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.optimize import least_squares

from gaitsim.scenario import scenario_from_dict
from gaitsim.simulate import sense, simulate_world
from gaitsim.stance.command import load_recordings

RELEASE_S = 0.04  # s
GRID = np.arange(-0.25, 0.45, 0.01)  # s from the gyro reversal
REVERSAL_FROM_DPS = 200.0  # deg/s, push-off rate the reversal must follow within REVERSAL_WINDOW_S
REVERSAL_WINDOW_S = 0.1
MIN_STRIDE_S = 0.6  # s between reversals
CHANNELS = ("speed (m/s)", "gyro y (deg/s)", "acc x (m/s^2)", "acc z (m/s^2)")
FITTED = (0, 2, 3)  # rows of CHANNELS in the fit
ACC_UNIT = 10.0  # m/s^2 weighing as 1 m/s in the fit
TWINS = Path("results/loop/gaitmap-healthy")


def profiles(t: np.ndarray, pos: np.ndarray, acc: np.ndarray, gyr: np.ndarray) -> np.ndarray:
    """(4, G) medians over strides of the channels :data:`CHANNELS` around each gyro reversal, from a site track
    pos (N, 3) m and the IMU's acc (N, 3) m/s^2 and gyr (N, 3) rad/s at times t (N,) s."""
    speed = np.linalg.norm(np.gradient(pos[:, :2], t, axis=0), axis=1)
    rate = np.degrees(gyr[:, 1])
    rows, last = [], -np.inf
    for i in np.flatnonzero((rate[:-1] > 0) & (rate[1:] <= 0)):
        before = rate[np.searchsorted(t, t[i] - REVERSAL_WINDOW_S):i + 1]
        if before.max() < REVERSAL_FROM_DPS or t[i] - last < MIN_STRIDE_S:
            continue
        at = t[i] + rate[i] / (rate[i] - rate[i + 1]) * (t[i + 1] - t[i])
        if at + GRID[0] < t[0] or at + GRID[-1] > t[-1]:
            continue
        last = t[i]
        rows.append([np.interp(at + GRID, t, x) for x in (speed, rate, acc[:, 0], acc[:, 2])])
    return np.median(np.array(rows), axis=0)


def recording_profiles(rec) -> np.ndarray:
    """:func:`profiles` of a recording against its reference track, over the samples the track covers."""
    ref = rec.reference
    ok = np.all(np.isfinite(ref.pos), axis=1)
    t = np.asarray(rec.t)
    inside = (t > ref.t[ok][0]) & (t < ref.t[ok][-1])
    track = CubicSpline(ref.t[ok], ref.pos[ok])(t[inside])
    return profiles(t[inside], track, rec.acc[inside], rec.gyr[inside])


def twin_profiles(doc: dict, x) -> np.ndarray:
    """:func:`profiles` of the twin document ``doc`` (ideal sensor) with toe release and lead ``x`` (4,)."""
    doc = copy.deepcopy(doc)
    doc["gait"].update(toe_release_accel_mps2=float(x[0]), toe_release_s=RELEASE_S,
                       swing_lead=[float(v) for v in x[1:]])
    scenario = scenario_from_dict(doc, "<swing twin>")
    twin = sense(*simulate_world(scenario, 0), None, 0)
    return profiles(twin.truth.t, twin.truth.pos, twin.acc, twin.gyr)


def fit(targets: list[tuple[np.ndarray, dict]], lead: bool) -> np.ndarray:
    """Release (m/s^2) and lead (3,) fitting the twins' profiles to the recordings' (module docstring); the lead
    held at zero unless ``lead``."""
    weight = np.array([1.0, 1.0, 1.0 / ACC_UNIT, 1.0 / ACC_UNIT])[list(FITTED), None]

    def residual(x):
        full = np.r_[x, np.zeros(4 - len(x))]
        return np.concatenate([(weight * (twin_profiles(doc, full) - measured)[list(FITTED)]).ravel()
                               for measured, doc in targets])
    size = 4 if lead else 1
    found = least_squares(residual, [20.0, 0.0, 0.0, 0.0][:size], diff_step=1e-3,
                          bounds=([0.0, -0.3, -0.3, -0.3][:size], [300.0, 0.3, 0.3, 0.3][:size])).x
    return np.r_[found, np.zeros(4 - size)]


def main() -> None:
    recordings = dict(load_recordings("gaitmap-healthy"))
    feet = {}
    for foot in ("left", "right"):
        with open(TWINS / foot / "twin.toml", "rb") as f:
            doc = tomllib.load(f)
        doc.pop("sensor", None)
        feet[foot] = (recording_profiles(recordings[foot]), doc)
    folds = {"left": ("left",), "right": ("right",), "both": ("left", "right")}
    fits = {(name, lead): fit([feet[f] for f in fitted], lead) for lead in (False, True)
            for name, fitted in folds.items()}
    print(f"toe release over {RELEASE_S} s; rms misfit (twin - Vicon/IMU) per foot; * = fitted on that foot")
    print("| fit on | release (m/s^2) | lead at 25/50/75 % | foot | " + " | ".join(CHANNELS) + " |")
    print("|---|---|---|---|" + "---|" * len(CHANNELS))
    for (name, _), x in [(("none", False), np.zeros(4))] + list(fits.items()):
        for foot, (measured, doc) in feet.items():
            rms = np.sqrt(np.mean((twin_profiles(doc, x) - measured) ** 2, axis=1))
            mark = "*" if foot in folds.get(name, ()) else ""
            print(f"| {name} | {x[0]:.1f} | {', '.join(f'{v:+.3f}' for v in x[1:])} | {foot}{mark} | "
                  + " | ".join(f"{v:.2f}" for v in rms) + " |")


if __name__ == "__main__":
    main()
