"""Experiment settings from a scenario file's [nav] and [experiment] tables, and the one-off calibrations.

The compensation is estimated the way a lab would: the readout calibration from the simulated calibration lab
(its own seed), the stance pseudo-velocity from tracked calibration walks (their own seeds) -- never from the
truth of the runs being scored.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from nav import detectors
from nav.calibration import load_calibration
from nav.ekf import FilterConfig
from nav.pipeline import NavOptions, prepare
from nav.recording import Recording
from nav.alignment import stationary_runs
from nav.zupt_velocity import StanceVelocityProfile, save_stance_velocity, to_heading_frame

from ..errors import ScenarioError
from ..imu.calibration_lab import run_lab
from ..ranges import check_ranges
from ..scenario import Scenario, fill, scenario_from_dict
from .tracker import TrackerSpec, track, velocity_within
from ..simulate import simulate_walk


@dataclass(frozen=True)
class NavSettings:
    """The [nav] table: detector and filter of every run (units in the names)."""

    detector: str = "shoe"
    threshold: float = 3.0e4
    sigma_a_mps2: float = 0.01
    sigma_g_dps: float = 0.1
    window: int = 3
    states: int = 9

    def options(self, **changes) -> NavOptions:
        base = NavOptions(detector=self.detector, threshold=self.threshold, sigma_a=self.sigma_a_mps2,
                          sigma_g=np.deg2rad(self.sigma_g_dps), window=self.window,
                          filter=FilterConfig(states=self.states))
        return dataclasses.replace(base, **changes)


@dataclass(frozen=True)
class ExperimentSettings:
    """The [experiment] table of the paper reproduction (see scenarios/paper.toml for each value's meaning)."""

    lab_seed: int = 101
    calibration_walk_seed: int = 202
    calibration_walks: int = 3
    tracker_rate_hz: float = 60.0
    tracker_resolution_m: float = 0.001
    tracker_noise_m: float = 0.0005
    stance_profile_knots: int = 21
    before_calibration_terms: tuple[str, ...] = ("bias",)
    threshold_sweep: tuple[float, ...] = (1e4, 2e4, 3e4, 4e4, 5e4)
    threshold_sweep_runs: int = 10
    fig4_thresholds: tuple[float, ...] = (1e4, 2e4, 3e4)
    cycle_count: int = 70
    heading_walk_length_m: float = 550.0
    budget_runs: int = 10
    sensitivity_runs: int = 4
    sensitivity_cadences: tuple[float, ...] = (70.0, 84.0, 100.0)
    sensitivity_mounts: tuple[str, ...] = ("toes", "instep", "heel")
    sensitivity_presets: tuple[str, ...] = ("bmi160", "vn200", "adis16497")
    sensitivity_detectors: tuple[str, ...] = ("shoe", "are", "mv", "mag")
    workers: int = 2


@dataclass(frozen=True)
class PaperTargets:
    """The [targets] table: the seed paper's numbers the reproduction is measured against (every key required;
    see scenarios/paper.toml for each one's source). Units in the names; deg/s for the heading drift."""

    perpendicular_error_before_m: float = math.nan
    along_track_error_before_m: float = math.nan
    final_error_before_m: float = math.nan
    final_error_after_max_m: float = math.nan
    reduction_min: float = math.nan
    heading_drift_dps: float = math.nan
    detected_stance_at_1e4_s: float = math.nan
    detected_stance_at_3e4_s: float = math.nan
    fig5_gap_max: float = math.nan
    relative_tolerance: float = math.nan

    def within(self, value: float, target: float) -> str:
        """"yes" when ``value`` lies within ``relative_tolerance`` x |target| of ``target``, else "no"."""
        return "yes" if abs(value - target) <= self.relative_tolerance * abs(target) else "no"


def targets_from_scenario(scenario: Scenario) -> PaperTargets:
    """Validate the [targets] table: every key of :class:`PaperTargets`, a number each."""
    where = f"{scenario.source} [targets]"
    targets = fill(PaperTargets, scenario.targets, where)
    missing = [f.name for f in dataclasses.fields(PaperTargets) if f.name not in scenario.targets]
    if missing:
        raise ScenarioError(f"{where}: missing key(s) {missing}; every one of them is required")
    for key, value in dataclasses.asdict(targets).items():
        if not math.isfinite(value):
            raise ScenarioError(f"{where}: {key} = {value!r} is not allowed; a target must be a finite number")
    return targets


def _tuple_fields(cls) -> dict:
    return {f.name: f.default for f in dataclasses.fields(cls) if isinstance(f.default, tuple)}


def settings_from_scenario(scenario: Scenario) -> tuple[NavSettings, ExperimentSettings]:
    """Validate the [nav] and [experiment] tables (unknown keys and wrong types refused)."""
    nav = fill(NavSettings, scenario.nav, f"{scenario.source} [nav]")
    check_ranges("nav", dataclasses.asdict(nav), f"{scenario.source} [nav]")
    if nav.detector not in detectors.DETECTORS:
        raise ScenarioError(f"{scenario.source} [nav]: detector = {nav.detector!r}; allowed: {detectors.DETECTORS}")
    if nav.states not in (9, 15, 24):
        raise ScenarioError(f"{scenario.source} [nav]: states = {nav.states}; allowed: 9, 15, 24")
    table = dict(scenario.experiment)
    lists = {}
    for key, default in _tuple_fields(ExperimentSettings).items():
        if key in table:
            value = table.pop(key)
            kind = type(default[0])
            if not (isinstance(value, list) and value and all(isinstance(v, (int, float, str)) for v in value)):
                raise ScenarioError(f"{scenario.source} [experiment]: {key} = {value!r} must be a non-empty list")
            lists[key] = tuple(kind(v) for v in value)
    exp = dataclasses.replace(fill(ExperimentSettings, table, f"{scenario.source} [experiment]"), **lists)
    unknown = [d for d in exp.sensitivity_detectors if d not in detectors.DETECTORS]
    if unknown:
        raise ScenarioError(f"{scenario.source} [experiment]: sensitivity_detectors has {unknown}; allowed: "
                            f"{detectors.DETECTORS}")
    check_ranges("experiment", dataclasses.asdict(exp), f"{scenario.source} [experiment]")
    return nav, exp


def scenario_doc(scenario: Scenario) -> dict:
    """The scenario as a TOML-like dict that :func:`gaitsim.scenario.scenario_from_dict` rebuilds (for tasks)."""
    import tomllib

    with open(scenario.source, "rb") as fh:
        return tomllib.load(fh)


def patched(doc: dict, **sections) -> dict:
    """A deep copy of ``doc`` with the given sections' keys replaced (``path`` is replaced whole)."""
    out = copy.deepcopy(doc)
    for section, table in sections.items():
        if section == "path" or table is None:
            out[section] = copy.deepcopy(table)
            if table is None:
                del out[section]
        else:
            out.setdefault(section, {}).update(copy.deepcopy(table))
    return out


def calibrate_sensor(scenario: Scenario, exp: ExperimentSettings, out: Path) -> Path:
    """Run the simulated calibration lab on the scenario's sensor (own seed) and write calibration.json."""
    path = out / "calibration.json"
    run_lab(scenario.sensor, np.random.default_rng(exp.lab_seed), out_path=path)
    return path


def calibration_walks(doc: dict, exp: ExperimentSettings) -> list[Recording]:
    """The calibration walks of scenario ``doc``: runs 0 .. calibration_walks - 1 with their own seed
    (``calibration_walk_seed``), never the scored runs."""
    scenario = scenario_from_dict(doc, "calibration walks")
    return [simulate_walk(scenario, seed=exp.calibration_walk_seed, run=k) for k in range(exp.calibration_walks)]


def matched_thresholds(doc: dict, nav: NavSettings, exp: ExperimentSettings, calibration: Path,
                       names: tuple[str, ...]) -> dict[str, float]:
    """Thresholds of the statistical detectors ``names`` at the [nav] detector's operating point.

    SHOE, ARE, MV and MAG divide different sums by sigma_a^2 or sigma_g^2, so one number means a different gate
    in each (a SHOE threshold bounds the sum of an accelerometer and a gyro term; ARE's the gyro term alone;
    MV's the window's spread). Each detector here gets, in its own statistic's units, the threshold that marks
    the same share of the calibration walks' samples stationary as the [nav] detector at its threshold (same
    sigmas and window, the readout calibration of ``before_calibration_terms`` applied, as in the scored
    variants): the detectors are compared at equal detected stance, the way detector evaluations compare them
    at one operating point.

    Returns
    -------
    {name: threshold (dimensionless)} for the names among ``nav.detectors.STATISTICS`` (empty if none); the
    [nav] detector keeps its own threshold.
    """
    statistical = [name for name in names if name in detectors.STATISTICS]
    if not statistical:
        return {}
    if nav.detector not in detectors.STATISTICS:
        raise ScenarioError(f"[experiment] sensitivity_detectors {statistical} are matched to the [nav] detector's "
                            f"operating point, but [nav] detector = {nav.detector!r}; allowed then: "
                            f"{detectors.STATISTICS}")
    cal = load_calibration(calibration)
    corrected = [(rec.gravity, *cal.correct(rec.acc, rec.gyr, terms=tuple(exp.before_calibration_terms)))
                 for rec in calibration_walks(doc, exp)]
    options = nav.options()  # the detector settings in SI

    def statistics(name: str) -> list[np.ndarray]:
        return [detectors.statistic(name, acc, gyr, options.sigma_a, options.sigma_g, options.window, gravity)
                for gravity, acc, gyr in corrected]

    share = detectors.marked_share(statistics(nav.detector), options.window, options.threshold)
    return {name: options.threshold if name == nav.detector else
            detectors.threshold_for_fraction(statistics(name), options.window, share) for name in statistical}


def fit_stance_velocity(doc: dict, nav: NavSettings, exp: ExperimentSettings, calibration: Path, out: Path,
                        threshold: float | None = None) -> tuple[Path, dict]:
    """Fit the stance pseudo-velocity from tracked calibration walks with their own seeds.

    Each calibration walk is recorded by the IMU (stance detected exactly as in the scored runs: same detector,
    threshold and readout calibration) and by the simulated 60 Hz tracker. Each detected stance of a step (not
    the standing rests before and after the walk, which the fitted model is then not applied to) gets the
    tracked velocity from the central differences inside it (:func:`~.tracker.velocity_within`), rotated into
    the foot's heading frame; the profile averages them over normalised detected-stance time. Detected stances
    shorter than two tracker periods (fragments next to the main stance) have no such difference and are left
    out: the tracker's velocity there is the landing's or the heel-off's, not the stance's.
    """
    threshold = nav.threshold if threshold is None else threshold
    spec = TrackerSpec(exp.tracker_rate_hz, exp.tracker_resolution_m, exp.tracker_noise_m)
    options = nav.options(threshold=threshold, calibration=calibration,
                          calibration_terms=exp.before_calibration_terms)
    stances, unresolved = [], 0
    for k, rec in enumerate(calibration_walks(doc, exp)):
        tracked = track(rec.truth, spec, np.random.default_rng([exp.calibration_walk_seed, k]))
        starts, ends = stationary_runs(prepare(rec, options).stationary)
        for a, b in list(zip(starts, ends))[1:-1]:  # the first and last runs are the rests around the walk
            vel = velocity_within(tracked, rec.t[a:b])
            if vel is None:
                unresolved += 1
            else:
                stances.append(to_heading_frame(vel, rec.truth.quat[a:b]))
    meta = {"threshold": threshold, "walks": exp.calibration_walks, "seed": exp.calibration_walk_seed,
            "tracker": dataclasses.asdict(spec), "stances": len(stances),
            "stances_shorter_than_the_tracker_difference": unresolved}
    model = StanceVelocityProfile.fit(stances, knots=exp.stance_profile_knots, metadata=meta)
    path = out / f"stance_velocity_{threshold:.0f}.json"
    save_stance_velocity(model, path)
    return path, {"mean_forward_mps": float(np.mean(np.concatenate([s[:, 0] for s in stances]))), **meta}
