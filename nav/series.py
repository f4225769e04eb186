"""Resampling of sampled series onto new times (linear interpolation, column by column)."""

from __future__ import annotations

import numpy as np


def resample(t_new, t: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Linear interpolation of every column of a series at new times.

    Parameters
    ----------
    t_new : scalar or (M,) times, in the unit of ``t``.
    t : (N,) increasing sample times.
    values : (N, k) samples, any unit.

    Returns
    -------
    (k,) for a scalar ``t_new``, else (M, k), in the unit of ``values``; outside ``t`` the end values are held
    (``numpy.interp``).
    """
    values = np.asarray(values, float)
    return np.stack([np.interp(t_new, t, values[:, i]) for i in range(values.shape[1])], axis=-1)
