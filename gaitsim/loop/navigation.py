"""What the loop's navigation part can compare, given the reference a recording has.

A recording comes with one of four kinds of reference, and its twin is measured against the same kind:

========== ======================================= ==============================================================
kind       what the recording holds                 navigation metrics compared (recording and twin alike)
========== ======================================= ==============================================================
track      a continuous position track               nav_length_ratio (stride lengths), nav_heading_drift,
           (reference.csv, > 2 rows)                 nav_final_error
endpoints  start and end positions only (2 rows;    nav_final_error
           a loop closure when they coincide)
distance   the walked distance (``--distance M``)    nav_length_ratio: navigated path between the stance middles /
                                                     the distance (the twin's: over its true path at the same
                                                     instants)
none       nothing                                   none: the loop compares signatures only
========== ======================================= ==============================================================

``--distance`` takes precedence over a recording's own reference. The filter is ``settings.NAV_OPTIONS``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nav import pipeline
from nav.alignment import stationary_runs
from nav.recording import Recording, RecordingError

from . import settings

NAV_UNITS = {"nav_length_ratio": "1", "nav_heading_drift": "deg/s", "nav_final_error": "m"}
KINDS = ("track", "endpoints", "distance", "none")


@dataclass(frozen=True)
class NavReference:
    """The kind of reference of a recording (module docstring) and, for ``distance``, the distance (m)."""

    kind: str
    distance_m: float | None = None

    def describe(self) -> str:
        """One sentence for the report: what the navigation part compares, or why it is absent."""
        return {
            "track": "continuous position reference: stride-length ratio, heading drift and final error compared",
            "endpoints": "start and end positions only (e.g. a loop closure): final position error compared",
            "distance": f"walked distance {self.distance_m} m given (--distance): navigated length / distance "
                        "compared",
            "none": "no reference (no reference.csv, no --distance): navigation residuals are absent; the loop "
                    "compares the IMU signatures only",
        }[self.kind]


def nav_reference(rec: Recording, distance_m: float | None = None) -> NavReference:
    """The reference kind of ``rec`` (module docstring).

    Raises
    ------
    RecordingError
        when ``distance_m`` is not a positive finite number (it names the value).
    """
    if distance_m is not None:
        if not (math.isfinite(distance_m) and distance_m > 0):
            raise RecordingError(f"--distance {distance_m}: the walked distance must be a positive number of metres")
        return NavReference("distance", float(distance_m))
    ref = rec.reference
    if ref is None or len(ref.t) < 2:
        return NavReference("none")
    return NavReference("track" if len(ref.t) > 2 else "endpoints")


def _stance_path_m(sol) -> float:
    """Horizontal path (m) of a solution through the middles of its ZUPT windows."""
    starts, ends = stationary_runs(sol.stationary)
    middles = sol.pos[(starts + ends - 1) // 2, :2]
    middles = middles[np.all(np.isfinite(middles), axis=1)]
    return float(np.sum(np.hypot(*np.diff(middles, axis=0).T))) if len(middles) > 1 else math.nan


def navigation_metrics(rec: Recording, ref: NavReference) -> tuple[dict, object]:
    """Navigate ``rec`` (``settings.NAV_OPTIONS``) and return (metrics of ``ref``'s kind, solution); a twin
    (which has its true track) is scored on the same kind as the recording it stands for."""
    has_track = rec.reference is not None and len(rec.reference.t) > 2
    if ref.kind == "none" or (ref.kind == "distance" and not has_track):
        sol = pipeline.navigate(rec, settings.NAV_OPTIONS)
        return ({"nav_length_ratio": _stance_path_m(sol) / ref.distance_m} if ref.kind == "distance" else {}), sol
    sol, score = pipeline.run(rec, settings.NAV_OPTIONS)
    ratio = float(score.get("stride_length_ratio", math.nan))
    drift = score.get("heading_drift_deg_per_s")
    final = float(score["final_error_m"])
    return {"track": {"nav_length_ratio": ratio, "nav_heading_drift": math.nan if drift is None else float(drift),
                      "nav_final_error": final},
            "endpoints": {"nav_final_error": final},
            "distance": {"nav_length_ratio": ratio}}[ref.kind], sol


def same_kind(sim: Recording, ref: NavReference) -> Recording:
    """The twin's measured-like recording ``sim`` (reference = its true track) reduced to ``ref``'s kind: for
    ``endpoints`` its first and last reference samples inside the IMU's span (a time skew drops samples at both
    ends); a track otherwise (``distance`` scores the twin against its own true path)."""
    if ref.kind == "endpoints":
        inside = np.flatnonzero((sim.reference.t >= sim.t[0]) & (sim.reference.t <= sim.t[-1]))[[0, -1]]
        sim.reference.t, sim.reference.pos = sim.reference.t[inside], sim.reference.pos[inside]
    return sim
