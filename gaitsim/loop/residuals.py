"""Residuals between two signatures (:mod:`gaitsim.loop.signature`): measured - twin, number by number.

For a scalar, ``measured - twin`` with uncertainty ``sqrt(se_measured^2 + se_twin^2 + floor^2)``; for a profile
``profile_<channel>``, the rms over the phase grid of the mean difference, with the rms of the combined standard
error (and the floor) as its uncertainty (pure noise then gives a ratio near 1, not 0). The floor is what the
twin fit itself is off by (measured by the loop on a twin of its own twin). A residual is at the noise level when
``|value| <= settings.NOISE_LEVEL * uncertainty``.

The Fig. 5 residuals (:mod:`gaitsim.loop.fig5`) are signature scalars of a recording with a position track,
measured only where the loop navigates (they run the filter at every threshold). Navigation residuals (length
ratio, heading drift) are added by :mod:`gaitsim.loop.attribution`, which runs
the filter.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import fig5, settings
from .signature import CHANNELS, Signature

UNITS = {
    "stance_gyro": "deg/s", **{f"stance_rate_{a}": "deg/s" for a in "xyz"}, "stance_acc_spread": "m/s^2", "stance_duration": "s", "stance_shoe": "log10",
    "acc_peak": "m/s^2", "gyr_peak": "deg/s", "hf40": "%", "hf80": "%", "onset_hf": "m/s^2", "acc_gyro_lag": "ms",
    "swing_axis_yaw": "deg", "stance_velocity": "m/s", "rest_acc_norm": "m/s^2", "rest_gyro_change": "deg/s",
    "rest_acc_change": "m/s^2", **{f"rest_{s}_noise_lag{k}": "1" for s in ("acc", "gyro") for k in (1, 2)}, "closure_forward": "m/s",
    "closure_left": "m/s", "closure_up": "m/s",
    "closure_roll": "deg", "closure_pitch": "deg",
    **{f"profile_{c}": ("m/s^2" if c.startswith("acc") else "deg/s") for c in CHANNELS}, **fig5.UNITS,
}


@dataclass
class Residual:
    """One compared number: measured, twin, their difference and its uncertainty (units in ``unit``)."""

    name: str
    unit: str
    measured: float
    twin: float
    value: float
    uncertainty: float

    @property
    def z(self) -> float:
        """|value| / uncertainty (inf when the uncertainty is zero and the value is not)."""
        if not math.isfinite(self.value):
            return math.nan
        if self.uncertainty <= 0:
            return 0.0 if self.value == 0 else math.inf
        return abs(self.value) / self.uncertainty

    @property
    def at_noise_level(self) -> bool:
        return bool(self.z <= settings.NOISE_LEVEL)

    def as_dict(self) -> dict:
        return {"name": self.name, "unit": self.unit, "measured": self.measured, "twin": self.twin,
                "value": self.value, "uncertainty": self.uncertainty, "z": self.z}


def compare(measured: Signature, twin: Signature, floors: dict | None = None) -> dict:
    """Residuals measured - twin for every number both signatures have (name -> :class:`Residual`).

    ``floors`` (name -> value in the residual's unit) adds, in quadrature, what the comparison itself is
    uncertain by beyond the stride-to-stride scatter (the twin fit's own error, see
    :func:`gaitsim.loop.attribution.comparison_noise`); ``settings.UNCERTAINTY_FLOOR`` is the least uncertainty."""
    floors = floors or {}

    def uncertainty(name: str, *parts: float) -> float:
        combined = math.sqrt(sum(float(np.nan_to_num(x)) ** 2 for x in (*parts, floors.get(name, 0.0))))
        return max(combined, settings.UNCERTAINTY_FLOOR.get(name, 0.0))

    out = {}
    for name, m in measured.scalars.items():
        w = twin.scalars.get(name)
        if w is None or not (math.isfinite(m.value) and math.isfinite(w.value)):
            continue
        out[name] = Residual(name, UNITS[name], m.value, w.value, m.value - w.value, uncertainty(name, m.se, w.se))
    for c in CHANNELS:
        m, w = measured.profiles[c], twin.profiles[c]
        name = f"profile_{c}"
        rms = float(np.sqrt(np.mean((m.mean - w.mean) ** 2)))
        out[name] = Residual(name, UNITS[name], float(np.sqrt(np.mean(m.mean**2))), float(np.sqrt(np.mean(w.mean**2))),
                             rms, uncertainty(name, float(np.sqrt(np.mean(m.se**2 + w.se**2)))))
    return out


def signature_misfit(res: dict) -> float:
    """Sum of z^2 over the signature residuals of ``res`` (name -> :class:`Residual`) with a finite z:
    navigation, ``settings.DERIVED`` and ``settings.REFITTED`` (closed by the twin's own fit) left out. The misfit
    the loop minimises and the held-out check scores."""
    return float(sum(r.z ** 2 for name, r in res.items() if not name.startswith("nav_") and name not in
                     settings.DERIVED + settings.REFITTED and math.isfinite(r.z)))


def profile_fit(measured: Signature, twin: Signature, factor: float = settings.PROFILE_SPREAD_FACTOR) -> dict:
    """Per channel, how far the twin's phase profile is from the recording's, in units of the recording's
    stride-to-stride standard deviation (not its standard error): the phases (% of the stride from the stance
    onset) where the twin's mean lies beyond ``factor`` of them, grouped into runs, and the largest ratio."""
    out = {}
    for c in CHANNELS:
        m, w = measured.profiles[c], twin.profiles[c]
        spread = np.maximum(m.strides.std(0, ddof=1), 1e-9)
        ratio = np.abs(m.mean - w.mean) / spread
        phase = 100.0 * np.arange(len(ratio)) / len(ratio)
        beyond = np.flatnonzero(ratio > factor)
        runs = np.split(beyond, np.flatnonzero(np.diff(beyond) > 1) + 1) if beyond.size else []
        out[c] = {"largest_ratio": float(ratio.max()), "within_share": float(np.mean(ratio <= factor)),
                  "phases_beyond_pct": [[float(phase[r[0]]), float(phase[r[-1]])] for r in runs]}
    return out
