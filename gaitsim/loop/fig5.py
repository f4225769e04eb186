"""The seed paper's Fig. 5 as loop residuals: how the shared filter's length underestimate and the IMU site's
velocity inside the detected stance windows change with the zero-velocity threshold.

The recording is swept against its position reference and the twin against its own true track at the IMU site,
both by :func:`gaitsim.stance.sweep.sweep` (the same code, mechanisation ``settings.NAV_OPTIONS.method``), at
the thresholds ``settings.FIG5_THRESHOLDS`` (1e4, 3e4, 5e4: the stance study's five would cost the loop 1.8x
per sweep). Each curve becomes two numbers (:data:`NUMBERS`), with the standard deviation of
the sweep's block bootstrap over strides (``settings.FIG5_BOOTSTRAP`` draws) as their standard error:

- ``fig5_underestimate_level_pp``: the length underestimate (percentage points of the reference distance between
  consecutive detected-stance middles), mean over the thresholds;
- ``fig5_underestimate_slope_pp``: the underestimate at the largest minus at the smallest threshold (5e4 - 1e4);
- ``fig5_window_velocity_level_mps``: the mean forward velocity of the track inside the detected windows (m/s),
  mean over the thresholds;
- ``fig5_window_velocity_slope_mps``: the same at the largest minus at the smallest threshold.

They exist only where the recording has a continuous position track (a twin is measured like its recording):
without one there is no underestimate and no in-window velocity to compare. Where the track is not the IMU
site's (ucr-fgo's undocumented reference point), the in-window velocity compares different points of the foot.
"""

from __future__ import annotations

import numpy as np

from nav.recording import Recording

from ..stance.sweep import sweep
from . import settings
from .signature import Scalar

# residual name -> (the sweep's curve, which summary of it: "level" or "slope", unit)
NUMBERS = {"fig5_underestimate_level_pp": ("underestimate_pct", "level", "pp"),
           "fig5_underestimate_slope_pp": ("underestimate_pct", "slope", "pp"),
           "fig5_window_velocity_level_mps": ("in_window_velocity_mps", "level", "m/s"),
           "fig5_window_velocity_slope_mps": ("in_window_velocity_mps", "slope", "m/s")}
UNITS = {name: unit for name, (_, _, unit) in NUMBERS.items()}


def fig5_scalars(rec: Recording, track_t: np.ndarray, track_pos: np.ndarray) -> dict:
    """The Fig. 5 numbers of ``rec`` against the track (t (M,) s, pos (M, 3) m) as signature scalars
    (name -> :class:`gaitsim.loop.signature.Scalar`, value and bootstrap standard deviation; module docstring)."""
    curves = {curve for curve, _, _ in NUMBERS.values()}
    swept = sweep(rec, track_t, track_pos, thresholds=settings.FIG5_THRESHOLDS, bootstrap=settings.FIG5_BOOTSTRAP,
                  method=settings.NAV_OPTIONS.method, quantities=tuple(sorted(curves)))
    return {name: Scalar(getattr(swept.curves[curve], part), getattr(swept.curves[curve], f"{part}_sd"))
            for name, (curve, part, _) in NUMBERS.items()}


def absent_because(reference_kind: str) -> str | None:
    """Why a recording with reference kind ``reference_kind`` (:data:`gaitsim.loop.navigation.KINDS`) has no
    Fig. 5 residuals, or None when it has them (a continuous track)."""
    if reference_kind == "track":
        return None
    return (f"no continuous position track (reference kind {reference_kind!r}): the length underestimate between "
            "detected stances and the in-window velocity need one, so the Fig. 5 residuals are absent")


def summary(before: dict, after: dict, reference_kind: str) -> dict:
    """The Fig. 5 residuals of a loop result for its report: name -> recording, twin before and after, residual
    and z before and after (residuals name -> :class:`gaitsim.loop.residuals.Residual`), or why they are absent."""
    why = absent_because(reference_kind)
    if why is not None:
        return {"absent_because": why}
    rows = {}
    for name in NUMBERS:
        b, a = before.get(name), after.get(name)
        if b is None:
            continue
        rows[name] = {"unit": b.unit, "recording": b.measured, "twin_before": b.twin, "residual_before": b.value,
                      "z_before": b.z, "twin_after": a.twin if a else None, "residual_after": a.value if a else None,
                      "z_after": a.z if a else None}
    return {"residuals": rows} if rows else {"absent_because": "the sweep found no walking stances to compare"}
