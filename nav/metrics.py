"""Scores of a navigation solution against truth or a reference track, and summaries across runs.

Sign conventions (all lengths in m, horizontal unless stated):

- Along-track and perpendicular axes: the true start->end direction u (horizontal) and its left normal
  n = z x u. For a straight walk these are "along the path" and "to the left of it".
- ``along_track_error_m`` = true distance - estimated end projected on u: **positive = the estimate is too
  short** (the length underestimate the seed paper studies). ``along_track_error_pct`` is that in % of the true
  start->end distance; ``length_ratio`` = estimated along-track distance / true distance.
- ``perpendicular_error_m``: estimated end on n, minus the true end's (zero by construction): positive = left.
- ``final_error_m``: horizontal distance between the estimated and true end points (``final_error_3d_m`` in 3D).
- ``heading_drift_deg_per_s``: slope of a least-squares line through the heading error (estimate - truth,
  unwrapped; from the attitude when both attitudes are known, else from the direction of the track seen from
  its start, on points more than 2 m away, which is another quantity: -0.016 instead of -0.033 deg/s on the same
  run; ``heading_drift_source`` says which, and the fallback issues a :class:`HeadingDriftWarning`);
  ``heading_drift_deg_per_100m`` = slope * duration / path length * 100.
- ``track_heading_drift_deg_per_s``: the track-direction slope, always (NaN when no point is 2 m from the start).
- ``path_length_ratio``: horizontal path length of the estimate over the reference's, both sampled every
  ``PATH_SAMPLE_INTERVAL``; it includes the swing's sub-stride path detail (on gaitmap's walk it reads 1.09,
  1.05 and 0.99 at 0.05, 0.25 and 1 s sampling).
- ``stride_length_ratio`` (when the ZUPT flags are given): the sum of the estimate's horizontal
  stance-to-stance distances (between the middles of consecutive ZUPT windows) over the reference's between
  the same instants: the trajectory-length ratio the seed paper studies, free of sub-stride path detail.
- ``ate_m``: RMS horizontal position error after the stated alignment: "start" = none beyond the common
  start point (the filter starts at the true position); ``ate_se2_m`` after the least-squares rotation about z
  and horizontal translation (Kabsch/Umeyama, no scale).
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from .alignment import stationary_runs, yaw_of
from .series import resample

TRACK_DIRECTION_MIN_DISTANCE = 2.0  # m, points closer to the start give no usable track direction
LOOP_DISTANCE = 1.0  # m, below this start->end distance the along/perpendicular axes are undefined
PATH_SAMPLE_INTERVAL = 0.25  # s, spacing of the polyline used for path lengths


class HeadingDriftWarning(UserWarning):
    """The heading drift was measured from the track direction because an attitude was missing."""


def _path_length(t: np.ndarray, pos: np.ndarray) -> float:
    grid = np.arange(t[0], t[-1], PATH_SAMPLE_INTERVAL)
    grid = np.append(grid, t[-1])
    xy = resample(grid, t, pos[:, :2])
    return float(np.sum(np.linalg.norm(np.diff(xy, axis=0), axis=1)))


def finite_rows(a: np.ndarray) -> np.ndarray:
    """(N,) bool, the rows of a (N, k) array with every value finite (``np.all(np.isfinite(a), axis=1)``, column
    by column: a third of the time on (N, 3))."""
    return np.logical_and.reduce([np.isfinite(a[:, i]) for i in range(a.shape[1])])


def _wrap(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2 * np.pi) - np.pi


def end_point_errors(est_end: np.ndarray, true_start: np.ndarray, true_end: np.ndarray) -> dict:
    """Along-track, perpendicular and final errors of an end point (see the module docstring for signs).

    Parameters
    ----------
    est_end, true_start, true_end : (3,) m, world ENU.
    """
    est_end, true_start, true_end = (np.asarray(a, float) for a in (est_end, true_start, true_end))
    d_true = (true_end - true_start)[:2]
    distance = float(np.hypot(*d_true))
    out = {
        "distance_m": distance,
        "final_error_m": float(np.hypot(*(est_end - true_end)[:2])),
        "final_error_3d_m": float(np.linalg.norm(est_end - true_end)),
        "vertical_error_m": float(est_end[2] - true_end[2]),
    }
    if distance < LOOP_DISTANCE:
        out.update(along_track_error_m=math.nan, along_track_error_pct=math.nan, length_ratio=math.nan,
                   perpendicular_error_m=math.nan)
        return out
    u = d_true / distance
    normal = np.array([-u[1], u[0]])
    d_est = (est_end - true_start)[:2]
    along = float(d_est @ u)
    out.update(
        along_track_error_m=distance - along,
        along_track_error_pct=100.0 * (distance - along) / distance,
        length_ratio=along / distance,
        perpendicular_error_m=float(d_est @ normal),
    )
    return out


def heading_drift(t: np.ndarray, heading_error: np.ndarray) -> float:
    """Slope (rad/s) of a least-squares line through an unwrapped heading error (rad) over time (s)."""
    ok = np.isfinite(heading_error)
    if ok.sum() < 2:
        return math.nan
    e = np.unwrap(heading_error[ok])
    return float(np.polyfit(t[ok], e, 1)[0])


def track_heading_error(est_pos: np.ndarray, true_pos: np.ndarray) -> np.ndarray:
    """Angle (rad) from the true to the estimated track direction seen from the common start; NaN near it."""
    d_true = true_pos[:, :2] - true_pos[0, :2]
    d_est = est_pos[:, :2] - true_pos[0, :2]
    err = _wrap(np.arctan2(d_est[:, 1], d_est[:, 0]) - np.arctan2(d_true[:, 1], d_true[:, 0]))
    far = np.hypot(d_true[:, 0], d_true[:, 1]) > TRACK_DIRECTION_MIN_DISTANCE
    return np.where(far, err, np.nan)


def se2_aligned(est_xy: np.ndarray, true_xy: np.ndarray) -> np.ndarray:
    """est_xy (M, 2) rotated and translated to fit true_xy (M, 2) in the least-squares sense (no scale)."""
    me, mt = est_xy.mean(axis=0), true_xy.mean(axis=0)
    h = (est_xy - me).T @ (true_xy - mt)
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(vt.T @ u.T))
    r = vt.T @ np.diag([1.0, d]) @ u.T
    return (est_xy - me) @ r.T + mt


def confusion(detected: np.ndarray, true_stance: np.ndarray) -> dict:
    """Detector confusion counts and rates against true stance labels (both (N,) bool)."""
    d = np.asarray(detected, bool)
    s = np.asarray(true_stance, bool)
    tp, fp = int(np.sum(d & s)), int(np.sum(d & ~s))
    fn, tn = int(np.sum(~d & s)), int(np.sum(~d & ~s))
    return {
        "true_positive": tp, "false_positive": fp, "false_negative": fn, "true_negative": tn,
        "precision": tp / (tp + fp) if tp + fp else math.nan,
        "recall": tp / (tp + fn) if tp + fn else math.nan,
        "accuracy": (tp + tn) / len(d) if len(d) else math.nan,
    }


def stance_match(detected: np.ndarray, true_stance: np.ndarray) -> dict:
    """Detected stationary runs matched to true stances, as counts of runs (not samples).

    A true stance is a run of True in ``true_stance``; a detected run is a run of True in ``detected``.

    Returns
    -------
    dict with ``true_stances``; ``detected_runs``; ``found`` (true stances with at least one detected sample);
    ``missed`` (true stances with none); ``found_fraction`` = found / true_stances; ``merged`` (detected runs
    touching two or more true stances: the swing between them was never seen, a stride is lost);
    ``spurious`` (detected runs touching no true stance: a zero-velocity update while the foot moves);
    ``split`` (true stances touched by two or more detected runs; harmless to the filter, reported for the
    reader).
    """
    d = np.asarray(detected, bool)
    s = np.asarray(true_stance, bool)
    if d.shape != s.shape or d.ndim != 1:
        raise ValueError(f"stance_match: detected {d.shape} and true_stance {s.shape} must be equal 1-D shapes")
    true_starts, _ = stationary_runs(s)
    first = np.zeros(len(s), int)
    first[true_starts] = 1
    stance_id = np.where(s, np.cumsum(first), 0)  # 1, 2, ... inside the true stances, 0 outside
    starts, _ = stationary_runs(d)
    if len(starts):
        # reduceat reaches to the next run's start; samples between runs are not detected and are masked out
        highest = np.maximum.reduceat(np.where(d, stance_id, 0), starts)
        lowest = np.minimum.reduceat(np.where(d & (stance_id > 0), stance_id, len(s) + 1), starts)
        touched = np.where(highest > 0, highest - lowest + 1, 0)
    else:
        touched = np.zeros(0, int)
    overlap_starts, _ = stationary_runs(d & s)
    runs_per_stance = np.bincount(stance_id[overlap_starts], minlength=len(true_starts) + 1)[1:]
    found = int(np.sum(runs_per_stance > 0))
    n_true = len(true_starts)
    return {
        "true_stances": n_true, "detected_runs": len(starts), "found": found, "missed": n_true - found,
        "found_fraction": found / n_true if n_true else math.nan,
        "merged": int(np.sum(touched >= 2)), "spurious": int(np.sum(touched == 0)),
        "split": int(np.sum(runs_per_stance >= 2)),
    }


def stride_length_ratio(t: np.ndarray, pos: np.ndarray, stationary: np.ndarray, ref_t: np.ndarray,
                        ref_pos: np.ndarray) -> float:
    """Sum of the estimate's horizontal distances between the middles of consecutive ZUPT windows over the
    reference's between the same instants (module docstring); NaN with fewer than two usable windows.

    Parameters
    ----------
    t : (N,) s, pos : (N, 3) m, stationary : (N,) bool -- the estimate and its ZUPT flags.
    ref_t : (M,) s, ref_pos : (M, 3) m -- finite rows only.
    """
    starts, ends = stationary_runs(stationary)
    middles = t[(starts + ends - 1) // 2]
    ok = np.all(np.isfinite(pos[(starts + ends - 1) // 2]), axis=1) & (middles >= ref_t[0]) & (middles <= ref_t[-1])
    middles = middles[ok]
    if len(middles) < 2:
        return math.nan
    est = resample(middles, t, pos[:, :2])
    ref = resample(middles, ref_t, ref_pos[:, :2])
    ref_length = float(np.sum(np.linalg.norm(np.diff(ref, axis=0), axis=1)))
    return float(np.sum(np.linalg.norm(np.diff(est, axis=0), axis=1))) / ref_length if ref_length > 0 else math.nan


def score(t: np.ndarray, pos: np.ndarray, ref_t: np.ndarray, ref_pos: np.ndarray, quat: np.ndarray | None = None,
          ref_quat: np.ndarray | None = None, stationary: np.ndarray | None = None, secondary: bool = True) -> dict:
    """Score an estimated track against a true or reference track.

    Parameters
    ----------
    t : (N,) s, pos : (N, 3) m -- the estimate (rows with NaN, e.g. before the start, are ignored).
    ref_t : (M,) s, ref_pos : (M, 3) m -- truth or reference on its own clock (NaN rows ignored).
    quat, ref_quat : (N, 4) and (M, 4) attitudes; when both are given the heading drift uses them.
    stationary : (N,) bool, the estimate's ZUPT flags; when given, ``stride_length_ratio`` is added.
    secondary : also score ``path_length_ratio``, ``stride_length_ratio``, ``track_heading_drift_deg_per_s`` and
        ``ate_se2_m`` (about a third of the cost); False leaves those keys out (Monte Carlo studies that read
        only the end-point errors, the heading drift and ``ate_m``). The other scores are the same either way.

    Returns
    -------
    dict of floats (see the module docstring), SI units in the key names.
    """
    t = np.asarray(t, float)
    pos = np.asarray(pos, float)
    ok = finite_rows(pos)
    t_est, p_est = t[ok], pos[ok]
    ref_t = np.asarray(ref_t, float)
    ref_pos = np.asarray(ref_pos, float)
    rok = finite_rows(ref_pos) & (ref_t >= t_est[0]) & (ref_t <= t_est[-1])
    rt, rp = ref_t[rok], ref_pos[rok]
    if len(rt) < 2:
        raise ValueError("score: the reference does not overlap the navigated time span")
    ep = resample(rt, t_est, p_est)
    out = end_point_errors(ep[-1], rp[0], rp[-1])
    duration = float(rt[-1] - rt[0])
    path = _path_length(rt, rp)
    out.update(duration_s=duration, path_length_m=path)
    if secondary:
        out["path_length_ratio"] = _path_length(rt, ep) / path if path else math.nan
        if stationary is not None:
            out["stride_length_ratio"] = stride_length_ratio(t, pos, np.asarray(stationary, bool), rt, rp)
    attitudes = quat is not None and ref_quat is not None
    if secondary or not attitudes:
        track_rate = heading_drift(rt, track_heading_error(ep, rp))
        if secondary:
            out["track_heading_drift_deg_per_s"] = math.degrees(track_rate)
    if attitudes:
        q_est = np.asarray(quat, float)[ok]
        yaw_est = np.interp(rt, t_est, np.unwrap(yaw_of(q_est)))
        rate = heading_drift(rt, _wrap(yaw_est - yaw_of(np.asarray(ref_quat, float)[rok])))
        out["heading_drift_source"] = "attitude yaw (estimate - truth)"
    else:
        missing = " and ".join(name for name, q in (("estimate", quat), ("reference", ref_quat)) if q is None)
        rate = track_rate
        out["heading_drift_source"] = (f"track direction seen from the start (estimate - reference): no {missing} "
                                       "attitude")
        warnings.warn(f"heading_drift_deg_per_s is the track-direction drift, not the attitude's: no {missing} "
                      "attitude was given (the two differ, e.g. -0.016 against -0.033 deg/s on one run)",
                      HeadingDriftWarning, stacklevel=2)
    out["heading_drift_deg_per_s"] = math.degrees(rate)
    out["heading_drift_deg_per_100m"] = math.degrees(rate) * duration / path * 100.0 if path else math.nan
    east, north = ep[:, 0] - rp[:, 0], ep[:, 1] - rp[:, 1]
    out["ate_m"] = float(np.sqrt(np.mean(east**2 + north**2)))  # the sum over the two axes, without a reduction
    out["ate_alignment"] = "start: none beyond the common start point"
    if secondary:
        aligned = se2_aligned(ep[:, :2], rp[:, :2])
        out["ate_se2_m"] = float(np.sqrt(np.mean(np.sum((aligned - rp[:, :2]) ** 2, axis=1))))
    return out


def error_ellipse(points: np.ndarray, sigmas: float = 3.0) -> dict:
    """The ``sigmas``-sigma ellipse of 2-D points (R, 2) m: centre, semi-axes (m) and major-axis angle (deg)."""
    points = np.asarray(points, float)
    centre = points.mean(axis=0)
    if len(points) < 2:
        return {"centre_m": centre.tolist(), "semi_major_m": math.nan, "semi_minor_m": math.nan,
                "angle_deg": math.nan, "sigmas": sigmas}
    cov = np.cov(points.T)
    values, vectors = np.linalg.eigh(cov)
    major = vectors[:, 1]
    return {"centre_m": centre.tolist(), "semi_major_m": float(sigmas * math.sqrt(max(values[1], 0.0))),
            "semi_minor_m": float(sigmas * math.sqrt(max(values[0], 0.0))),
            "angle_deg": math.degrees(math.atan2(major[1], major[0])), "sigmas": sigmas}


def summarise_runs(scores: list[dict]) -> dict:
    """Mean, standard deviation, min and max of every numeric score over runs, and the 3-sigma end-point ellipse.

    The ellipse is of the (along-track error, perpendicular error) pairs, in m.
    """
    out = {"runs": len(scores)}
    keys = [k for k in scores[0] if isinstance(scores[0][k], (int, float)) and not isinstance(scores[0][k], bool)]
    for k in keys:
        v = np.array([s[k] for s in scores], float)
        out[k] = {"mean": float(np.nanmean(v)), "std": float(np.nanstd(v, ddof=1)) if len(v) > 1 else math.nan,
                  "min": float(np.nanmin(v)), "max": float(np.nanmax(v))}
    if "along_track_error_m" in keys and "perpendicular_error_m" in keys:
        pts = np.array([[s["along_track_error_m"], s["perpendicular_error_m"]] for s in scores], float)
        out["end_point_ellipse_3sigma"] = error_ellipse(pts[np.all(np.isfinite(pts), axis=1)], 3.0)
    return out
