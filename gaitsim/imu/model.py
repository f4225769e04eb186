"""IMU forward model: true body-frame specific force and angular rate -> what the sensor outputs.

Parameters live in an immutable :class:`SensorSpec` (SI inside; datasheet units only in
:mod:`gaitsim.imu.config`). :func:`apply_sensor` applies, in this order (each term independent and off at its
default value):

1. **Mounting misalignment.** The sensor frame is the foot (body) frame rotated by
   ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (``mounting_misalignment = (roll, pitch, yaw)``); the sensor sees
   ``f_s = R^T f``, ``w_s = R^T w``.
2. **Sampling instants.** Output sample k is taken at true time ``tau_k = t_0 + k dt / (1 + clock_error)``
   (a clock running fast by ``clock_error`` samples more often), the gyro at ``tau_k + accel_gyro_skew``.
   Truth is read there through a cubic spline (only when one of these terms is on; otherwise the samples
   are the input samples exactly). The sensor samples over the input time span; samples whose (gyro)
   instants fall outside it are dropped, so the output may be longer or shorter than the input. The reported timestamp is the sensor's own clock,
   ``t_0 + k dt``, plus white timestamp jitter (std ``timestamp_jitter``).
3. **Deterministic errors**, through :meth:`nav.calibration.Calibration.distort` (one implementation shared
   with the compensation; without temperature terms its sums are done in step 5's pass, in its order:
   :meth:`~nav.calibration.Calibration.distort_terms`)::

       f_m = M_a f + b_a            w_m = M_g w + G_g f + G2_g (f*f) + b_g

   with ``b = bias + turn-on draw`` (the turn-on bias ~ N(0, bias_repeatability^2), drawn once per run).
4. **Temperature**, with ``dT = T(t) - temperature_ref``: ``x_m <- b + (1 + temp_scale dT) (x_m - b)
   + temp_bias dT`` per axis (scale on everything but the bias, then a bias slope).
5. **Bias instability**: a first-order Gauss-Markov bias per axis, correlation time
   ``bias_instability_tau``, stationary std ``0.664 B / 0.6174`` so that the peak of its Allan deviation
   (reached at 1.89 tau_c) reads the datasheet value as ``0.664 B``, the IEEE flicker-floor convention;
   it starts from its stationary distribution.
   **Rate random walk**: a bias doing a random walk from zero, Allan deviation ``K sqrt(tau/3)``; it is
   simulated on its own, whatever the bias instability. Both slow processes are simulated exactly at a
   coarse step ``h`` (16 samples, or ``tau_c / 20`` if shorter) and linearly interpolated to the samples;
   their spectra differ from the continuous processes only above ``1 / (2 h)``, where white noise
   dominates by orders of magnitude.
   **White noise**: sample std ``N sqrt(fs)`` (noise density N), from float32 standard normals (numpy's,
   drawn in a compiled loop: :mod:`gaitsim.imu.normals`).
6. **Bandwidth**: a Butterworth low-pass of order ``filter_order`` and cutoff ``*_bandwidth`` acting on the sum
   above, started in steady state on the first sample so a static start has no transient. ``filter_kind``
   says where it sits: ``"digital"``, the sensor's digital filter at the output rate (bilinear transform,
   exact -3 dB at the cutoff, a zero at the Nyquist frequency), or ``"analogue"``, a front end ahead of the
   sampling (the analogue filter's poles mapped by z = exp(s / fs), no zeros but at z = 0, unit gain at DC:
   for order 1 the RC recursion ``y[k] = y[k-1] + (1 - exp(-2 pi f_c / fs)) (x[k] - y[k-1])``; the aliasing of
   its stop band is not modelled).
7. **Quantisation** to multiples of ``*_resolution``, then **saturation** (clip) at ``+-*_range``.

Random draws: the run's Generator spawns one child per stream in :data:`RANDOM_STREAMS` (always all of
them, in that order); a term draws only from its own child, so switching a term on or off never changes
the realisation of the others, and a seeded run is reproducible.
"""

from __future__ import annotations

import dataclasses
import math
import sys
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from gaitsim.errors import ScenarioError
from gaitsim.imu.allan import BIAS_INSTABILITY_FLOOR, GAUSS_MARKOV_PEAK
from gaitsim.imu.units import si_unit
from nav import quaternion
from nav.calibration import Calibration, add_in_order

FILTER_KINDS = ("digital", "analogue")  # where the bandwidth low-pass sits (module docstring, step 6)

# parameter name -> (unit kind, shape, default). "axes" values are per-axis (3,) vectors, "matrix" (3, 3).
PARAMETERS: dict[str, tuple[str, str, object]] = {
    "accel_noise_density": ("accel_noise_density", "axes", 0.0),
    "gyro_noise_density": ("gyro_noise_density", "axes", 0.0),
    "accel_bias": ("acceleration", "axes", 0.0),
    "gyro_bias": ("angular_rate", "axes", 0.0),
    "accel_bias_repeatability": ("acceleration", "axes", 0.0),
    "gyro_bias_repeatability": ("angular_rate", "axes", 0.0),
    "accel_bias_instability": ("acceleration", "axes", 0.0),
    "gyro_bias_instability": ("angular_rate", "axes", 0.0),
    "accel_bias_instability_tau": ("time", "scalar", 100.0),
    "gyro_bias_instability_tau": ("time", "scalar", 100.0),
    "accel_random_walk": ("accel_random_walk", "axes", 0.0),
    "gyro_random_walk": ("gyro_random_walk", "axes", 0.0),
    "accel_misalignment": ("matrix", "matrix", np.eye(3)),
    "gyro_misalignment": ("matrix", "matrix", np.eye(3)),
    "gyro_g_sensitivity": ("g_sensitivity", "matrix", np.zeros((3, 3))),
    "gyro_g2_sensitivity": ("g2_sensitivity", "matrix", np.zeros((3, 3))),
    "accel_resolution": ("acceleration", "scalar", 0.0),
    "gyro_resolution": ("angular_rate", "scalar", 0.0),
    "accel_range": ("acceleration", "scalar", np.inf),
    "gyro_range": ("angular_rate", "scalar", np.inf),
    "accel_bandwidth": ("frequency", "scalar", np.inf),
    "gyro_bandwidth": ("frequency", "scalar", np.inf),
    "accel_temp_bias": ("accel_temperature_coefficient", "axes", 0.0),
    "gyro_temp_bias": ("gyro_temperature_coefficient", "axes", 0.0),
    "accel_temp_scale": ("scale_temperature_coefficient", "axes", 0.0),
    "gyro_temp_scale": ("scale_temperature_coefficient", "axes", 0.0),
    "temperature": ("temperature", "ramp", 25.0),
    "temperature_ref": ("temperature", "scalar", 25.0),
    "clock_error": ("ratio", "scalar", 0.0),
    "timestamp_jitter": ("time", "scalar", 0.0),
    "accel_gyro_skew": ("time", "scalar", 0.0),
    "mounting_misalignment": ("angle", "axes", 0.0),
}
_SHAPES = {"axes": (3,), "matrix": (3, 3), "scalar": (), "ramp": (2,)}
_NON_NEGATIVE = ("noise_density", "repeatability", "bias_instability", "random_walk", "resolution", "jitter")
_POSITIVE = ("_tau", "_range", "_bandwidth")

RANDOM_STREAMS = ("accel_turn_on", "gyro_turn_on", "accel_instability", "gyro_instability",
                  "accel_random_walk", "gyro_random_walk", "accel_white", "gyro_white", "timestamp_jitter")
SLOW_PROCESS_STEP = 16  # samples between nodes of the simulated bias-instability / random-walk processes
COMPILED_FROM_SAMPLES = 1_000_000  # records this long take the compiled kernels even when numba is not loaded yet


def _as_parameter(name: str, value) -> np.ndarray:
    """Read-only float array of the parameter's shape; a scalar broadcasts to 3 axes, to both ramp ends."""
    _kind, shape_name, _default = PARAMETERS[name]
    shape = _SHAPES[shape_name]
    array = np.array(value, dtype=float)
    if array.ndim == 0 and shape_name in ("axes", "ramp"):
        array = np.full(shape, float(array))
    if array.shape != shape:
        raise ScenarioError(f"{name}: expected {'a number' if not shape else f'shape {shape}'} "
                            f"(a number also works for per-axis values), got {np.asarray(value).tolist()!r}")
    if np.any(np.isnan(array)) or (np.any(np.isinf(array)) and not name.endswith(("_range", "_bandwidth"))):
        raise ScenarioError(f"{name}: value {array.tolist()} must be finite")
    if name.endswith(_NON_NEGATIVE) and np.any(array < 0):
        raise ScenarioError(f"{name}: value {array.tolist()} must be >= 0")
    if name.endswith(_POSITIVE) and np.any(array <= 0):
        raise ScenarioError(f"{name}: value {array.tolist()} must be > 0 (use inf to switch a range or "
                            f"bandwidth off)")
    if name.endswith("misalignment") and shape_name == "matrix" and abs(np.linalg.det(array)) < 1e-6:
        raise ScenarioError(f"{name}: matrix {array.tolist()} is singular")
    array.setflags(write=False)
    return array


@dataclass(frozen=True)
class SensorSpec:
    """Immutable IMU error parameters, SI units (see :data:`PARAMETERS` for each name's unit kind).

    Attributes
    ----------
    name : preset (or custom) name.
    source : where the figures come from (datasheet, paper).
    parameters : mapping parameter name -> read-only array (SI); names missing take their defaults.
    filter_order : Butterworth order of the bandwidth low-pass (1..8).
    filter_kind : where that low-pass sits: ``"digital"`` or ``"analogue"`` (module docstring, step 6).
    withheld : True when the recording metadata must not declare the parameters (blind tests).
    """

    name: str = "custom"
    source: str = ""
    parameters: dict = field(default_factory=dict)
    filter_order: int = 2
    withheld: bool = False
    filter_kind: str = "digital"

    def __post_init__(self):
        unknown = set(self.parameters) - set(PARAMETERS)
        if unknown:
            raise ScenarioError(f"unknown sensor parameter(s) {sorted(unknown)}; choose from {list(PARAMETERS)}")
        complete = {name: _as_parameter(name, self.parameters.get(name, default))
                    for name, (_kind, _shape, default) in PARAMETERS.items()}
        object.__setattr__(self, "parameters", _ReadOnlyDict(complete))
        if not (isinstance(self.filter_order, int) and 1 <= self.filter_order <= 8):
            raise ScenarioError(f"filter_order: value {self.filter_order!r} must be an integer in 1..8")
        if self.filter_kind not in FILTER_KINDS:
            raise ScenarioError(f"filter_kind: value {self.filter_kind!r} must be one of {list(FILTER_KINDS)}")

    def __getitem__(self, name: str) -> np.ndarray:
        return self.parameters[name]

    def __reduce__(self):
        """Pickled (e.g. for a worker process) as its constructor's arguments, so it comes back validated and
        read-only."""
        return SensorSpec, (self.name, self.source, dict(self.parameters), self.filter_order, self.withheld,
                            self.filter_kind)

    def replace(self, **changes) -> "SensorSpec":
        """A new spec with some parameters (SI) or the fields name/source/filter_order/filter_kind/withheld
        changed; this spec is left as it is."""
        top = {k: changes.pop(k) for k in ("name", "source", "filter_order", "filter_kind", "withheld")
               if k in changes}
        return dataclasses.replace(self, parameters={**self.parameters, **changes}, **top)

    def deterministic(self, turn_on_accel=None, turn_on_gyro=None) -> Calibration:
        """The deterministic error terms as a :class:`nav.calibration.Calibration` (what a perfect lab would
        measure), optionally with turn-on bias draws (3,) (m/s^2, rad/s) added to the constant biases."""
        g2 = self["gyro_g2_sensitivity"]
        return Calibration(
            b_a=self["accel_bias"] + (0.0 if turn_on_accel is None else turn_on_accel),
            M_a=self["accel_misalignment"],
            b_g=self["gyro_bias"] + (0.0 if turn_on_gyro is None else turn_on_gyro), M_g=self["gyro_misalignment"], G_g=self["gyro_g_sensitivity"],
            G2_g=g2 if np.any(g2) else None, source=f"sensor spec {self.name!r} (true values)",
        )

    def declared(self) -> dict:
        """JSON-ready description for meta.json: every parameter in SI with its unit name, or only
        ``{"withheld": true}`` when the scenario asked to withhold them."""
        if self.withheld:
            return {"withheld": True}
        parameters = {}
        for name, (kind, _shape, _default) in PARAMETERS.items():
            value = self[name]
            listed = np.where(np.isinf(value), np.nan, value).tolist()
            parameters[name] = {"value": _inf_to_text(listed, value), "unit": si_unit(kind)}
        return {"withheld": False, "name": self.name, "source": self.source, "filter_order": self.filter_order,
                "filter_kind": self.filter_kind, "parameters": parameters}


def _inf_to_text(listed, value: np.ndarray):
    """JSON has no infinity: write ``"inf"`` for an infinite scalar (a switched-off range or bandwidth)."""
    return "inf" if value.ndim == 0 and np.isinf(value) else listed


class _ReadOnlyDict(dict):
    """A dict that refuses item assignment (keeps a SensorSpec immutable)."""

    def _refuse(self, *args, **kwargs):
        raise TypeError("SensorSpec parameters are immutable; use SensorSpec.replace(...)")

    __setitem__ = __delitem__ = update = pop = popitem = clear = setdefault = _refuse


@lru_cache(maxsize=1)
def _gauss_markov_std_per_instability() -> float:
    """Stationary GM std per unit of datasheet bias instability B: 0.664 / 0.6174."""
    return BIAS_INSTABILITY_FLOOR / GAUSS_MARKOV_PEAK[1]


# ------------------------------------------------------------- numpy reference of gaitsim.imu.kernels


def first_order_recursion(first: np.ndarray, steps: np.ndarray, decay: float) -> np.ndarray:
    """(J+1, 3) nodes of the recursion nodes[0] = first, nodes[j+1] = decay nodes[j] + steps[j] (``steps`` (J, 3)):
    the arithmetic of scipy's ``lfilter([1], [1, -decay], steps, zi=decay * first)`` after ``first``."""
    decay = float(decay)
    columns = []
    for axis in range(3):  # Python floats: the same IEEE operations, axis by axis
        value = float(first[axis])
        column = [value]
        for change in steps[:, axis].tolist():
            value = decay * value + change
            column.append(value)
        columns.append(column)
    return np.ascontiguousarray(np.array(columns).T)


def add_stochastic_terms(out: np.ndarray, signal: np.ndarray, addends: tuple, instability: tuple, walk: tuple,
                         white_std: np.ndarray, rng: np.random.Generator, resolution: float, limit: float) -> None:
    """``out`` (n, 3) = ``signal`` (n, 3; may be ``out``) + each of ``addends`` in turn (the deterministic terms'
    sums: :func:`nav.calibration.add_in_order`) + bias instability + random walk (each a pair
    (nodes (J, 3), node_step), linearly interpolated between the nodes; no nodes: off) + white noise of
    per-axis std ``white_std`` (3,) (float32 normals from ``rng``; all zero: off), then quantised and clipped
    (:func:`quantise_and_clip`), each sum rounded in this order."""
    if out is not signal:
        out[:] = signal
    add_in_order(out, addends)
    samples = np.arange(out.shape[0])
    for nodes, node_step in (instability, walk):
        if nodes.shape[0]:
            node = samples // node_step
            frac = ((samples - node * node_step) / node_step)[:, None]
            before = nodes[node]
            out += before + frac * (nodes[node + 1] - before)
    if np.any(white_std):
        out += rng.standard_normal(out.shape, dtype=np.float32) * white_std
    quantise_and_clip(out, resolution, limit)


def quantise_and_clip(x: np.ndarray, resolution: float, limit: float) -> None:
    """Round ``x`` to multiples of ``resolution`` (0: off; halves to even), then clip at +-``limit`` (inf:
    off); in place."""
    if resolution > 0:
        np.divide(x, resolution, out=x)
        np.round(x, out=x)
        np.multiply(x, resolution, out=x)
    if np.isfinite(limit):
        np.clip(x, -limit, limit, out=x)


def _implementation(n: int):
    """Where the stochastic terms are computed for a record of n samples: the compiled kernels
    (:mod:`gaitsim.imu.kernels`) for a long record or once numba is loaded, else this module's numpy reference
    (numba's first use in a process costs more than a short record's sensor stage). Both give the same bits."""
    if n >= COMPILED_FROM_SAMPLES or "numba" in sys.modules:
        from gaitsim.imu import kernels

        return kernels
    return sys.modules[__name__]


# ---------------------------------------------------------------------------------------------- pieces


def _node_count(n: int, node_step: int) -> int:
    """Nodes needed so that nodes[(n-1)//node_step + 1] exists."""
    return (n - 1) // node_step + 2


def gauss_markov_nodes(n: int, dt: float, instability: np.ndarray, tau_c: float, rng: np.random.Generator,
                       recursion=first_order_recursion) -> tuple[np.ndarray, int]:
    """Nodes of a bias-instability process for n samples: first-order Gauss-Markov, stationary from the
    start, simulated exactly at every ``node_step``-th sample (module docstring, step 5).

    Parameters
    ----------
    n : samples to cover.
    dt : sample interval, s.
    instability : (3,) datasheet bias instability B (signal unit).
    tau_c : correlation time, s.
    rng : the term's own Generator.
    recursion : :func:`first_order_recursion` or its compiled twin (the same nodes).

    Returns
    -------
    nodes : (J, 3) process values at samples 0, node_step, 2 node_step, ... (J >= (n - 1) // node_step + 2).
    node_step : samples between nodes.
    """
    node_step = int(max(1, min(SLOW_PROCESS_STEP, np.floor(tau_c / (20.0 * dt)))))
    sigma = _gauss_markov_std_per_instability() * np.asarray(instability)
    decay = np.exp(-node_step * dt / tau_c)
    draws = rng.standard_normal((_node_count(n, node_step), 3))
    first = draws[0] * sigma
    steps = draws[1:] * (sigma * np.sqrt(1.0 - decay**2))
    return recursion(first, steps, decay), node_step


def random_walk_nodes(n: int, dt: float, walk: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, int]:
    """Nodes (J, 3) and node step of a rate-random-walk bias starting at zero, for n samples; ``walk`` (3,)
    is K in (signal unit)/sqrt(s); simulated exactly at the nodes (see :func:`gauss_markov_nodes`)."""
    node_step = SLOW_PROCESS_STEP
    steps = rng.standard_normal((_node_count(n, node_step) - 1, 3)) * (np.asarray(walk) * np.sqrt(node_step * dt))
    return np.concatenate([np.zeros((1, 3)), np.cumsum(steps, axis=0)]), node_step


_NO_NODES = (np.zeros((0, 3)), 1)  # a slow process that is off


def low_pass(x: np.ndarray, cutoff_hz: float, rate_hz: float, order: int, kind: str = "digital") -> np.ndarray:
    """Butterworth low-pass along axis 0, digital or analogue (module docstring, step 6), started in steady
    state on the first sample (no start transient).

    Raises ScenarioError when the cutoff is not below the Nyquist frequency.
    """
    if cutoff_hz >= 0.5 * rate_hz:
        raise ScenarioError(f"bandwidth {cutoff_hz} Hz must be below half the sample rate ({0.5 * rate_hz} Hz)")
    from scipy.signal import butter, sosfilt, sosfilt_zi, zpk2sos

    if kind == "digital":
        sos = butter(order, cutoff_hz, fs=rate_hz, output="sos")
    else:
        _, s_poles, _ = butter(order, 2.0 * math.pi * cutoff_hz, analog=True, output="zpk")
        poles = np.exp(s_poles / rate_hz)
        sos = zpk2sos(np.zeros(order), poles, float(np.real(np.prod(1.0 - poles))))
    zi = sosfilt_zi(sos)[:, :, None] * x[0][None, None, :]
    return sosfilt(sos, x, axis=0, zi=zi)[0]


def mounting_rotation(roll_pitch_yaw: np.ndarray) -> np.ndarray:
    """R (3, 3) mapping sensor-frame vectors into the foot frame, R = Rz(yaw) Ry(pitch) Rx(roll), angles rad."""
    roll, pitch, yaw = roll_pitch_yaw
    return quaternion.to_matrix(quaternion.from_euler_zyx(yaw, pitch, roll))


def _is_identity(cal: Calibration) -> bool:
    """True when the deterministic terms change nothing (skipped for speed; the result is identical)."""
    return (not np.any(cal.b_a) and not np.any(cal.b_g) and not np.any(cal.G_g) and cal.G2_g is None
            and np.array_equal(cal.M_a, np.eye(3)) and np.array_equal(cal.M_g, np.eye(3)))


def _temperature_at(spec: SensorSpec, temperature, t: np.ndarray, instants: np.ndarray) -> np.ndarray:
    """Temperature (degC) at the sample instants: the spec's ramp, a constant, or a profile given at ``t``."""
    if temperature is None:
        start, end = spec["temperature"]
        span = t[-1] - t[0]
        return start + (end - start) * (instants - t[0]) / (span if span > 0 else 1.0)
    temperature = np.asarray(temperature, float)
    if temperature.ndim == 0:
        return np.full(instants.shape, float(temperature))
    if temperature.shape != t.shape:
        raise ValueError(f"temperature profile: expected shape {t.shape} (one value per input sample), "
                         f"got {temperature.shape}")
    return np.interp(instants, t, temperature)


# ---------------------------------------------------------------------------------------------- model


def apply_sensor(spec: SensorSpec, t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, rng: np.random.Generator,
                 temperature=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Turn true specific force and angular rate into sensor output (see the module docstring for the order).

    Parameters
    ----------
    spec : sensor parameters.
    t : (N,) sample times of the truth, s, uniform grid.
    acc : (N, 3) true specific force, m/s^2, body (foot) frame.
    gyr : (N, 3) true angular rate, rad/s, body (foot) frame.
    rng : the run's Generator; children are spawned from it (see :data:`RANDOM_STREAMS`).
    temperature : None (use the spec's ramp), a constant (degC) or an (N,) profile at ``t`` (degC).

    Returns
    -------
    t_meas : (M,) reported timestamps, s (M == N unless clock error or skew are on).
    acc_meas : (M, 3) measured specific force, m/s^2, sensor frame.
    gyr_meas : (M, 3) measured angular rate, rad/s, sensor frame.
    """
    t = np.asarray(t, float)
    acc = np.asarray(acc, float)
    gyr = np.asarray(gyr, float)
    if acc.shape != (t.size, 3) or gyr.shape != (t.size, 3):
        raise ValueError(f"acc and gyr must be ({t.size}, 3) like t, got {acc.shape} and {gyr.shape}")
    if t.size < 2:
        raise ValueError("need at least 2 samples")
    streams = dict(zip(RANDOM_STREAMS, rng.spawn(len(RANDOM_STREAMS))))
    dt = (t[-1] - t[0]) / (t.size - 1)
    rate_hz = 1.0 / dt
    p = spec.parameters

    # 1. mounting
    if np.any(p["mounting_misalignment"]):
        to_sensor = mounting_rotation(p["mounting_misalignment"]).T
        acc = acc @ to_sensor.T
        gyr = gyr @ to_sensor.T

    # 2. sampling instants
    clock, skew = float(p["clock_error"]), float(p["accel_gyro_skew"])
    if clock or skew:
        from scipy.interpolate import CubicSpline

        k = np.arange(int(np.floor((t.size - 1) * (1.0 + clock))) + 1)
        instants = t[0] + k * dt / (1.0 + clock)
        keep = (instants >= t[0]) & (instants <= t[-1]) & (instants + skew >= t[0]) & (instants + skew <= t[-1])
        k, instants = k[keep], instants[keep]
        acc = CubicSpline(t, acc, axis=0)(instants) if clock else acc[keep]
        gyr = CubicSpline(t, gyr, axis=0)(instants + skew)
        t_meas = t[0] + k * dt
    else:
        instants = t
        t_meas = t.copy()
    n = t_meas.size
    if p["timestamp_jitter"] > 0:
        t_meas = t_meas + streams["timestamp_jitter"].standard_normal(n) * p["timestamp_jitter"]

    # 3. deterministic errors (with this run's turn-on bias)
    turn_on = {s: streams[f"{s}_turn_on"].standard_normal(3) * p[f"{s}_bias_repeatability"]
               if np.any(p[f"{s}_bias_repeatability"]) else np.zeros(3) for s in ("accel", "gyro")}
    deterministic = spec.deterministic(turn_on["accel"], turn_on["gyro"])
    scale_on = np.any(p["accel_temp_scale"]) or np.any(p["gyro_temp_scale"])
    bias_on = np.any(p["accel_temp_bias"]) or np.any(p["gyro_temp_bias"])
    if _is_identity(deterministic):  # not copied: step 5 writes the output arrays (a pass over memory saved)
        (acc_m, acc_addends), (gyr_m, gyr_addends) = (acc, ()), (gyr, ())
    elif scale_on or bias_on:
        (acc_m, gyr_m), acc_addends, gyr_addends = deterministic.distort(acc, gyr), (), ()
    else:  # the sums are done in step 5's pass
        (acc_m, acc_addends), (gyr_m, gyr_addends) = deterministic.distort_terms(acc, gyr)

    # 4. temperature
    if scale_on or bias_on:
        if acc_m is acc:
            acc_m, gyr_m = acc.copy(), gyr.copy()
        delta = (_temperature_at(spec, temperature, t, instants) - p["temperature_ref"])[:, None]
        for out, bias, s in ((acc_m, deterministic.b_a, "accel"), (gyr_m, deterministic.b_g, "gyro")):
            out += (out - bias) * (p[f"{s}_temp_scale"] * delta) + p[f"{s}_temp_bias"] * delta

    # 5.-7. stochastic terms, bandwidth, quantisation and saturation: one pass unless a bandwidth is on
    implementation = _implementation(n)
    measured = []
    for signal, addends, s in ((acc_m, acc_addends, "accel"), (gyr_m, gyr_addends, "gyro")):
        instability, walk = _NO_NODES, _NO_NODES
        if np.any(p[f"{s}_bias_instability"]):
            instability = gauss_markov_nodes(n, dt, p[f"{s}_bias_instability"], float(p[f"{s}_bias_instability_tau"]),
                                             streams[f"{s}_instability"], implementation.first_order_recursion)
        if np.any(p[f"{s}_random_walk"]):
            walk = random_walk_nodes(n, dt, p[f"{s}_random_walk"], streams[f"{s}_random_walk"])
        white_std = np.asarray(p[f"{s}_noise_density"] * np.sqrt(rate_hz))
        bandwidth, resolution, limit = (float(p[f"{s}_{name}"]) for name in ("bandwidth", "resolution", "range"))
        filtered = np.isfinite(bandwidth)
        resolution_now, limit_now = (0.0, np.inf) if filtered else (resolution, limit)  # else after the filter
        given = signal is acc or signal is gyr  # an input array: never written, the output is a new array
        if not addends and instability is _NO_NODES and walk is _NO_NODES and not np.any(white_std) and \
                not resolution_now and limit_now == np.inf:
            out = signal.copy() if given else signal  # nothing to add
        else:
            in_place = not given and signal.flags.c_contiguous and signal.flags.writeable
            out = signal if in_place else np.empty(signal.shape)  # C order: the pass's one compiled type
            implementation.add_stochastic_terms(out, signal, addends, instability, walk, white_std,
                                                streams[f"{s}_white"], resolution_now, limit_now)
        if filtered:
            out = low_pass(out, bandwidth, rate_hz, spec.filter_order, spec.filter_kind)
            implementation.quantise_and_clip(out, resolution, limit)
        measured.append(out)
    acc_m, gyr_m = measured
    return t_meas, acc_m, gyr_m
