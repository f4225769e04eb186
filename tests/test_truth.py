"""Laws the ground-truth simulator must obey: gravity, rigid-body kinematics, C4 joins, strapdown consistency,
the rolling foot in stance (still contact, velocity about the contact, displacement = integral of velocity),
turns and closure, determinism."""

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import simpson
from scipy.optimize import brentq

from gaitsim.world import smooth
from gaitsim.world.foot import FootModel, Mount
from gaitsim.world.gait import plan_stances
from gaitsim.world.profile import FootTrajectory
from gaitsim.scenario import load_scenario, scenario_from_dict
from gaitsim.simulate import run_generators, simulate_walk
from nav import quaternion as Q
from strapdown_reference import integrate_increments, rk4_windows

ROOT = Path(__file__).resolve().parents[1]
G = 9.81


@pytest.fixture(scope="module")
def straight():
    return simulate_walk(load_scenario(ROOT / "scenarios/straight_100m.toml"))


def short_walk(**sections):
    doc = {"path": {"kind": "straight", "length_m": 7.0, "yaw_deg": 30.0}, "gait": {"stand_start_s": 1.0, "stand_end_s": 1.0}}
    for key, table in sections.items():
        if key == "path":
            doc["path"] = table
        else:
            doc.setdefault(key, {}).update(table)
    return scenario_from_dict(doc, "test")


def test_static_foot_reads_gravity_and_zero_rate():
    foot = FootModel()
    s = foot.sample(np.zeros((1, 6)), np.zeros((1, 6)), np.zeros((1, 6)))
    np.testing.assert_allclose(s.acc[0], [0, 0, G], atol=1e-12)
    np.testing.assert_allclose(s.gyr[0], 0, atol=1e-15)


@pytest.mark.parametrize("pitch_deg, roll_deg", [(17.0, 0.0), (-30.0, 12.0)])
def test_tilted_foot_reads_rotated_gravity(pitch_deg, roll_deg):
    foot = FootModel()
    qpos = np.array([[0.1, -0.2, 0.05, 0.7, np.deg2rad(pitch_deg), np.deg2rad(roll_deg)]])
    s = foot.sample(qpos, np.zeros((1, 6)), np.zeros((1, 6)))
    c = Q.to_matrix(Q.from_euler_zyx(0.7, np.deg2rad(pitch_deg), np.deg2rad(roll_deg)))
    np.testing.assert_allclose(s.acc[0], c.T @ [0, 0, G], atol=1e-12)
    np.testing.assert_allclose(s.quat[0], Q.from_euler_zyx(0.7, np.deg2rad(pitch_deg), np.deg2rad(roll_deg)), atol=1e-12)


def test_mujoco_sensors_equal_rigid_body_formulas():
    """MuJoCo's site accelerometer and gyro equal p'' + a x r + w x (w x r) - g and R^T w from the joint stacks."""
    scen = short_walk(mount={"site": "instep", "offset_m": [0.01, -0.02, 0.0], "rpy_deg": [5.0, -3.0, 10.0]})
    foot = FootModel(scen.mount)
    plan = plan_stances(scen.walk, run_generators(3)[0])
    traj = FootTrajectory(scen.walk, plan, foot.toe_length)
    t = np.linspace(0.0, plan.t_end, 3001)
    j = traj.joints(t)
    s = foot.sample(j[:, 0].T, j[:, 1].T, j[:, 2].T)
    (yaw, pitch, roll) = j[3:, 0]
    (dyaw, dpitch, droll) = j[3:, 1]
    (ddyaw, ddpitch, ddroll) = j[3:, 2]
    rz = Q.to_matrix(Q.from_euler_zyx(yaw, 0 * yaw, 0 * yaw))
    rzy = Q.to_matrix(Q.from_euler_zyx(yaw, pitch, 0 * yaw))
    r = Q.to_matrix(Q.from_euler_zyx(yaw, pitch, roll))
    ez = np.array([0, 0, 1.0])
    ey = rz[:, :, 1]
    ex = rzy[:, :, 0]
    w_zy = dyaw[:, None] * ez + dpitch[:, None] * ey
    w = w_zy + droll[:, None] * ex
    alpha = (ddyaw[:, None] * ez + ddpitch[:, None] * ey + dpitch[:, None] * np.cross(dyaw[:, None] * ez, ey)
             + ddroll[:, None] * ex + droll[:, None] * np.cross(w_zy, ex))
    lever = np.einsum("nij,j->ni", r, foot.lever_arm)
    a = j[:3, 2].T + np.cross(alpha, lever) + np.cross(w, np.cross(w, lever))
    site = Q.to_matrix(s.quat)
    f_expected = np.einsum("nji,nj->ni", site, a - [0, 0, -G])
    w_expected = np.einsum("nji,nj->ni", site, w)
    assert np.abs(s.acc - f_expected).max() < 1e-9 * np.abs(f_expected).max()
    assert np.abs(s.gyr - w_expected).max() < 1e-10 * np.abs(w_expected).max()


def _sole_joins(traj, plan) -> np.ndarray:
    """Times where the pitch crosses +-b (the rolling sole's joins between heel, sole and toe contact)."""
    b = 0.5 * traj.walk.micro.contact_transfer_pitch
    t = np.linspace(0.0, plan.t_end, 400001)
    pitch = traj.pitch.stack(t)[0]
    out = []
    for level in (-b, b):
        for i in np.flatnonzero(np.diff(np.sign(pitch - level)) != 0):
            out.append(brentq(lambda x: traj.pitch.stack(np.array([x]))[0, 0] - level, t[i], t[i + 1], xtol=1e-13))
    return np.array(out)


def test_joint_trajectories_are_c4_at_every_knot():
    scen = short_walk(micromotion={"stance_roll_rate_dps": 20.0, "stance_rotation_dps": [4.0, 3.0, -6.0],
                                   "stance_yaw_pivot_frac": 0.2, "contact_radius_m": 0.01,
                                   "creep_velocity_mps": [0.01, 0.002, 0.0]},
                      impact={"ringing_hz": 60.0, "ringing_damping": 0.15, "ringing_accel_mps2": 15.0},
                      gait={"toe_release_accel_mps2": 40.0, "swing_lead": [0.03, -0.1, -0.05]},
                      path={"kind": "arc", "radius_m": 5.0, "turn_deg": 80.0, "yaw_deg": 0.0})
    plan = plan_stances(scen.walk, run_generators(5)[0])
    traj = FootTrajectory(scen.walk, plan, 0.2)
    imp, mm = scen.walk.impact, scen.walk.micro
    knots = np.concatenate([
        plan.t_ic, plan.t_ff, plan.t_ho, plan.t_to, plan.t_ff - imp.slap_duration_s,
        plan.t_ic + imp.heel_strike_duration_s, plan.t_ff - mm.creep_ramp_s, plan.t_ho + mm.creep_ramp_s,
        plan.t_ff + mm.creep_ramp_s, plan.t_ho - mm.creep_ramp_s,
        plan.t_ff - imp.slap_duration_s + mm.loading_duration_s, _sole_joins(traj, plan),
        plan.t_to - scen.walk.gait.toe_release_s,
    ])
    ring = smooth.Ringing(0.0, 60.0, 0.15, 15.0)
    events = np.concatenate([plan.t_ic[1:], plan.t_ff[1:]])
    knots = np.concatenate([knots, events + ring.period, events + ring.duration - ring.period, events + ring.duration])
    knots = knots[(knots > 1e-3) & (knots < plan.t_end - 1e-3)]
    eps = 1e-9
    jumps = np.abs(traj.joints(knots + eps) - traj.joints(knots - eps)).max(axis=2)  # (6, 5)
    scale = np.abs(traj.joints(np.linspace(0, plan.t_end, 20001))).max(axis=2) + 1e-12
    assert (jumps / scale).max() < 1e-5, jumps / scale


def test_exact_increments_reproduce_the_99m_walk_within_1mm(straight):
    tr = straight.truth
    dt = tr.t[1] - tr.t[0]
    _, _, p = integrate_increments(tr.quat[0], tr.vel[0], tr.pos[0], tr.dv[:-1], tr.dth[:-1], dt)
    assert np.linalg.norm(p - tr.pos[-1]) < 1e-3


def test_rk4_on_point_samples_stays_within_5mm_per_10s(straight):
    tr = straight.truth
    dt = tr.t[1] - tr.t[0]
    m = int(round(10.0 / dt)) + 4
    starts = np.arange(0, len(tr.t) - m, m)
    idx = starts[:, None] + np.arange(m)
    q, v, p = rk4_windows(tr.quat[starts + 1], tr.vel[starts + 1], tr.pos[starts + 1], tr.gyr[idx], tr.acc[idx], dt)
    err = np.linalg.norm(p - tr.pos[starts + m - 3], axis=1)
    assert err.max() < 5e-3, err


def _site_velocity_integral(traj, foot, t0, t1, points=4001):
    """Simpson integral over [t0, t1] of the IMU site's velocity as MuJoCo's sensor reports it from the joints."""
    t = np.linspace(t0, t1, points)
    j = traj.joints(t)
    v = foot.sample(j[:, 0].T, j[:, 1].T, j[:, 2].T).vel
    return simpson(v, x=t, axis=0)


def test_true_displacement_equals_the_integral_of_the_true_velocity(straight):
    """Over the labelled stance of events.csv and over an arbitrary window inside it, the site's true
    displacement (positions) equals the integral of its true velocity (MuJoCo's velocity sensor)."""
    scen = load_scenario(ROOT / "scenarios/straight_100m.toml")
    foot = FootModel(scen.mount)
    plan = plan_stances(scen.walk, run_generators(scen.seed)[0])
    traj = FootTrajectory(scen.walk, plan, foot.toe_length)
    ev = straight.events
    for k in (3, 20):
        integral = _site_velocity_integral(traj, foot, ev.t_ff[k], ev.t_ho[k])
        np.testing.assert_allclose(ev.stance_displacement[k], integral, atol=1e-9)
        assert np.linalg.norm(ev.stance_displacement[k]) > 1e-4  # the foot does move in stance
        t0, t1 = ev.t_ff[k] + 0.037, ev.t_ho[k] - 0.081
        moved = traj.point(np.array([t1]), foot.lever_arm) - traj.point(np.array([t0]), foot.lever_arm)
        np.testing.assert_allclose(moved[0], _site_velocity_integral(traj, foot, t0, t1), atol=1e-9)
    # and the recorded IMU trajectory moves by that much between the nearest samples (to sampling resolution)
    tr = straight.truth
    k = 10
    i0, i1 = np.searchsorted(tr.t, [ev.t_ff[k], ev.t_ho[k]])
    speed = np.abs(tr.vel[[i0, i1]]).max()
    assert np.linalg.norm(tr.pos[i1] - tr.pos[i0] - ev.stance_displacement[k]) < 2 * speed / 800.0 + 1e-9


STILL_ROLL = {"pronation_rate_dps": 0.0, "loading_roll_rate_dps": 0.0, "stance_rate_sd_frac": 0.0}


def _contact_kinematics(traj, t):
    """World position of the ground contact, angular velocity (world) and heel velocity at times t."""
    j = traj.joints(t)
    (yaw, pitch, _), (dyaw, dpitch, droll) = j[3:, 0], j[3:, 1]
    heel, heel_vel = j[:3, 0].T, j[:3, 1].T
    rz = Q.to_matrix(Q.from_euler_zyx(yaw, 0 * yaw, 0 * yaw))
    rzy = Q.to_matrix(Q.from_euler_zyx(yaw, pitch, 0 * yaw))
    w = dyaw[:, None] * [0.0, 0.0, 1.0] + dpitch[:, None] * rz[:, :, 1] + droll[:, None] * rzy[:, :, 0]
    offset = traj.sole.contact_offset(pitch)
    height = traj.sole.heel_height(pitch)
    heading = np.stack([np.cos(yaw), np.sin(yaw), 0 * yaw], -1)
    contact = heel + offset[:, None] * heading - height[:, None] * [0.0, 0.0, 1.0]
    return contact, w, heel_vel, heel, heading, dpitch


def _release_velocity(walk, plan, k, t) -> np.ndarray:
    """(N,) m/s, forward velocity of stance k's toe release at times t (zero outside it)."""
    g = walk.gait
    return smooth.release(plan.t_to[k], g.toe_release_s, g.toe_release_accel_mps2).stack(t)[1]


@pytest.mark.parametrize("radius, creep, release", [(0.0, 0.0, 0.0), (0.012, 0.004, 0.0), (0.0, 0.0, 40.0)])
def test_the_contact_point_moves_only_by_its_creep_compliance_and_toe_release(radius, creep, release):
    """The material point of the foot at the ground contact moves at creep + contact radius x pitch rate
    (forward, in the walking frame) + the toe release in the push-off's last ``toe_release_s``: still without
    them, for every stance phase the sole rolls through."""
    scen = short_walk(micromotion={**STILL_ROLL, "contact_radius_m": radius, "creep_velocity_mps": [creep, 0, 0]},
                      gait={"stride_length_sd_m": 0.0, "toe_release_accel_mps2": release})
    plan = plan_stances(scen.walk, run_generators(4)[0])
    traj = FootTrajectory(scen.walk, plan, 0.2)
    k = 2
    mm = scen.walk.micro
    t = np.linspace(plan.t_ic[k] + scen.walk.impact.heel_strike_duration_s + 1e-4, plan.t_to[k], 3001)
    contact, w, heel_vel, heel, heading, dpitch = _contact_kinematics(traj, t)
    material = heel_vel + np.cross(w, contact - heel)
    ramped = (t > plan.t_ff[k] - mm.creep_ramp_s) & (t < plan.t_ho[k] + mm.creep_ramp_s)
    plateau = (t > plan.t_ff[k]) & (t < plan.t_ho[k])
    expected = (radius * dpitch + _release_velocity(scen.walk, plan, k, t))[:, None] * heading
    np.testing.assert_allclose(material[~ramped], expected[~ramped], atol=1e-9)
    np.testing.assert_allclose(material[plateau], expected[plateau] + creep * heading[plateau], atol=1e-9)
    slid = material[-1] @ heading[-1] - radius * dpitch[-1]  # at toe off
    np.testing.assert_allclose(slid, release * scen.walk.gait.toe_release_s / 2, atol=1e-9)


def test_the_toe_leaves_the_ground_accelerating_at_the_release_and_the_swing_lead_moves_only_the_middle():
    """With a toe release, the foot's contact point has, at toe off, the release's velocity a d / 2 and
    acceleration a along the walking direction; a swing lead moves the heel by lead x the swing's horizontal
    travel at a quarter, half and three quarters of each swing and leaves both of its ends (value and four
    derivatives) where the swing without it has them."""
    gait = {"stride_length_sd_m": 0.0, "toe_release_accel_mps2": 0.0, "swing_lead": [0.0, 0.0, 0.0]}
    lead = [0.05, -0.1, 0.02]
    plain = short_walk(micromotion=STILL_ROLL, gait=gait)
    led = short_walk(micromotion=STILL_ROLL, gait={**gait, "swing_lead": lead})
    plan = plan_stances(plain.walk, run_generators(4)[0])
    a, b = FootTrajectory(plain.walk, plan, 0.2), FootTrajectory(led.walk, plan, 0.2)
    k = 2
    t0, t1 = plan.t_to[k], plan.t_ic[k + 1]
    ends = np.array([t0, t1])
    np.testing.assert_allclose(b.joints(ends), a.joints(ends), rtol=0, atol=1e-9)
    phases = t0 + np.array([0.25, 0.5, 0.75]) * (t1 - t0)
    travel = np.linalg.norm(a.joints(np.array([t1]))[:2, 0, 0] - a.joints(np.array([t0]))[:2, 0, 0])
    direction = np.array([np.cos(np.mean(plan.yaw[k:k + 2])), np.sin(np.mean(plan.yaw[k:k + 2]))])
    moved = (b.joints(phases) - a.joints(phases))[:2, 0].T @ direction
    np.testing.assert_allclose(moved, np.multiply(lead, travel), atol=1e-9)

    released = short_walk(micromotion=STILL_ROLL, gait={**gait, "toe_release_accel_mps2": 40.0})
    traj = FootTrajectory(released.walk, plan, 0.2)
    step = 1e-4
    t = plan.t_to[k] - np.array([step, 0.0])
    contact, w, heel_vel, heel, heading, _ = _contact_kinematics(traj, t)
    forward = np.einsum("ni,ni->n", heel_vel + np.cross(w, contact - heel), heading)  # the contact's material point
    d = released.walk.gait.toe_release_s
    np.testing.assert_allclose(forward[-1], 40.0 * d / 2, atol=1e-9)
    np.testing.assert_allclose((forward[1] - forward[0]) / step, 40.0, rtol=1e-3)


def test_imu_velocity_is_the_rotation_about_the_contact():
    """MuJoCo's IMU-site velocity equals w x (r_imu - r_contact) in every phase of the stance (a fixed toe: no
    release), and its forward part in foot flat is pitch rate x height of the site above the ground (the
    rolling foot's law)."""
    scen = short_walk(micromotion=STILL_ROLL, mount={"site": "instep"},
                      gait={"stride_length_sd_m": 0.0, "toe_release_accel_mps2": 0.0})
    foot = FootModel(scen.mount)
    plan = plan_stances(scen.walk, run_generators(4)[0])
    traj = FootTrajectory(scen.walk, plan, foot.toe_length)
    k = 2
    t = np.linspace(plan.t_ic[k] + 0.02, plan.t_to[k], 2001)
    j = traj.joints(t)
    s = foot.sample(j[:, 0].T, j[:, 1].T, j[:, 2].T)
    contact, w, _, _, heading, dpitch = _contact_kinematics(traj, t)
    np.testing.assert_allclose(s.vel, np.cross(w, s.pos - contact), atol=1e-9)
    flat = (t > plan.t_ff[k] + 0.05) & (t < plan.t_ho[k] - 0.05)
    forward = np.einsum("ni,ni->n", s.vel, heading)[flat]
    assert np.abs(forward - dpitch[flat] * (s.pos[flat, 2] - contact[flat, 2])).max() < 1e-9
    assert dpitch[flat].min() > 0  # the heel rises through foot flat: the site moves forward


def test_without_micromotion_the_stance_is_exactly_still():
    rec = simulate_walk(short_walk(micromotion={"enabled": False}))
    tr = rec.truth
    assert tr.stance.sum() > 0.3 * len(tr.t)
    assert np.abs(tr.vel[tr.stance]).max() < 1e-12
    assert np.abs(tr.gyr[tr.stance]).max() < 1e-12
    np.testing.assert_allclose(rec.events.stance_displacement, 0, atol=1e-12)


def test_arc_heading_after_n_strides_is_n_times_the_turn():
    radius, turn_deg = 8.0, 90.0
    rec = simulate_walk(short_walk(path={"kind": "arc", "radius_m": radius, "turn_deg": turn_deg, "yaw_deg": 0.0},
                                   gait={"stride_length_sd_m": 0.0}))
    ev, tr = rec.events, rec.truth
    n = len(ev.t_ic) - 1
    per_stride = np.deg2rad(turn_deg) / n
    for k in (1, n // 2, n):
        i = np.searchsorted(tr.t, ev.t_ff[k])
        yaw = Q.to_euler_zyx(tr.quat[i])[0]
        assert abs(np.angle(np.exp(1j * (yaw - k * per_stride)))) < 1e-12


def test_closed_loop_closes():
    scen = load_scenario(ROOT / "scenarios/loop_turns.toml")
    rec = simulate_walk(scen)
    tr = rec.truth
    foot = FootModel(scen.mount)
    heel = tr.pos - Q.rotate(tr.quat, foot.lever_arm)
    np.testing.assert_allclose(heel[-1, :2], heel[0, :2], atol=1e-9)
    ev = rec.events
    yaw = np.unwrap(Q.to_euler_zyx(tr.quat[np.searchsorted(tr.t, ev.t_ff + 0.05)])[0])
    turns = np.diff(yaw)
    assert turns.max() > 0.3 and turns.min() < -0.3  # both left and right turns


def test_same_seed_same_walk_other_seed_other_strides():
    scen = short_walk()
    a, b, c = simulate_walk(scen, seed=4), simulate_walk(scen, seed=4), simulate_walk(scen, seed=5)
    np.testing.assert_array_equal(a.truth.as_table(), b.truth.as_table())
    assert not np.allclose(np.diff(a.events.t_ic), np.diff(c.events.t_ic))


def test_default_walk_peaks_and_spectrum(straight):
    """Default impacts give 5-15 g peaks with the energy mostly below 80 Hz (anchors §7)."""
    tr = straight.truth
    mag = np.linalg.norm(tr.acc, axis=1)
    assert 5 * G < mag.max() < 15 * G
    a = mag[tr.t > 2.5] - mag[tr.t > 2.5].mean()
    spec = np.abs(np.fft.rfft(a)) ** 2
    f = np.fft.rfftfreq(a.size, tr.t[1] - tr.t[0])
    assert spec[f > 80].sum() / spec.sum() < 0.02


def test_smoothstep_and_pulse_shapes():
    s = np.linspace(0, 1, 11)
    np.testing.assert_allclose(np.polynomial.polynomial.polyval(s, smooth.SMOOTHSTEP)[[0, -1]], [0, 1])
    assert smooth.PULSE_AREA == pytest.approx(256 / 630, rel=1e-12)  # 256 * B(5, 5)


QUIET_STANCE = {**STILL_ROLL, "heel_rise_rate_start_dps": 0.0, "heel_rise_growth_dps3": 0.0}


def test_stance_roll_over_rate_is_linear_through_foot_flat():
    rate = 18.0
    rec = simulate_walk(short_walk(micromotion={**QUIET_STANCE, "stance_roll_rate_dps": rate},
                                   gait={"stride_length_sd_m": 0.0}))
    tr, ev = rec.truth, rec.events
    k = 2
    m = (tr.t >= ev.t_ff[k]) & (tr.t <= ev.t_ho[k])
    s = (tr.t[m] - ev.t_ff[k]) / (ev.t_ho[k] - ev.t_ff[k])
    # pitch and yaw are still in this foot flat, so the body rate is the roll rate about x
    np.testing.assert_allclose(np.rad2deg(tr.gyr[m, 0]), rate * (1 - 2 * s), atol=1e-9)
    np.testing.assert_allclose(tr.gyr[m, 1:], 0, atol=1e-12)
    assert np.mean(np.abs(np.rad2deg(tr.gyr[m, 0]))) == pytest.approx(rate / 2, rel=0.01)
    # the roll at heel off equals the roll at foot flat: the toes-mounted IMU ends foot flat where it began
    np.testing.assert_allclose(rec.events.stance_displacement[k], 0.0, atol=1e-9)


def test_the_heel_rise_rate_grows_with_the_square_of_the_time_since_foot_flat():
    start, growth = 2.0, 40.0
    rec = simulate_walk(short_walk(micromotion={**QUIET_STANCE, "heel_rise_rate_start_dps": start,
                                                "heel_rise_growth_dps3": growth}, gait={"stride_length_sd_m": 0.0}))
    tr, ev = rec.truth, rec.events
    k = 2
    m = (tr.t >= ev.t_ff[k]) & (tr.t <= ev.t_ho[k])
    tau = tr.t[m] - ev.t_ff[k]
    np.testing.assert_allclose(np.rad2deg(tr.gyr[m, 1]), start + growth * tau**2, atol=1e-9)
    np.testing.assert_allclose(tr.gyr[m][:, [0, 2]], 0, atol=1e-12)


def test_loading_roll_and_pronation_are_mirrored_for_a_right_foot():
    table = {"stance_rate_sd_frac": 0.0}
    left = simulate_walk(short_walk(micromotion=table), seed=3).truth
    right = simulate_walk(short_walk(micromotion={**table, "foot": "right"}), seed=3).truth
    flat = left.stance  # the swing's roll is the gait's, not mirrored
    np.testing.assert_allclose(right.gyr[flat, 0], -left.gyr[flat, 0], atol=1e-12)
    np.testing.assert_allclose(right.gyr[flat, 1], left.gyr[flat, 1], atol=1e-12)
    assert np.abs(left.gyr[flat, 0]).max() > np.deg2rad(3.0)


def test_impact_ringing_adds_a_damped_resonance_at_its_frequency():
    f0, zeta, accel = 65.0, 0.1, 20.0
    base = simulate_walk(short_walk(), seed=2).truth
    ring = simulate_walk(short_walk(impact={"ringing_hz": f0, "ringing_damping": zeta, "ringing_accel_mps2": accel}),
                         seed=2).truth
    diff = ring.acc[:, 2] - base.acc[:, 2]
    assert 0.5 * accel < np.abs(diff).max() < 1.5 * accel
    spec = np.abs(np.fft.rfft(diff)) ** 2
    f = np.fft.rfftfreq(diff.size, ring.t[1] - ring.t[0])
    assert abs(f[np.argmax(spec)] - f0) < 2.0
    # the oscillation is vertical displacement of the contact: sub-millimetre, and C4 (integrators unaffected)
    assert np.abs(ring.pos - base.pos).max() < accel / (2 * np.pi * f0) ** 2 * 1.5


def test_mount_rotation_rotates_the_sensor_axes():
    rpy = (12.0, -8.0, 0.0)
    foot = FootModel(Mount(rpy=tuple(np.deg2rad(rpy))))
    s = foot.sample(np.zeros((1, 6)), np.zeros((1, 6)), np.zeros((1, 6)))
    c = Q.to_matrix(Q.from_euler_zyx(0.0, np.deg2rad(rpy[1]), np.deg2rad(rpy[0])))
    np.testing.assert_allclose(s.acc[0], c.T @ [0, 0, G], atol=1e-12)


@pytest.mark.parametrize("axis", [0, 2])
def test_stance_rotation_turns_the_foot_at_its_rate_about_its_pivot(axis):
    """Roll or yaw alone: the body rate in the held part of foot flat is exactly the configured rate; the yaw
    pivot (the heel contact by default) does not move; the angle reached is rate * (foot flat - ramp), held
    through the push-off, and gone by the next foot flat."""
    rates = [0.0, 0.0, 0.0]
    rates[axis] = 7.0
    scen = short_walk(micromotion={**QUIET_STANCE, "stance_rotation_dps": rates}, gait={"stride_length_sd_m": 0.0})
    foot = FootModel(scen.mount)
    plan = plan_stances(scen.walk, run_generators(4)[0])
    traj = FootTrajectory(scen.walk, plan, foot.toe_length)
    mm = scen.walk.micro
    k = 2
    t = np.linspace(plan.t_ff[k] + mm.creep_ramp_s, plan.t_ho[k] - mm.creep_ramp_s, 200)
    j = traj.joints(t)
    s = foot.sample(j[:, 0].T, j[:, 1].T, j[:, 2].T)
    expected = np.zeros(3)
    expected[axis] = np.deg2rad(7.0)
    np.testing.assert_allclose(s.gyr, np.broadcast_to(expected, s.gyr.shape), atol=1e-12)
    if axis == 2:  # the heel point stays above the same ground point
        heel = traj.point(t, np.zeros(3))
        assert np.abs(heel[:, :2] - heel[0, :2]).max() < 1e-12
    held = np.deg2rad(7.0) * (plan.t_ho[k] - plan.t_ff[k] - mm.creep_ramp_s)
    yaw_pitch_roll = traj.angles(np.array([plan.t_ho[k], plan.t_to[k] - 1e-9, plan.t_ff[k + 1]]))[:, 0]
    offsets = yaw_pitch_roll - traj.angles(np.array([plan.t_ff[k]]))[:, 0]
    got = offsets[{0: 2, 2: 0}[axis]]
    assert got[0] == pytest.approx(held, rel=1e-9)
    assert got[1] == pytest.approx(held, rel=1e-9)
    assert abs(got[2]) < 1e-12


def test_stance_rotation_pitch_adds_to_the_heel_rise():
    rate = 3.0
    rec = simulate_walk(short_walk(micromotion={**QUIET_STANCE, "stance_rotation_dps": [0.0, rate, 0.0]},
                                   gait={"stride_length_sd_m": 0.0}))
    tr, ev = rec.truth, rec.events
    m = (tr.t >= ev.t_ff[2]) & (tr.t <= ev.t_ho[2])
    np.testing.assert_allclose(np.rad2deg(tr.gyr[m, 1]), rate, atol=1e-9)


def test_every_joint_stack_row_is_the_derivative_of_the_row_above():
    """Finite differences of each derivative row match the next row, with every stance feature switched on."""
    scen = short_walk(micromotion={"stance_roll_rate_dps": 15.0, "stance_rotation_dps": [4.0, 3.0, -6.0],
                                   "stance_yaw_pivot_frac": 0.3, "contact_radius_m": 0.01},
                      impact={"ringing_hz": 40.0, "ringing_accel_mps2": 10.0})
    plan = plan_stances(scen.walk, run_generators(2)[0])
    traj = FootTrajectory(scen.walk, plan, 0.2)
    h = 1e-5
    t = np.linspace(0.5, plan.t_end - 0.5, 4001)
    ahead, behind, here = traj.joints(t + h), traj.joints(t - h), traj.joints(t)
    numeric = (ahead[:, :-1] - behind[:, :-1]) / (2 * h)
    scale = np.abs(here[:, 1:]).max(axis=2, keepdims=True) + 1e-9
    # central differences err by h^2/6 times the next derivative: 2e-5 of the scale at the sharp heel strike
    assert (np.abs(numeric - here[:, 1:]) / scale).max() < 1e-4


def test_hermite_pieces_match_value_and_four_derivatives_at_every_knot():
    rng = np.random.default_rng(1)
    knots = np.cumsum(rng.uniform(0.01, 0.5, 6))
    stacks = rng.normal(size=(6, 5)) * [1.0, 10.0, 1e2, 1e3, 1e4]
    piece = smooth.hermite(knots, stacks)
    for side in (-1e-12, 1e-12):  # the left and right limits both equal the given stack
        at = np.clip(knots + side, knots[0], knots[-1])
        got = np.stack([piece.pp(at, nu=j) for j in range(5)], axis=1)
        scale = np.abs(stacks).max(axis=0)
        assert np.all(np.abs(got - stacks) <= 1e-6 * scale), (got - stacks) / scale
    assert piece.pp.c.shape == (10, 5)  # degree 9 on each of the 5 intervals


def test_piecewise_stack_rows_equal_the_polynomial_derivatives():
    rng = np.random.default_rng(2)
    knots = np.cumsum(rng.uniform(0.01, 0.5, 6))
    piece = smooth.hermite(knots, rng.normal(size=(6, 5)) * [1.0, 10.0, 1e2, 1e3, 1e4])
    t = np.sort(rng.uniform(knots[0] - 0.1, knots[-1] + 0.1, 200))
    inside = (t >= knots[0]) & (t <= knots[-1])
    expected = np.stack([piece.pp(t, nu=j) for j in range(5)])
    expected[1:, ~inside] = 0.0  # held value outside, zero derivatives
    expected[0, t < knots[0]], expected[0, t > knots[-1]] = piece.before, piece.after
    np.testing.assert_allclose(piece.stack(t), expected, rtol=1e-9, atol=1e-9 * np.abs(expected).max())


def test_accumulate_on_the_window_equals_adding_the_whole_stack_bit_for_bit():
    rng = np.random.default_rng(3)
    knots = np.cumsum(rng.uniform(0.01, 0.5, 6))
    piece = smooth.hermite(knots, rng.normal(size=(6, 5)) * [1.0, 10.0, 1e2, 1e3, 1e4])
    t = np.sort(np.concatenate([rng.uniform(knots[0] - 0.5, knots[-1] + 0.5, 300), knots[[0, -1]]]))
    # samples on both sides, only before, only after, none outside
    for times in (t, t[t < knots[2]], t[t > knots[3]], t[(t >= knots[0]) & (t <= knots[-1])]):
        start = np.zeros((smooth.NDER, times.size))
        start[0] = rng.normal(size=times.size)
        expected = start + piece.stack(times)
        smooth.accumulate(start, times, piece.t0, piece.t1, lambda times, _: piece.stack(times))
        assert np.array_equal(start, expected)


def _pieces(rng, count):
    """``count`` Piecewise on disjoint increasing windows: of 1 and 3 pieces, zero or not before them."""
    out = []
    for j in range(count):
        knots = 2.0 * j + np.cumsum(rng.uniform(0.05, 0.4, 2 + 2 * (j % 2)))
        stacks = rng.normal(size=(knots.size, 5)) * [1.0, 10.0, 1e2, 1e3, 1e4]
        if j % 3:
            stacks[0] = 0.0  # zero before its window
        if j == 4:
            stacks[:] = 0.0  # identically zero (skipped by PieceTable.add_to)
        out.append(smooth.hermite(knots, stacks))
    return out


def test_piece_table_gives_each_function_its_own_stack_bit_for_bit():
    rng = np.random.default_rng(4)
    pieces = _pieces(rng, 5)
    t = np.sort(rng.uniform(-0.5, 10.5, 2000))
    function = np.minimum((t // 2.0).astype(int), 4).clip(0)  # each function on a run of samples in order
    table = smooth.PieceTable(pieces)
    expected = np.concatenate([pieces[j].stack(t[function == j]) for j in range(5)], axis=1)
    assert np.array_equal(table.stack(t, function), expected)
    with pytest.raises(ValueError, match="one degree"):
        smooth.PieceTable([pieces[0], smooth.lift(0.0, 1.0, 1.0)])


def test_accumulate_of_several_windows_equals_adding_every_stack_in_turn_bit_for_bit():
    rng = np.random.default_rng(5)
    pieces = _pieces(rng, 6)
    table = smooth.PieceTable(pieces)
    t = np.sort(rng.uniform(-0.5, 12.5, 3000))
    out = np.zeros((2, smooth.NDER, t.size))
    out[:, 0] = rng.normal(size=(2, t.size))
    expected = out.copy()
    for piece in pieces:
        expected += piece.stack(t)
    smooth.accumulate(out, t, table.t0, table.t1, lambda times, f: np.stack([table.stack(times, f)] * 2))
    assert np.array_equal(out, expected)
    with pytest.raises(ValueError, match="disjoint"):
        smooth.accumulate(out, t, [0.0, 1.0], [1.5, 2.0], table.stack)