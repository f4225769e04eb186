"""Recordings as gaitmap's sensor DataFrames, and gaitmap's trajectories as solutions (mad-lab-fau/gaitmap).

gaitmap's single-sensor data is a pandas DataFrame with columns ``acc_x, acc_y, acc_z`` (m/s^2) and
``gyr_x, gyr_y, gyr_z`` (deg/s), one row per sample, and a separate sampling rate (Hz): the rows carry no times.
Its foot sensor frame (FSF) is right-handed with x toward the tip of the shoe, y to the left and z up: the
project's body frame. Converting is therefore the identity on the axes and rad/s <-> deg/s on the angular rate;
the test suite checks it against gaitmap itself (its data checks accept the frames, and its RtsKalman navigates
a converted recording along the true track). gaitmap's foot *body* frame (FBF: anterior-posterior,
medio-lateral, superior-inferior, mirrored for the left and right foot) is reached from the FSF with gaitmap's
``gaitmap.utils.coordinate_conversion.convert_to_fbf``.

gaitmap's trajectory methods (``RtsKalman``, ``ForwardBackwardIntegration``, ...) return ``len(data) + 1`` rows
of ``position_`` (pos_x, pos_y, pos_z in m) and ``orientation_`` (q_x, q_y, q_z, q_w: scipy's scalar-last order),
the initial state first: row k is the state after k samples, at ``t_0 + k / rate``.

Needs pandas (``pip install 'gaitsim[interop]'``); gaitmap itself is needed only to run its algorithms.
"""

from __future__ import annotations

import warnings

import numpy as np

from nav.checks import JITTER_TOLERANCE
from nav.recording import Recording, RecordingError

ACC_COLUMNS = ["acc_x", "acc_y", "acc_z"]
GYR_COLUMNS = ["gyr_x", "gyr_y", "gyr_z"]
SENSOR_COLUMNS = ACC_COLUMNS + GYR_COLUMNS  # gaitmap's SF_COLS
POSITION_COLUMNS = ["pos_x", "pos_y", "pos_z"]
ORIENTATION_COLUMNS = ["q_x", "q_y", "q_z", "q_w"]


def _pandas():
    try:
        import pandas
    except ImportError:
        raise ImportError("gaitmap DataFrames need pandas: pip install 'gaitsim[interop]'") from None
    return pandas


def to_gaitmap(rec: Recording):
    """A recording as gaitmap single-sensor data.

    Returns
    -------
    (data, sampling_rate_hz): the DataFrame (acc m/s^2, gyr deg/s, FSF = body frame, index = sample number) and
    the rate from the median sample interval. gaitmap assumes a constant rate: intervals deviating more than
    ``nav.checks.JITTER_TOLERANCE`` from the median are counted in a warning (the samples are not resampled).
    """
    pd = _pandas()
    dt = np.diff(rec.t)
    median = float(np.median(dt))
    irregular = int(np.sum(np.abs(dt - median) > JITTER_TOLERANCE * median))
    if irregular:
        warnings.warn(f"to_gaitmap: {irregular} of {len(dt)} sample intervals deviate more than "
                      f"{JITTER_TOLERANCE:.0%} from the median {median:.6g} s; gaitmap assumes a constant rate and "
                      "the samples are passed as they are", stacklevel=2)
    data = pd.DataFrame(np.column_stack([rec.acc, np.degrees(rec.gyr)]), columns=SENSOR_COLUMNS)
    data.index.name = "sample"
    return data, 1.0 / median


def from_gaitmap(data, sampling_rate_hz: float, meta: dict | None = None) -> Recording:
    """A recording from gaitmap single-sensor data (acc m/s^2, gyr deg/s, FSF); sample k at k / rate.

    Raises
    ------
    RecordingError
        naming the missing columns, or a rate that is not positive.
    """
    missing = [c for c in SENSOR_COLUMNS if c not in data.columns]
    if missing:
        raise RecordingError(f"from_gaitmap: missing column(s) {missing}; gaitmap sensor data has {SENSOR_COLUMNS} "
                             "(a multi-sensor DataFrame: pass data[sensor_name])")
    if not sampling_rate_hz > 0:
        raise RecordingError(f"from_gaitmap: sampling_rate_hz = {sampling_rate_hz!r} must be > 0")
    values = data[SENSOR_COLUMNS].to_numpy(dtype=float)
    t = np.arange(len(values)) / float(sampling_rate_hz)
    info = {"source": "gaitmap DataFrame", "sampling": {"rate_hz": float(sampling_rate_hz)},
            "frames": {"body": "gaitmap's foot sensor frame (x toes, y left, z up): the project's body frame"}}
    return Recording(t=t, acc=values[:, :3], gyr=np.radians(values[:, 3:]), meta={**info, **(meta or {})})


def solution_from_gaitmap(method, t0: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t, pos, quat) of a gaitmap trajectory result (``position_``, ``orientation_``; module docstring):
    times (s) ``t0 + k / sampling_rate_hz``, positions (m), attitudes body -> world scalar first; ready for
    :func:`nav.conformance.write_solution_file`."""
    pos = method.position_[POSITION_COLUMNS].to_numpy(dtype=float)
    q = method.orientation_[ORIENTATION_COLUMNS].to_numpy(dtype=float)
    t = t0 + np.arange(len(pos)) / float(method.sampling_rate_hz)
    return t, pos, np.column_stack([q[:, 3], q[:, :3]])
