"""Any implementation's navigation solution scored against a fixture: the solution file and pass/fail per metric.

Solution file (``gaitsim score SOLUTION FIXTURE``): a CSV, plain or gzip-compressed (``.gz``), with a header row
of column names; other columns are ignored, so the shared filter's own ``solution.csv`` qualifies.

==============================  ========================================================================
column                          content
==============================  ========================================================================
``t``                           s, on the fixture's clock (``imu.csv``'s t), increasing; any subset of samples
``pos_x, pos_y, pos_z``         m, world ENU (z up), the fixture's world: start at the truth's position and
                                heading (``truth.csv``) at the sample you start navigating at
``q_w, q_x, q_y, q_z``          optional: attitude body -> world, scalar first. Without it the attitude heading
                                drift is not scored (said so in the result), and only the track-direction drift is
``zupt``                        optional: 1 where the filter applied a zero-velocity update; adds the
                                stride-length ratio
==============================  ========================================================================

Rows with a NaN position (before the filter starts) are ignored. The scores are :func:`nav.metrics.score`'s.

Tolerances (``tolerances.json`` of a fixture, made by :func:`tolerances`): for each metric the shared filter's
value on the fixture (the *reference*), the mean and standard deviation sigma of the metric over Monte Carlo
runs of the same walk and sensor (new stride variability and sensor noise per run), and the tolerance
``max(k sigma, floor)``. A solution passes a metric when ``|value - reference| <= tolerance``, and passes the
fixture when it passes every metric that can be scored.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import metrics, storage
from .recording import RecordingError, read_recording, write_csv
from .series import resample

REQUIRED_COLUMNS = ("t", "pos_x", "pos_y", "pos_z")
ATTITUDE_COLUMNS = ("q_w", "q_x", "q_y", "q_z")
ZUPT_COLUMN = "zupt"
SOLUTION_RESOLUTION = {"pos": 6, "q": 9}  # decimal places (m, 1) of a reference solution as stored: 1 um, 1e-9
UNIT_QUATERNION_TOLERANCE = 1e-3  # |q| - 1 beyond this is not an attitude quaternion
TOLERANCES_FILE = "tolerances.json"
REFERENCE_FOLDER = "reference-solution"

# metric -> (unit kind for its floor, needs the solution's attitude)
METRICS = {
    "along_track_error_m": ("m", False),
    "perpendicular_error_m": ("m", False),
    "final_error_m": ("m", False),
    "vertical_error_m": ("m", False),
    "ate_m": ("m", False),
    "path_length_ratio": ("1", False),
    "stride_length_ratio": ("1", False),
    "heading_drift_deg_per_s": ("deg/s", True),
    "track_heading_drift_deg_per_s": ("deg/s", False),
}


@dataclass
class SolutionFile:
    """A solution read from a file (module docstring); ``quat`` and ``zupt`` are None when the file has none.

    Attributes
    ----------
    t : (N,) s.   pos : (N, 3) m.   quat : (N, 4) or None.   zupt : (N,) bool or None.   source : the path.
    """

    t: np.ndarray
    pos: np.ndarray
    quat: np.ndarray | None
    zupt: np.ndarray | None
    source: str


def read_solution_file(path: str | Path) -> SolutionFile:
    """Read a solution file (module docstring).

    Raises
    ------
    RecordingError
        naming the file and the column: missing t/pos columns, time not increasing, attitudes that are not unit
        quaternions.
    """
    path = Path(path)
    if not path.is_file():
        raise RecordingError(f"{path}: solution file not found")
    with storage.open_text(path) as fh:
        header = [h.strip() for h in fh.readline().strip().split(",")]
    missing = [c for c in REQUIRED_COLUMNS if c not in header]
    if missing:
        raise RecordingError(f"{path}: missing column(s) {missing}; a solution needs {list(REQUIRED_COLUMNS)} "
                             f"(optional {list(ATTITUDE_COLUMNS)}, {ZUPT_COLUMN!r}); the header has {header}")
    has_q = all(c in header for c in ATTITUDE_COLUMNS)
    partial_q = [c for c in ATTITUDE_COLUMNS if c in header]
    if partial_q and not has_q:
        raise RecordingError(f"{path}: attitude columns {partial_q} without the others; give all of "
                             f"{list(ATTITUDE_COLUMNS)} or none")
    names = list(REQUIRED_COLUMNS) + (list(ATTITUDE_COLUMNS) if has_q else []) + (
        [ZUPT_COLUMN] if ZUPT_COLUMN in header else [])
    table = np.loadtxt(path, delimiter=",", skiprows=1, usecols=[header.index(c) for c in names], ndmin=2)
    t = table[:, 0]
    if len(t) < 2 or np.any(np.diff(t) <= 0) or not np.all(np.isfinite(t)):
        raise RecordingError(f"{path}: column t must hold at least two finite, increasing times (s)")
    quat = table[:, 4:8] if has_q else None
    if quat is not None:
        norm = np.linalg.norm(quat, axis=1)
        bad = np.isfinite(norm) & (np.abs(norm - 1.0) > UNIT_QUATERNION_TOLERANCE)
        if bad.any():
            first = int(np.flatnonzero(bad)[0])
            raise RecordingError(f"{path}: columns q_w..q_z: {int(bad.sum())} rows are not unit quaternions (first "
                                 f"at row {first}: |q| = {norm[first]:.6g}); give the attitude body -> world, "
                                 "scalar first")
    zupt = table[:, -1] > 0.5 if ZUPT_COLUMN in names else None
    return SolutionFile(t=t, pos=table[:, 1:4], quat=quat, zupt=zupt, source=str(path))


def write_solution_file(path: str | Path, t: np.ndarray, pos: np.ndarray, quat: np.ndarray | None = None,
                        zupt: np.ndarray | None = None, resolution: dict[str, int] | None = None) -> Path:
    """Write a solution file (module docstring), gzip-compressed when ``path`` ends in ``.gz``; positions and
    attitudes rounded to ``resolution`` (decimal places of m and 1) when given, else exact."""
    columns = list(REQUIRED_COLUMNS) + (list(ATTITUDE_COLUMNS) if quat is not None else []) + (
        [ZUPT_COLUMN] if zupt is not None else [])
    parts = [np.asarray(t, float)[:, None], np.asarray(pos, float)]
    parts += [np.asarray(quat, float)] if quat is not None else []
    parts += [np.asarray(zupt, float)[:, None]] if zupt is not None else []
    write_csv(Path(path), tuple(columns), np.hstack(parts), resolution)
    return Path(path)


def score_file(solution: SolutionFile, fixture: str | Path) -> dict:
    """:func:`nav.metrics.score` of a solution against a fixture's truth; the attitude drift only with the
    solution's attitude (no silent track-direction fallback: that is ``track_heading_drift_deg_per_s``)."""
    truth = read_recording(fixture).truth
    if truth is None:
        raise RecordingError(f"{fixture}: not a fixture (no truth table)")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", metrics.HeadingDriftWarning)  # handled below, per metric
        scores = metrics.score(solution.t, solution.pos, truth.t, truth.pos, solution.quat,
                               truth.quat if solution.quat is not None else None, solution.zupt)
    if solution.quat is None:
        scores["heading_drift_deg_per_s"] = math.nan
    return scores


def tolerances(reference: dict, monte_carlo: list[dict], sigmas: float, floors: dict[str, float]) -> dict:
    """Per metric of :data:`METRICS`: the reference value, Monte Carlo mean, std (ddof=1), runs and the
    tolerance ``max(sigmas * std, floor)`` (floor by unit kind: ``floors["m"]``, ``["1"]``, ``["deg/s"]``).
    Metrics undefined on the fixture (NaN reference, e.g. along-track on a closed loop) are left out."""
    out = {}
    for name, (kind, _) in METRICS.items():
        value = reference.get(name, math.nan)
        if value is None or not math.isfinite(value):
            continue
        runs = np.array([s.get(name, math.nan) for s in monte_carlo], float)
        runs = runs[np.isfinite(runs)]
        std = float(np.std(runs, ddof=1)) if len(runs) > 1 else math.nan
        out[name] = {"reference": float(value), "monte_carlo_mean": float(np.mean(runs)) if len(runs) else math.nan,
                     "monte_carlo_std": std, "monte_carlo_runs": int(len(runs)), "floor": floors[kind],
                     "tolerance": max(sigmas * std, floors[kind]) if math.isfinite(std) else floors[kind],
                     "unit": kind}
    return out


def verdicts(scores: dict, table: dict, has_attitude: bool) -> dict:
    """Pass/fail per metric of a fixture's tolerance table (``tolerances.json`` ``metrics``), and overall.

    Returns
    -------
    dict with ``metrics`` (per metric: status "pass" | "fail" | "not scored", value, reference, tolerance,
    difference, reason) and ``passed`` (every scored metric passes, and at least one was scored).
    """
    out = {}
    for name, tol in table.items():
        needs_attitude = METRICS.get(name, ("", False))[1]
        value = scores.get(name, math.nan)
        entry = {"reference": tol["reference"], "tolerance": tol["tolerance"], "value": value}
        if needs_attitude and not has_attitude:
            entry.update(status="not scored", reason="the solution has no attitude (q_w..q_z); the track-direction "
                                                     "drift is scored as track_heading_drift_deg_per_s instead")
        elif value is None or not math.isfinite(value):
            entry.update(status="not scored", reason="undefined for this solution (e.g. no zupt column for "
                                                     "stride_length_ratio)")
        else:
            difference = value - tol["reference"]
            entry.update(difference=difference, status="pass" if abs(difference) <= tol["tolerance"] else "fail")
        out[name] = entry
    scored = [e for e in out.values() if e["status"] != "not scored"]
    return {"metrics": out, "passed": bool(scored) and all(e["status"] == "pass" for e in scored)}


def difference(solution: SolutionFile, reference: SolutionFile) -> dict:
    """Horizontal distance (m) between two solutions over their common time span (the reference resampled at the
    solution's times): RMS, largest, and the samples compared. Informative: it is not a pass/fail rule."""
    ok = np.all(np.isfinite(solution.pos), axis=1) & (solution.t >= reference.t[0]) & (solution.t <= reference.t[-1])
    if ok.sum() < 1:
        return {"rms_horizontal_m": math.nan, "max_horizontal_m": math.nan, "samples": 0}
    gap = np.linalg.norm(solution.pos[ok, :2] - resample(solution.t[ok], reference.t, reference.pos[:, :2]), axis=1)
    return {"rms_horizontal_m": float(np.sqrt(np.mean(gap**2))), "max_horizontal_m": float(gap.max()),
            "samples": int(ok.sum())}
