"""One call from a recording to a navigation solution and its score.

Steps: check the input (nav.checks) -> compensation step 1, readout calibration (optional) -> zero-velocity
detection -> alignment on the first stationary window -> ZUPT-aided EKF with compensation step 2, the stance
pseudo-velocity (optional) -> scores against truth or the recording's reference.

Heading: given (``NavOptions.heading``), else the true heading at the start when the recording has truth, else
the direction that makes the solution's first leg (first 3 m) point along the reference's first leg (found with
a first pass at heading 0), else 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from . import detectors, metrics
from .adaptive_detector import AdaptiveThreshold, detect_adaptive
from .alignment import DEFAULT_MIN_SAMPLES, align, first_leg_direction, yaw_of
from .checks import check_recording, check_stance_found
from .ekf import FilterConfig, FilterOutput, run_filter, run_filter_batch
from .recording import Recording, RecordingError
from .solution import Solution
from .zupt_velocity import load_stance_velocity

METHODS = ("auto", "rk4", "increments")
ALL_CALIBRATION_TERMS = ("bias", "misalignment", "g_sensitivity")


@dataclass(frozen=True)
class NavOptions:
    """What to run. Units: SI.

    Attributes
    ----------
    detector : "shoe", "are", "mv", "mag", "adaptive" (SHOE with a threshold that follows the gait,
        nav.adaptive_detector) or "oracle" (the recording's true stance labels).
    threshold : detector threshold gamma (dimensionless); the floor gamma_0 for "adaptive". Default 3e4 (OpenShoe).
    sigma_a : m/s^2, sigma_g : rad/s, window : samples -- detector parameters (OpenShoe: 0.01, 0.1 deg/s, 3);
        "adaptive" takes its window from ``adaptive.window_s`` instead.
    adaptive : AdaptiveThreshold, ratio, span (s) and window (s) of the "adaptive" detector.
    filter : FilterConfig (states, noise densities, ZUPT noise, ...).
    method : "auto" (exact increments when the recording's IMU is its exact truth and no calibration is
        applied, else "rk4"), "rk4" or "increments".
    calibration : None, a Calibration (nav.calibration) or a path to a calibration file: step 1.
    calibration_terms : which terms of it to apply.
    stance_velocity : None (zero pseudo-velocity), a model with ``heading_velocity(stationary) -> (N, 3)``
        (nav.zupt_velocity), a path to a model JSON, or an (N, 3) array (m/s, heading frame): step 2.
    rts : RTS-smooth the solution.
    heading : rad, initial heading of the body x axis counter-clockwise from east; None: see the module docstring.
    gravity : m/s^2; None: the recording's ``meta["sampling"]["gravity_mps2"]`` if present, else
        ``filter.gravity``.
    align_min_samples : shortest stationary window accepted for the alignment, samples.
    """

    detector: str = "shoe"
    threshold: float = detectors.DEFAULT_THRESHOLD
    sigma_a: float = detectors.DEFAULT_SIGMA_A
    sigma_g: float = detectors.DEFAULT_SIGMA_G
    window: int = detectors.DEFAULT_WINDOW
    adaptive: AdaptiveThreshold = field(default_factory=AdaptiveThreshold)
    filter: FilterConfig = field(default_factory=FilterConfig)
    method: str = "auto"
    calibration: object = None
    calibration_terms: tuple = ALL_CALIBRATION_TERMS
    stance_velocity: object = None
    rts: bool = False
    heading: float | None = None
    gravity: float | None = None
    align_min_samples: int = DEFAULT_MIN_SAMPLES

    def __post_init__(self):
        if self.detector not in detectors.DETECTORS:
            raise ValueError(f"NavOptions.detector = {self.detector!r}; allowed: {detectors.DETECTORS}")
        if self.method not in METHODS:
            raise ValueError(f"NavOptions.method = {self.method!r}; allowed: {METHODS}")


@dataclass
class _Prepared:
    """One recording made ready for the filter."""

    t: np.ndarray
    acc: np.ndarray
    gyr: np.ndarray
    stationary: np.ndarray
    method: str
    start: int
    quat0: np.ndarray
    pos0: np.ndarray
    pseudo_velocity: np.ndarray
    heading_source: str
    info: dict


def _gravity(rec: Recording, options: NavOptions) -> float:
    if options.gravity is not None:
        return float(options.gravity)
    return float(rec.meta.get("sampling", {}).get("gravity_mps2", options.filter.gravity))


def _calibrate(rec: Recording, options: NavOptions) -> tuple[np.ndarray, np.ndarray, dict]:
    if options.calibration is None:
        return np.asarray(rec.acc, float), np.asarray(rec.gyr, float), {"applied": False}
    from .calibration import load_calibration

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
        return detectors.oracle(rec.t, rec.truth.stance)
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


def _pseudo_velocity(options: NavOptions, stationary: np.ndarray) -> tuple[np.ndarray, str]:
    model = options.stance_velocity
    if model is None:
        return np.zeros((len(stationary), 3)), "zero"
    if isinstance(model, (str, Path)):
        description = f"model file {model}"
        model = load_stance_velocity(model)
    elif isinstance(model, np.ndarray):
        if model.shape != (len(stationary), 3):
            raise ValueError(f"NavOptions.stance_velocity array has shape {model.shape}; "
                             f"expected ({len(stationary)}, 3)")
        return np.asarray(model, float), "per-sample array"
    else:
        description = type(model).__name__
    return model.heading_velocity(stationary), description


def prepare(rec: Recording, options: NavOptions = NavOptions()) -> _Prepared:
    """Checks, calibration, detection, alignment and pseudo-velocity of one recording (no filtering)."""
    gravity = _gravity(rec, options)
    report = check_recording(rec, gravity)
    acc, gyr, cal_info = _calibrate(rec, options)
    result = _detect(rec, acc, gyr, options, gravity)
    check_stance_found(result.stationary, str(result.params.as_dict()),
                       float(result.statistic.min()) if result.statistic.size else math.nan)
    method = _method(rec, options, cal_info["applied"])
    alignment = align(acc, result.stationary, 0.0, options.align_min_samples)
    start = alignment.start
    if options.heading is not None:
        yaw, heading_source = float(options.heading), "given"
    elif rec.truth is not None:
        yaw, heading_source = float(yaw_of(rec.truth.quat[start])), "truth at the start"
    elif rec.reference is not None:
        yaw, heading_source = 0.0, "reference first leg"
    else:
        yaw, heading_source = 0.0, "default 0 (no truth or reference)"
    alignment = align(acc, result.stationary, yaw, options.align_min_samples)
    if rec.truth is not None:
        pos0 = np.asarray(rec.truth.pos[start], float)
    elif rec.reference is not None:
        ref = rec.reference
        ok = np.all(np.isfinite(ref.pos), axis=1)
        pos0 = np.array([np.interp(rec.t[start], ref.t[ok], ref.pos[ok, i]) for i in range(3)])
    else:
        pos0 = np.zeros(3)
    pseudo, pseudo_source = _pseudo_velocity(options, result.stationary)
    if method == "increments":
        acc, gyr = rec.truth.dv, rec.truth.dth
    info = {
        "detector": result.params.as_dict(),
        "stationary_fraction": float(result.stationary.mean()),
        "filter": replace(options.filter, gravity=gravity).as_dict(),
        "mechanisation": method,
        "alignment": {"start_sample": start, "end_sample": alignment.end, "roll_deg": math.degrees(alignment.roll),
                      "pitch_deg": math.degrees(alignment.pitch), "heading_source": heading_source},
        "calibration": cal_info,
        "stance_velocity": pseudo_source,
        "rts": options.rts,
        "warnings": report.warnings,
        "input_counts": report.counts,
    }
    return _Prepared(np.asarray(rec.t, float), acc, gyr, result.stationary, method, start, alignment.quat0, pos0,
                     pseudo, heading_source, info)


def _solution(p: _Prepared, out: FilterOutput, yaw: float) -> Solution:
    p.info["alignment"]["heading_deg"] = math.degrees(yaw)
    p.info["skipped_updates"] = int(out.skipped_updates)
    return Solution(p.t, out.pos, out.vel, out.quat, p.stationary, p.start, out.bias_acc[-1], out.bias_gyr[-1],
                    out.gsens[-1], p.info)


def _reference_heading(rec: Recording, p: _Prepared, pos: np.ndarray) -> float:
    """Heading (rad) that turns a heading-0 solution's first leg onto the reference's first leg."""
    ref_dir, t_leg = first_leg_direction(rec.reference.t, rec.reference.pos, p.t[p.start])
    if not math.isfinite(ref_dir):
        return 0.0
    est = np.array([np.interp(t_leg, p.t[p.start:], pos[p.start:, i]) for i in range(2)]) - pos[p.start, :2]
    return ref_dir - math.atan2(est[1], est[0])


def _with_heading(p: _Prepared, yaw: float) -> np.ndarray:
    from . import quaternion as quat

    return quat.multiply(quat.from_euler_zyx(yaw, 0.0, 0.0), p.quat0)


def _config(p: _Prepared) -> FilterConfig:
    return FilterConfig(**p.info["filter"])


def navigate(rec: Recording, options: NavOptions = NavOptions()) -> Solution:
    """Navigate one recording; see the module docstring for the steps."""
    p = prepare(rec, options)
    cfg = _config(p)

    def once(q0):
        return run_filter(p.t, p.acc, p.gyr, p.stationary, q0, pos0=p.pos0, start=p.start, config=cfg,
                          method=p.method, pseudo_velocity=p.pseudo_velocity, rts=options.rts)

    out = once(p.quat0)
    yaw = float(yaw_of(p.quat0))
    if p.heading_source == "reference first leg":
        turn = _reference_heading(rec, p, out.pos)
        yaw += turn
        out = once(_with_heading(p, turn))
    return _solution(p, out, yaw)


def navigate_batch(recs: list[Recording], options: NavOptions = NavOptions()) -> list[Solution]:
    """Navigate many recordings of equal length in one compiled filter call (a Monte Carlo batch).

    Preparation (checks, detection, alignment) is per recording; the filter runs all recordings in lock-step
    arrays, spread over cores. Each result equals :func:`navigate` on that recording.
    """
    preps = [prepare(r, options) for r in recs]
    lengths = {len(p.t) for p in preps}
    methods = {p.method for p in preps}
    if len(lengths) != 1 or len(methods) != 1:
        raise ValueError(f"navigate_batch: recordings must share length and mechanisation; got lengths "
                         f"{sorted(lengths)} and methods {sorted(methods)}")
    configs = {tuple(sorted(p.info["filter"].items())) for p in preps}
    if len(configs) != 1:
        raise ValueError("navigate_batch: recordings imply different filter configurations (gravity in meta.json)")
    cfg = _config(preps[0])

    def once(q0):
        return run_filter_batch(np.stack([p.t for p in preps]), np.stack([p.acc for p in preps]),
                                np.stack([p.gyr for p in preps]), np.stack([p.stationary for p in preps]), q0,
                                pos0=np.stack([p.pos0 for p in preps]), start=np.array([p.start for p in preps]),
                                config=cfg, method=preps[0].method,
                                pseudo_velocity=np.stack([p.pseudo_velocity for p in preps]), rts=options.rts)

    out = once(np.stack([p.quat0 for p in preps]))
    yaws = [float(yaw_of(p.quat0)) for p in preps]
    needs_turn = [p.heading_source == "reference first leg" for p in preps]
    if any(needs_turn):
        turns = [_reference_heading(r, p, out.pos[i]) if needs_turn[i] else 0.0
                 for i, (r, p) in enumerate(zip(recs, preps))]
        out = once(np.stack([_with_heading(p, turn) for p, turn in zip(preps, turns)]))
        yaws = [y + turn for y, turn in zip(yaws, turns)]
    solutions = []
    for i, p in enumerate(preps):
        single = FilterOutput(out.quat[i], out.vel[i], out.pos[i], out.bias_acc[i], out.bias_gyr[i], out.gsens[i],
                              out.p_diag[i], out.skipped_updates[i])
        solutions.append(_solution(p, single, yaws[i]))
    return solutions


def score_solution(rec: Recording, sol: Solution) -> dict:
    """Scores of a solution (nav.metrics) plus the run's parameters; keys documented in nav.metrics."""
    result = {"scored_against": None}
    if rec.truth is not None:
        result.update(metrics.score(sol.t, sol.pos, rec.truth.t, rec.truth.pos, sol.quat, rec.truth.quat,
                                    sol.stationary))
        result["scored_against"] = "truth"
        result["detector_confusion"] = metrics.confusion(sol.stationary[sol.start:], rec.truth.stance[sol.start:])
    elif rec.reference is not None:
        result.update(metrics.score(sol.t, sol.pos, rec.reference.t, rec.reference.pos,
                                    stationary=sol.stationary))
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
    sol = navigate(rec, options)
    return sol, score_solution(rec, sol)
