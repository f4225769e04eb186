"""One call from recordings to navigation solutions and their scores.

Steps: check the input (nav.checks) -> compensation step 1, readout calibration (optional) -> zero-velocity
detection -> alignment on the first stationary window -> ZUPT-aided EKF with compensation step 2, the stance
velocity (optional) -> scores against truth or the recording's reference.

Heading (:class:`HeadingSource`): given (``NavOptions.heading``), else the true heading at the start when the
recording has truth, else the direction that makes the solution's first leg (first 3 m) point along the
reference's first leg (found with a first pass at heading 0), else 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from enum import Enum
from pathlib import Path

import numpy as np

from . import detectors, metrics
from . import quaternion as quat
from .adaptive_detector import AdaptiveThreshold, detect_adaptive
from .calm_anchor import CalmAnchor, detect_anchored
from .alignment import DEFAULT_MIN_SAMPLES, align, first_leg_direction, yaw_of
from .calibration import TERM_GROUPS, load_calibration
from .checks import ALLOWABLE, CheckReport, check_recording, check_stance_found
from .constants import DEFAULT_SIGMA_A, DEFAULT_SIGMA_G, DEFAULT_THRESHOLD, DEFAULT_WINDOW
from .ekf import FilterConfig, FilterOutput, run_filter, run_filter_batch
from .recording import Recording, RecordingError
from .series import resample
from .solution import Solution
from .strapdown import METHODS as STRAPDOWN_METHODS
from .zupt_velocity import load_stance_velocity

METHODS = ("auto",) + STRAPDOWN_METHODS


class HeadingSource(Enum):
    """Where the initial heading comes from; the value is what ``info["alignment"]["heading_source"]`` says."""

    GIVEN = "given"
    TRUTH = "truth at the start"
    REFERENCE_FIRST_LEG = "reference first leg"
    DEFAULT = "default 0 (no truth or reference)"


@dataclass(frozen=True)
class NavOptions:
    """What to run. Units: SI.

    Attributes
    ----------
    detector : "anchored" (the default: OpenShoe's SHOE that also takes each stride's calmest stretch where the
        fixed threshold finds nothing, nav.calm_anchor), "shoe", "are", "mv", "mag", "adaptive" (SHOE with a
        threshold that follows the gait, nav.adaptive_detector) or "oracle" (the recording's true stance labels).
    threshold : detector threshold gamma (dimensionless); the floor gamma_0 for "adaptive". Default 3e4 (OpenShoe).
    sigma_a : m/s^2, sigma_g : rad/s, window : samples -- detector parameters (OpenShoe: 0.01, 0.1 deg/s, 3);
        "adaptive" takes its window from ``adaptive.window_s`` instead.
    anchor : CalmAnchor, span (s), widening and cap of the "anchored" detector.
    adaptive : AdaptiveThreshold, ratio, span (s) and window (s) of the "adaptive" detector.
    filter : FilterConfig (states, noise densities, ZUPT noise, ...).
    method : "auto" (exact increments when the recording's IMU is its exact truth and no calibration is
        applied, else "rk4"), "rk4" or "increments".
    calibration : None, a Calibration (nav.calibration) or a path to a calibration file: step 1.
    calibration_terms : which terms of it to apply.
    stance_velocity : None (zero), a model with ``stance_velocity(stationary) -> (N, 3)`` (nav.zupt_velocity), a
        path to a model JSON, or an (N, 3) array (m/s, heading frame): step 2.
    rts : RTS-smooth the solution.
    heading : rad, initial heading of the body x axis counter-clockwise from east; None: see the module docstring.
    gravity : m/s^2; None: the recording's (``Recording.gravity``). It replaces ``filter.gravity``.
    align_min_samples : shortest stationary window accepted for the alignment, samples.
    allow : input checks (``nav.checks.ALLOWABLE``: "rate", "units", "closure") whose refusal is turned into a
        warning; default none.
    """

    detector: str = "anchored"
    threshold: float = DEFAULT_THRESHOLD
    sigma_a: float = DEFAULT_SIGMA_A
    sigma_g: float = DEFAULT_SIGMA_G
    window: int = DEFAULT_WINDOW
    anchor: CalmAnchor = field(default_factory=CalmAnchor)
    adaptive: AdaptiveThreshold = field(default_factory=AdaptiveThreshold)
    filter: FilterConfig = field(default_factory=FilterConfig)
    method: str = "auto"
    calibration: object = None
    calibration_terms: tuple = TERM_GROUPS
    stance_velocity: object = None
    rts: bool = False
    heading: float | None = None
    gravity: float | None = None
    align_min_samples: int = DEFAULT_MIN_SAMPLES
    allow: tuple[str, ...] = ()

    def __post_init__(self):
        unknown = sorted(set(self.allow) - set(ALLOWABLE))
        if unknown:
            raise ValueError(f"NavOptions.allow = {unknown}: unknown check names; allowed: {ALLOWABLE}")
        if self.detector not in detectors.DETECTORS:
            raise ValueError(f"NavOptions.detector = {self.detector!r}; allowed: {detectors.DETECTORS}")
        if self.method not in METHODS:
            raise ValueError(f"NavOptions.method = {self.method!r}; allowed: {METHODS}")


@dataclass
class PreparedRecording:
    """One recording made ready for the filter (:func:`prepare`).

    Attributes
    ----------
    t : (N,) s; acc, gyr : (N, 3) what the filter integrates (m/s^2 and rad/s, or the truth's increments m/s
        and rad when ``method`` is "increments").
    stationary : (N,) bool, detected stance (the ZUPT samples).
    method : "rk4" or "increments".
    start : first navigated sample; quat0 : (4,) attitude there at the heading of ``heading_source`` (0 for
        the reference's first leg, turned after a first pass); pos0 : (3,) m.
    stance_velocity : (N, 3) m/s, heading frame, the ZUPT's velocity per sample.
    heading_source : HeadingSource.
    info : dict, what the solution's ``info`` reports.
    """

    t: np.ndarray
    acc: np.ndarray
    gyr: np.ndarray
    stationary: np.ndarray
    method: str
    start: int
    quat0: np.ndarray
    pos0: np.ndarray
    stance_velocity: np.ndarray
    heading_source: HeadingSource
    info: dict


def _gravity(rec: Recording, options: NavOptions) -> float:
    return float(options.gravity) if options.gravity is not None else rec.gravity


def _calibrate(rec: Recording, options: NavOptions) -> tuple[np.ndarray, np.ndarray, dict]:
    if options.calibration is None:
        return np.asarray(rec.acc, float), np.asarray(rec.gyr, float), {"applied": False}
    cal = options.calibration
    source = str(cal) if isinstance(cal, (str, Path)) else getattr(cal, "source", "")
    if isinstance(cal, (str, Path)):
        cal = load_calibration(cal)
    acc, gyr = cal.correct(rec.acc, rec.gyr, terms=tuple(options.calibration_terms))
    return np.asarray(acc, float), np.asarray(gyr, float), {"applied": True, "source": source,
                                                            "terms": list(options.calibration_terms)}


def _detect(rec: Recording, acc: np.ndarray, gyr: np.ndarray, options: NavOptions,
            gravity: float) -> detectors.DetectorResult:
    if options.detector == "oracle":
        if rec.truth is None:
            raise RecordingError("detector 'oracle' needs the recording's truth (truth.csv with a stance column)")
        if len(rec.truth.t) != len(rec.t):
            raise RecordingError(f"detector 'oracle' needs the truth on the IMU's samples; truth.csv has "
                                 f"{len(rec.truth.t)} rows, imu.csv {len(rec.t)}")
        return detectors.oracle(rec.t, rec.truth.stance)
    if options.detector == "anchored":
        return detect_anchored(rec.t, acc, gyr, options.threshold, options.sigma_a, options.sigma_g, options.window,
                               options.anchor, gravity)
    if options.detector == "adaptive":
        return detect_adaptive(rec.t, acc, gyr, options.threshold, options.sigma_a, options.sigma_g, options.adaptive,
                               gravity)
    return detectors.detect(options.detector, rec.t, acc, gyr, options.threshold, options.sigma_a, options.sigma_g,
                            options.window, gravity)


def _method(rec: Recording, options: NavOptions, calibrated: bool) -> str:
    exact_imu = (rec.truth is not None and not calibrated and np.array_equal(rec.acc, rec.truth.acc)
                 and np.array_equal(rec.gyr, rec.truth.gyr))
    if options.method == "increments" and rec.truth is None:
        raise RecordingError("method 'increments' needs the recording's truth increments (truth.csv dv_*, dth_*)")
    if options.method == "increments" and calibrated:
        raise ValueError("method 'increments' integrates the truth's exact increments; it cannot be combined with a "
                         "calibration (use method 'rk4' or 'auto')")
    if options.method == "auto":
        return "increments" if exact_imu else "rk4"
    return options.method


def _stance_velocity(options: NavOptions, stationary: np.ndarray) -> tuple[np.ndarray, str]:
    """(N, 3) m/s stance velocity per sample and a description of where it came from."""
    source = options.stance_velocity
    if source is None:
        return np.zeros((len(stationary), 3)), "zero"
    if isinstance(source, (str, Path)):
        description = f"model file {source}"
        source = load_stance_velocity(source)
    elif isinstance(source, np.ndarray):
        if source.shape != (len(stationary), 3):
            raise ValueError(f"NavOptions.stance_velocity array has shape {source.shape}; "
                             f"expected ({len(stationary)}, 3)")
        return np.asarray(source, float), "per-sample array"
    else:
        description = type(source).__name__
    return source.stance_velocity(stationary), description


def _initial_heading(rec: Recording, options: NavOptions, start: int) -> tuple[float, HeadingSource]:
    """Heading (rad) for the alignment and where it comes from (0 for the reference's first leg: turned later)."""
    if options.heading is not None:
        return float(options.heading), HeadingSource.GIVEN
    if rec.truth is not None:
        return float(yaw_of(rec.truth.quat[start])), HeadingSource.TRUTH
    if rec.reference is not None:
        return 0.0, HeadingSource.REFERENCE_FIRST_LEG
    return 0.0, HeadingSource.DEFAULT


def _initial_position(rec: Recording, start: int) -> np.ndarray:
    """(3,) m, the truth's or the reference's position at the start sample, else the origin."""
    if rec.truth is not None:
        return np.asarray(rec.truth.pos[start], float)
    if rec.reference is not None:
        ref = rec.reference
        ok = np.all(np.isfinite(ref.pos), axis=1)
        return resample(rec.t[start], ref.t[ok], ref.pos[ok])
    return np.zeros(3)


def _checked(rec: Recording, options: NavOptions, reports: dict) -> CheckReport:
    """The input checks of ``rec`` at the options' gravity and allowances; ``reports`` holds those already run on
    this recording, by (gravity, allowances): each pair is checked once."""
    key = (_gravity(rec, options), tuple(sorted(options.allow)))
    if key not in reports:
        reports[key] = check_recording(rec, key[0], allow=options.allow)
    return reports[key]


def prepare(rec: Recording, options: NavOptions = NavOptions()) -> PreparedRecording:
    """Checks, calibration, detection, alignment and stance velocity of one recording (no filtering)."""
    return _prepare(rec, options, {})


def _prepare(rec: Recording, options: NavOptions, reports: dict) -> PreparedRecording:
    """:func:`prepare` with the input checks of :func:`_checked` (``reports``: those already run on ``rec``)."""
    gravity = _gravity(rec, options)
    report = _checked(rec, options, reports)
    acc, gyr, cal_info = _calibrate(rec, options)
    result = _detect(rec, acc, gyr, options, gravity)
    check_stance_found(result.stationary, str(result.params.as_dict()),
                       float(result.statistic.min()) if result.statistic.size else math.nan)
    method = _method(rec, options, cal_info["applied"])
    start = align(acc, result.stationary, 0.0, options.align_min_samples).start
    yaw, heading_source = _initial_heading(rec, options, start)
    alignment = align(acc, result.stationary, yaw, options.align_min_samples)
    stance_velocity, stance_velocity_source = _stance_velocity(options, result.stationary)
    if method == "increments":
        acc, gyr = rec.truth.dv, rec.truth.dth
    info = {
        "detector": result.params.as_dict(),
        "stationary_fraction": float(result.stationary.mean()),
        "filter": replace(options.filter, gravity=gravity).as_dict(),
        "mechanisation": method,
        "alignment": {"start_sample": start, "end_sample": alignment.end, "roll_deg": math.degrees(alignment.roll),
                      "pitch_deg": math.degrees(alignment.pitch), "heading_source": heading_source.value},
        "calibration": cal_info,
        "stance_velocity": stance_velocity_source,
        "rts": options.rts,
        "warnings": list(report.warnings),
        "input_counts": dict(report.counts),
    }
    return PreparedRecording(np.asarray(rec.t, float), acc, gyr, result.stationary, method, start, alignment.quat0,
                             _initial_position(rec, start), stance_velocity, heading_source, info)


def _solution(p: PreparedRecording, out: FilterOutput, yaw: float) -> Solution:
    p.info["alignment"]["heading_deg"] = math.degrees(yaw)
    p.info["skipped_updates"] = int(out.skipped_updates)
    return Solution(p.t, out.pos, out.vel, out.quat, p.stationary, p.start, out.bias_acc[-1], out.bias_gyr[-1],
                    out.gsens[-1], p.info)


def _reference_heading(rec: Recording, p: PreparedRecording, pos: np.ndarray) -> float:
    """Heading (rad) that turns a heading-0 solution's first leg onto the reference's first leg."""
    ref_dir, t_leg = first_leg_direction(rec.reference.t, rec.reference.pos, p.t[p.start])
    if not math.isfinite(ref_dir):
        return 0.0
    est = resample(t_leg, p.t[p.start:], pos[p.start:, :2]) - pos[p.start, :2]
    return ref_dir - math.atan2(est[1], est[0])


def _turned(p: PreparedRecording, yaw: float) -> np.ndarray:
    """The prepared initial attitude turned by ``yaw`` (rad) about the vertical."""
    return quat.multiply(quat.from_euler_zyx(yaw, 0.0, 0.0), p.quat0)


def _filter(preps: list[PreparedRecording], quat0: list[np.ndarray], rts: bool) -> list[FilterOutput]:
    """The EKF over prepared recordings from the initial attitudes ``quat0``: one run, or one batch call; the
    estimates' history only for the smoother (a solution keeps the final biases and g-sensitivity)."""
    config = FilterConfig(**preps[0].info["filter"])
    if len(preps) == 1:
        p = preps[0]
        return [run_filter(p.t, p.acc, p.gyr, p.stationary, quat0[0], pos0=p.pos0, start=p.start, config=config,
                           method=p.method, stance_velocity=p.stance_velocity, rts=rts, history=rts)]
    out = run_filter_batch(np.stack([p.t for p in preps]), np.stack([p.acc for p in preps]),
                           np.stack([p.gyr for p in preps]), np.stack([p.stationary for p in preps]), np.stack(quat0),
                           pos0=np.stack([p.pos0 for p in preps]), start=np.array([p.start for p in preps]),
                           config=config, method=preps[0].method,
                           stance_velocity=np.stack([p.stance_velocity for p in preps]), rts=rts, history=rts)
    return [out.of_run(i) for i in range(len(preps))]


def _navigate_together(recs: list[Recording], preps: list[PreparedRecording], rts: bool) -> list[Solution]:
    """Filter prepared recordings in one call; a second pass turns those headed by the reference's first leg."""
    outs = _filter(preps, [p.quat0 for p in preps], rts)
    yaws = [float(yaw_of(p.quat0)) for p in preps]
    by_reference = [p.heading_source is HeadingSource.REFERENCE_FIRST_LEG for p in preps]
    if any(by_reference):
        turns = [_reference_heading(rec, p, out.pos) if turn else 0.0
                 for rec, p, out, turn in zip(recs, preps, outs, by_reference)]
        outs = _filter(preps, [_turned(p, turn) for p, turn in zip(preps, turns)], rts)
        yaws = [yaw + turn for yaw, turn in zip(yaws, turns)]
    return [_solution(p, out, yaw) for p, out, yaw in zip(preps, outs, yaws)]


def navigate(recordings: Recording | list[Recording], options: NavOptions = NavOptions()) -> Solution | list[Solution]:
    """Navigate one recording, or several; see the module docstring for the steps.

    Parameters
    ----------
    recordings : a Recording, or a list of them.
    options : NavOptions, the same for all.

    Returns
    -------
    A Solution for a Recording; a list of Solutions, in order, for a list. Several recordings that share their
    length, mechanisation and filter configuration (gravity) run in one compiled filter call, spread over cores
    (a Monte Carlo batch); otherwise one after the other. Preparation is per recording either way, and each
    result equals navigating that recording alone (the same compiled code per run).
    """
    if isinstance(recordings, Recording):
        return _navigate_together([recordings], [prepare(recordings, options)], options.rts)[0]
    recs = list(recordings)
    preps = [prepare(rec, options) for rec in recs]
    shared = {(len(p.t), p.method, tuple(sorted(p.info["filter"].items()))) for p in preps}
    if len(shared) == 1:
        return _navigate_together(recs, preps, options.rts)
    return [_navigate_together([rec], [p], options.rts)[0] for rec, p in zip(recs, preps)]


def navigate_variants(rec: Recording, variants: list[NavOptions]) -> list[Solution]:
    """Navigate one recording under several option sets (a study's pipeline variants), in order.

    The recording's input checks run once per gravity and allowance set, not once per variant. Each solution
    equals ``navigate(rec, options)``. The variants are filtered one after the other: the batch call costs more
    than separate runs for two or three runs on one core (it stacks the inputs), so it pays only across cores.
    """
    reports: dict = {}
    return [_navigate_together([rec], [_prepare(rec, options, reports)], options.rts)[0] for options in variants]


def score_solution(rec: Recording, sol: Solution, secondary: bool = True) -> dict:
    """Scores of a solution (nav.metrics) plus the run's parameters; keys documented in nav.metrics
    (``secondary``: see :func:`nav.metrics.score`)."""
    result = {"scored_against": None}
    if rec.truth is not None:
        result.update(metrics.score(sol.t, sol.pos, rec.truth.t, rec.truth.pos, sol.quat, rec.truth.quat,
                                    sol.stationary, secondary))
        result["scored_against"] = "truth"
        if len(rec.truth.t) == len(sol.t):  # stance labels on the IMU's samples (no clock error or skew)
            result["detector_confusion"] = metrics.confusion(sol.stationary[sol.start:], rec.truth.stance[sol.start:])
    elif rec.reference is not None:
        result.update(metrics.score(sol.t, sol.pos, rec.reference.t, rec.reference.pos,
                                    stationary=sol.stationary, secondary=secondary))
        result["scored_against"] = "reference"
    end = sol.pos[-1]
    result["estimated_end_m"] = end.tolist()
    result["estimated_start_to_end_m"] = float(np.hypot(*(end - sol.pos[sol.start])[:2]))
    det = sol.info["detector"]
    result.update({k: det[k] for k in ("detector", "threshold", "sigma_a_m_s2", "sigma_g_rad_s", "window_samples",
                                       "fs_hz")})
    result["bias_acc_estimate_m_s2"] = sol.bias_acc.tolist()
    result["bias_gyr_estimate_rad_s"] = sol.bias_gyr.tolist()
    result["info"] = sol.info
    return result


def run(rec: Recording, options: NavOptions = NavOptions()) -> tuple[Solution, dict]:
    """Navigate and score one recording: ``(solution, score)``."""
    return run_variants(rec, [options])[0]


def run_variants(rec: Recording, variants: list[NavOptions], secondary: bool = True) -> list[tuple[Solution, dict]]:
    """Navigate (:func:`navigate_variants`) and score one recording under several option sets: ``(solution,
    score)`` per variant, in order (``secondary``: see :func:`nav.metrics.score`)."""
    return [(sol, score_solution(rec, sol, secondary)) for sol in navigate_variants(rec, variants)]
