"""The effect library: what a twin may lack, each one a simulator parameter a user's scenario can switch on.

Every effect names the scenario key it sets (so a fitted magnitude can be pasted into a scenario), its unit,
the residuals it moves (:mod:`gaitsim.loop.residuals`, plus the navigation residuals ``nav_length_ratio`` and
``nav_heading_drift``), the range searched, and a closed-form first guess where one exists. Magnitudes are
fitted by :mod:`gaitsim.loop.attribution` with a 1-D search that re-simulates the twin (sensor-side effects only
re-run the sensor model on the cached walk).

| effect | scenario key | unit | moves |
|---|---|---|---|
| stance_creep | [micromotion] creep_velocity_mps (forward) | m/s | stance_velocity, Fig. 5, nav_length_ratio |
| stance_kinematics | [micromotion] heel_rise_rate_start_dps, heel_rise_growth_dps3, loading_roll_rate_dps, pronation_rate_dps, all x the factor | 1 | stance_rate_x/y/z, stance_gyro, stance_acc_spread, stance_duration, stance_velocity, Fig. 5, nav_length_ratio |
| stance_roll | [micromotion] stance_roll_rate_dps | deg/s | stance_gyro, stance_acc_spread, stance_duration |
| stance_rotation | [micromotion] stance_rotation_dps (direction from the residual) | deg/s | stance_rate_x/y/z, stance_gyro, stance_acc_spread, stance_duration, stance_velocity, Fig. 5, nav_length_ratio |
| impact_ringing | [impact] ringing_accel_mps2 (ringing_hz from the residual spectrum) | m/s^2 | onset_hf, hf40, hf80, acc_peak, stance_acc_spread, stance_duration |
| bandwidth | [sensor] accel_bandwidth = gyro_bandwidth | Hz | rest_acc_noise_lag1, _lag2, rest_gyro_noise_lag1, _lag2, hf40, hf80, onset_hf, acc_peak, gyr_peak, acc_gyro_lag, stance_acc_spread, stance_duration, profiles |
| accel_gyro_skew | [sensor] accel_gyro_skew | ms | acc_gyro_lag, gyro profiles |
| bandwidth_first_order | [sensor] accel_bandwidth = gyro_bandwidth, filter_order = 1 | Hz | as bandwidth |
| bandwidth_analogue | [sensor] accel_bandwidth = gyro_bandwidth, filter_order = 1, filter_kind = "analogue" | Hz | as bandwidth |
| gyro_scale_x, _y, _z | [sensor] gyro_misalignment, one row x (1 + s) | % | stride closure, gyro profiles, navigation |
| accel_scale_x, _y, _z | [sensor] accel_misalignment, one row x (1 + s) | % | stride closure, rest_acc_norm, acc profiles, navigation |
| accel_bias_x, _y, _z | [sensor] accel_bias, one component + b (mount tilt kept on the rest reading) | m/s^2 | stride closure, rest_acc_norm, acc profiles, navigation |
| g_sensitivity | [sensor] gyro_g_sensitivity = k I (gyro_bias keeps the rest reading) | deg/s/(m/s^2) | stride closure tilt, navigation |
| saturation | [sensor] accel_range | m/s^2 | acc_peak, hf40, hf80, onset_hf, accelerometer profiles |

"Fig. 5" are the four Fig. 5 residuals (:mod:`gaitsim.loop.fig5`: the length underestimate's and the in-window
velocity's level and slope over the zero-velocity thresholds), present where the recording has a position track.
The stance effects that move the IMU site in stance move them. Only ``stance_kinematics``, the effect meant to
explain them, is searched on them (``Effect.sweeps``: every candidate twin swept, ~5x the cost of a signature);
the others are searched on the signature residuals they move and meet the Fig. 5 residuals at the fitted
magnitude, as they meet navigation.

The stride closure (``closure_*``, :mod:`gaitsim.loop.closure`) is what tells the sensor's scale, bias, time and
g-sensitivity errors apart: each turns gravity or the specific force its own way while the foot pitches. The
``rest_gyro_change`` and ``rest_acc_change`` residuals (a sensor drift between the first and the last rest) are
moved by no effect: a drifting bias is outside the library and is reported unexplained.

The sensor's linear errors (scales, accelerometer biases, the skew, the g-sensitivity: ``Effect.linear``) are
also fitted together: a real sensor has several at once, and one of them alone can stand in for a pair (a
consumer accelerometer's offsets along x and z read as a z scale error, the x offset hidden in the mount pitch
fitted at rest; :func:`gaitsim.loop.attribution.fit_joint`).

Roll and pitch of the sensor on the foot are part of the twin's mount fit (gravity at rest), so the library's
misalignment is the remaining yaw. A fitted magnitude equal to the twin's current value means "no change".
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from nav import quaternion as quat
from nav.alignment import tilt_from_specific_force
from nav.recording import Recording

from ..scenario import Scenario, section_table
from ..world.foot import FootModel
from . import fig5, settings
from .signature import Signature

ACC_PROFILES = ("profile_acc_x", "profile_acc_y", "profile_acc_z")
GYR_PROFILES = ("profile_gyr_x", "profile_gyr_y", "profile_gyr_z")
CLOSURE = ("closure_forward", "closure_left", "closure_up", "closure_roll", "closure_pitch")
NAV = ("nav_length_ratio", "nav_heading_drift", "nav_final_error")
FIG5 = tuple(fig5.NUMBERS)
REST_NOISE = tuple(f"rest_{sensor}_noise_lag{lag}" for sensor in ("acc", "gyro") for lag in (1, 2))
# the stance model's rotation rates (scenario keys, [micromotion]) that stance_kinematics scales together
STANCE_RATE_KEYS = ("heel_rise_rate_start_dps", "heel_rise_growth_dps3", "loading_roll_rate_dps", "pronation_rate_dps")


@dataclass(frozen=True)
class Effect:
    """One entry of the library.

    Attributes
    ----------
    name, description : what it is.
    key : the scenario key(s) it sets, as "[section] key".
    unit : unit of the magnitude.
    moves : residual names it changes (the loop tries it on these).
    bounds : (low, high) searched magnitude range, in ``unit`` (the recording's rate may narrow it).
    log_scale : search on a logarithmic scale (bounds must then be > 0).
    changes : (magnitude, context) -> {section: {key: value}} merged into the twin's scenario document.
    first_guess : (residuals, context) -> magnitude or None, a closed-form estimate from the residuals.
    refine : the context (a direction) comes from the residuals: fit once more from the first fit's residuals.
    sweeps : its magnitude is searched on the Fig. 5 residuals it moves too (each candidate twin swept).
    linear : a deterministic linear error of the sensor (scale, bias, skew, g-sensitivity): magnitude 0 leaves
        the twin as it is (the skew is the twin's own only until the effect is named, and a named effect is not
        fitted again) and small magnitudes change the sensor output in proportion, so such effects are also fitted
        together, several at once, on a model linearised about the twin and refined by simulation
        (:func:`gaitsim.loop.attribution.fit_joint`).
    """

    name: str
    description: str
    key: str
    unit: str
    moves: tuple
    bounds: tuple
    changes: Callable
    first_guess: Callable = lambda res, ctx: None
    log_scale: bool = False
    refine: bool = False
    sweeps: bool = False
    linear: bool = False

    def search_bounds(self, context: dict) -> tuple[float, float]:
        """Bounds for this recording: a bandwidth stays below ``settings.BAND_TOP_SHARE`` times the sample rate; a
        clipping level
        cannot lie below the largest accelerometer reading the recording holds (searched up to 1.5 times it)."""
        low, high = self.bounds
        if self.name == "bandwidth":
            high = min(high, settings.BAND_TOP_SHARE * context["rate_hz"])
        if self.name == "saturation":
            low = max(low, 0.98 * context["largest_acc_component"])
            high = min(high, 1.5 * context["largest_acc_component"])
        return low, high

    def __reduce__(self):
        """An effect is a library entry: it travels to a worker process (pickled) as its name."""
        return library_effect, (self.name,)


def library_effect(name: str) -> "Effect":
    """The library's effect called ``name``."""
    return BY_NAME[name]


def _value(res: dict, name: str, side: str = "value") -> float | None:
    r = res.get(name)
    return None if r is None else getattr(r, side)


def _roll_guess(res, ctx):
    m, w = _value(res, "stance_gyro", "measured"), _value(res, "stance_gyro", "twin")
    if m is None:
        return None
    return ctx["stance_roll_rate_dps"] + 2.0 * math.sqrt(max(m * m - w * w, 0.0))


def _rotation_target(ctx: dict) -> np.ndarray:
    """Stance rotation (deg/s, foot frame) that would close the signed core-stance rate residual."""
    return np.asarray(ctx["stance_rotation_target_dps"], float)


def _rotation_changes(magnitude: float, ctx: dict) -> dict:
    """The rotation ``magnitude`` (deg/s) along the target direction, and the contact creep that keeps the
    sensor's forward stance velocity: rotating about pivots on the heel-toe line moves a sensor at height z and
    side offset y forward by ``w_pitch z - w_yaw y``, a translation the gyro does not measure (the stance
    velocity residual does, where a reference exists)."""
    target = _rotation_target(ctx)
    norm = float(np.linalg.norm(target))
    rotation = magnitude * (target / norm if norm > 0 else np.zeros(3))
    change = np.radians(rotation - np.asarray(ctx["stance_rotation_dps"], float))
    _, side, height = ctx["imu_site_m"]
    creep = np.asarray(ctx["creep_velocity_mps"], float).copy()
    creep[0] -= change[1] * height - change[2] * side
    return {"micromotion": {"stance_rotation_dps": rotation.tolist(), "creep_velocity_mps": creep.tolist()}}


def _kinematics_changes(factor: float, ctx: dict) -> dict:
    """The twin's stance rotation rates (:data:`STANCE_RATE_KEYS`: heel rise at foot flat and its growth,
    loading roll pulse, held pronation) all multiplied by ``factor`` (1 = no change): a foot that rolls over its
    contact faster or slower through the whole stance, its IMU site's velocity following (rate times height)."""
    return {"micromotion": {key: factor * ctx["stance_rates"][key] for key in STANCE_RATE_KEYS}}


def _kinematics_guess(res, ctx):
    """The factor that scales the twin's mean core-stance |rate| to the recording's (both include sensor noise)."""
    m, w = _value(res, "stance_gyro", "measured"), _value(res, "stance_gyro", "twin")
    return None if m is None or not w > 0 else m / w


def _creep_guess(res, ctx):
    v = _value(res, "stance_velocity")
    return None if v is None else ctx["creep_mps"] + v


def _bias_guess(axis: int):
    """Closed-form first guess of an accelerometer bias on ``axis`` from the rest norm: the norm residual over
    that axis's share of the rest specific force (None where the axis is near horizontal at rest: the norm
    cannot see it there)."""
    def guess(res, ctx):
        value = _value(res, "rest_acc_norm")
        rest = np.asarray(ctx["rest_specific_force"], float)
        share = rest[axis] / max(float(np.linalg.norm(rest)), 1e-9)
        return None if value is None or abs(share) < 0.5 else value / share
    return guess


def _bias_changes(axis: int, mps2: float, ctx: dict) -> dict:
    """The twin's accelerometer bias with ``mps2`` (m/s^2) added on ``axis``, and its mount roll and pitch
    turned by what that bias changes in the tilt read from the rest specific force: the twin's tilt was read
    from the recording at rest, where the bias acts too, so the twin's rest reading must stay the recording's
    (a bias on a horizontal axis is otherwise a mount pitch or roll at rest; the stride closure tells them
    apart)."""
    bias = np.array(ctx["accel_bias"], float)
    rest = np.asarray(ctx["rest_specific_force"], float)
    old = np.array(tilt_from_specific_force(rest - bias))
    bias[axis] += mps2
    roll, pitch = np.asarray(ctx["mount_roll_pitch_rad"]) + np.array(tilt_from_specific_force(rest - bias)) - old
    return _sensor(accel_bias=[bias.tolist(), "m/s^2"],
                   mounting_misalignment=[[float(roll), float(pitch), ctx["mount_yaw_rad"]], "rad"])


def _sensor(**items) -> dict:
    return {"sensor": items}


def _scaled_axis(matrix, axis: int, percent: float) -> list:
    """The twin's 3x3 sensor matrix with the output of its ``axis`` (that row) scaled by 1 + ``percent`` / 100:
    a scale error of that axis on top of what the twin already has (another axis's scale named before included)."""
    out = np.array(matrix, float)
    out[axis] *= 1.0 + percent / 100.0
    return out.tolist()


def _g_sensitivity_changes(magnitude: float, ctx: dict) -> dict:
    """G_g raised by ``magnitude`` (deg/s per m/s^2) on every axis, and the twin's gyro bias lowered by what that
    adds at rest (``magnitude`` times the rest specific force): the bias was measured on the recording at rest,
    where its g-sensitivity already acts, so the twin's rest reading must stay the recording's."""
    g_sensitivity = np.asarray(ctx["gyro_g_sensitivity"]) + np.eye(3) * magnitude
    bias = np.asarray(ctx["gyro_bias_rad_s"]) - math.radians(magnitude) * np.asarray(ctx["rest_specific_force"])
    return _sensor(gyro_g_sensitivity=[g_sensitivity.tolist(), "deg/s/(m/s^2)"], gyro_bias=[bias.tolist(), "rad/s"])


LIBRARY: tuple[Effect, ...] = (
    Effect("stance_creep", "forward creep of the foot during foot flat (stance micro-motion magnitude)",
           "[micromotion] creep_velocity_mps", "m/s", ("stance_velocity", "nav_length_ratio") + FIG5, (-0.02, 0.06),
           lambda m, ctx: {"micromotion": {"creep_velocity_mps": [m, 0.0, 0.0]}}, _creep_guess),
    Effect("stance_kinematics", "the rolling foot's stance rotation rates (heel rise, loading roll, pronation) "
           "scaled together by one factor (1 = the twin's current rates; the IMU site's stance velocity follows, "
           "pitch rate times its height above the contact)",
           "[micromotion] " + ", ".join(STANCE_RATE_KEYS), "1",
           ("stance_rate_x", "stance_rate_y", "stance_rate_z", "stance_gyro", "stance_acc_spread", "stance_duration",
            "stance_velocity", "nav_length_ratio") + FIG5, (0.0, 4.0), _kinematics_changes, _kinematics_guess,
           sweeps=True),
    Effect("stance_roll", "roll-over of the foot about the heel-toe axis during stance (micro-rotation)",
           "[micromotion] stance_roll_rate_dps", "deg/s",
           ("stance_gyro", "stance_acc_spread", "stance_duration"), (0.0, 60.0),
           lambda m, ctx: {"micromotion": {"stance_roll_rate_dps": m}}, _roll_guess),
    Effect("stance_rotation", "sustained rotation of the standing foot (roll, pitch, yaw rates over foot flat; the "
           "direction is the core-stance rate residual turned into the foot frame, the magnitude is fitted)",
           "[micromotion] stance_rotation_dps", "deg/s",
           ("stance_rate_x", "stance_rate_y", "stance_rate_z", "stance_gyro", "stance_acc_spread", "stance_duration",
            "stance_velocity", "nav_length_ratio") + FIG5, (0.0, 30.0),
           _rotation_changes, lambda res, ctx: float(np.linalg.norm(_rotation_target(ctx))), refine=True),
    Effect("impact_ringing", "damped vertical ringing of foot and mount after heel strike and forefoot slap",
           "[impact] ringing_accel_mps2 (ringing_hz from the residual spectrum)", "m/s^2",
           ("onset_hf", "hf40", "hf80", "acc_peak", "stance_acc_spread", "stance_duration"),
           (0.0, 300.0),
           lambda m, ctx: {"impact": {"ringing_hz": ctx["ringing_hz"], "ringing_accel_mps2": m}}),
    *(Effect(name, f"low-pass of the sensor ({kind} Butterworth of order {order}, same cutoff on both sensors)",
             "[sensor] accel_bandwidth, gyro_bandwidth, filter_order, filter_kind", "Hz",
             REST_NOISE + ("hf40", "hf80", "onset_hf", "acc_peak", "gyr_peak", "acc_gyro_lag", "stance_acc_spread",
                           "stance_duration") + ACC_PROFILES + GYR_PROFILES + CLOSURE, (8.0, 400.0),
             lambda m, ctx, order=order, kind=kind: _sensor(accel_bandwidth=[m, "Hz"], gyro_bandwidth=[m, "Hz"],
                                                            filter_order=order, filter_kind=kind), log_scale=True)
      for name, order, kind in (("bandwidth", 2, "digital"), ("bandwidth_first_order", 1, "digital"),
                                ("bandwidth_analogue", 1, "analogue"))),
    Effect("accel_gyro_skew", "time skew between accelerometer and gyro sampling (> 0: gyro later)",
           "[sensor] accel_gyro_skew", "ms", ("acc_gyro_lag",) + GYR_PROFILES + CLOSURE, (-20.0, 20.0),
           lambda m, ctx: _sensor(accel_gyro_skew=[m, "ms"]),
           lambda res, ctx: None if _value(res, "acc_gyro_lag") is None else -_value(res, "acc_gyro_lag"),
           linear=True),
    *(Effect(f"{sensor}_scale_{axis}", f"{label} scale factor error of the sensor's {axis} axis alone",
             f"[sensor] {sensor}_misalignment[{i}][{i}]", "%", CLOSURE + profiles + NAV + extra, (-6.0, 6.0),
             lambda m, ctx, key=f"{sensor}_misalignment", i=i: _sensor(**{key: [_scaled_axis(ctx[key], i, m), "1"]}),
             linear=True)
      for sensor, label, profiles, extra in (("gyro", "gyro", GYR_PROFILES, ()),
                                             ("accel", "accelerometer", ACC_PROFILES, ("rest_acc_norm",)))
      for i, axis in enumerate("xyz")),
    *(Effect(f"accel_bias_{axis}", f"accelerometer bias of the sensor's {axis} axis",
             f"[sensor] accel_bias[{i}]", "m/s^2", CLOSURE + ACC_PROFILES + NAV + ("rest_acc_norm",), (-1.5, 1.5),
             lambda m, ctx, i=i: _bias_changes(i, m, ctx), _bias_guess(i), linear=True)
      for i, axis in enumerate("xyz")),
    Effect("g_sensitivity", "gyro g-sensitivity, equal on the three axes (G_g = k I, added to the twin's; the "
           "twin's gyro bias, found at rest where the g-sensitivity acts too, loses k times the rest specific force)",
           "[sensor] gyro_g_sensitivity, gyro_bias", "deg/s/(m/s^2)", ("closure_roll", "closure_pitch") + NAV,
           (-0.05, 0.05), _g_sensitivity_changes, linear=True),
    Effect("saturation", "accelerometer range limit (clipping)", "[sensor] accel_range", "m/s^2",
           ("acc_peak", "hf40", "hf80", "onset_hf") + ACC_PROFILES, (20.0, 400.0),
           lambda m, ctx: _sensor(accel_range=[m, "m/s^2"]),
           lambda res, ctx: ctx["largest_acc_component"] if ctx["largest_acc_component"] < 350 else None,
           log_scale=True),
)
BY_NAME = {e.name: e for e in LIBRARY}


def ringing_frequency(measured: Signature, twin: Signature) -> float:
    """Frequency (Hz) where the measured |a| spectrum most exceeds the twin's, as the log ratio of the two
    spectra smoothed over ``settings.RINGING_SMOOTHING_HZ`` (a damped resonance is a broad bump; a single
    stride's spectrum is a comb of stride harmonics), between ``settings.RINGING_BAND_HZ`` and
    ``settings.BAND_TOP_SHARE`` times the sample rate; NaN when the band is empty."""
    f_m, p_m = measured.spectrum
    f_t, p_t = twin.spectrum
    p_t = np.interp(f_m, f_t, p_t)
    width = max(1, int(round(settings.RINGING_SMOOTHING_HZ / (f_m[1] - f_m[0]))))
    kernel = np.ones(width) / width
    tiny = 1e-12 * max(p_m.max(), p_t.max(), 1e-300)
    excess = np.log(np.convolve(p_m, kernel, "same") + tiny) - np.log(np.convolve(p_t, kernel, "same") + tiny)
    band = (f_m >= settings.RINGING_BAND_HZ) & (f_m <= settings.BAND_TOP_SHARE * measured.rate_hz)
    if not band.any():
        return math.nan
    return float(f_m[band][np.argmax(excess[band])])


def clipped_runs(acc: np.ndarray) -> int:
    """Number of flat tops in an accelerometer record (N, 3): runs of at least two consecutive samples of one
    axis within ``settings.CLIP_BAND`` of the largest reading of any axis. A sensor that clips holds its limit while the
    true force is beyond it; an unclipped impact peak is a single sample (gaitmap's readings that touch +-16 g
    are isolated samples: no flat top)."""
    top = np.abs(acc) >= (1.0 - settings.CLIP_BAND) * np.max(np.abs(acc))
    edges = np.diff(np.vstack([np.zeros((1, 3), int), top.astype(int), np.zeros((1, 3), int)]), axis=0)
    lengths = [np.flatnonzero(edges[:, i] == -1) - np.flatnonzero(edges[:, i] == 1) for i in range(3)]
    return int(sum(np.sum(n >= 2) for n in lengths))


def context(rec: Recording, twin: Scenario, measured: Signature, twin_sig: Signature) -> dict:
    """Recording-dependent inputs of the effects: sample rate, ringing frequency, largest accelerometer reading,
    whether the recording has the Fig. 5 residuals, mean specific force (m/s^2, sensor frame) over the detected stances, the twin's gyro bias (rad/s),
    the twin's current creep, stance rotation, roll rate, stance rotation rates (:data:`STANCE_RATE_KEYS`), IMU site (m, foot frame) and sensor roll/pitch on
    the foot (rad), and the stance rotation (deg/s, foot frame) that closes the core-stance rate residual (the
    twin's, plus the residual turned from the sensor into the foot frame by the twin's mounting misalignment).
    Values are in the units of the scenario keys the effects set, the mount's roll and pitch in rad (the yaw
    effect writes them back unchanged)."""
    micro = section_table(twin.walk.micro, digits=None)
    site = FootModel(twin.mount).lever_arm
    roll, pitch, yaw = twin.sensor["mounting_misalignment"] if twin.sensor is not None else np.zeros(3)
    sensor_to_foot = quat.to_matrix(quat.from_euler_zyx(yaw, pitch, roll))
    rate_gap = np.array([measured.scalars[f"stance_rate_{a}"].value - twin_sig.scalars[f"stance_rate_{a}"].value
                         for a in "xyz"])
    rotation = np.asarray(micro["stance_rotation_dps"], float) + sensor_to_foot @ rate_gap
    return {"rate_hz": measured.rate_hz,
            "stance_rotation_dps": list(micro["stance_rotation_dps"]),
            "stance_rates": {key: float(micro[key]) for key in STANCE_RATE_KEYS},
            "stance_rotation_target_dps": rotation.tolist(),
            "imu_site_m": site.tolist(),
            "ringing_hz": round(ringing_frequency(measured, twin_sig), 1),
            "largest_acc_component": float(np.max(np.abs(rec.acc))),
            "clipped_runs": clipped_runs(rec.acc),
            "has_fig5": all(name in measured.scalars for name in fig5.NUMBERS),
            "creep_velocity_mps": list(micro["creep_velocity_mps"]),
            "creep_mps": float(micro["creep_velocity_mps"][0]),
            "stance_roll_rate_dps": float(micro["stance_roll_rate_dps"]),
            "mount_roll_pitch_rad": [float(roll), float(pitch)],
            "mount_yaw_rad": float(yaw),
            **{key: (np.asarray(twin.sensor[key]) if twin.sensor is not None else np.eye(3)).tolist()
               for key in ("gyro_misalignment", "accel_misalignment")},
            "gyro_g_sensitivity": np.degrees(np.asarray(twin.sensor["gyro_g_sensitivity"])
                                             if twin.sensor is not None else np.zeros((3, 3))).tolist(),
            "gyro_bias_rad_s": (np.asarray(twin.sensor["gyro_bias"]) if twin.sensor is not None
                                else np.zeros(3)).tolist(),
            "accel_bias": (np.asarray(twin.sensor["accel_bias"]) if twin.sensor is not None
                           else np.zeros(3)).tolist(),
            "rest_specific_force": rec.acc[measured.stationary].mean(0).tolist()}


def applicable(effect: Effect, ctx: dict) -> bool:
    """False when the recording cannot show the effect: ringing without a usable spectrum band, saturation
    without flat tops at the largest reading (:func:`clipped_runs`; lower impact peaks alone are as well the
    gait's), the stance kinematics without the Fig. 5 residuals (no position track: the stance rates alone are
    as well a sustained rotation's or a mount's, :mod:`gaitsim.loop.fig5`)."""
    if effect.name == "impact_ringing":
        return math.isfinite(ctx["ringing_hz"]) and ctx["ringing_hz"] >= settings.MIN_RINGING_HZ
    if effect.name == "saturation" and ctx["clipped_runs"] < settings.MIN_CLIPPED_RUNS:
        return False
    if effect.name == "stance_kinematics" and not ctx["has_fig5"]:
        return False
    low, high = effect.search_bounds(ctx)
    return high > low
