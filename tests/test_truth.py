"""Laws the ground-truth simulator must obey: gravity, rigid-body kinematics, C4 joins, strapdown consistency,
micro-motion integrals, turns and closure, determinism."""

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

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


def test_joint_trajectories_are_c4_at_every_knot():
    scen = short_walk(micromotion={"stance_roll_rate_dps": 20.0, "stance_rotation_dps": [4.0, 3.0, -6.0],
                                   "stance_rotation_pivot_frac": [0.7, 0.2]},
                      impact={"ringing_hz": 60.0, "ringing_damping": 0.15, "ringing_accel_mps2": 15.0},
                      path={"kind": "arc", "radius_m": 5.0, "turn_deg": 80.0, "yaw_deg": 0.0})
    plan = plan_stances(scen.walk, run_generators(5)[0])
    traj = FootTrajectory(scen.walk, plan, 0.2)
    imp, mm = scen.walk.impact, scen.walk.micro
    knots = np.concatenate([
        plan.t_ic, plan.t_ff, plan.t_ho, plan.t_to, plan.t_ff - imp.slap_duration_s,
        plan.t_ic + imp.heel_strike_duration_s, plan.t_ff - mm.creep_ramp_s, plan.t_ho + mm.creep_ramp_s,
        plan.t_ff + mm.settle_duration_s, plan.t_ho - mm.heel_off_duration_s / 2, plan.t_ho + mm.heel_off_duration_s / 2,
        plan.t_ff + mm.creep_ramp_s, plan.t_ho - mm.creep_ramp_s,
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


def _profile_integral(t0, t1, ff, ho, mm, axis):
    """Integral over [t0, t1] of the configured micro-motion velocity, written from the documented shapes."""
    step = lambda s: np.clip(s, 0, 1) ** 5 * (126 - 420 * s + 540 * s**2 - 315 * s**3 + 70 * s**4)  # noqa: E731
    pulse = lambda s: np.where((s > 0) & (s < 1), 256 * s**4 * (1 - s) ** 4, 0.0)  # noqa: E731

    def v(t):
        up = step((t - ff + mm.creep_ramp_s) / mm.creep_ramp_s) if t < ff else 1.0
        down = 1 - step((t - ho) / mm.creep_ramp_s) if t > ho else 1.0
        plateau = mm.creep_velocity_mps[axis] * (up if t < ff else down)
        return (plateau + mm.settle_velocity_mps[axis] * pulse((t - ff) / mm.settle_duration_s)
                + mm.heel_off_velocity_mps[axis] * pulse((t - ho + mm.heel_off_duration_s / 2) / mm.heel_off_duration_s))

    return quad(v, t0, t1, points=[ff, ho], limit=200, epsabs=1e-13)[0]


def test_stance_displacement_equals_integral_of_configured_velocity(straight):
    scen = load_scenario(ROOT / "scenarios/straight_100m.toml")
    mm = scen.walk.micro
    ev = straight.events
    yaw = np.deg2rad(90.0)
    for k in range(1, len(ev.t_ic) - 1, 7):
        local = [_profile_integral(ev.t_ff[k], ev.t_ho[k], ev.t_ff[k], ev.t_ho[k], mm, a) for a in range(3)]
        expected = [np.cos(yaw) * local[0] - np.sin(yaw) * local[1], np.sin(yaw) * local[0] + np.cos(yaw) * local[1], local[2]]
        np.testing.assert_allclose(ev.stance_displacement[k], expected, atol=1e-6)
    # and the recorded IMU trajectory moves by that much between the nearest samples (to sampling resolution)
    tr = straight.truth
    k = 10
    i0, i1 = np.searchsorted(tr.t, [ev.t_ff[k], ev.t_ho[k]])
    assert np.linalg.norm(tr.pos[i1] - tr.pos[i0] - ev.stance_displacement[k]) < 0.02 * 1.3e-3 + 1e-5


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
        i = np.searchsorted(tr.t, ev.t_ff[k] + 0.05)
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


def test_stance_roll_over_rate_is_linear_through_foot_flat():
    rate = 18.0
    rec = simulate_walk(short_walk(micromotion={"stance_roll_rate_dps": rate}, gait={"stride_length_sd_m": 0.0}))
    tr, ev = rec.truth, rec.events
    k = 2
    m = (tr.t >= ev.t_ff[k]) & (tr.t <= ev.t_ho[k])
    s = (tr.t[m] - ev.t_ff[k]) / (ev.t_ho[k] - ev.t_ff[k])
    # pitch and yaw are still in foot flat, so the body rate is the roll rate about x
    np.testing.assert_allclose(np.rad2deg(tr.gyr[m, 0]), rate * (1 - 2 * s), atol=1e-9)
    np.testing.assert_allclose(tr.gyr[m, 1:], 0, atol=1e-12)
    assert np.mean(np.abs(np.rad2deg(tr.gyr[m, 0]))) == pytest.approx(rate / 2, rel=0.01)
    # the contact axis does not move: the heel and toe contact points keep their micro-motion only
    np.testing.assert_allclose(np.linalg.norm(rec.events.stance_displacement[k]), 0.00534, rtol=0.1)


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


QUIET_STANCE = {"creep_velocity_mps": [0.0, 0.0, 0.0], "settle_velocity_mps": [0.0, 0.0, 0.0],
                "heel_off_velocity_mps": [0.0, 0.0, 0.0]}


@pytest.mark.parametrize("axis, pivot", [(0, None), (1, "pitch"), (2, "yaw")])
def test_stance_rotation_turns_the_foot_at_its_rate_about_its_pivot(axis, pivot):
    """One axis at a time, the body rate in the held part of foot flat is exactly the configured rate; the
    pivot (toe contact for pitch, heel contact for yaw by default) does not move; the angle reached is
    rate * (foot flat - ramp), held through the push-off, and gone by the next foot flat."""
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
    pivots = {"pitch": [foot.toe_length, 0.0, 0.0], "yaw": [0.0, 0.0, 0.0]}
    if pivot is not None:
        still = traj.point(t, np.array(pivots[pivot]))
        assert np.abs(still - still[0]).max() < 1e-12
    held = np.deg2rad(7.0) * (plan.t_ho[k] - plan.t_ff[k] - mm.creep_ramp_s)
    yaw_pitch_roll = traj.angles(np.array([plan.t_ho[k], plan.t_to[k] - 1e-9, plan.t_ff[k + 1]]))[:, 0]
    offsets = yaw_pitch_roll - traj.angles(np.array([plan.t_ff[k]]))[:, 0]
    got = offsets[{0: 2, 1: 1, 2: 0}[axis]]
    assert got[0] == pytest.approx(held, rel=1e-9)
    if axis != 1:  # the push-off pitch adds to the held pitch
        assert got[1] == pytest.approx(held, rel=1e-9)
    assert abs(got[2]) < 1e-12


def test_stance_rotation_moves_the_imu_as_a_rigid_body_about_the_pivots():
    """A heel-side IMU under a pitch about the toe moves up at pitch rate x distance to the toe contact, and
    the events' stance displacement is the IMU's (attitudes differ at the two ends of foot flat)."""
    rate = 3.0
    scen = short_walk(micromotion={**QUIET_STANCE, "stance_rotation_dps": [0.0, rate, 0.0]},
                      mount={"site": "heel"}, gait={"stride_length_sd_m": 0.0})
    rec = simulate_walk(scen, seed=4)
    tr, ev = rec.truth, rec.events
    foot = FootModel(scen.mount)
    k = 2
    m = (tr.t > ev.t_ff[k] + 0.05) & (tr.t < ev.t_ho[k] - 0.05)
    lever = foot.lever_arm - [foot.toe_length, 0.0, 0.0]  # IMU from the pivot, foot frame
    speed = np.deg2rad(rate) * np.hypot(lever[0], lever[2])
    assert np.linalg.norm(tr.vel[m], axis=1) == pytest.approx(np.full(m.sum(), speed), rel=0.02)
    assert tr.vel[m, 2].mean() == pytest.approx(np.deg2rad(rate) * -lever[0], rel=0.02)
    i0, i1 = np.searchsorted(tr.t, [ev.t_ff[k], ev.t_ho[k]])
    assert np.linalg.norm(tr.pos[i1] - tr.pos[i0] - ev.stance_displacement[k]) < speed / scen.rate_hz * 2
    assert ev.stance_displacement[k, 2] > 0.8 * speed * (ev.t_ho[k] - ev.t_ff[k] - 0.05)


def test_every_joint_stack_row_is_the_derivative_of_the_row_above():
    """Finite differences of each derivative row match the next row, with every stance feature switched on."""
    scen = short_walk(micromotion={"stance_roll_rate_dps": 15.0, "stance_rotation_dps": [4.0, 3.0, -6.0],
                                   "stance_rotation_pivot_frac": [0.8, 0.3]},
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
