"""Blind tests of the loop: effects put into a realistic recording by a few lines of numpy, not by the simulator.

The base recordings are short straight walks (``settings.BLIND_WALK_LENGTH_M`` at ``settings.BLIND_RATE_HZ``)
of two uncalibrated sensors (``paper-vn200``: biases, misalignment, g-sensitivity; ``bmi160``: consumer
noise, bias repeatability, 16-bit quantisation), stripped to what a measured recording carries (IMU samples and
a ``settings.BLIND_REFERENCE_RATE_HZ`` position reference, like a motion tracker;
:func:`gaitsim.measured.reference.as_measured`). Each case then changes the IMU samples with its own numpy code
(:data:`INJECTIONS`), independent of the simulator's sensor model and of the effect library. The loop runs on the
untouched recording as well: what it names there is the sensor's own calibration error and is subtracted
(an effect it names there with the same name is compared by the change of its magnitude).

What a case is credited with is the change it made to the loop's estimate (a paired comparison): its named
magnitude less the untouched recording's estimate of the same effect. That estimate is the magnitude named there,
or, for an effect the untouched run did not name (below the noise level on its own), the effect fitted to the
untouched run's final twin (:func:`untouched_estimates`; effects whose magnitude is additive, not a cutoff or a
range). A sensor's own error can project onto a library effect without being significant alone: paper-vn200's
anisotropic G_g (G_xx +0.0041, G_zz -0.0022 deg/s/(m/s^2)) turns the stride's roll closure as an isotropic
g-sensitivity of about 0.02 would, since the isotropic effect's x and z paths nearly cancel there. Each row also
keeps the rule that subtracts only what the untouched run named (``found_subtracting_named``).

The magnitude compared is the library's equivalent figure (``expected``): a gyro delay of tau is an
``accel_gyro_skew`` of -tau (the library's skew samples the gyro later); a first-order low-pass (here the
exponential smoothing of a sampled RC stage) is named by its cutoff, by any library low-pass (the forms differ
most above a fifth of the sample rate: a digital Butterworth has a zero at the Nyquist frequency, an analogue
stage none); a mount rotation about z is the change of the sensor's yaw on the foot in the final twin
(:data:`TWIN_YAW`, :func:`twin_yaw`), which the twin's mount fit finds before any effect and again after each
(:func:`gaitsim.loop.mount_fit.fit_yaw`). The bias ramp is outside the library: the loop must leave it
unexplained.

A run of the consumer sensor (:data:`RUNS`: a rearfoot strike at 170 steps/min, ``settings.BLIND_RUN_LENGTH_M``)
takes every case too: the loop gives it a running twin (:mod:`gaitsim.loop.twin`).

The same injections also go into shared measured recordings (:data:`MEASURED`: x-io's short walk, a walker the
stance model was never fitted to, and gaitmap's right foot: real feet the twin reproduces only in part, with their
own sensors' errors), for the effects a real recording's loop can be asked to see (:data:`MEASURED_CASES`), and
are judged the same way against that recording's untouched run (the loop's default budget of effects).
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from nav.recording import Recording

from ..measured import load_dataset
from ..measured.reference import as_measured
from ..scenario import scenario_from_dict
from ..simulate import simulate_walk
from . import attribution, settings
from . import effects as fx
from .twin import TwinSimulator

SENSORS = ("paper-vn200", "bmi160")
RUNS = {"bmi160-run": ("bmi160", "run-rearfoot", 170.0)}  # source -> sensor preset, gait kind, steps/min
TWIN_YAW = "twin_yaw"  # what a mount rotation about z is found as: the twin's fitted yaw on the foot, not an effect
MEASURED = ("xio-ngimu/short_walk", "gaitmap-healthy/right")  # dataset/recording of the shared data


def gyro_delay(t, acc, gyr, ms):
    """The gyro delayed by ``ms`` (linear interpolation of its samples at t - delay)."""
    return acc, np.stack([np.interp(t - ms / 1000.0, t, g) for g in gyr.T], axis=1)


def low_pass(t, acc, gyr, hz):
    """A first-order low-pass of cutoff ``hz`` on both sensors (exponential smoothing, started settled)."""
    alpha = 1.0 - math.exp(-2.0 * math.pi * hz * float(np.median(np.diff(t))))
    out = []
    for x in (acc, gyr):
        y = np.empty_like(x)
        y[0] = x[0]
        for k in range(1, len(x)):
            y[k] = y[k - 1] + alpha * (x[k] - y[k - 1])
        out.append(y)
    return tuple(out)


def g_sensitivity(t, acc, gyr, dps_per_mps2):
    """Gyro output plus k times the specific force on every axis (k in deg/s per m/s^2)."""
    return acc, gyr + math.radians(dps_per_mps2) * acc


def gyro_scale_y(t, acc, gyr, percent):
    """The gyro's y axis (pitch) scaled by 1 + percent / 100."""
    return acc, gyr * np.array([1.0, 1.0 + percent / 100.0, 1.0])


def accel_scale_x(t, acc, gyr, percent):
    """The accelerometer's x axis scaled by 1 + percent / 100."""
    return acc * np.array([1.0 + percent / 100.0, 1.0, 1.0]), gyr


def mount_yaw(t, acc, gyr, deg):
    """The sensor turned by ``deg`` about its z axis on the foot (both sensors read in the turned axes)."""
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    turn = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    return acc @ turn.T, gyr @ turn.T


def gyro_bias_ramp(t, acc, gyr, dps):
    """A gyro bias growing linearly from 0 to ``dps`` deg/s (on x, -y, z) over the recording."""
    ramp = (t - t[0]) / (t[-1] - t[0])
    return acc, gyr + np.radians(dps) * ramp[:, None] * np.array([0.6, -0.6, 1.0]) / math.sqrt(2.72)


@dataclass(frozen=True)
class BlindCase:
    """One injected effect: its injection, magnitude and unit, and what the loop should name with which
    magnitude (``expected``; library effect names, or ``"unexplained"`` for an effect outside the library)."""

    name: str
    inject: object
    magnitude: float
    unit: str
    named: tuple
    expected: float


CASES = (
    BlindCase("gyro_delay", gyro_delay, 4.0, "ms", ("accel_gyro_skew",), -4.0),
    BlindCase("low_pass", low_pass, 25.0, "Hz", ("bandwidth_first_order", "bandwidth_analogue", "bandwidth"), 25.0),
    BlindCase("g_sensitivity", g_sensitivity, 0.02, "deg/s/(m/s^2)", ("g_sensitivity",), 0.02),
    BlindCase("gyro_scale_y", gyro_scale_y, 2.0, "%", ("gyro_scale_y",), 2.0),
    BlindCase("accel_scale_x", accel_scale_x, 2.0, "%", ("accel_scale_x",), 2.0),
    BlindCase("mount_yaw", mount_yaw, 6.0, "deg", (TWIN_YAW,), 6.0),
    BlindCase("gyro_bias_ramp", gyro_bias_ramp, 0.5, "deg/s", ("unexplained",), math.nan),
)
BY_NAME = {c.name: c for c in CASES}
MEASURED_CASES = tuple(BY_NAME[name] for name in ("gyro_delay", "gyro_scale_y", "mount_yaw"))


def cases(source: str) -> tuple[BlindCase, ...]:
    """The cases run on ``source``: every case on a simulated sensor, :data:`MEASURED_CASES` on a recording."""
    return MEASURED_CASES if source in MEASURED else CASES


@lru_cache(maxsize=len(SENSORS) + len(RUNS) + len(MEASURED))
def base_recording(source: str, seed: int = settings.BLIND_SEED) -> Recording:
    """The untouched recording of ``source``: a simulated sensor's measured-like walk (module docstring) or run
    (:data:`RUNS`), or a shared measured recording (``dataset/recording`` of :data:`MEASURED`, from the default
    data folder)."""
    if source in MEASURED:
        dataset, name = source.split("/")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the loader's data-quality counts are in the recording's meta
            return {r.meta["recording"]: r for r in load_dataset(dataset)}[name]
    sensor, length = (RUNS[source][0], settings.BLIND_RUN_LENGTH_M) if source in RUNS else (source,
                                                                                        settings.BLIND_WALK_LENGTH_M)
    doc = {"path": {"kind": "straight", "length_m": length},
           "sampling": {"rate_hz": settings.BLIND_RATE_HZ}, "sensor": {"preset": sensor, "withhold": True}}
    if source in RUNS:
        doc["gait"] = {"kind": RUNS[source][1], "cadence_steps_per_min": RUNS[source][2]}
    return as_measured(simulate_walk(scenario_from_dict(doc, f"<blind {source}>"), seed=seed),
                       settings.BLIND_REFERENCE_RATE_HZ)


def blind_recording(source: str, case: BlindCase | None) -> Recording:
    """The base recording of ``source`` with ``case``'s effect injected (untouched for None)."""
    rec = base_recording(source)
    if case is None:
        return rec
    acc, gyr = case.inject(rec.t, rec.acc.copy(), rec.gyr.copy(), case.magnitude)
    return dataclasses.replace(rec, acc=np.asarray(acc, float), gyr=np.asarray(gyr, float))


def run(source: str, case: BlindCase | None) -> attribution.LoopResult:
    """The loop on the blind recording (at most ``settings.BLIND_EFFECTS`` effects on a simulated sensor's walk,
    the loop's default on a measured recording)."""
    most = settings.MAX_EFFECTS if source in MEASURED else settings.BLIND_EFFECTS
    return attribution.run_loop(blind_recording(source, case), max_effects=most)


def named_effects(result: attribution.LoopResult) -> dict:
    """Effect name -> fitted magnitude of every effect the loop named."""
    return {a["effect"]: a["magnitude"] for a in result.attributions if a["effect"] != "unexplained"}


def equivalent_effects(result: attribution.LoopResult) -> dict:
    """Effect name -> fitted magnitude of every candidate that fit as well as a named effect (``equivalent``)."""
    return {e["effect"]: e["magnitude"] for a in result.attributions for e in a.get("equivalent", [])}


def twin_yaw(result: attribution.LoopResult) -> float:
    """The sensor's yaw on the foot (deg) in the final twin: its mount fit, re-fitted after each effect."""
    return math.degrees(result.twin_after.scenario.sensor["mounting_misalignment"][2])


def unexplained(result: attribution.LoopResult) -> list:
    """The residuals the loop left unexplained."""
    return [a["residual"] for a in result.attributions if a["effect"] == "unexplained"]


def untouched_estimates(case: BlindCase, result: attribution.LoopResult, untouched: attribution.LoopResult,
                        simulate: TwinSimulator | None = None) -> dict:
    """Effect name -> the untouched run's estimate of each of ``case``'s expected effects that the loop named on
    the case but not on the untouched recording: the effect fitted to the untouched run's final twin, on the
    residuals it moves, as the loop fits it (:func:`gaitsim.loop.attribution.fit_effect`). Only effects with an
    additive magnitude (zero: absent) are estimated; a cutoff frequency or a range has no such difference."""
    named, before = named_effects(result), named_effects(untouched)
    wanted = [fx.BY_NAME[name] for name in case.named if name in fx.BY_NAME and name in named
              and name not in before and not fx.BY_NAME[name].log_scale]
    if not wanted:
        return {}
    simulate = simulate or TwinSimulator()
    ctx = fx.context(untouched.measured.recording, untouched.twin_after.scenario, untouched.measured.signature,
                     untouched.after.signature)
    return {effect.name: attribution.fit_effect(simulate, effect, untouched.twin_after, untouched.measured,
                                                untouched.residuals_after, ctx, untouched.noise).magnitude
            for effect in wanted}


def verdict(case: BlindCase, result: attribution.LoopResult, untouched: attribution.LoopResult,
            estimates: dict | None = None) -> dict:
    """What the loop named on the case beyond the ``untouched`` recording's result (an effect named there too,
    or estimated there (``estimates``, :func:`untouched_estimates`), counts only when its magnitude moved by more
    than ``settings.BLIND_MAGNITUDE_TOLERANCE`` of the untouched one, and counts by that change), and whether it
    is the injected effect within that tolerance of the expected figure. An effect outside the library is found
    when the loop names nothing beyond the untouched recording and leaves a residual unexplained that it did not
    leave unexplained there. ``found_as`` says whether the injected effect was named or only fit as well as the
    effect named (``equivalent``: the recording did not tell them apart); ``found`` counts the named ones alone.
    ``found_subtracting_named`` is ``found`` without the estimates (only what the untouched run named
    subtracted)."""
    estimates = estimates or {}
    row = _verdict(case, result, untouched, {**estimates, **named_effects(untouched)})
    row["untouched_estimated"] = estimates
    row["found_subtracting_named"] = (_verdict(case, result, untouched, named_effects(untouched))["found"]
                                      if estimates else row["found"])
    return row


def _verdict(case: BlindCase, result: attribution.LoopResult, untouched: attribution.LoopResult,
             before: dict) -> dict:
    """:func:`verdict` with ``before`` (effect name -> magnitude) as the untouched recording's estimates."""

    def beyond(effects: dict) -> dict:
        return {name: m - before.get(name, 0.0) for name, m in effects.items()
                if name not in before or abs(m - before[name]) > settings.BLIND_MAGNITUDE_TOLERANCE * abs(before[name])}

    new, alternatives = beyond(named_effects(result)), beyond(equivalent_effects(result))
    turned = twin_yaw(result) - twin_yaw(untouched)
    if TWIN_YAW in case.named and turned:  # a yaw is found by the twin's mount fit
        new[TWIN_YAW] = turned
    left = [name for name in unexplained(result) if name not in unexplained(untouched)]
    row = {"case": case.name, "injected": case.magnitude, "unit": case.unit, "expected_effect": "/".join(case.named),
           "expected_magnitude": case.expected, "named_beyond_untouched": new,
           "equivalent_beyond_untouched": alternatives, "unexplained_beyond_untouched": left}
    if case.named == ("unexplained",):
        row["found"] = bool(left) and not new
        row["found_as"] = "unexplained" if row["found"] else None
        row["found_magnitude"] = math.nan
        return row

    def close(magnitude: float) -> bool:
        return abs(magnitude - case.expected) <= settings.BLIND_MAGNITUDE_TOLERANCE * abs(case.expected)

    hits = [(name, new[name]) for name in case.named if name in new]
    row["found_effect"], row["found_magnitude"] = hits[0] if hits else (None, math.nan)
    row["found"] = bool(hits) and close(hits[0][1])
    as_good = [name for name in case.named if name in alternatives and close(alternatives[name])]
    row["found_as"] = "named" if row["found"] else ("equivalent" if hits and as_good else None)
    return row
