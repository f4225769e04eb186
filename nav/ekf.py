"""Closed-loop error-state EKF for ZUPT-aided foot-mounted inertial navigation (flat earth, ENU).

States (true minus estimated, reset to zero after each correction): position (m), velocity (m/s) and attitude
(rad, world-frame small angle) -- 9 states; + accelerometer bias (m/s^2) and gyro bias (rad/s) -- 15; + the 9
coefficients of the gyro g-sensitivity matrix G (rad/s per m/s^2, row-major; ``w_meas = w + b_g + G f``, after
Bancroft & Lachapelle) -- 24.

- Propagation: the nominal state by the strapdown of nav.strapdown (RK4 on point samples, or exact increments);
  the covariance by Phi = I + F dt and Q = diag(noise density^2) * dt (continuous white noise integrated over
  the sample interval, so results do not depend on the sample rate through the noise model).
- Updates: Joseph form ``(I-KH) P (I-KH)^T + K R K^T``, symmetrised; each correction is injected into the
  nominal state at once (closed loop).
- ZUPT: the pseudo-measurement "velocity = stance velocity", the stance velocity given per sample in the foot's
  heading frame (x along the foot's horizontal heading, z up; rotated by the current yaw estimate). Zero by
  default.
- Optional: zero angular-rate update (needs the gyro bias states), level-walking height constraint at ZUPTs
  (off unless asked), RTS smoother over the whole recording (state only; memory N * n^2 * 8 bytes).

Defaults follow OpenShoe's filter (anchors §3) converted to ENU and to noise densities: OpenShoe adds a
per-sample standard deviation sigma every sample at 820 Hz, which is the density sigma/sqrt(820 Hz).
"""

from __future__ import annotations

import math
from collections import namedtuple
from dataclasses import asdict, dataclass, fields

import numba
import numpy as np

from ._numba import ekf as kernels
from .compiled import kernel_array
from .constants import DEFAULT_GRAVITY
from .strapdown import mechanisation_mode

STATE_SIZES = (9, 15, 24)
OPENSHOE_RATE_HZ = 820.0  # the sample rate at which OpenShoe's per-sample noise values are converted


@dataclass(frozen=True)
class FilterConfig:
    """Filter settings; every field in SI units.

    Attributes
    ----------
    states : 9, 15 or 24 (see the module docstring). Default 9 (OpenShoe's default).
    gravity : m/s^2, magnitude of gravity (0, 0, -gravity). Default 9.81.
    acc_noise_density : m/s^2/sqrt(Hz) (= m/s/sqrt(s)), process noise on velocity. Default OpenShoe's
        0.5 m/s^2 per sample at 820 Hz = 0.01746.
    gyr_noise_density : rad/s/sqrt(Hz) (= rad/sqrt(s)), process noise on attitude. Default OpenShoe's 0.5 deg/s
        per sample at 820 Hz = 3.047e-4.
    acc_bias_random_walk : m/s^2/sqrt(s), bias driving noise. Default 1e-7 m/s^2 per sample at 820 Hz
        = 2.864e-6.
    gyr_bias_random_walk : rad/s/sqrt(s), bias driving noise. Default 1e-7 rad/s per sample at 820 Hz
        = 2.864e-6.
    gsens_random_walk : (rad/s)/(m/s^2)/sqrt(s), g-sensitivity driving noise. Default 0 (constant).
    zupt_sigma : m/s, ZUPT pseudo-measurement noise std per axis. Default 0.01 (OpenShoe).
    zaru : bool, apply a zero angular-rate update at stationary samples (needs states >= 15). Default False.
    zaru_sigma : rad/s, its noise std per axis. Default 0.1 deg/s.
    level_sigma : m, std of the optional "height = initial height" constraint at ZUPTs; 0 disables it (default).
    p0_pos : m, p0_vel : m/s, p0_tilt : rad (roll, pitch), p0_yaw : rad -- initial standard deviations.
        Defaults 1e-5 m, 1e-5 m/s, 0.1 deg, 0.1 deg (OpenShoe).
    p0_acc_bias : m/s^2, p0_gyr_bias : rad/s -- initial bias std. Defaults 0.3 m/s^2, 0.3 deg/s (OpenShoe).
    p0_gsens : (rad/s)/(m/s^2), initial g-sensitivity std. Default 0.005 deg/s per m/s^2 (the seed paper's
        coefficients are ~0.002 deg/s per m/s^2).
    """

    states: int = 9
    gravity: float = DEFAULT_GRAVITY
    acc_noise_density: float = 0.5 / math.sqrt(OPENSHOE_RATE_HZ)
    gyr_noise_density: float = math.radians(0.5) / math.sqrt(OPENSHOE_RATE_HZ)
    acc_bias_random_walk: float = 1e-7 * math.sqrt(OPENSHOE_RATE_HZ)
    gyr_bias_random_walk: float = 1e-7 * math.sqrt(OPENSHOE_RATE_HZ)
    gsens_random_walk: float = 0.0
    zupt_sigma: float = 0.01
    zaru: bool = False
    zaru_sigma: float = math.radians(0.1)
    level_sigma: float = 0.0
    p0_pos: float = 1e-5
    p0_vel: float = 1e-5
    p0_tilt: float = math.radians(0.1)
    p0_yaw: float = math.radians(0.1)
    p0_acc_bias: float = 0.3
    p0_gyr_bias: float = math.radians(0.3)
    p0_gsens: float = math.radians(0.005)

    def __post_init__(self):
        if self.states not in STATE_SIZES:
            raise ValueError(f"FilterConfig.states = {self.states}; allowed: {STATE_SIZES}")
        if self.zaru and self.states < 15:
            raise ValueError("FilterConfig.zaru = True needs the gyro bias states (states = 15 or 24); "
                             f"got states = {self.states}")
        for name in ("gravity", "zupt_sigma", "zaru_sigma", "p0_pos", "p0_vel", "p0_tilt", "p0_yaw",
                     "p0_acc_bias", "p0_gyr_bias", "p0_gsens"):
            if not getattr(self, name) > 0:
                raise ValueError(f"FilterConfig.{name} = {getattr(self, name)} must be > 0")
        for name in ("acc_noise_density", "gyr_noise_density", "acc_bias_random_walk", "gyr_bias_random_walk",
                     "gsens_random_walk", "level_sigma"):
            if not getattr(self, name) >= 0:
                raise ValueError(f"FilterConfig.{name} = {getattr(self, name)} must be >= 0")

    def for_kernel(self) -> "KernelConfig":
        """The settings as the named tuple the compiled filter reads (nav._numba.ekf), field by field."""
        return KernelConfig(*(type(f.default)(getattr(self, f.name)) for f in fields(self)))

    def as_dict(self) -> dict:
        return asdict(self)


# FilterConfig's fields in their order, as a named tuple numba compiles (one type per field: states int, zaru
# bool, the rest float); adding a field to FilterConfig adds it here
KernelConfig = namedtuple("KernelConfig", [f.name for f in fields(FilterConfig)])


@dataclass
class FilterOutput:
    """Filter estimates per sample (rows before the start sample are NaN); a leading run axis in batch mode.

    Attributes
    ----------
    quat : (..., N, 4) attitude body->world (w, x, y, z).
    vel : (..., N, 3) m/s, pos : (..., N, 3) m -- world ENU.
    bias_acc : (..., N, 3) m/s^2, bias_gyr : (..., N, 3) rad/s, gsens : (..., N, 9) rad/s per m/s^2 -- the
        estimates (zero when not estimated).
    p_diag : (..., N, states) filtered error-state variances (SI units squared).
    Without the estimates' history (``history=False`` in :func:`run_filter`) bias_acc, bias_gyr, gsens and
    p_diag have one row in place of N: the last sample's.
    skipped_updates : int or (R,) array, updates skipped because a covariance was not positive definite.
    """

    quat: np.ndarray
    vel: np.ndarray
    pos: np.ndarray
    bias_acc: np.ndarray
    bias_gyr: np.ndarray
    gsens: np.ndarray
    p_diag: np.ndarray
    skipped_updates: int | np.ndarray

    def of_run(self, r: int) -> "FilterOutput":
        """The estimates of run ``r`` of a batch output (views, no copy)."""
        return FilterOutput(self.quat[r], self.vel[r], self.pos[r], self.bias_acc[r], self.bias_gyr[r],
                            self.gsens[r], self.p_diag[r], self.skipped_updates[r])


def empty_outputs(shape: tuple[int, ...], states: int, history: bool = True) -> FilterOutput:
    """Uninitialised estimate arrays for ``shape`` (runs, samples) or (samples,); the filter fills every row.
    ``history`` False: one row for the biases, g-sensitivity and variances (the last sample's)."""
    def rows(*tail):
        return np.empty(shape + tail)

    def estimates(*tail):
        return np.empty(shape[:-1] + (1,) + tail) if not history else rows(*tail)

    return FilterOutput(rows(4), rows(3), rows(3), estimates(3), estimates(3), estimates(9), estimates(states), 0)


def per_sample_stance_velocity(stance_velocity, shape: tuple[int, ...]) -> np.ndarray:
    """(shape..., 3) m/s: the ZUPT's stance velocity per sample from None (zero), a (3,) constant or an array."""
    if stance_velocity is None:
        return np.zeros(shape + (3,))
    v = kernel_array(stance_velocity, float, shape + (3,))
    if not np.all(np.isfinite(v)):
        raise ValueError("stance_velocity (the ZUPT's velocity) contains NaN or inf values")
    return v


def check_filter_inputs(t, acc, gyr, stationary, start: int):
    """(t, acc, gyr, stationary) as contiguous float64 / bool arrays of shapes (N,), (N, 3), (N, 3), (N,), and
    ``start`` checked to lie in 0..N-1; a ValueError naming the mismatch otherwise."""
    t = kernel_array(t, float)
    acc = kernel_array(acc, float)
    gyr = kernel_array(gyr, float)
    n = len(t)
    stationary = kernel_array(stationary, bool)
    if stationary.shape != (n,) or acc.shape != (n, 3) or gyr.shape != (n, 3):
        raise ValueError(f"run_filter: shapes t {t.shape}, acc {acc.shape}, gyr {gyr.shape}, stationary "
                         f"{stationary.shape} do not match (N,), (N,3), (N,3), (N,)")
    if not 0 <= start < n:
        raise ValueError(f"run_filter: start sample {start} outside 0..{n - 1}")
    return t, acc, gyr, stationary


def check_history(history: bool, rts: bool) -> None:
    """ValueError when the RTS smoother is asked for without the estimates' history it reads back."""
    if rts and not history:
        raise ValueError("run_filter: rts=True needs history=True (the smoother reads every sample's estimates)")


def run_filter(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, stationary: np.ndarray, quat0: np.ndarray,
               vel0=(0.0, 0.0, 0.0), pos0=(0.0, 0.0, 0.0), start: int = 0, config: FilterConfig = FilterConfig(),
               method: str = "rk4", stance_velocity: np.ndarray | None = None, rts: bool = False,
               history: bool = True) -> FilterOutput:
    """Run the ZUPT-aided EKF over one recording.

    Parameters
    ----------
    t : (N,) s, strictly increasing.
    acc : (N, 3) m/s^2 specific force, or m/s increments ``dv`` when ``method="increments"``.
    gyr : (N, 3) rad/s angular rate, or rad increments ``dth`` when ``method="increments"``.
    stationary : (N,) bool, samples where the ZUPT (and ZARU, if configured) is applied.
    quat0 : (4,) attitude at sample ``start`` (body->world, w first); vel0 (m/s), pos0 (m): world ENU.
    start : index of the first navigated sample (earlier rows of the output are NaN).
    config : FilterConfig.
    method : "rk4" (point samples) or "increments" (exact dv, dth; see nav.strapdown).
    stance_velocity : None (zero), a (3,) constant or an (N, 3) per-sample velocity in m/s in the foot's
        heading frame (x forward along the horizontal heading, y left, z up), used at stationary samples.
    rts : smooth the state with an RTS pass after the forward filter.
    history : keep the bias, g-sensitivity and variance estimates of every sample (default); False keeps the last
        sample's alone (see :class:`FilterOutput`), which for 15 states cuts what the filter writes per sample
        from 40 to 10 numbers (the trajectory). The smoother reads the history back: False with ``rts`` is an
        error.

    Returns
    -------
    FilterOutput.
    """
    t, acc, gyr, stationary = check_filter_inputs(t, acc, gyr, stationary, start)
    n = len(t)
    mode = mechanisation_mode(method)
    check_history(history, rts)
    stance_velocity = per_sample_stance_velocity(stance_velocity, (n,))
    out = empty_outputs((n,), config.states, history)
    q0 = np.asarray(quat0, float) / np.linalg.norm(quat0)
    out.skipped_updates = kernels.filter_run(
        mode, t, acc, gyr, stationary, stance_velocity, int(start), q0, kernel_array(vel0, float),
        kernel_array(pos0, float), config.for_kernel(), bool(rts), out.quat, out.vel, out.pos, out.bias_acc,
        out.bias_gyr, out.gsens, out.p_diag)
    return out


def run_filter_batch(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, stationary: np.ndarray, quat0: np.ndarray,
                     vel0=None, pos0=None, start=None, config: FilterConfig = FilterConfig(), method: str = "rk4",
                     stance_velocity: np.ndarray | None = None, rts: bool = False, history: bool = True) -> FilterOutput:
    """Run the filter over R recordings of N samples each in one compiled call (runs spread over cores).

    Same parameters as :func:`run_filter` with a leading run axis: t (R, N) or (N,) shared, acc and gyr
    (R, N, 3), stationary (R, N), quat0 (R, 4), vel0 and pos0 (R, 3) (default zero), start (R,) (default 0),
    stance_velocity None, (3,), (R, 3) or (R, N, 3). Results equal :func:`run_filter` on each run (same compiled
    code per run).
    """
    acc = kernel_array(acc, float)
    gyr = kernel_array(gyr, float)
    if acc.ndim != 3 or acc.shape[2] != 3 or gyr.shape != acc.shape:
        raise ValueError(f"run_filter_batch: acc {acc.shape} and gyr {gyr.shape} must both be (R, N, 3)")
    runs, n = acc.shape[:2]
    t = kernel_array(t, float, (runs, n))
    stationary = kernel_array(stationary, bool, (runs, n))
    if stance_velocity is not None and np.ndim(stance_velocity) == 2:  # one constant per run
        stance_velocity = np.asarray(stance_velocity, float)[:, None, :]
    stance_velocity = per_sample_stance_velocity(stance_velocity, (runs, n))
    q0 = np.asarray(quat0, float).reshape(runs, 4)
    q0 = kernel_array(q0 / np.linalg.norm(q0, axis=1, keepdims=True), float)
    vel0 = kernel_array(0.0 if vel0 is None else vel0, float, (runs, 3))
    pos0 = kernel_array(0.0 if pos0 is None else pos0, float, (runs, 3))
    start = kernel_array(0 if start is None else start, np.int64, (runs,))
    if np.any(start < 0) or np.any(start >= n):
        raise ValueError(f"run_filter_batch: start samples {start} outside 0..{n - 1}")
    check_history(history, rts)
    out = empty_outputs((runs, n), config.states, history)
    skipped = np.zeros(runs, np.int64)
    with numba.parallel_chunksize(1):  # runs handed out one at a time: a core busy with other work takes fewer
        kernels.filter_batch(mechanisation_mode(method), t, acc, gyr, stationary, stance_velocity, start,
                             q0, vel0, pos0, config.for_kernel(), bool(rts), out.quat, out.vel, out.pos,
                             out.bias_acc, out.bias_gyr, out.gsens, out.p_diag, skipped)
    out.skipped_updates = skipped
    return out


def compile_filter() -> None:
    """Compile the filter's kernels in this process, single run and batch, or load them from numba's cache.

    Called before starting worker processes: they then load the compiled filter from the cache instead of each
    compiling it at the same time (50-70 s of CPU per process for the single run, about 20 s more for the batch).
    """
    n = 4
    t = np.arange(n) * 0.01
    acc = np.tile([0.0, 0.0, DEFAULT_GRAVITY], (n, 1))
    stationary = np.ones(n, bool)
    run_filter(t, acc, np.zeros((n, 3)), stationary, [1.0, 0.0, 0.0, 0.0])
    run_filter_batch(t, acc[None], np.zeros((1, n, 3)), stationary, [1.0, 0.0, 0.0, 0.0])
