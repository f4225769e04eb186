"""A recording seen as a measured one: IMU samples and a position reference, nothing a real sensor lacks."""

from __future__ import annotations

import numpy as np

from nav.recording import Recording, Reference
from nav.series import resample


def as_measured(rec: Recording, reference_rate_hz: float | None = None) -> Recording:
    """What a measured recording of the same walk would carry: IMU samples, the sampling part of meta, and the
    true positions as a reference (every sample, or resampled at ``reference_rate_hz`` Hz); no truth, no events,
    no gait or sensor parameters."""
    truth = rec.truth
    if reference_rate_hz is None:
        ref = Reference(truth.t.copy(), truth.pos.copy())
    else:
        t_ref = np.arange(truth.t[0], truth.t[-1], 1.0 / reference_rate_hz)
        ref = Reference(t_ref, resample(t_ref, truth.t, truth.pos))
    meta = {"sampling": dict(rec.meta.get("sampling", {})), "reference": {"kind": "position"}}
    return Recording(t=rec.t, acc=rec.acc, gyr=rec.gyr, meta=meta, reference=ref)


def reference_track(rec: Recording) -> tuple[np.ndarray, np.ndarray] | tuple[None, None]:
    """(t s, pos m) of the recording's continuous position reference, or (None, None) when it has none or only
    its start and end (e.g. a loop closure)."""
    ref = rec.reference
    if ref is None or len(ref.t) <= 2:
        return None, None
    return np.asarray(ref.t, float), np.asarray(ref.pos, float)
