"""Where the length underestimate is made: results/stance/findings.md, "Where the filter loses the length".

Per stride (consecutive detected-stance middles, as in `gaitsim stance`), the estimated horizontal displacement
minus the reference's splits exactly into two parts:

- the **velocity integral**: the trapezoid integral of the filter's velocity over the stride minus the reference
  length (what the strapdown velocity, corrected at each update, carries);
- the **position corrections**: the displacement minus that integral (what the zero-velocity updates move the
  position by, through the position-velocity covariance, beyond the velocity they correct),

both along the stride's estimated direction. Also printed: the mean velocity of the filter, forward along the
stride and up, at the last sample before each detected stance (the strapdown's velocity the first update sees),
and the reference's there. The recording is compared with its stance twin (:mod:`gaitsim.stance.twin`: the
recording's gait, rate and IMU site, the default stance model) read by the ideal sensor and by the calibrated
sensor of the recording's class, all integrated from point samples (RK4) at SHOE thresholds 1e4, 3e4 and 5e4.

A second table follows each recording's velocity error (filter minus reference, forward along the stride and up,
mean over strides), the norm of the specific force and the rate about y (medians) over the 200 ms before each
stance's first detected sample and 30 ms into it, at SHOE 3e4: when the error the first update sees arose.

Run from the repository root (it reads ../shared/data; ~20 s)::

    python3 -m studies.underestimate_split
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import CubicSpline

from gaitsim.stance.command import DATASETS, SENSORS, SITES, load_recordings
from gaitsim.stance.events import group_stances
from gaitsim.stance.sweep import nav_options
from gaitsim.stance.twin import TwinSpec, match_timing, measure_gait, simulate_sensed_and_ideal
from nav import pipeline

THRESHOLDS = (1e4, 3e4, 5e4)
ONSET_GRID_S = np.arange(-0.20, 0.031, 0.01)  # s from each stance's first detected sample
STRIDE_M = (0.3, 3.0)  # m, strides outside are not scored (turns, the walk's ends)


def _strides(rec, track_t: np.ndarray, track_pos: np.ndarray, threshold: float):
    """The track as a spline, the solution, the sample times and, per scored stride, (middle, next middle, first
    sample of the next stance, reference length m)."""
    ok = np.all(np.isfinite(track_pos), axis=1)
    track = CubicSpline(track_t[ok], track_pos[ok])
    sol = pipeline.navigate(rec, nav_options(threshold, method="rk4"))
    t = np.asarray(rec.t)
    stationary = np.asarray(sol.stationary, bool).copy()
    stationary[:sol.start] = False
    stances = group_stances(t, stationary)
    middles = stances.middles()
    strides = []
    for (m0, m1), (first, _) in zip(zip(middles[:-1], middles[1:]), stances.bounds[1:]):
        if t[m0] < track_t[ok][0] or t[m1] > track_t[ok][-1]:
            continue
        reference = np.linalg.norm(track(t[m1])[:2] - track(t[m0])[:2])
        if STRIDE_M[0] < reference < STRIDE_M[1]:
            strides.append((m0, m1, first, reference))
    return track, sol, t, strides


def onset_profile(rec, track_t: np.ndarray, track_pos: np.ndarray, threshold: float) -> np.ndarray:
    """(4, G): mean forward and up velocity error (m/s), median |f| (m/s^2) and median rate about y (deg/s) on
    :data:`ONSET_GRID_S` around each stance's first detected sample."""
    track, sol, t, strides = _strides(rec, track_t, track_pos, threshold)
    rows = []
    for m0, m1, first, _ in strides:
        moved = sol.pos[m1, :2] - sol.pos[m0, :2]
        along, true_along = moved / np.linalg.norm(moved), track(t[m1])[:2] - track(t[m0])[:2]
        true_along = true_along / np.linalg.norm(true_along)
        times = t[first] + ONSET_GRID_S
        vel = np.stack([np.interp(times, t, sol.vel[:, i]) for i in range(3)], -1)
        ref = track(times, 1)
        rows.append([vel[:, :2] @ along - ref[:, :2] @ true_along, vel[:, 2] - ref[:, 2],
                     np.interp(times, t, np.linalg.norm(rec.acc, axis=1)),
                     np.interp(times, t, np.degrees(rec.gyr[:, 1]))])
    rows = np.array(rows)
    return np.stack([rows[:, 0].mean(0), rows[:, 1].mean(0), np.median(rows[:, 2], 0), np.median(rows[:, 3], 0)])


def split(rec, track_t: np.ndarray, track_pos: np.ndarray, threshold: float) -> dict:
    """Length error (% of the reference length) = velocity integral + position corrections, and the mean forward
    and up velocities (mm/s) of the filter and of the reference at the sample before each detected stance."""
    track, sol, t, strides = _strides(rec, track_t, track_pos, threshold)
    rows = []
    for m0, m1, first, reference in strides:
        moved = sol.pos[m1, :2] - sol.pos[m0, :2]
        along = moved / np.linalg.norm(moved)
        integral = np.trapezoid(sol.vel[m0:m1 + 1, :2], t[m0:m1 + 1], axis=0)
        onset = first - 1
        reference_velocity = track(t[onset], 1)
        rows.append([np.linalg.norm(moved) - reference, integral @ along - reference, (moved - integral) @ along,
                     reference, sol.vel[onset, :2] @ along, sol.vel[onset, 2], reference_velocity[:2] @ along,
                     reference_velocity[2]])
    r = np.array(rows)
    total = r[:, 3].sum()
    return {"strides": len(r), "error_pct": 100 * r[:, 0].sum() / total, "integral_pct": 100 * r[:, 1].sum() / total,
            "corrections_pct": 100 * r[:, 2].sum() / total, "onset_forward_mmps": 1000 * r[:, 4].mean(),
            "onset_up_mmps": 1000 * r[:, 5].mean(), "reference_forward_mmps": 1000 * r[:, 6].mean(),
            "reference_up_mmps": 1000 * r[:, 7].mean()}


def main() -> None:
    print("| recording | path | SHOE | strides | length error (%) = velocity integral + position corrections | "
          "onset forward / up, filter (mm/s) | the reference there |")
    print("|---|---|---|---|---|---|---|")
    for dataset in DATASETS:
        for name, rec in load_recordings(dataset):
            ref = rec.reference
            gait = measure_gait(rec, ref.t, ref.pos)
            doc = match_timing(gait, TwinSpec(mount=SITES[dataset][0], micromotion={"foot": name},
                                              sensor=SENSORS[dataset]))
            sensed, ideal = simulate_sensed_and_ideal(doc)
            paths = {"recording": (rec, ref.t, ref.pos), "twin, ideal sensor": (ideal, ideal.truth.t, ideal.truth.pos),
                     "twin, its class's sensor": (sensed, sensed.truth.t, sensed.truth.pos)}
            for label, (r, track_t, track_pos) in paths.items():
                for threshold in THRESHOLDS:
                    s = split(r, track_t, track_pos, threshold)
                    print(f"| {dataset}/{name} | {label} | {threshold:.0e} | {s['strides']} | {s['error_pct']:+.2f} = "
                          f"{s['integral_pct']:+.2f} + {s['corrections_pct']:+.2f} | {s['onset_forward_mmps']:+.0f} / "
                          f"{s['onset_up_mmps']:+.0f} | {s['reference_forward_mmps']:+.0f} / "
                          f"{s['reference_up_mmps']:+.0f} |")


def onset_tables() -> None:
    print("\n| recording | row | " + " | ".join(f"{1000 * x:.0f}" for x in ONSET_GRID_S) + " |")
    print("|---|---|" + "---|" * len(ONSET_GRID_S))
    for dataset in DATASETS:
        for name, rec in load_recordings(dataset):
            forward, up, force, rate = onset_profile(rec, rec.reference.t, rec.reference.pos, 3e4)
            for label, row, scale in (("forward error (mm/s)", forward, 1000), ("up error (mm/s)", up, 1000),
                                      ("specific force norm (m/s^2)", force, 1), ("rate about y (deg/s)", rate, 1)):
                print(f"| {dataset}/{name} | {label} | " + " | ".join(f"{scale * x:.0f}" for x in row) + " |")


if __name__ == "__main__":
    main()
    onset_tables()
