"""The seed paper's calibration lab, simulated with the same sensor model (tilt table, rate table, shaker).

The lab only sees what a real lab sees: the simulated readouts and its own, known table motion. It never
reads the sensor's true error values to form its estimates. (It does set up its simulated conditions: the
sensor is bolted to the table by its case, so the foot-mounting rotation is not applied, and the room is at
the sensor's reference temperature.)

Procedure of :func:`run_lab` (one continuous power-on session, so one turn-on bias):

* **Tilt table + rate table.** The sensor is held in the 24 orientations that put each of its axes up or
  down (four headings each). In each orientation: a static dwell, a dwell at a constant table rate
  +Omega about the vertical and one at -Omega. The whole sequence is repeated ``cycles`` times; switching
  orientation every few seconds keeps slow bias drift out of the estimates. The first ``settle_s`` of each
  dwell is discarded (the bandwidth filter's transient after the instantaneous table move).
* **Least squares** on the dwell means (known specific force ``f = R^T (0, 0, g)``, known rate
  ``w = R^T (0, 0, +-Omega)``, R the sensor-to-world orientation of the table)::

      mean f_m = M_a f + b_a                   (4 unknowns per accelerometer axis)
      mean w_m = M_g w + G_g f + b_g           (7 unknowns per gyro axis)

  1-sigma uncertainties are ``s^2 (X^T X)^-1`` with ``s^2`` the residual variance of that axis (so they
  include whatever bias drift the residuals show); the biases' uncertainty adds, in quadrature, the Allan
  deviation of the time-ordered residuals at a quarter of the session (the session-mean drift that the
  constant term absorbs and the residuals cannot show). The g^2-sensitivity is not identifiable from axis-up/down
  positions (``f * f`` is the same for +g and -g) and is not estimated (``G2_g = None``).

:func:`shaker_g_sensitivity` reproduces the paper's Fig. 8: a sinusoidal specific force of amplitude A at
each frequency along each sensor axis (axis up on a vertical shaker), gyro readouts demodulated at the
shaking frequency by least squares (sin, cos, constant) into complex amplitudes Y. Two estimates of column
k of G_g are returned: the in-phase regression ``G = Re(Y_g conj(Y_ref)) / |Y_ref|^2`` (the least-squares
slope of gyro on reference) and the signed amplitude ratio ``G_amplitude = sign(G) |Y_g| / |Y_ref|`` (what
a shaker plot such as Fig. 8 shows).

What the sensor bandwidth does to them: both triads pass their own low-pass H_a(f), H_g(f).
Against the shaker's known (commanded) acceleration (``reference="table"``, a lab with a reference
accelerometer) the estimates are ``Re(H_g) G`` and ``|H_g| G``: the amplitude ratio stays flat to about half
the cutoff (2nd-order Butterworth: -3 % at 0.5 f_c, -10 % at 0.7 f_c) and then falls; the in-phase slope
falls much earlier because of the filter's phase lag (about -29 % at 0.5 f_c). Against the IMU's own
accelerometer (``reference="imu"``) they are ``Re(H_g / H_a) G`` and ``|H_g / H_a| G``: exactly flat when
both triads share one filter, whatever the cutoff -- the low-pass then hides itself. With bandwidth off both
are flat at G for every frequency below Nyquist.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gaitsim.imu.allan import allan_deviation
from gaitsim.imu.model import SensorSpec, apply_sensor
from nav.calibration import Calibration, save_calibration
from nav.constants import DEFAULT_GRAVITY

LAB_GRAVITY = DEFAULT_GRAVITY  # m/s^2, the lab's known local gravity (the simulator's world's)


def table_orientations() -> np.ndarray:
    """The 24 proper rotations (24, 3, 3) whose entries are 0 or +-1: sensor-to-world orientations that
    put each sensor axis up or down, with four headings each."""
    found = []
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1.0, -1.0), repeat=3):
            rotation = np.zeros((3, 3))
            rotation[np.arange(3), perm] = signs
            if np.linalg.det(rotation) > 0:
                found.append(rotation)
    return np.array(found)


def axis_up_orientation(axis: int) -> np.ndarray:
    """A sensor-to-world rotation (3, 3) that points sensor axis ``axis`` (0, 1, 2) up (world z)."""
    for rotation in table_orientations():
        if rotation[2, axis] == 1.0:
            return rotation
    raise AssertionError("unreachable: every axis has an up orientation")


def _segment_means(values: np.ndarray, n_segments: int, per_segment: int, settle: int) -> np.ndarray:
    """Means (n_segments, 3) of consecutive segments of ``per_segment`` samples, skipping ``settle`` each."""
    usable = values[: n_segments * per_segment].reshape(n_segments, per_segment, 3)
    return usable[:, settle:, :].mean(axis=1)


def _least_squares(regressors: np.ndarray, observed: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per output column: parameters (p, 3) of observed = regressors @ parameters, their 1-sigma (p, 3)
    from the residual variance of that column, and the residuals (n, 3)."""
    n_obs, n_par = regressors.shape
    if n_obs <= n_par:
        raise ValueError(f"least squares needs more than {n_par} observations, got {n_obs}")
    parameters, *_ = np.linalg.lstsq(regressors, observed, rcond=None)
    residuals = observed - regressors @ parameters
    residual_variance = np.sum(residuals**2, axis=0) / (n_obs - n_par)
    unscaled = np.diag(np.linalg.inv(regressors.T @ regressors))
    return parameters, np.sqrt(unscaled[:, None] * residual_variance[None, :]), residuals


def _session_drift(residuals: np.ndarray, dwell_s: float) -> np.ndarray:
    """1-sigma (3,) of slow bias drift on the time scale of the session: the Allan deviation of the
    time-ordered dwell residuals at a quarter of the session. A bias estimated over one session carries the
    session's mean of the in-run drift, which the residuals cannot show (the constant absorbs it)."""
    clusters = max(1, residuals.shape[0] // 4)
    _taus, adev = allan_deviation(residuals, 1.0 / dwell_s, clusters=[clusters])
    return adev[0]


def run_lab(spec: SensorSpec, rng: np.random.Generator, *, rate_hz: float = 800.0, dwell_s: float = 5.0,
            settle_s: float = 0.5, cycles: int = 2, table_rate_dps: float = 100.0,
            out_path: str | Path | None = None) -> Calibration:
    """Simulate the tilt-table / rate-table calibration and estimate b_a, M_a, b_g, M_g, G_g.

    Parameters
    ----------
    spec : the sensor under test (simulated; its true values are never read by the estimator).
    rng : Generator of this lab session.
    rate_hz : output rate of the sensor during the lab, Hz.
    dwell_s : length of each static or constant-rate dwell, s.
    settle_s : discarded start of each dwell, s.
    cycles : repetitions of the whole orientation sequence.
    table_rate_dps : rate-table speed, deg/s (both directions are used).
    out_path : if given, the calibration file is written there (JSON, :func:`nav.calibration.save_calibration`).

    Returns
    -------
    Calibration with 1-sigma uncertainties in ``sigma`` and ``G2_g = None``.
    """
    per_segment = int(round(dwell_s * rate_hz))
    settle = int(round(settle_s * rate_hz))
    if settle >= per_segment - 1:
        raise ValueError(f"settle_s={settle_s} s must be shorter than dwell_s={dwell_s} s")
    omega = np.deg2rad(table_rate_dps)
    up = np.array([0.0, 0.0, 1.0])
    known_f, known_w = [], []
    for _cycle in range(cycles):
        for rotation in table_orientations():
            for spin in (0.0, omega, -omega):
                known_f.append(rotation.T @ up * LAB_GRAVITY)
                known_w.append(rotation.T @ up * spin)
    known_f, known_w = np.array(known_f), np.array(known_w)
    n_segments = known_f.shape[0]
    t = np.arange(n_segments * per_segment) / rate_hz
    on_table = spec.replace(mounting_misalignment=np.zeros(3))
    _t_meas, acc_m, gyr_m = apply_sensor(on_table, t, np.repeat(known_f, per_segment, axis=0),
                                         np.repeat(known_w, per_segment, axis=0), rng,
                                         temperature=float(spec["temperature_ref"]))
    complete = acc_m.shape[0] // per_segment
    mean_f = _segment_means(acc_m, complete, per_segment, settle)
    mean_w = _segment_means(gyr_m, complete, per_segment, settle)
    known_f, known_w = known_f[:complete], known_w[:complete]
    ones = np.ones((complete, 1))

    accel_par, accel_sig, accel_res = _least_squares(np.hstack([known_f, ones]), mean_f)
    gyro_par, gyro_sig, gyro_res = _least_squares(np.hstack([known_w, known_f, ones]), mean_w)
    accel_sig[3] = np.hypot(accel_sig[3], _session_drift(accel_res, dwell_s))
    gyro_sig[6] = np.hypot(gyro_sig[6], _session_drift(gyro_res, dwell_s))
    estimate = dict(M_a=accel_par[:3].T, b_a=accel_par[3], M_g=gyro_par[:3].T, G_g=gyro_par[3:6].T, b_g=gyro_par[6])
    sigma = dict(M_a=accel_sig[:3].T, b_a=accel_sig[3], M_g=gyro_sig[:3].T, G_g=gyro_sig[3:6].T, b_g=gyro_sig[6])
    calibration = Calibration(
        **estimate, sigma=sigma,
        source=(f"simulated calibration lab: {complete} dwells of {dwell_s} s (24 orientations x static/+-"
                f"{table_rate_dps} deg/s x {cycles} cycles) at {rate_hz} Hz, sensor {spec.name!r}"),
    )
    if out_path is not None:
        save_calibration(calibration, out_path)
    return calibration


@dataclass(frozen=True)
class ShakerResult:
    """Per-frequency g-sensitivity estimates of :func:`shaker_g_sensitivity`.

    Attributes
    ----------
    freqs_hz : (F,) shaking frequencies, Hz.
    G : (F, 3, 3) in-phase (least-squares) estimate of G_g, column k from shaking along axis k,
        rad/s per m/s^2.
    G_amplitude : (F, 3, 3) signed amplitude-ratio estimate, rad/s per m/s^2.
    sigma : (F, 3, 3) 1-sigma of either estimate from the demodulation residuals, rad/s per m/s^2.
    reference : "table" (commanded acceleration) or "imu" (the sensor's own accelerometer).
    """

    freqs_hz: np.ndarray
    G: np.ndarray
    G_amplitude: np.ndarray
    sigma: np.ndarray
    reference: str


def shaker_g_sensitivity(spec: SensorSpec, rng: np.random.Generator, freqs_hz, *, amplitude: float = 4 * LAB_GRAVITY,
                         dwell_s: float = 8.0, settle_s: float = 0.5, rate_hz: float = 800.0,
                         reference: str = "table") -> ShakerResult:
    """Simulate shaker runs and estimate the gyro g-sensitivity at each frequency (the paper's Fig. 8).

    Parameters
    ----------
    spec : the sensor under test.
    rng : Generator of this session (one continuous run over all axes and frequencies).
    freqs_hz : shaking frequencies, Hz (below rate_hz / 2).
    amplitude : amplitude of the sinusoidal specific force, m/s^2.
    dwell_s, settle_s : length of each run and its discarded start, s.
    rate_hz : sensor output rate, Hz.
    reference : "table" (regress on the commanded acceleration) or "imu" (on the sensor's accelerometer
        along the shaking axis); see the module docstring for what the bandwidth does to each.
    """
    if reference not in ("table", "imu"):
        raise ValueError(f"reference: {reference!r} is not one of 'table', 'imu'")
    freqs_hz = np.asarray(freqs_hz, float)
    if np.any(freqs_hz <= 0) or np.any(freqs_hz >= 0.5 * rate_hz):
        raise ValueError(f"freqs_hz must lie in (0, {0.5 * rate_hz}) Hz, got {freqs_hz.tolist()}")
    per_segment = int(round(dwell_s * rate_hz))
    settle = int(round(settle_s * rate_hz))
    local_t = np.arange(per_segment) / rate_hz
    axes_freqs = [(axis, f) for axis in range(3) for f in freqs_hz]
    acc = np.empty((len(axes_freqs) * per_segment, 3))
    for i, (axis, f) in enumerate(axes_freqs):
        vertical = LAB_GRAVITY + amplitude * np.sin(2 * np.pi * f * local_t)
        acc[i * per_segment:(i + 1) * per_segment] = vertical[:, None] * axis_up_orientation(axis)[2][None, :]
    t = np.arange(acc.shape[0]) / rate_hz
    on_shaker = spec.replace(mounting_misalignment=np.zeros(3))
    _t_meas, acc_m, gyr_m = apply_sensor(on_shaker, t, acc, np.zeros_like(acc), rng,
                                         temperature=float(spec["temperature_ref"]))

    G = np.zeros((freqs_hz.size, 3, 3))
    G_amplitude = np.zeros_like(G)
    sigma = np.zeros_like(G)
    kept_t = local_t[settle:]
    for i, (axis, f) in enumerate(axes_freqs):
        rows = slice(i * per_segment + settle, (i + 1) * per_segment)
        phase = 2 * np.pi * f * kept_t
        regressors = np.column_stack([np.sin(phase), np.cos(phase), np.ones_like(phase)])
        gyro_par, gyro_sig, _ = _least_squares(regressors, gyr_m[rows])
        y_gyro = gyro_par[0] + 1j * gyro_par[1]
        if reference == "table":
            y_ref = complex(amplitude)
        else:
            accel_par, _, _ = _least_squares(regressors, acc_m[rows])
            y_ref = complex(accel_par[0, axis], accel_par[1, axis])
        k = i % freqs_hz.size
        G[k, :, axis] = np.real(y_gyro * np.conj(y_ref)) / abs(y_ref) ** 2
        G_amplitude[k, :, axis] = np.sign(G[k, :, axis]) * np.abs(y_gyro) / abs(y_ref)
        sigma[k, :, axis] = gyro_sig[0] / abs(y_ref)
    return ShakerResult(freqs_hz=freqs_hz, G=G, G_amplitude=G_amplitude, sigma=sigma, reference=reference)
