"""Where the strapdown velocity error of the landing arises, localised with the Vicon pose (issue 11; the section
"The landing's velocity error against the Vicon pose" of results/stance/findings.md).

Per stride of gaitmap-healthy left and right (the strides of :mod:`studies.underestimate_split` at SHOE 3e4), from
the previous stance's last detected sample (less :data:`LEAD_S`) to :data:`END_S` after the stance's first detected
sample, four velocity changes of the IMU site since the window's start (world frame, forward along the stride, up):

- **a, reference**: the site's velocity from the marker pose (the loader's lever arm and clock offset);
- **b, strapdown**: from the filter's attitude at the window's start, the gyro and accelerometer by RK4
  (:func:`nav.strapdown.integrate`; the filter's own velocity error, as no update falls inside);
- **c, Vicon attitude x IMU specific force** (hybrid 1: if b's error stays here, the accelerometer makes it, not
  the gyro);
- **d, strapdown attitude x Vicon specific force** (hybrid 2: the site's acceleration minus gravity, rotated into
  the sensor frame by the Vicon attitude; its error is the attitude's, ``(C_imu C_vicon^T - I)(a - g)``).

c and d (and b once more, as a check) are integrated by Simpson on each sample interval with the specific force at
the interval's middle by the cubic of :func:`nav.strapdown.mid_samples` (RK4's), so their differences are the
inputs', not the integrators'. b's heading is turned onto the Vicon's at the window's start (a yaw only, so b keeps
its own tilt error). Errors (b, c, d minus a) are read as 20 ms block means at :data:`POINTS` and differenced over
:data:`STEPS`; a profile on a 10 ms grid around forefoot contact (FF) says when they arise.

The sensor-to-marker rotation: the loader's (Kabsch on the angular rates) leaves the still specific force 3-6 deg
off the vertical, because a rate dominated by the sagittal swing fixes the rotation about that axis poorly. Here
its tilt is taken from gravity instead (the mean direction of the specific force over the detected stances against
the marker frame's vertical, the smallest rotation between them); the rotation about the vertical stays the
rates'. The reference's own uncertainties are shown by moving the lever arm by 2 cm and the clock by 2 ms, and by
the lever arm's x and z fitted on the slaps alone (:func:`slap_lever_arm`), where the split of the landing between
heel strike and slap is decided.

The diagnostic is checked on the stance twin (:mod:`gaitsim.stance.twin`, ideal sensor): with the exact truth pose
the errors must vanish up to RK4's on point samples; the truth resampled at 100 Hz and low-passed like the Vicon
(zero-phase Butterworth, :data:`CUTOFFS_HZ`) shows how the pose's bandwidth biases a, c and d.

Named hypotheses (:func:`hypotheses`) correct the recording for one sensor error each and re-run b and c; the
integration is also repeated on an 8 times finer grid of the band-limited interpolation (:func:`fine_strapdown`).

Run from the repository root (it reads ../shared/data; ~45 s)::

    python3 -m studies.slap_error
"""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.signal import butter, lfilter, resample_poly
from scipy.spatial.transform import Rotation, Slerp
from scipy.stats import spearmanr

from gaitsim.measured import mocap
from gaitsim.measured.gaitmap import MOCAP_RATE_HZ, gaitmap_foot_pose, read_markers
from gaitsim.stance.command import SITES, load_recordings
from gaitsim.stance.events import gait_events, group_stances
from gaitsim.stance.sweep import nav_options
from gaitsim.stance.twin import TwinSpec, match_timing, measure_gait, simulate_sensed_and_ideal
from nav import pipeline, strapdown
from nav import quaternion as quat
from nav.constants import STANDARD_GRAVITY
from studies import mount_rate
from studies.underestimate_split import _strides

DATA = "../shared/data"
DATASET = "gaitmap-healthy"
THRESHOLD = 3e4  # SHOE gamma of the onset table in findings.md
LEAD_S = 0.03  # s, each window starts this long before the previous stance's last detected sample (still foot)
END_S = 0.05  # s, and ends this long after the stance's first detected sample
CUTOFFS_HZ = (None, 12.0, 6.0)  # pose low-pass (None: the raw 100 Hz markers, cubic spline)
UP = np.array([0.0, 0.0, 1.0])
# the points the errors are read at: (event, offset s); events: last (the previous stance's last detected sample),
# ic, ff (:mod:`gaitsim.stance.events`), first (the stance's first detected sample)
POINTS = {"previous stance": ("last", -0.01), "initial contact": ("ic", 0.0), "heel rocker": ("ff", -0.03),
          "after the slap": ("ff", 0.04), "stance": ("first", 0.03)}
# the steps between points; the points of "swing", "landing", "loading" and "stride" lie where the foot's rate is
# near zero (at IC its sagittal part crosses zero), so their steps do not depend on the lever arm; "heel rocker"
# lies in the rocker's ~100 deg/s rotation, so the split of "landing" into "heel strike" and "slap" does
STEPS = {"swing": ("previous stance", "initial contact"), "heel strike": ("initial contact", "heel rocker"),
         "slap": ("heel rocker", "after the slap"), "landing": ("initial contact", "after the slap"),
         "loading": ("after the slap", "stance"), "stride": ("previous stance", "stance")}
GAP_MARGIN_S = 0.05  # s, windows this close to a marker dropout are left out
FINE_FACTOR = 8  # the finer integration's grid: 8 x 204.8 Hz
SLAP_FIT_HZ = 20.0  # Hz, band of the lever arm fitted on the slaps (12-30 Hz give x within 1.3 cm of it)
BLOCK_S = 0.02  # s, the errors are averaged over this block around each point (the reference's noise)


@dataclass
class Pose:
    """A pose reference of the IMU site: position (a piecewise polynomial, derivatives by ``nu``) and the sensor's
    attitude (sensor -> world), both on the IMU clock shifted by ``clock_offset`` (s, ``t_pose = t_imu + offset``)."""

    position: object
    attitude: Slerp
    clock_offset: float = 0.0
    gaps: np.ndarray = field(default_factory=lambda: np.empty(0))  # s, pose clock: samples filled in (dropouts)

    def velocity(self, t: np.ndarray) -> np.ndarray:
        return self.position(t + self.clock_offset, 1)

    def specific_force(self, t: np.ndarray, gravity: float) -> np.ndarray:
        """(N, 3) m/s^2, world frame."""
        return self.position(t + self.clock_offset, 2) + gravity * UP

    def rotation(self, t: np.ndarray) -> np.ndarray:
        """(N, 3, 3) sensor -> world."""
        return self.attitude(t + self.clock_offset).as_matrix()


def sampled_pose(t: np.ndarray, site: np.ndarray, rotation: np.ndarray, rate_hz: float, cutoff_hz: float | None,
                 clock_offset: float = 0.0) -> Pose:
    """The pose from samples (t (M,) s at ``rate_hz``, site (M, 3) m, rotation (M, 3, 3) sensor -> world), optionally
    low-passed at ``cutoff_hz`` (zero-phase, position and the rotation's entries, then re-orthonormalised), the
    position as a cubic spline and the attitude slerped."""
    if cutoff_hz is not None:
        site = mocap.lowpass(site, cutoff_hz, rate_hz)
        rotation = mocap.lowpass(rotation, cutoff_hz, rate_hz)
    return Pose(CubicSpline(t, site), Slerp(t, Rotation.from_matrix(rotation)), clock_offset)


def exact_pose(truth) -> Pose:
    """The twin's exact pose: the truth's velocity as a cubic spline (so the velocity is exact at the samples)."""
    return Pose(CubicSpline(truth.t, truth.vel).antiderivative(), Slerp(truth.t, Rotation.from_quat(truth.quat,
                                                                                                   scalar_first=True)))


def half_grid(t: np.ndarray) -> np.ndarray:
    """(2N-1,) s, the samples and the middles of their intervals."""
    out = np.empty(2 * len(t) - 1)
    out[0::2], out[1::2] = t, 0.5 * (t[:-1] + t[1:])
    return out


def integrated(t: np.ndarray, force_world: np.ndarray, gravity: float) -> np.ndarray:
    """(N, 3) m/s, velocity change since t[0] from the specific force on :func:`half_grid` (2N-1, 3) m/s^2 (Simpson
    per interval)."""
    g = force_world - gravity * UP
    steps = (np.diff(t) / 6.0)[:, None] * (g[0:-2:2] + 4.0 * g[1::2] + g[2::2])
    return np.vstack([np.zeros(3), np.cumsum(steps, axis=0)])


def on_half_grid(t: np.ndarray, samples: np.ndarray) -> np.ndarray:
    """(2N-1, 3) sensor-frame samples (N, 3) with their interval middles by :func:`nav.strapdown.mid_samples`."""
    mids = strapdown.mid_samples(t, samples)
    out = np.empty((2 * len(t) - 1, 3))
    out[0::2], out[1::2] = samples, mids[:-1]
    return out


@dataclass
class Window:
    """One stride's window (module docstring), on its IMU samples.

    Attributes
    ----------
    t : (N,) s from the stance's first detected sample.
    reference, strapdown, vicon_attitude, vicon_force : (N, 3) m/s, velocity changes a, b, c, d since t[0], world
        (the pose's frame).
    strapdown_simpson : (N, 3) m/s, b's attitude and specific force integrated like c and d (the integrators' check).
    attitude_error : (N, 3) rad, rotation vector of the strapdown's attitude against the pose's, world.
    forward : (3,) unit vector along the stride.   force_norm : (N,) m/s^2, abs(f) of the samples.
    events : {"last", "ic", "ff", "first"}: s from the first detected sample.   first_time : s, that sample's time.
    turn : (3, 3) the yaw that turns the filter's frame onto the pose's.
    """

    t: np.ndarray
    reference: np.ndarray
    strapdown: np.ndarray
    vicon_attitude: np.ndarray
    vicon_force: np.ndarray
    strapdown_simpson: np.ndarray
    attitude_error: np.ndarray
    forward: np.ndarray
    force_norm: np.ndarray
    events: dict
    first_time: float
    turn: np.ndarray


def window(rec, sol, pose: Pose, events: dict, forward: np.ndarray, gravity: float,
           acc: np.ndarray | None = None, gyr: np.ndarray | None = None) -> Window:
    """The four velocity changes of one swing and landing of ``rec`` (module docstring): from :data:`LEAD_S` before
    ``events["last"]`` (the previous stance's last detected sample) to :data:`END_S` after ``events["first"]``;
    ``events`` (sample indices) are kept as times from the first. ``acc`` / ``gyr`` (N, 3) replace the recording's
    samples in b and c (a hypothesis' corrected sensor)."""
    t_all = np.asarray(rec.t, float)
    acc = np.asarray(rec.acc if acc is None else acc, float)
    gyr = np.asarray(rec.gyr if gyr is None else gyr, float)
    first = events["first"]
    k0 = int(np.searchsorted(t_all, t_all[events["last"]] - LEAD_S))
    k1 = int(np.searchsorted(t_all, t_all[first] + END_S)) + 1
    t = t_all[k0:k1]
    fine = half_grid(t)
    vicon_rot = pose.rotation(fine)
    track = strapdown.integrate(t, acc[k0:k1], gyr[k0:k1], sol.quat[k0], gravity=gravity)
    imu_rot = quat.to_matrix(track.quat)
    start_error = vicon_rot[0] @ imu_rot[0].T
    turn = Rotation.from_euler("z", np.arctan2(start_error[1, 0] - start_error[0, 1],
                                              start_error[0, 0] + start_error[1, 1])).as_matrix()
    imu_rot_fine = Slerp(t, Rotation.from_matrix(turn @ imu_rot))(fine).as_matrix()
    f_imu = on_half_grid(t, acc[k0:k1])
    f_vicon_world = pose.specific_force(fine, gravity)
    f_vicon_sensor = np.einsum("nji,nj->ni", vicon_rot, f_vicon_world)
    error = Rotation.from_matrix(imu_rot_fine[0::2] @ np.transpose(vicon_rot[0::2], (0, 2, 1))).as_rotvec()
    velocity = pose.velocity(t)
    return Window(
        t=t - t_all[first],
        reference=velocity - velocity[0],
        strapdown=track.vel @ turn.T,
        vicon_attitude=integrated(t, np.einsum("nij,nj->ni", vicon_rot, f_imu), gravity),
        vicon_force=integrated(t, np.einsum("nij,nj->ni", imu_rot_fine, f_vicon_sensor), gravity),
        strapdown_simpson=integrated(t, np.einsum("nij,nj->ni", imu_rot_fine, f_imu), gravity),
        attitude_error=error, forward=forward, force_norm=np.linalg.norm(acc[k0:k1], axis=1),
        events={name: t_all[k] - t_all[first] for name, k in events.items()}, first_time=t_all[first], turn=turn)


def forward_up(w: Window, values: np.ndarray) -> np.ndarray:
    """(N, 2) the forward and up parts of world vectors (N, 3) of a window."""
    return np.column_stack([values @ w.forward, values[:, 2]])


def pitch_error(w: Window) -> np.ndarray:
    """(N,) rad, the strapdown's attitude error about the horizontal axis left of forward (up x forward: positive
    turns the forward axis down, the sense of a sagittal toes-down rate)."""
    return w.attitude_error @ np.cross(UP, w.forward)


def errors(w: Window) -> dict:
    """{"b", "c", "d": (N, 2) m/s forward and up velocity errors against the reference; "pitch": (N, 1) rad}."""
    return {"b": forward_up(w, w.strapdown - w.reference), "c": forward_up(w, w.vicon_attitude - w.reference),
            "d": forward_up(w, w.vicon_force - w.reference), "pitch": pitch_error(w)[:, None]}


def points(w: Window) -> np.ndarray:
    """(P,) s from the first detected sample: :data:`POINTS` of this stance."""
    return np.array([w.events[event] + offset for event, offset in POINTS.values()])


def block_means(w: Window, values: np.ndarray, at: np.ndarray) -> np.ndarray:
    """(P, k) means of ``values`` (N, k) over +-``BLOCK_S`` / 2 around the times ``at`` (P,) s (1 ms grid)."""
    fine = at[:, None] + np.arange(-0.5 * BLOCK_S, 0.5 * BLOCK_S + 1e-9, 0.001)[None, :]
    return np.stack([np.interp(fine, w.t, values[:, j]).mean(axis=1) for j in range(values.shape[1])], -1)


def steps(windows: list[Window]) -> dict:
    """{quantity: (K, S, k)}: each stride's change of each error over :data:`STEPS` (block means at the points)."""
    out = {}
    for w in windows:
        at = points(w)
        for name, values in errors(w).items():
            means = block_means(w, values, at)
            names = list(POINTS)
            out.setdefault(name, []).append([means[names.index(b)] - means[names.index(a)] for a, b in STEPS.values()])
    return {k: np.array(v) for k, v in out.items()}


def profile(windows: list[Window], grid: np.ndarray, event: str = "ff") -> dict:
    """{quantity: (G, k)} mean over strides of each error on ``grid`` (s from ``event``), less its value at the
    grid's start; also the median |f| (m/s^2) there ("force")."""
    out = {}
    for w in windows:
        at = w.events[event] + grid
        for name, values in {**errors(w), "force": w.force_norm[:, None]}.items():
            v = np.stack([np.interp(at, w.t, values[:, j]) for j in range(values.shape[1])], -1)
            out.setdefault(name, []).append(v if name == "force" else v - v[:1])
    return {k: np.median(v, 0) if k == "force" else np.mean(v, 0) for k, v in out.items()}


def stance_windows(rec, pose: Pose, threshold: float = THRESHOLD, **sensor) -> list[Window]:
    """The windows of every scored stride of ``rec`` (pose-tracked site), forward along the stride."""
    track_t = np.asarray(rec.t, float)
    track_pos = pose.position(track_t + pose.clock_offset)
    track, sol, t, strides = _strides(rec, track_t, track_pos, threshold)
    gravity = float(sol.info["filter"]["gravity"])
    stationary = np.asarray(sol.stationary, bool).copy()
    stationary[:sol.start] = False
    stances = group_stances(t, stationary)
    ev = gait_events(rec.gyr, stances)
    out = []
    for m0, m1, first, _ in strides:
        s = int(np.flatnonzero(stances.bounds[:, 0] == first)[0])
        if t[first] + END_S > t[-1] or s == 0 or not (ev.ic[s] >= 0 and ev.ff[s] > ev.ic[s]):
            continue
        span = np.array([t[stances.bounds[s - 1, 1] - 1] - LEAD_S, t[first] + END_S]) + pose.clock_offset
        if np.any((pose.gaps > span[0] - GAP_MARGIN_S) & (pose.gaps < span[1] + GAP_MARGIN_S)):
            continue
        along = track(t[m1])[:2] - track(t[m0])[:2]
        forward = np.append(along / np.linalg.norm(along), 0.0)
        events = {"last": stances.bounds[s - 1, 1] - 1, "ic": ev.ic[s], "ff": ev.ff[s], "first": first}
        out.append(window(rec, sol, pose, events, forward, gravity, **sensor))
    return out


def gravity_tilted_mount(rec, marker_rotation: Slerp, mount: np.ndarray,
                         clock_offset: float) -> tuple[np.ndarray, float]:
    """The mount rotation (sensor -> marker frame) with its tilt taken from gravity (module docstring), and the
    angle (deg) it turned the loader's ``mount`` by."""
    t = np.asarray(rec.t, float)
    still = pipeline.prepare(rec, nav_options(THRESHOLD, method="rk4")).stationary
    still &= (t + clock_offset > marker_rotation.times[0]) & (t + clock_offset < marker_rotation.times[-1])
    sensor_up = rec.acc[still] / np.linalg.norm(rec.acc[still], axis=1, keepdims=True)
    mean_sensor = (sensor_up @ mount.T).mean(axis=0)
    mean_marker = np.einsum("nji,j->ni", marker_rotation(t[still] + clock_offset).as_matrix(), UP).mean(axis=0)
    tilt, _ = Rotation.align_vectors(mean_marker[None], mean_sensor[None])
    return tilt.as_matrix() @ mount, float(np.degrees(tilt.magnitude()))


def vicon_poses(side: str, rec, lever_shift=(0.0, 0.0, 0.0), clock_shift: float = 0.0) -> tuple[dict, dict]:
    """{cutoff: Pose} of the IMU site on one gaitmap foot from its three markers (dropouts filled linearly, their
    times kept in ``gaps``), with the loader's lever arm moved by ``lever_shift`` (m, marker frame) and its clock
    offset by ``clock_shift`` (s); and what was used: clock offset (s), lever arm (m), the mount's tilt correction
    (deg)."""
    t_mocap, markers, _ = read_markers(DATA)
    pose = gaitmap_foot_pose(side, DATA)
    marker_set = markers[side]
    gaps = t_mocap[np.any([np.isnan(v).any(axis=1) for v in marker_set.values()], axis=0)]
    filled = {k: mount_rate.filled_markers(v, t_mocap) for k, v in marker_set.items()}
    origin, rotation = mocap.marker_frame(filled["FCC"], filled["TOE"], filled["FM5"], side)
    mount, tilt_deg = gravity_tilted_mount(rec, Slerp(t_mocap, Rotation.from_matrix(rotation)), pose.mount_rotation,
                                           pose.clock_offset)
    lever = pose.lever_arm + np.asarray(lever_shift)
    offset = pose.clock_offset + clock_shift
    poses = {c: sampled_pose(t_mocap, origin + rotation @ lever, rotation @ mount, MOCAP_RATE_HZ, c, offset)
             for c in CUTOFFS_HZ}
    for p in poses.values():
        p.gaps = gaps
    return poses, {"clock_offset_s": offset, "lever_arm_m": lever, "mount_tilt_deg": tilt_deg}


def slap_lever_arm(side: str, rec, windows: list[Window], cutoff_hz: float = SLAP_FIT_HZ) -> tuple[np.ndarray, dict]:
    """(3,) m, marker frame: the loader's lever arm with its x and z fitted like the loader's
    (:func:`gaitsim.measured.mocap.fit_lever_arm`) but on the slaps alone (FF - 30 ms to FF + 40 ms of every window)
    and at ``cutoff_hz`` instead of 6 Hz: there the sagittal rate stops at 200+ rad/s^2, and its tangential
    acceleration fixes the point's x and z against the pivot. A rotation about y says nothing of y, which stays the
    loader's. Also {"loader", "slaps"}: the rms (m/s^2) of the slap samples' specific-force misfit with either."""
    t_mocap, markers, _ = read_markers(DATA)
    pose = gaitmap_foot_pose(side, DATA)
    filled = {k: mount_rate.filled_markers(v, t_mocap) for k, v in markers[side].items()}
    origin, rotation = mocap.marker_frame(filled["FCC"], filled["TOE"], filled["FM5"], side)
    mount, _ = gravity_tilted_mount(rec, Slerp(t_mocap, Rotation.from_matrix(rotation)), pose.mount_rotation,
                                    pose.clock_offset)
    kin = mocap.body_kinematics(origin, rotation, MOCAP_RATE_HZ, cutoff_hz)
    t = np.asarray(rec.t, float)
    on_imu = t_mocap - pose.clock_offset
    use = np.zeros(len(t_mocap), bool)
    for w in windows:
        ff = w.first_time + w.events["ff"]
        use |= (on_imu >= ff + POINTS["heel rocker"][1]) & (on_imu <= ff + POINTS["after the slap"][1])
    force = np.full((len(t_mocap), 3), np.nan)
    acc = CubicSpline(t, mocap.lowpass(rec.acc, cutoff_hz, 1.0 / np.median(np.diff(t))))(on_imu[use])
    force[use] = np.einsum("nij,jk,nk->ni", kin.rotation[use], mount, acc)
    fitted = mocap.fit_lever_arm(kin, force, use)[0]
    lever = np.array([fitted[0], pose.lever_arm[1], fitted[2]])
    misfit = {name: float(np.sqrt(np.mean(np.sum((force[use] - kin.point_specific_force(arm)[use]) ** 2, axis=1))))
              for name, arm in (("loader", pose.lever_arm), ("slaps", lever))}
    return lever, misfit


def twin_poses(truth) -> dict:
    """{"exact": the truth, cutoff: the truth sampled at the Vicon's rate and low-passed like it}."""
    t100 = np.arange(truth.t[0], truth.t[-1], 1.0 / MOCAP_RATE_HZ)
    site = CubicSpline(truth.t, truth.vel).antiderivative()(t100) + truth.pos[0]
    rotation = Slerp(truth.t, Rotation.from_quat(truth.quat, scalar_first=True))(t100).as_matrix()
    return {"exact": exact_pose(truth), **{c: sampled_pose(t100, site, rotation, MOCAP_RATE_HZ, c) for c in CUTOFFS_HZ}}


# ---- the hypotheses: each gives the sensor read the other way (the recording corrected for the named error) ----

def shifted(t: np.ndarray, values: np.ndarray, tau: float) -> np.ndarray:
    """(N, 3) ``values`` read ``tau`` s later (cubic spline; a sensor that lags by tau, corrected)."""
    return CubicSpline(t, values)(np.clip(t + tau, t[0], t[-1]))


def band_limited(values: np.ndarray, cutoff_hz: float, rate_hz: float) -> np.ndarray:
    """(N, 3) ``values`` through a causal 2nd-order Butterworth low-pass (a band limit with its group delay)."""
    b, a = butter(2, cutoff_hz / (0.5 * rate_hz))
    return lfilter(b, a, values, axis=0)


def compressed_above(acc: np.ndarray, knee: float, fraction: float) -> np.ndarray:
    """(N, 3) ``acc`` whose magnitude above ``knee`` (m/s^2) is read ``fraction`` too high: the correction of a
    sensor that under-reads large specific forces by that fraction of the excess."""
    norm = np.linalg.norm(acc, axis=1, keepdims=True)
    return acc * (1.0 + fraction * np.maximum(norm - knee, 0.0) / norm)


def hypotheses(rec) -> dict:
    """{name: (acc, gyr) (N, 3) each}: the recording's samples corrected for one named error each (module docstring
    of the findings section gives the sizes' sources)."""
    t, acc, gyr = np.asarray(rec.t, float), np.asarray(rec.acc, float), np.asarray(rec.gyr, float)
    rate = 1.0 / np.median(np.diff(t))
    cross = np.eye(3)
    cross[2, 0] = cross[0, 2] = 0.01
    g_sensitivity = np.radians(0.1) / STANDARD_GRAVITY  # rad/s per m/s^2, 0.1 deg/s/g along each axis
    return {
        "accelerometer 2.5 ms late": (shifted(t, acc, 0.0025), gyr),
        "accelerometer 2.5 ms early": (shifted(t, acc, -0.0025), gyr),
        "accelerometer 5 ms late": (shifted(t, acc, 0.005), gyr),
        "accelerometer band 40 Hz narrower (causal 2nd order, added)": (band_limited(acc, 40.0, rate), gyr),
        "accelerometer z scale -1 %": (acc * np.array([1.0, 1.0, 1.01]), gyr),
        "accelerometer reads 5 % low above 5 g": (compressed_above(acc, 5 * STANDARD_GRAVITY, 0.05), gyr),
        "accelerometer cross-axis x<->z 1 %": (acc @ np.linalg.inv(cross).T, gyr),
        "gyro g-sensitivity 0.1 deg/s/g": (acc, gyr - g_sensitivity * acc),
    }


def fine_strapdown(rec, w: Window, sol, factor: int = FINE_FACTOR) -> np.ndarray:
    """(N, 3) m/s: b integrated on a ``factor`` times finer grid of the band-limited interpolation (polyphase,
    :func:`scipy.signal.resample_poly`) of the recording's samples, read back at the window's samples, heading
    turned like b's (its start attitude is b's)."""
    t_all = np.asarray(rec.t, float)
    k0 = int(np.searchsorted(t_all, w.first_time + w.t[0] - 1e-9))
    pad = 64
    lo, hi = max(k0 - pad, 0), min(k0 + len(w.t) + pad, len(t_all))
    fine_acc = resample_poly(rec.acc[lo:hi], factor, 1, axis=0)
    fine_gyr = resample_poly(rec.gyr[lo:hi], factor, 1, axis=0)
    fine_t = t_all[lo] + np.arange(len(fine_acc)) * (t_all[1] - t_all[0]) / factor
    s0 = (k0 - lo) * factor
    s1 = s0 + (len(w.t) - 1) * factor + 1
    track = strapdown.integrate(fine_t[s0:s1], fine_acc[s0:s1], fine_gyr[s0:s1], sol.quat[k0],
                                gravity=float(sol.info["filter"]["gravity"]))
    return track.vel[::factor] @ w.turn.T


# ---- tables ----

def cell(values: np.ndarray, scale: float = 1000.0, digits: int = 0) -> str:
    """'median [25 %, 75 %] mean' of per-stride values, times ``scale``."""
    q = scale * np.percentile(values, [50, 25, 75])
    return f"{q[0]:+.{digits}f} [{q[1]:+.{digits}f}, {q[2]:+.{digits}f}] {scale * values.mean():+.{digits}f}"


def fwd_up(values: np.ndarray) -> str:
    """'forward / up' medians (mm/s) of per-stride (K, 2) values."""
    return f"{1000 * np.median(values[:, 0]):+.0f} / {1000 * np.median(values[:, 1]):+.0f}"


def feet_and_twins():
    """(side, recording, its twin read by the ideal sensor) of both gaitmap feet."""
    for side, rec in load_recordings(DATASET, DATA):
        gait = measure_gait(rec, rec.reference.t, rec.reference.pos)
        doc = match_timing(gait, TwinSpec(mount=SITES[DATASET][0], micromotion={"foot": side}))
        yield side, rec, simulate_sensed_and_ideal(doc)[1]


def twin_table(feet) -> None:
    print("\n### The twin check (ideal sensor): the truth as the pose, or sampled at 100 Hz and low-passed like the "
          "Vicon\n")
    print("median over strides, forward / up (mm/s); b-RK4 - Simpson: the largest |difference| of the two\n"
          "integrations of b over the window")
    print("\n| foot | pose | strides | " + " | ".join(f"{s}: b / c / d" for s in STEPS) + " | b: RK4 - Simpson |")
    print("|---|---|---|" + "---|" * (len(STEPS) + 1))
    for side, _, twin in feet:
        for label, pose in twin_poses(twin.truth).items():
            ws = stance_windows(twin, pose)
            st = steps(ws)
            integrators = max(np.abs(w.strapdown - w.strapdown_simpson).max() for w in ws)
            name = label if label == "exact" else f"100 Hz, low-pass {label or 'none'}"
            print(f"| {side} | {name} | {len(ws)} | "
                  + " | ".join(" ; ".join(fwd_up(st[q][:, i]) for q in "bcd") for i in range(len(STEPS)))
                  + f" | {1000 * integrators:.1f} |")


def real_table(feet) -> dict:
    print("\n### The recording against the Vicon pose (raw 100 Hz markers, cubic spline)\n")
    print("per stride, median [quartiles] (mm/s; pitch: deg, strapdown minus Vicon about the lateral axis)\n")
    print("| foot | quantity | " + " | ".join(STEPS) + " |")
    print("|---|---|" + "---|" * len(STEPS))
    out = {}
    for side, rec, _ in feet:
        poses, info = vicon_poses(side, rec)
        ws = stance_windows(rec, poses[None])
        out[side] = ws
        st = steps(ws)
        for q, label in (("b", "b strapdown"), ("c", "c Vicon attitude x IMU force"), ("d", "d strapdown attitude x "
                                                                                              "Vicon force")):
            for j, axis in enumerate(("forward", "up")):
                print(f"| {side} ({len(ws)}) | {label}, {axis} | " + " | ".join(cell(st[q][:, i, j]) for i in
                                                                                 range(len(STEPS))) + " |")
        print(f"| {side} | pitch error | " + " | ".join(cell(st["pitch"][:, i, 0], np.degrees(1.0), 2) for i in
                                                      range(len(STEPS))) + " |")
        when = np.array([[w.events[e] for e in ("last", "ic", "ff")] for w in ws])
        print(f"| {side} | events (ms from the first detected sample) | previous stance's last "
              f"{1000 * np.median(when[:, 0]):.0f}, IC {1000 * np.median(when[:, 1]):.0f}, FF "
              f"{1000 * np.median(when[:, 2]):.0f} (medians); mount tilt corrected by {info['mount_tilt_deg']:.1f} "
              "deg, "
              f"clock offset {1000 * info['clock_offset_s']:+.2f} ms |" + " |" * (len(STEPS) - 1))
    return out


def sensitivity_table(feet, slap_levers: dict) -> None:
    print("\n### The reference's uncertainties: the steps (b ; c, forward / up, mm/s, medians) with the pose changed\n")
    variants = {"as fitted": {}, "lever arm x -2 cm": {"lever_shift": (-0.02, 0, 0)},
                "lever arm x +2 cm": {"lever_shift": (0.02, 0, 0)}, "lever arm y -2 cm": {"lever_shift": (0, -0.02, 0)},
                "lever arm y +2 cm": {"lever_shift": (0, 0.02, 0)}, "lever arm z -2 cm": {"lever_shift": (0, 0, -0.02)},
                "lever arm z +2 cm": {"lever_shift": (0, 0, 0.02)}, "clock -2 ms": {"clock_shift": -0.002},
                "clock +2 ms": {"clock_shift": 0.002}}
    print("| foot | pose | " + " | ".join(STEPS) + " |")
    print("|---|---|" + "---|" * len(STEPS))
    for side, rec, _ in feet:
        loader_lever = vicon_poses(side, rec)[1]["lever_arm_m"]
        slap_lever, misfit = slap_levers[side]
        print(f"| {side} | lever arm (cm, marker frame): the loader's {np.round(100 * loader_lever, 1)}, fitted on the "
              f"slaps at {SLAP_FIT_HZ:g} Hz {np.round(100 * slap_lever, 1)}; the slaps' specific-force misfit "
              f"{misfit['loader']:.2f} against {misfit['slaps']:.2f} m/s^2 rms |" + " |" * (len(STEPS) - 1))
        for label, change in {**variants, "lever arm fitted on the slaps": {"lever_shift": slap_lever - loader_lever}
                              }.items():
            poses, _ = vicon_poses(side, rec, **change)
            cutoffs = CUTOFFS_HZ if label == "as fitted" else (None,)
            for c in cutoffs:
                st = steps(stance_windows(rec, poses[c]))
                name = label if c is None else f"low-pass {c:g} Hz"
                print(f"| {side} | {name} | " + " | ".join(f"{fwd_up(st['b'][:, i])} ; {fwd_up(st['c'][:, i])}"
                                                           for i in range(len(STEPS))) + " |")


def profile_table(windows: dict, slap_windows: dict) -> None:
    grid = np.round(np.arange(-0.16, 0.0601, 0.01), 3)
    print("\n### When: mean error over strides around forefoot contact (FF), from FF - 160 ms (mm/s; abs(f): median, "
          "m/s^2)\n")
    print("| foot | quantity | " + " | ".join(f"{1000 * g:+.0f}" for g in grid) + " |")
    print("|---|---|" + "---|" * len(grid))
    for side, ws in windows.items():
        pr = profile(ws, grid)
        for q in ("b", "c", "d"):
            for j, axis in enumerate(("forward", "up")):
                print(f"| {side} | {q} {axis} | " + " | ".join(f"{1000 * x:+.0f}" for x in pr[q][:, j]) + " |")
        print(f"| {side} | pitch error (deg) | " + " | ".join(f"{np.degrees(x):+.2f}" for x in pr["pitch"][:, 0])
              + " |")
        print(f"| {side} | abs(f) | " + " | ".join(f"{x:.0f}" for x in pr["force"][:, 0]) + " |")
        pr = profile(slap_windows[side], grid)
        for q in ("b", "c"):
            print(f"| {side} | {q} up, lever arm fitted on the slaps | " + " | ".join(f"{1000 * x:+.0f}"
                                                                               for x in pr[q][:, 1]) + " |")


def impact_impulse(w: Window) -> float:
    """m/s, the integral of abs(f) - g over its positive part from IC to FF (trapezoid on the samples)."""
    inside = (w.t >= w.events["ic"]) & (w.t <= w.events["ff"])
    return float(np.trapezoid(np.maximum(w.force_norm[inside] - STANDARD_GRAVITY, 0.0), w.t[inside]))


def slap_force_table(feet, windows: dict) -> None:
    grid = np.arange(-0.025, 0.0151, 0.005)
    print("\n### The slap's specific force (means, m/s^2): IMU x Vicon attitude, and the Vicon site's\n")
    print("world up and forward, and the IMU's rate about y (deg/s), at ms from FF\n")
    print("| foot | quantity | " + " | ".join(f"{1000 * g:+.0f}" for g in grid) + " |")
    print("|---|---|" + "---|" * len(grid))
    for side, rec, _ in feet:
        pose = vicon_poses(side, rec)[0][None]
        t = np.asarray(rec.t, float)
        rows = {"IMU up": [], "Vicon up": [], "IMU forward": [], "Vicon forward": [], "rate about y": []}
        for w in windows[side]:
            at = w.first_time + w.events["ff"] + grid
            f_imu = np.einsum("nij,nj->ni", pose.rotation(at), np.stack([np.interp(at, t, rec.acc[:, j])
                                                                          for j in range(3)], -1))
            f_vicon = pose.specific_force(at, STANDARD_GRAVITY)
            for label, f in (("IMU", f_imu), ("Vicon", f_vicon)):
                rows[f"{label} up"].append(f[:, 2])
                rows[f"{label} forward"].append(f @ w.forward)
            rows["rate about y"].append(np.degrees(np.interp(at, t, rec.gyr[:, 1])))
        for label, values in rows.items():
            print(f"| {side} | {label} | " + " | ".join(f"{x:+.1f}" for x in np.mean(values, axis=0)) + " |")


def hypothesis_table(feet, windows: dict) -> None:
    shown = ("slap", "landing", "stride")
    index = [list(STEPS).index(name) for name in shown]
    print("\n### Hypotheses: the steps b ; c (forward / up, mm/s, medians) with the recording corrected for each named "
          "error\n")
    print("| foot | sensor read as | " + " | ".join(shown) + " |")
    print("|---|---|" + "---|" * len(shown))
    for side, rec, _ in feet:
        poses, _ = vicon_poses(side, rec)
        runs = {"as recorded": windows[side]}
        runs.update({label: stance_windows(rec, poses[None], acc=acc, gyr=gyr)
                     for label, (acc, gyr) in hypotheses(rec).items()})
        for label, ws in runs.items():
            st = steps(ws)
            print(f"| {side} | {label} | " + " | ".join(f"{fwd_up(st['b'][:, i])} ; {fwd_up(st['c'][:, i])}"
                                                       for i in index) + " |")
        sol = pipeline.navigate(rec, nav_options(THRESHOLD, method="rk4"))
        st = steps([dataclasses.replace(w, strapdown=fine_strapdown(rec, w, sol)) for w in windows[side]])
        print(f"| {side} | b integrated on {FINE_FACTOR}x band-limited interpolation | "
              + " | ".join(f"{fwd_up(st['b'][:, i])} ; -" for i in index) + " |")
    print("\nClipping: the per-stride landing step of c (up) against the stride's sampled peak abs(f), the landing's\n"
          "size seen by the Vicon (the forward speed it takes out of the foot: no sampling phase changes it, and its\n"
          "noise is not c's up) and the impact's impulse the IMU reads (the integral of abs(f) - g over its positive\n"
          "part from IC to FF, which the sampling phase changes far less than the peak); Spearman rank correlations\n")
    print("| foot | strides with a sampled peak >= 14 g | c up, those / the others (mm/s, medians) | "
          "correlation with the peak | with the Vicon's landing speed | with the impulse |")
    print("|---|---|---|---|---|---|")
    landing = list(STEPS).index("landing")
    for side, ws in windows.items():
        peaks = np.array([w.force_norm.max() for w in ws])
        up = steps(ws)["c"][:, landing, 1]
        at = [list(POINTS).index(p) for p in STEPS["landing"]]
        impact = np.array([-np.diff(block_means(w, forward_up(w, w.reference)[:, :1], points(w)[at])[:, 0])[0]
                           for w in ws])
        impulse = np.array([impact_impulse(w) for w in ws])
        high = peaks >= 14 * STANDARD_GRAVITY
        print(f"| {side} | {high.sum()} of {len(ws)} | {1000 * np.median(up[high]):+.0f} / "
              f"{1000 * np.median(up[~high]):+.0f} | " + " | ".join(f"{spearmanr(x, up)[0]:+.2f}"
                                                                   for x in (peaks, impact, impulse)) + " |")


def main() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the loaders' data-quality warnings
        feet = list(feet_and_twins())
        twin_table(feet)
        windows = real_table(feet)
        slap_levers = {side: slap_lever_arm(side, rec, windows[side]) for side, rec, _ in feet}
        sensitivity_table(feet, slap_levers)
        slap_windows = {side: stance_windows(rec, vicon_poses(side, rec, lever_shift=slap_levers[side][0]
                                                              - vicon_poses(side, rec)[1]["lever_arm_m"])[0][None])
                        for side, rec, _ in feet}
        profile_table(windows, slap_windows)
        slap_force_table(feet, windows)
        hypothesis_table(feet, windows)


if __name__ == "__main__":
    main()
