"""The digital twin of a recording: a scenario fitted to it, simulated and navigated like the recording.

Fit (:func:`fit_twin`; every number it used goes into ``Twin.notes``):

- **Timing.** Cadence from the median stride period of the IMU-detected strides; ``cycle_sd_frac`` from their
  spread.
- **Gait shape** (:mod:`gaitsim.loop.gait_fit`): the phase fractions, the pitch angles, rates and
  accelerations at heel strike and toe off, and the forefoot slap, fitted so that the simulator's pitch rate
  over a stride matches the recording's rate about its dominant axis (gaitmap: 35-40 deg/s rms left, against
  ~170 deg/s for the default gait).
- **Walk or run** (:func:`_gait_shapes`): a recording at least ``settings.WALK_RUN_SPEED_MPS`` fast (stride length
  x stride rate) is a run, and its twin starts from the running defaults of :mod:`gaitsim.world.gaits` (a foot
  never still in stance, a swing that stops at a pitch maximum, harder landings) with the strike, rearfoot or
  forefoot, whose fitted pitch rate matches better (simulated runs: 42-50 deg/s rms; a walking twin of a run
  peaks at half its rate). A fitted shape whose simulated strides the detector cannot cut is passed over for
  the next candidate, the kinds' unfitted defaults last; the note ``gait_kind`` says which was taken.
- **Clearance.** With a continuous position track, ``swing_height_m`` is scaled by measured / twin median
  height of the track in swing above the stance level.
- **Stride length and turns.** From the position track at the stance centres (the reference when it has more
  than two samples, else the IMU-navigated track): stride length = median stance-to-stance distance; the path is
  those points simplified (Ramer-Douglas-Peucker, ``settings.PATH_TOLERANCE_M``) into a polyline with rounded
  corners (the first of ``settings.CORNER_RADII_M`` and half a stride that fits the legs); a U-turn (corner
  above ``settings.HAIRPIN_TURN``) becomes a hairpin, its return leg moved sideways by two corner radii.
  When no polyline fits, a straight walk of the same length.
- **Rest.** ``stand_start_s`` / ``stand_end_s`` from the first / last detected rest (at least ``settings.MIN_REST_S``).
- **Sensor position** on the foot (:mod:`gaitsim.loop.mount_fit`): the height above the sole read from the
  push-off (a rigid turn about the still toe contact, :func:`gaitsim.loop.push_off.push_off_height`), and the
  position along the foot that best reproduces the recording's accelerometer phase profiles where the foot turns
  about a ground contact (linear least squares over three simulations).
- **Foot side.** The stance model's roll (pronation) is a left foot's and is mirrored for a right foot: the twin
  is a right foot when the recording's mean core-stance roll rate (``stance_rate_x``) is negative.
- **Mount.** Roll and pitch of the sensor on the foot from the mean specific force at the quietest window, and
  its yaw from the swing axis (:func:`refit_yaw`, before the sensor position, and again after every effect the
  loop adds), written as the sensor's ``mounting_misalignment`` (roll, pitch, yaw). The yaw is the twin's, not an
  effect of the library: an added yaw would be undone by the re-fit after it.
- **Sensor noise and gyro bias**: white-noise densities std / sqrt(rate) per axis from the quietest
  ``settings.QUIET_WINDOW_S`` of the recording, and the mean angular rate over every detected rest's core as the
  gyro bias. :func:`match_noise` rescales the densities so that the twin's *output* has the recording's static
  standard deviation (once effects such as a bandwidth filter the noise, the density that gives it is larger).

Cadence and clearance are then corrected by simulating the twin and matching the same statistics
(``settings.FIT_ITERATIONS`` rounds), so they do not rely on how a detector sees the simulator's events.

The twin holds a :class:`gaitsim.scenario.Scenario` (SI objects, validated once); changes come as TOML-shaped
``{section: {key: value}}`` tables (what a user would paste into a scenario file) and are converted by
:func:`gaitsim.scenario.with_changes`. A :class:`TwinSimulator`, owned by one loop run, simulates twins and keeps
their ideal-sensor walks, so effects that only change the sensor cost one sensor-model pass.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from nav.alignment import stationary_runs, tilt_from_specific_force
from nav.checks import quietest_window
from nav.recording import Events, Recording, Truth
from nav.series import resample

from ..errors import ScenarioError
from ..measured.reference import reference_track
from ..scenario import Scenario, fill, scenario_document, scenario_from_dict, with_changes
from ..simulate import sense, simulate_world
from ..world import path as paths
from ..world.foot import FootModel
from ..world.gait import GaitParams, ImpactParams, MicroMotionParams
from ..world.gaits import CADENCE_SPAN, run_tables
from . import gait_fit, mount_fit, settings
from .push_off import push_off_height
from .signature import Signature, rest_core, signature


@dataclass
class Twin:
    """A fitted twin: its scenario (SI objects), how each value was found, and the seed it is simulated with."""

    scenario: Scenario
    notes: dict = field(default_factory=dict)
    seed: int = settings.TWIN_SEED

    def with_changes(self, changes: dict) -> "Twin":
        """A copy with TOML-shaped ``{section: {key: value}}`` changes (keys and units of a scenario file).

        Raises
        ------
        ScenarioError
            when the changed scenario is not a valid one.
        """
        return Twin(with_changes(self.scenario, changes, "<twin>"), dict(self.notes), self.seed)

    def document(self) -> dict:
        """The twin's scenario as a TOML-shaped document (what a user can save as a scenario file)."""
        return scenario_document(self.scenario)


class TwinSimulator:
    """Simulates twins for one loop run, keeping the ideal-sensor walks used last, up to ``budget_mb`` MB of their
    truth (at least two), keyed on what they depend on (walk, mount, rate, gravity, seed): an effect that only
    changes the sensor costs one sensor-model pass, and the twin every round returns to stays kept."""

    def __init__(self, budget_mb: float = settings.TRUTH_CACHE_MB):
        self.budget_bytes = budget_mb * 1e6
        self._walks: dict[tuple, tuple[Truth, Events, dict]] = {}

    def __call__(self, twin: Twin, seed: int | None = None) -> Recording:
        """The twin's recording (``seed`` default the twin's): its walk, then its sensor."""
        seed = twin.seed if seed is None else seed
        s = twin.scenario
        key = (s.walk, s.mount, s.rate_hz, s.gravity, seed)
        walk = self._walks.pop(key, None)
        if walk is None:
            walk = simulate_world(s, seed)
            size = _truth_bytes(walk[0])
            while len(self._walks) >= 2 and (len(self._walks) + 1) * size > self.budget_bytes:
                self._walks.pop(next(iter(self._walks)))  # the one used longest ago
        self._walks[key] = walk
        return sense(*walk, s.sensor, seed)


def _truth_bytes(truth: Truth) -> int:
    """Bytes held by the arrays of ``truth``."""
    return sum(value.nbytes for value in vars(truth).values() if isinstance(value, np.ndarray))


def match_noise(twin: Twin, simulate: TwinSimulator) -> Twin:
    """Rescale the twin's white-noise densities so its quietest-window output std equals the recording's
    (``notes["static_std"]``); one multiplicative correction per axis."""
    target = twin.notes.get("static_std")
    sensor = twin.scenario.sensor
    if target is None or sensor is None:
        return twin
    rec = simulate(twin)
    q0, q1 = quietest_window(rec.acc, int(settings.QUIET_WINDOW_S * twin.scenario.rate_hz))
    densities = {}
    for key, data, want in (("accel_noise_density", rec.acc, target["acc_mps2"]),
                            ("gyro_noise_density", rec.gyr, target["gyr_rad_s"])):
        have = np.maximum(data[q0:q1].std(0, ddof=1), 1e-12)
        densities[key] = sensor[key] * np.asarray(want) / have
    return Twin(dataclasses.replace(twin.scenario, sensor=sensor.replace(**densities)), twin.notes, twin.seed)


# ------------------------------------------------------------------------------------------------ statistics
def _swing_height(t: np.ndarray, sig: Signature, pos_t, pos) -> float:
    """Median over strides of the highest track point in swing above the mean of the two stance levels (m)."""
    heights = []
    for (s0, s1), (c0, c1) in zip(sig.strides, sig.stances):
        z_stance = np.interp([t[(c0 + c1) // 2], t[min(s1 + (c1 - c0) // 2, len(t) - 1)]], pos_t, pos[:, 2])
        inside = (pos_t >= t[c1]) & (pos_t <= t[s1])
        z = pos[inside, 2]
        z = z[np.isfinite(z)]
        if z.size:
            heights.append(z.max() - z_stance.mean())
    return float(np.median(heights)) if heights else math.nan


def gait_statistics(rec: Recording, sig: Signature, pos_t=None, pos=None) -> dict:
    """The statistics the twin is matched on by simulation (module docstring): period (s), its relative spread,
    swing_height (m, NaN without a track)."""
    periods = rec.t[sig.strides[:, 1]] - rec.t[sig.strides[:, 0]]
    height = _swing_height(rec.t, sig, pos_t, pos) if pos is not None else math.nan
    return {"period_s": float(np.median(periods)), "period_sd_frac": float(np.std(periods) / np.mean(periods)),
            "swing_height_m": height}


# ------------------------------------------------------------------------------------------------ path
def path_table(points: np.ndarray, stride_length: float) -> tuple[dict, str]:
    """A [path] table through the stance centres ``points`` (K, 2) m, and how it was built: a polyline with the
    first corner radius that fits its legs (and is at least one step, the last tried one step and
    ``settings.RADIUS_MARGIN_M``, so that round-off in the built path keeps it valid), else a straight walk."""
    simple = paths.simplify(points, settings.PATH_TOLERANCE_M)
    length = float(np.sum(np.hypot(*np.diff(points, axis=0).T)))
    if len(simple) > 2:
        for radius in (*settings.CORNER_RADII_M, stride_length / 2 + settings.RADIUS_MARGIN_M):
            waypoints = paths.hairpins(simple, radius, settings.HAIRPIN_TURN)
            if (radius >= stride_length / 2 and paths.corners_fit(waypoints, radius)
                    and paths.polyline(waypoints, radius).length >= stride_length):
                table = {"kind": "polyline", "waypoints_m": waypoints.tolist(), "corner_radius_m": radius}
                return table, f"polyline of {len(waypoints)} points, corner radius {radius} m"
    d = simple[-1] - simple[0]
    yaw = math.degrees(math.atan2(d[1], d[0])) if np.hypot(*d) > settings.STRAIGHT_MIN_SPAN_M else 0.0
    return ({"kind": "straight", "length_m": max(length, stride_length), "yaw_deg": yaw},
            "straight walk of the same length (no polyline fitted the track)")


# ------------------------------------------------------------------------------------------------ fit
def _rest_runs(t: np.ndarray, stationary: np.ndarray) -> tuple[float, float]:
    """Durations (s) of the first and the last detected rest, at least ``settings.MIN_REST_S``."""
    starts, ends = stationary_runs(stationary)
    least = settings.MIN_REST_S
    first = t[ends[0] - 1] - t[starts[0]] if len(starts) else least
    last = t[ends[-1] - 1] - t[starts[-1]] if len(starts) else least
    return max(least, float(first)), max(least, float(last))


def _rest_gyro_mean(rec: Recording, stationary: np.ndarray, quiet: tuple[int, int]) -> np.ndarray:
    """Mean angular rate (rad/s) over the core (:func:`gaitsim.loop.signature.rest_core`: less
    ``settings.REST_MARGIN_S`` at both ends, where a detected rest reaches into the heel off) of every detected
    rest whose core lasts at least ``settings.QUIET_WINDOW_S``, or over the quietest window when there is none:
    the gyro bias the twin is given. Over 0.5 s of a consumer gyro its standard error is ~0.03 deg/s, as large
    as the heading drifts compared, so every rest sample counts."""
    cores = [rest_core(rec.t, run) for run in zip(*stationary_runs(stationary))]
    cores = [c for c in cores if c.stop > c.start and rec.t[c.stop - 1] - rec.t[c.start] >= settings.QUIET_WINDOW_S]
    rest = np.concatenate([rec.gyr[c] for c in cores]) if cores else rec.gyr[quiet[0]:quiet[1]]
    return rest.mean(axis=0)


def _track(rec: Recording, solution) -> tuple[np.ndarray, np.ndarray, str]:
    pos_t, pos = reference_track(rec)
    if pos is not None:
        return pos_t, pos, "reference"
    return solution.t, solution.pos, "IMU-navigated track"


def fit_twin(rec: Recording, sig: Signature, solution, simulate: TwinSimulator) -> Twin:
    """Fit a twin to ``rec`` (its signature ``sig`` and navigation ``solution``), simulating it with
    ``simulate``; see the module docstring."""
    rate = float(round(sig.rate_hz, 1))
    gravity = sig.gravity
    notes = {}
    track_t, track, source = _track(rec, solution)
    centres = rec.t[(sig.stances[:, 0] + sig.stances[:, 1]) // 2]
    ok = np.isfinite(track[:, 0])
    xy = resample(centres, track_t[ok], track[ok, :2])
    steps = np.hypot(*np.diff(xy, axis=0).T)
    stride_length = float(np.median(steps)) if len(steps) else settings.DEFAULT_STRIDE_LENGTH_M
    stationary = sig.stationary
    all_centres = rec.t[(sig.stance_runs[:, 0] + sig.stance_runs[:, 1]) // 2]
    all_xy = resample(all_centres, track_t[ok], track[ok, :2])
    path, path_note = path_table(all_xy, stride_length)
    stand_start, stand_end = _rest_runs(rec.t, stationary)
    q0, q1 = quietest_window(rec.acc, int(settings.QUIET_WINDOW_S * sig.rate_hz))
    roll, pitch = tilt_from_specific_force(rec.acc[q0:q1].mean(0))
    acc_sd = np.maximum(rec.acc[q0:q1].std(0, ddof=1), settings.MIN_ACC_SD_MPS2)
    gyr_sd = np.maximum(rec.gyr[q0:q1].std(0, ddof=1), settings.MIN_GYR_SD_RAD_S)
    measured = gait_statistics(rec, sig, *((track_t, track) if source == "reference" else (None, None)))
    doc = {
        "scenario": {"name": "twin", "description": f"digital twin of {rec.meta.get('recording', 'a recording')}"},
        "path": path,
        "gait": {"cadence_steps_per_min": 120.0 / measured["period_s"], "stride_length_m": stride_length,
                 "cycle_sd_frac": min(settings.MAX_CYCLE_SD_FRAC, measured["period_sd_frac"]),
                 "stand_start_s": stand_start, "stand_end_s": stand_end},
        "sampling": {"rate_hz": rate, "gravity_mps2": gravity},
        "sensor": {"preset": "ideal",
                   "accel_noise_density": [(acc_sd / math.sqrt(rate)).tolist(), "m/s^2/sqrt(Hz)"],
                   "gyro_noise_density": [(gyr_sd / math.sqrt(rate)).tolist(), "rad/s/sqrt(Hz)"],
                   "gyro_bias": [_rest_gyro_mean(rec, stationary, (q0, q1)).tolist(), "rad/s"],
                   **_mount_angles(roll, pitch, 0.0)["sensor"]},
    }
    foot = "right" if sig.scalars["stance_rate_x"].value < 0 else "left"
    notes.update(static_std={"acc_mps2": acc_sd.tolist(), "gyr_rad_s": gyr_sd.tolist()},
                 measured_statistics=measured, track=source, path=path_note,
                 stride_length_m=stride_length, quiet_window_s=[float(rec.t[q0]), float(rec.t[q1 - 1])])
    refused = []
    for tables, kind_note in _gait_shapes(gait_fit.stride_profile(rec.t, rec.acc, rec.gyr, sig), doc["gait"]):
        doc.update(gait=tables["gait"], impact=tables["impact"], micromotion={**tables["micromotion"], "foot": foot})
        shaped = Twin(scenario_from_dict(doc, "<twin>"), {**notes, "gait_shape_fit": kind_note.pop("shape_fit"),
                                                          "gait_kind": {**kind_note, "refused": refused}})
        try:
            _signature_of(simulate(shaped))
            break
        except ValueError as exc:  # a gait shape whose strides the detector cannot cut: the next candidate
            refused.append(f"{kind_note['kind']} ({kind_note['shape']}): {exc}")
    twin, yaw_quality = refit_yaw(shaped, sig, simulate)
    gait = twin.scenario.walk.gait
    phases = mount_fit.contact_phases(gait.heel_rocker_frac, gait.foot_flat_frac, gait.push_off_frac)
    lag = sig.scalars["acc_gyro_lag"].value
    height, height_se, ahead = push_off_height(rec.t, rec.acc, rec.gyr, sig.stances, lag if math.isfinite(lag) else 0.0)
    site, site_quality = mount_fit.fit_lever_arm(
        sig, lambda r: simulate(twin.with_changes({"mount": mount_table(r)})), phases, height)
    twin = twin.with_changes({"mount": mount_table(site)})
    twin.notes["mount_fit"] = {**site_quality, **yaw_quality, "push_off_height_m": height,
                               "push_off_height_se_m": height_se, "push_off_ahead_of_pivot_m": ahead}
    twin = match_noise(twin, simulate)
    for _ in range(settings.FIT_ITERATIONS):
        twin = _correct(twin, measured, simulate)
    twin.notes["twin_statistics"] = _twin_statistics(twin, measured, simulate)
    return twin


def _gait_shapes(profile: gait_fit.StrideProfile, timing: dict):
    """The twin's candidate [gait], [impact] and [micromotion] tables, best first, each with what decided it: walking
    or running, with the gait shape fitted to the recording's stride ``profile``
    (:func:`gaitsim.loop.gait_fit.fit_pitch_profile`) on top of ``timing`` (the [gait] keys of cadence, stride
    length, their spread and the rests). :func:`fit_twin` takes the first whose simulation the detector cuts into
    strides.

    A recording whose speed (stride length x stride rate) reaches ``settings.WALK_RUN_SPEED_MPS`` is a run: its twin
    starts from the running defaults of :mod:`gaitsim.world.gaits` at the recording's cadence (held inside the span
    they are documented for; a running foot is never still in stance, its swing stops at a pitch maximum), and the
    rearfoot and the forefoot strike are ranked by how well their fitted pitch rate matches the recording's.
    Slower recordings keep the walking defaults of :class:`gaitsim.world.gait.GaitParams`. After the fitted shapes
    come the kinds' defaults unfitted (a fit can reach a shape whose stance the detector misses)."""
    cadence = timing["cadence_steps_per_min"]
    speed = timing["stride_length_m"] * cadence / 120.0
    note = {"speed_mps": speed, "walk_run_speed_mps": settings.WALK_RUN_SPEED_MPS}
    if speed < settings.WALK_RUN_SPEED_MPS:
        starts, bounds = {"walk": {"gait": {}, "impact": {}, "micromotion": {}}}, settings.PITCH_FIT_BOUNDS
    else:
        held = float(np.clip(cadence, *CADENCE_SPAN["run-rearfoot"]))
        starts = {kind: run_tables(held, forefoot=kind == "run-forefoot") for kind in ("run-rearfoot", "run-forefoot")}
        bounds = settings.RUN_PITCH_FIT_BOUNDS
    fitted = []
    for kind, tables in starts.items():
        gait = {**tables["gait"], **timing}
        shape, quality = gait_fit.fit_pitch_profile(
            profile, fill(GaitParams, gait, "<twin> [gait]"), fill(ImpactParams, tables["impact"], "<twin> [impact]"),
            fill(MicroMotionParams, tables["micromotion"], "<twin> [micromotion]"), bounds)
        fitted.append((quality["rms_rate_misfit_fit_dps"], kind, quality,
                       {"gait": {**gait, **shape["gait"]}, "impact": {**tables["impact"], **shape["impact"]},
                        "micromotion": tables["micromotion"]}))
    misfits = {kind: misfit for misfit, kind, _, _ in fitted}
    for _, kind, quality, tables in sorted(fitted, key=lambda f: f[0]):
        yield tables, {**note, "kind": kind, "shape": "fitted", "rms_rate_misfit_dps": misfits, "shape_fit": quality}
    for kind, tables in starts.items():
        yield ({**tables, "gait": {**tables["gait"], **timing}},
               {**note, "kind": kind, "shape": "defaults", "rms_rate_misfit_dps": misfits, "shape_fit": None})


def _signature_of(rec: Recording) -> Signature:
    """The signature of a twin's recording (raises ValueError when it has fewer than three regular strides)."""
    return signature(rec.t, rec.acc, rec.gyr, gravity=rec.gravity)


def refit_yaw(twin: Twin, measured: Signature, simulate: TwinSimulator) -> tuple[Twin, dict]:
    """``twin`` with the sensor's yaw on the foot fitted to the recording's swing axis from its current yaw
    (:func:`gaitsim.loop.mount_fit.fit_yaw`), and what the fit did. Done in the fit and again after every effect
    the loop adds: a change of the foot's motion (its stance rates, say) turns the swing axis as well."""
    roll, pitch, yaw = twin.scenario.sensor["mounting_misalignment"]
    fitted, quality = mount_fit.fit_yaw(
        measured, lambda y: simulate(twin.with_changes(_mount_angles(roll, pitch, y))), math.degrees(yaw))
    return twin.with_changes(_mount_angles(roll, pitch, fitted)), quality


def with_effect(twin: Twin, changes: dict, measured: Signature, simulate: TwinSimulator) -> Twin:
    """``twin`` with an effect's scenario ``changes`` added, as the loop adds it: the yaw re-fitted to the
    recording's swing axis (:func:`refit_yaw`), then the noise re-matched (:func:`match_noise`)."""
    changed, _ = refit_yaw(twin.with_changes(changes), measured, simulate)
    return match_noise(changed, simulate)


def _mount_angles(roll: float, pitch: float, yaw_deg: float) -> dict:
    """A [sensor] table turning the sensor on the foot by ``roll``, ``pitch`` (rad) and ``yaw_deg`` (deg)."""
    return {"sensor": {"mounting_misalignment": [[math.degrees(roll), math.degrees(pitch), yaw_deg], "deg"]}}


def mount_table(site: np.ndarray) -> dict:
    """A [mount] table putting the IMU site at ``site`` (m, foot frame from the heel contact)."""
    return {"site": "toes", "offset_m": (np.asarray(site, float) - FootModel().lever_arm).tolist()}


def _twin_statistics(twin: Twin, measured: dict, simulate: TwinSimulator) -> dict:
    sim = simulate(twin)
    sig = signature(sim.t, sim.acc, sim.gyr)
    track = (sim.truth.t, sim.truth.pos) if math.isfinite(measured["swing_height_m"]) else (None, None)
    return gait_statistics(sim, sig, *track)


def _correct(twin: Twin, measured: dict, simulate: TwinSimulator) -> Twin:
    """One matching round: scale the cadence and the clearance by twin / measured statistics (kept only when the
    scenario stays valid; a skipped correction is noted)."""
    have = _twin_statistics(twin, measured, simulate)
    gait = twin.scenario.walk.gait
    changes = {"cadence_steps_per_min": gait.cadence_steps_per_min * have["period_s"] / measured["period_s"]}
    if math.isfinite(measured["swing_height_m"]) and have["swing_height_m"] > 0:
        changes["swing_height_m"] = float(np.clip(gait.swing_height_m * measured["swing_height_m"]
                                                  / have["swing_height_m"], *settings.SWING_HEIGHT_BOUNDS_M))
    try:
        return twin.with_changes({"gait": changes})
    except ScenarioError as exc:
        twin.notes.setdefault("fit_warnings", []).append(f"correction skipped: {exc}")
        return twin
