"""The digital twin of a recording: a scenario document fitted to it, simulated and navigated like the recording.

Fit (:func:`fit_twin`; every number it used goes into ``Twin.notes``):

- **Timing.** Cadence from the median stride period of the IMU-detected strides; ``cycle_sd_frac`` from their
  spread.
- **Gait shape** (:mod:`gaitsim.loop.gait_fit`): the phase fractions, the pitch angles, rates and
  accelerations at heel strike and toe off, and the forefoot slap, fitted so that the simulator's pitch rate
  over a stride matches the recording's rate about its dominant axis (gaitmap: 35-40 deg/s rms left, against
  ~170 deg/s for the default gait).
- **Clearance.** With a continuous position track, ``swing_height_m`` is scaled by measured / twin median
  height of the track in swing above the stance level.
- **Stride length and turns.** From the position track at the stance centres (the reference when it has more
  than two samples, else the IMU-navigated track): stride length = median stance-to-stance distance; the path is
  those points simplified (Ramer-Douglas-Peucker, ``PATH_TOLERANCE_M``) into a polyline with rounded corners;
  a U-turn (corner above ``HAIRPIN_DEG``) becomes a hairpin, its return leg moved sideways by two corner radii.
  When no polyline fits, a straight walk of the same length.
- **Rest.** ``stand_start_s`` / ``stand_end_s`` from the first / last detected rest (at least 0.5 s).
- **Sensor position** on the foot (:mod:`gaitsim.loop.mount_fit`): the position along the foot and the height
  that best reproduce the recording's accelerometer phase profiles where the foot turns about a ground contact
  (linear least squares over three simulations).
- **Mount.** Roll and pitch of the sensor on the foot from the mean specific force at the quietest window,
  written as the sensor's ``mounting_misalignment`` (roll, pitch, 0); the library's ``mount_yaw`` effect
  fits the remaining yaw.
- **Sensor noise and gyro bias**: white-noise densities std / sqrt(rate) per axis from the quietest
  ``QUIET_WINDOW_S`` of the recording, and the mean angular rate over every detected rest as the gyro bias. :func:`match_noise` rescales the
  densities so that the twin's *output* has the recording's static standard deviation (once effects such as
  a bandwidth filter the noise, the density that gives it is larger).

Cadence and clearance are then corrected by simulating the twin and matching the same statistics
(``FIT_ITERATIONS`` rounds), so they do not rely on how a detector sees the simulator's events.
"""

from __future__ import annotations

import copy
import dataclasses
import json
import math
from dataclasses import dataclass, field

import numpy as np

from nav import pipeline
from nav.alignment import stationary_runs, tilt_from_specific_force
from nav.checks import quietest_window
from nav.recording import Recording, Reference

from ..errors import ScenarioError
from ..world.gait import GaitParams, ImpactParams
from ..imu.config import sensor_from_table
from ..scenario import scenario_from_dict
from ..simulate import sense, simulate_walk
from ..world.foot import FootModel
from . import gait_fit, mount_fit, residuals

TWIN_SEED = 7
FIT_ITERATIONS = 2
PATH_TOLERANCE_M = 0.3
HAIRPIN_DEG = 120.0
QUIET_WINDOW_S = 0.5
REST_MARGIN_S = 0.25  # s, trimmed from both ends of a detected rest before its gyro mean is taken
NAV_OPTIONS = pipeline.NavOptions(method="rk4")  # both sides are navigated from their IMU samples


@dataclass
class Twin:
    """A fitted twin: the scenario document (TOML-shaped dict) and how each value was found."""

    doc: dict
    notes: dict = field(default_factory=dict)
    seed: int = TWIN_SEED

    def with_changes(self, changes: dict) -> "Twin":
        """A copy with ``{section: {key: value}}`` merged into the document."""
        doc = copy.deepcopy(self.doc)
        for section, table in changes.items():
            doc.setdefault(section, {}).update(copy.deepcopy(table))
        return Twin(doc, dict(self.notes), self.seed)


# ------------------------------------------------------------------------------------------------ simulation
_TRUTH_CACHE: dict = {}
_TRUTH_CACHE_SIZE = 8


def simulate(twin: Twin, seed: int | None = None) -> Recording:
    """Simulate the twin (``seed`` default the twin's). The ideal-sensor walk is cached per (walk, seed), so
    effects that only change the [sensor] table cost one sensor-model pass."""
    seed = twin.seed if seed is None else seed
    walk_doc = {k: v for k, v in twin.doc.items() if k != "sensor"}
    key = (json.dumps(walk_doc, sort_keys=True, default=str), seed)
    base = _TRUTH_CACHE.get(key)
    if base is None:
        base = simulate_walk(scenario_from_dict(walk_doc, "<twin>"), seed=seed)
        if len(_TRUTH_CACHE) >= _TRUTH_CACHE_SIZE:
            _TRUTH_CACHE.pop(next(iter(_TRUTH_CACHE)))
        _TRUTH_CACHE[key] = base
    if "sensor" not in twin.doc:
        return base
    spec = sensor_from_table(twin.doc["sensor"], "<twin> [sensor]")
    return sense(base.truth, base.events, base.meta, spec, seed)


def match_noise(twin: Twin) -> Twin:
    """Rescale the twin's white-noise densities so its quietest-window output std equals the recording's
    (``notes["static_std"]``); one multiplicative correction per axis."""
    target = twin.notes.get("static_std")
    if target is None or "sensor" not in twin.doc:
        return twin
    rec = simulate(twin)
    rate = twin.doc["sampling"]["rate_hz"]
    q0, q1 = quietest_window(rec.acc, int(QUIET_WINDOW_S * rate))
    sensor = dict(twin.doc["sensor"])
    for key, data, want in (("accel_noise_density", rec.acc, target["acc_mps2"]),
                            ("gyro_noise_density", rec.gyr, target["gyr_rad_s"])):
        have = np.maximum(data[q0:q1].std(0, ddof=1), 1e-12)
        value, unit = sensor[key]
        sensor[key] = [(np.asarray(value, float) * np.asarray(want) / have).tolist(), unit]
    return Twin({**twin.doc, "sensor": sensor}, twin.notes, twin.seed)


def as_measured(rec: Recording, reference_rate_hz: float | None = None) -> Recording:
    """What a measured recording of the same walk would carry: IMU samples, the sampling part of meta, and the
    true positions as a reference (every sample, or resampled at ``reference_rate_hz``); no truth, no events,
    no gait or sensor parameters."""
    truth = rec.truth
    if reference_rate_hz is None:
        ref = Reference(truth.t.copy(), truth.pos.copy())
    else:
        t_ref = np.arange(truth.t[0], truth.t[-1], 1.0 / reference_rate_hz)
        ref = Reference(t_ref, np.stack([np.interp(t_ref, truth.t, truth.pos[:, i]) for i in range(3)], -1))
    meta = {"sampling": dict(rec.meta.get("sampling", {})), "reference": {"kind": "position"}}
    return Recording(t=rec.t, acc=rec.acc, gyr=rec.gyr, meta=meta, reference=ref)


def reference_track(rec: Recording) -> tuple[np.ndarray, np.ndarray] | tuple[None, None]:
    """(t, pos) of the recording's continuous position reference, or (None, None) (e.g. loop closure only)."""
    ref = rec.reference
    if ref is None or len(ref.t) <= 2:
        return None, None
    return np.asarray(ref.t, float), np.asarray(ref.pos, float)


# ------------------------------------------------------------------------------------------------ statistics
def _swing_height(t: np.ndarray, sig: residuals.Signature, pos_t, pos) -> float:
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


def gait_statistics(rec: Recording, sig: residuals.Signature, pos_t=None, pos=None) -> dict:
    """The statistics the twin is matched on by simulation (module docstring): period (s), its relative spread,
    swing_height (m, NaN without a track)."""
    periods = rec.t[sig.strides[:, 1]] - rec.t[sig.strides[:, 0]]
    height = _swing_height(rec.t, sig, pos_t, pos) if pos is not None else math.nan
    return {"period_s": float(np.median(periods)), "period_sd_frac": float(np.std(periods) / np.mean(periods)),
            "swing_height_m": height}


# ------------------------------------------------------------------------------------------------ path
def _simplify(points: np.ndarray, tolerance: float) -> np.ndarray:
    """Ramer-Douglas-Peucker simplification of a 2-D polyline (m)."""
    if len(points) < 3:
        return points
    a, b = points[0], points[-1]
    d = b - a
    length = np.hypot(*d)
    rel = points - a
    dist = np.abs(d[0] * rel[:, 1] - d[1] * rel[:, 0]) / length if length > 0 else np.hypot(rel[:, 0], rel[:, 1])
    i = int(np.argmax(dist))
    if dist[i] <= tolerance:
        return np.array([a, b])
    return np.vstack([_simplify(points[:i + 1], tolerance)[:-1], _simplify(points[i:], tolerance)])


def _hairpins(points: np.ndarray, radius: float) -> np.ndarray:
    """Move the legs after every corner sharper than HAIRPIN_DEG sideways by 2 radius (to the turn's side)."""
    pts = points.copy()
    for i in range(1, len(pts) - 1):
        d0, d1 = pts[i] - pts[i - 1], pts[i + 1] - pts[i]
        turn = math.degrees(math.atan2(d0[0] * d1[1] - d0[1] * d1[0], d0 @ d1))
        if abs(turn) > HAIRPIN_DEG:
            u = d0 / np.hypot(*d0)
            side = np.array([-u[1], u[0]]) * (1.0 if turn >= 0 else -1.0)
            pts = np.vstack([pts[:i + 1], pts[i] + 2 * radius * side, pts[i + 1:] + 2 * radius * side])
            return _hairpins(pts, radius)
    return pts


def path_table(points: np.ndarray, stride_length: float) -> tuple[dict, str]:
    """A [path] table through the stance centres ``points`` (K, 2) m, and how it was built."""
    simple = _simplify(points, PATH_TOLERANCE_M)
    length = float(np.sum(np.hypot(*np.diff(points, axis=0).T)))
    gait = GaitParams(stride_length_m=stride_length)
    if len(simple) > 2:
        for radius in (1.0, 0.75, 0.5, stride_length / 2):
            table = {"kind": "polyline", "waypoints_m": _hairpins(simple, radius).tolist(), "corner_radius_m": radius}
            try:
                scenario_from_dict({"path": table, "gait": {"stride_length_m": stride_length}}, "<twin path>")
                return table, f"polyline of {len(table['waypoints_m'])} points, corner radius {radius} m"
            except ScenarioError:
                continue
    d = simple[-1] - simple[0]
    yaw = math.degrees(math.atan2(d[1], d[0])) if np.hypot(*d) > 0.5 else 0.0
    return ({"kind": "straight", "length_m": max(length, gait.stride_length_m), "yaw_deg": yaw},
            "straight walk of the same length (no polyline fitted the track)")


# ------------------------------------------------------------------------------------------------ fit
def _rest_runs(t: np.ndarray, stationary: np.ndarray) -> tuple[float, float]:
    starts, ends = stationary_runs(stationary)
    first = t[ends[0] - 1] - t[starts[0]] if len(starts) else 0.5
    last = t[ends[-1] - 1] - t[starts[-1]] if len(starts) else 0.5
    return max(0.5, float(first)), max(0.5, float(last))


def _rest_gyro_mean(rec: Recording, stationary: np.ndarray, quiet: tuple[int, int]) -> np.ndarray:
    """Mean angular rate (rad/s) over every detected rest of at least ``QUIET_WINDOW_S`` after trimming
    ``REST_MARGIN_S`` from both ends (a detected rest reaches into the first heel off), or over the quietest
    window when there is none: the gyro bias the twin is given. Over 0.5 s of a consumer gyro its standard
    error is ~0.03 deg/s, as large as the heading drifts compared, so every rest sample counts."""
    starts, ends = stationary_runs(stationary)
    margin = int(round(REST_MARGIN_S / np.median(np.diff(rec.t))))
    inner = [(s + margin, e - margin) for s, e in zip(starts, ends)
             if rec.t[e - 1 - margin] - rec.t[s + margin] >= QUIET_WINDOW_S] if margin < len(rec.t) // 4 else []
    rest = np.concatenate([rec.gyr[s:e] for s, e in inner]) if inner else rec.gyr[quiet[0]:quiet[1]]
    return rest.mean(axis=0)


def _track(rec: Recording, solution) -> tuple[np.ndarray, np.ndarray, str]:
    pos_t, pos = reference_track(rec)
    if pos is not None:
        return pos_t, pos, "reference"
    return solution.t, solution.pos, "IMU-navigated track"


def fit_twin(rec: Recording, sig: residuals.Signature, solution) -> Twin:
    """Fit a twin to ``rec`` (its signature ``sig`` and navigation ``solution``); see the module docstring."""
    rate = float(round(sig.rate_hz, 1))
    gravity = float(rec.meta.get("sampling", {}).get("gravity_mps2", 9.81))
    notes = {}
    track_t, track, source = _track(rec, solution)
    centres = rec.t[(sig.stances[:, 0] + sig.stances[:, 1]) // 2]
    xy = np.stack([np.interp(centres, track_t[np.isfinite(track[:, 0])], track[np.isfinite(track[:, 0]), i])
                   for i in range(2)], -1)
    steps = np.hypot(*np.diff(xy, axis=0).T)
    stride_length = float(np.median(steps)) if len(steps) else 1.4
    stationary = pipeline.detectors.detect("shoe", rec.t, rec.acc, rec.gyr, gravity=gravity).stationary
    stances = residuals.stance_intervals(rec.t, stationary)
    all_centres = rec.t[(stances[:, 0] + stances[:, 1]) // 2]
    ok = np.isfinite(track[:, 0])
    all_xy = np.stack([np.interp(all_centres, track_t[ok], track[ok, i]) for i in range(2)], -1)
    path, path_note = path_table(all_xy, stride_length)
    stand_start, stand_end = _rest_runs(rec.t, stationary)
    q0, q1 = quietest_window(rec.acc, int(QUIET_WINDOW_S * sig.rate_hz))
    roll, pitch = tilt_from_specific_force(rec.acc[q0:q1].mean(0))
    acc_sd = np.maximum(rec.acc[q0:q1].std(0, ddof=1), 1e-5)
    gyr_sd = np.maximum(rec.gyr[q0:q1].std(0, ddof=1), 1e-6)
    measured = gait_statistics(rec, sig, *((track_t, track) if source == "reference" else (None, None)))
    doc = {
        "scenario": {"name": "twin", "description": f"digital twin of {rec.meta.get('recording', 'a recording')}"},
        "path": path,
        "gait": {"cadence_steps_per_min": 120.0 / measured["period_s"], "stride_length_m": stride_length,
                 "cycle_sd_frac": min(0.1, measured["period_sd_frac"]),
                 "stand_start_s": stand_start, "stand_end_s": stand_end},
        "sampling": {"rate_hz": rate, "gravity_mps2": gravity},
        "sensor": {"preset": "ideal",
                   "accel_noise_density": [(acc_sd / math.sqrt(rate)).tolist(), "m/s^2/sqrt(Hz)"],
                   "gyro_noise_density": [(gyr_sd / math.sqrt(rate)).tolist(), "rad/s/sqrt(Hz)"],
                   "gyro_bias": [_rest_gyro_mean(rec, stationary, (q0, q1)).tolist(), "rad/s"],
                   "mounting_misalignment": [[math.degrees(roll), math.degrees(pitch), 0.0], "deg"]},
    }
    shape, shape_quality = gait_fit.fit_pitch_profile(gait_fit.stride_profile(rec.t, rec.acc, rec.gyr, sig),
                                                      GaitParams(**doc["gait"]), ImpactParams())
    doc["gait"].update(shape["gait"])
    doc["impact"] = shape["impact"]
    notes.update(static_std={"acc_mps2": acc_sd.tolist(), "gyr_rad_s": gyr_sd.tolist()},
                 measured_statistics=measured, gait_shape_fit=shape_quality, track=source, path=path_note,
                 stride_length_m=stride_length, quiet_window_s=[float(rec.t[q0]), float(rec.t[q1 - 1])])
    twin = Twin(doc, notes)
    gait = doc["gait"]
    phases = mount_fit.contact_phases(gait["heel_rocker_frac"], gait["foot_flat_frac"], gait["push_off_frac"])
    site, site_quality = mount_fit.fit_lever_arm(
        sig, lambda r: simulate(twin.with_changes({"mount": mount_table(r)})), phases)
    twin = twin.with_changes({"mount": mount_table(site)})
    twin.notes["mount_fit"] = site_quality
    twin = match_noise(twin)
    for _ in range(FIT_ITERATIONS):
        twin = _correct(twin, measured)
    twin.notes["twin_statistics"] = _twin_statistics(twin, measured)
    return twin


def mount_table(site: np.ndarray) -> dict:
    """A [mount] table putting the IMU site at ``site`` (m, foot frame from the heel contact)."""
    return {"site": "toes", "offset_m": (np.asarray(site, float) - FootModel().lever_arm).tolist()}


def _twin_statistics(twin: Twin, measured: dict) -> dict:
    sim = simulate(twin)
    sig = residuals.signature(sim.t, sim.acc, sim.gyr)
    track = (sim.truth.t, sim.truth.pos) if math.isfinite(measured["swing_height_m"]) else (None, None)
    return gait_statistics(sim, sig, *track)


def _correct(twin: Twin, measured: dict) -> Twin:
    """One matching round: scale the cadence and the clearance by twin / measured statistics."""
    have = _twin_statistics(twin, measured)
    fields = dataclasses.asdict(GaitParams(**twin.doc["gait"]))
    changes = {"cadence_steps_per_min": fields["cadence_steps_per_min"] * have["period_s"] / measured["period_s"]}
    if math.isfinite(measured["swing_height_m"]) and have["swing_height_m"] > 0:
        changes["swing_height_m"] = float(np.clip(fields["swing_height_m"] * measured["swing_height_m"]
                                                  / have["swing_height_m"], 0.01, 0.3))
    out = twin.with_changes({"gait": changes})
    try:
        scenario_from_dict({k: v for k, v in out.doc.items() if k != "sensor"}, "<twin>")
    except ScenarioError as exc:
        out.notes.setdefault("fit_warnings", []).append(f"correction skipped: {exc}")
        return twin
    return out
