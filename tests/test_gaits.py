"""Gaits (issue 17): the laws of the truth hold for every gait kind, the kinds reach the published foot peaks, a
forefoot strike turns about its toe contact, stops stand still, and bad gait keys are refused by name."""

import dataclasses

import numpy as np
import pytest

from gaitsim.errors import ScenarioError
from gaitsim.scenario import scenario_from_dict
from gaitsim.simulate import run_generators, simulate_walk
from gaitsim.world.foot import FootModel, Mount
from gaitsim.world.gait import plan_stances
from gaitsim.world.gaits import PUBLISHED_PEAKS
from gaitsim.world.profile import FootTrajectory, swing_maximum
from strapdown_reference import integrate_increments

G = 9.81
GAITS = {
    "walk-60": {"kind": "walk", "cadence_steps_per_min": 60.0},
    "walk-130": {"kind": "walk", "cadence_steps_per_min": 130.0},
    "run-rearfoot-180": {"kind": "run-rearfoot", "cadence_steps_per_min": 180.0},
    "run-forefoot-150": {"kind": "run-forefoot", "cadence_steps_per_min": 150.0},
    "stop-and-go": {"kind": "walk", "stop_every_strides": 2, "stop_duration_s": 1.5},
}


def gait_walk(gait: dict, length_m: float = 9.0, **sections):
    doc = {"path": {"kind": "straight", "length_m": length_m, "yaw_deg": 30.0},
           "gait": {"stand_start_s": 1.0, "stand_end_s": 1.0, **gait}, **sections}
    return scenario_from_dict(doc, "test")


@pytest.fixture(scope="module", params=sorted(GAITS))
def gait_run(request):
    scen = gait_walk(GAITS[request.param])
    return request.param, scen, simulate_walk(scen)


def test_joint_trajectories_are_c4_at_every_event(gait_run):
    _, scen, _ = gait_run
    plan = plan_stances(scen.walk, run_generators(0)[0])
    traj = FootTrajectory(scen.walk, plan, 0.2)
    imp = scen.walk.impact
    knots = np.concatenate([plan.t_ic, plan.t_ff, plan.t_ho, plan.t_to, plan.t_ff - imp.slap_duration_s,
                            plan.t_ic + imp.heel_strike_duration_s, swing_maximum(plan, scen.walk.gait)[0]])
    knots = knots[(knots > 1e-3) & (knots < plan.t_end - 1e-3)]
    jumps = np.abs(traj.joints(knots + 1e-9) - traj.joints(knots - 1e-9)).max(axis=2)
    scale = np.abs(traj.joints(np.linspace(0, plan.t_end, 20001))).max(axis=2) + 1e-12
    assert (jumps / scale).max() < 1e-5


def test_exact_increments_reproduce_a_stride(gait_run):
    """From one heel strike to past the next (both impacts included), the increments integrate to the truth."""
    tr, ev = gait_run[2].truth, gait_run[2].events
    i0, i1 = np.searchsorted(tr.t, [ev.t_ic[1] - 0.05, ev.t_ic[2] + 0.05])
    dt = tr.t[1] - tr.t[0]
    _, _, p = integrate_increments(tr.quat[i0], tr.vel[i0], tr.pos[i0], tr.dv[i0:i1], tr.dth[i0:i1], dt)
    assert np.linalg.norm(p - tr.pos[i1]) < 1e-4  # float64 round-off of ~1500 steps; a wrong increment is cm


def test_the_labelled_stance_is_the_foot_flat_of_a_walk_and_the_contact_of_a_run(gait_run):
    """The truth's stance label covers [t_ff, t_ho) of a walk (nearly still there) and the whole ground contact
    [t_ic, t_to) of a run (meta.json says which); events.csv's displacement over each labelled stance equals the
    integral of MuJoCo's velocity of the IMU site over it, and the sampled track moves by it."""
    from scipy.integrate import simpson

    name, scen, rec = gait_run
    tr, ev = rec.truth, rec.events
    running = name.startswith("run")
    start, end = (ev.t_ic, ev.t_to) if running else (ev.t_ff, ev.t_ho)
    assert rec.meta["stance_label"].startswith("ground contact" if running else "foot flat")
    inside = np.zeros(tr.t.size, bool)
    for a, b in zip(start, end):
        inside |= (tr.t >= a) & (tr.t < b)
    inside[tr.t >= start[-1]] = True
    np.testing.assert_array_equal(tr.stance, inside)
    speed = np.linalg.norm(tr.vel[tr.stance], axis=1).max()
    if not running:
        assert speed < 0.1, name  # a walking foot flat is (almost) still
    foot = FootModel(scen.mount)
    traj = FootTrajectory(scen.walk, plan_stances(scen.walk, run_generators(scen.seed)[0]), foot.toe_length)
    for k in (1, len(ev.t_ic) // 2):
        t = np.linspace(start[k], end[k], 8001)
        j = traj.joints(t)
        integral = simpson(foot.sample(j[:, 0].T, j[:, 1].T, j[:, 2].T).vel, x=t, axis=0)
        np.testing.assert_allclose(ev.stance_displacement[k], integral, atol=1e-8)
        i0, i1 = np.searchsorted(tr.t, [start[k], end[k]])
        assert np.linalg.norm(tr.pos[i1] - tr.pos[i0] - ev.stance_displacement[k]) < 2 * speed / scen.rate_hz + 1e-9


@pytest.mark.parametrize("name", ["walk-130", "run-rearfoot-180", "run-forefoot-150"])
def test_kinds_keep_their_published_timing(name):
    """Walking has more stance than swing, running a flight phase (stance < 50 %), and running contact is short."""
    scen = gait_walk(GAITS[name])
    g = scen.walk.gait
    stance = g.heel_rocker_frac + g.foot_flat_frac + g.push_off_frac
    contact_s = stance * g.cycle_s
    if name.startswith("walk"):
        assert stance > 0.5
    else:
        assert 0.3 < stance < 0.45 and 0.15 < contact_s < 0.35


RUN_PEAK_MISS = pytest.mark.xfail(strict=True, reason=(
    "known miss: with the swing turning back at its pitch maximum (95-109 deg) both running strikes peak at their "
    "toe-off rate, 1000-1040 deg/s, below the published ~1500; the rearfoot's 1335-1374 came from a sole-up "
    "swing sweeping ~185 deg back (gaitsim.world.gaits). The ~1500 is unconfirmed: the measured running feet found "
    "(RBDS markers at 2.5-4.5 m/s, gaitsim.world.gaits) peak at 620-830 deg/s"))


@pytest.mark.parametrize("kind, cadence, published", [
    ("walk", 103.0, "walk"),
    pytest.param("run-rearfoot", 150.0, "run", marks=RUN_PEAK_MISS),
    pytest.param("run-rearfoot", 180.0, "run", marks=RUN_PEAK_MISS),
    pytest.param("run-forefoot", 165.0, "run", marks=RUN_PEAK_MISS)])
def test_peaks_are_within_20_percent_of_published_foot_imu_measurements(kind, cadence, published):
    rec = simulate_walk(gait_walk({"kind": kind, "cadence_steps_per_min": cadence}, length_m=30.0))
    accel_g = np.linalg.norm(rec.truth.acc, axis=1).max() / G
    gyro_dps = np.degrees(np.linalg.norm(rec.truth.gyr, axis=1).max())
    peaks = PUBLISHED_PEAKS[published]
    low, high = peaks["accel_g"]
    assert 0.8 * low <= accel_g <= 1.2 * high, accel_g
    low, high = peaks["gyro_dps"]
    assert 0.8 * low <= gyro_dps <= 1.2 * high, gyro_dps


SOLE_UP_DEG = 135.0  # pitch past which the sole faces more up than back (90 deg: toes straight down, sole back)


@pytest.mark.parametrize("kind", ["run-rearfoot", "run-forefoot"])
@pytest.mark.parametrize("cadence", [150.0, 165.0, 180.0])
def test_a_running_foot_stops_turning_at_its_swing_maximum_and_never_turns_sole_up(kind, cadence):
    """After toe off the running foot turns toes down until the deceleration of the walking recordings' reversal
    stops it (gaitsim.world.gaits), then back: no swing pitch exceeds that maximum, none reaches sole-up. (The
    swing without the knot rose to 164-185 deg, toes pointing backward, sole up.)"""
    scen = gait_walk({"kind": kind, "cadence_steps_per_min": cadence}, length_m=30.0)
    plan = plan_stances(scen.walk, run_generators(0)[0])
    traj = FootTrajectory(scen.walk, plan, 0.2)
    t_max, pitch_max = swing_maximum(plan, scen.walk.gait)
    assert t_max.size == plan.n_strides
    for k in range(plan.n_strides):
        pitch = traj.pitch.stack(np.linspace(plan.t_to[k], plan.t_ic[k + 1], 4000))[0]
        assert pitch.max() <= pitch_max[k] + 1e-9
    assert np.degrees(pitch_max).max() < SOLE_UP_DEG


@pytest.mark.parametrize("cadence", [60.0, 103.0, 130.0])
def test_the_walking_reversal_puts_the_swing_maximum_where_the_running_knot_does(cadence):
    """The walking kinds turn back after toe off by the reversal measured on the shared recordings (their toe-off
    pitch acceleration); their swing maximum then lies where swing_maximum puts the running knot: the toe-off
    rate stopped by a steady deceleration at that reversal."""
    scen = gait_walk({"kind": "walk", "cadence_steps_per_min": cadence}, length_m=20.0)
    gait = scen.walk.gait
    plan = plan_stances(scen.walk, run_generators(0)[0])
    traj = FootTrajectory(scen.walk, plan, 0.2)
    t_max, pitch_max = swing_maximum(plan, dataclasses.replace(gait, pitch_accel_to_swing_max=gait.pitch_accel_toe_off))
    for k in range(1, plan.n_strides):
        t = np.linspace(plan.t_to[k], plan.t_ic[k + 1], 20001)
        pitch = traj.pitch.stack(t)[0]
        i = pitch.argmax()
        assert abs(t[i] - t_max[k]) < 1e-3  # s, of a 23-50 ms rise
        assert abs(pitch[i] - pitch_max[k]) < np.radians(0.05)  # of a 2.7 deg rise


@pytest.mark.parametrize("name", ["walk-60", "run-rearfoot-150", "run-forefoot-150", "run-rearfoot-180"])
def test_push_off_pitch_rises_from_level(name):
    """From heel off to toe off the toes stay down: a pitch below level would put the heel under the ground
    (the running reversal that once did so at 150 steps/min)."""
    gait = GAITS.get(name) or {"kind": "run-rearfoot", "cadence_steps_per_min": 150.0}
    scen = gait_walk(gait, length_m=20.0)
    plan = plan_stances(scen.walk, run_generators(0)[0])
    traj = FootTrajectory(scen.walk, plan, 0.2)
    for k in range(1, plan.n_strides):
        pitch = traj.pitch.stack(np.linspace(plan.t_ho[k], plan.t_to[k], 400))[0]
        assert pitch.min() > 0.0


def test_forefoot_strike_turns_about_the_still_toe_contact():
    """While the toes are down by more than half the sole's transfer pitch, the toe contact is the contact:
    it stays put while the heel comes down; below that the foot rolls onto its sole."""
    scen = gait_walk(GAITS["run-forefoot-150"], micromotion={"enabled": False})
    plan = plan_stances(scen.walk, run_generators(0)[0])
    foot = FootModel(Mount(), G)
    traj = FootTrajectory(scen.walk, plan, foot.toe_length)
    toe = np.array([foot.toe_length, 0.0, 0.0])
    half_transfer = 0.5 * scen.walk.micro.contact_transfer_pitch
    for k in range(1, plan.n_strides):
        t = np.linspace(plan.t_ic[k] + scen.walk.impact.heel_strike_duration_s, plan.t_ff[k], 200)
        t = t[traj.pitch.stack(t)[0] >= half_transfer]
        assert t.size > 20
        moved = traj.point(t, toe) - traj.point(t[:1], toe)
        assert np.abs(moved).max() < 1e-9  # the toe contact stays put while the heel comes down
        heel = traj.point(np.array([plan.t_ic[k], plan.t_ff[k]]), np.zeros(3))
        assert heel[0, 2] - heel[1, 2] > 0.02  # the heel starts in the air and lands at foot flat


def test_stops_stand_exactly_still_for_their_duration():
    scen = gait_walk(GAITS["stop-and-go"], length_m=12.0)
    plan = plan_stances(scen.walk, run_generators(0)[0])
    stops = np.flatnonzero(~plan.walking[1:-1]) + 1
    assert list(stops) == list(range(2, plan.n_strides, 2))
    flat = plan.t_ho - plan.t_ff
    np.testing.assert_allclose(flat[stops] - np.median(flat[plan.walking]), 1.5, atol=0.05)
    rec = simulate_walk(scen)
    for k in stops:
        inside = (rec.truth.t > rec.events.t_ff[k]) & (rec.truth.t < rec.events.t_ho[k])
        assert np.abs(rec.truth.vel[inside]).max() < 1e-12
        np.testing.assert_allclose(rec.events.stance_displacement[k], 0.0, atol=1e-12)


@pytest.mark.parametrize("gait, fragment", [
    ({"kind": "jog"}, "kind = 'jog' is not allowed; allowed: custom, walk, run-rearfoot, run-forefoot"),
    ({"kind": "walk", "cadence_steps_per_min": 150.0}, "cadence_steps_per_min = 150.0 is not allowed with kind = 'walk'"),
    ({"kind": "run-forefoot", "pitch_heel_strike_deg": -10.0}, "pitch_heel_strike_deg = -10.0"),
    ({"forefoot_strike": True}, "lands toes down"),
    ({"kind": "run-rearfoot", "pitch_accel_to_swing_max_dps2": -1000.0}, "pitch_accel_to_swing_max_dps2 = -1000.0"),
    ({"labelled_stance": "midstance"}, "labelled_stance = 'midstance' is not allowed; allowed: 'foot_flat', 'contact'"),
])
def test_bad_gait_kind_keys_are_refused_by_name(gait, fragment):
    with pytest.raises(ScenarioError, match="test \\[gait\\]") as err:
        gait_walk(gait)
    assert fragment in str(err.value)


def test_written_keys_override_the_kind_and_the_paper_walk_is_unchanged():
    walk = gait_walk({"kind": "walk", "cadence_steps_per_min": 100.0, "stride_length_m": 1.2}).walk.gait
    assert walk.stride_length_m == 1.2 and walk.swing_frac > 0.38
    assert gait_walk({}).walk.gait == gait_walk({"kind": "custom"}).walk.gait


@pytest.mark.parametrize("kind", ["run-rearfoot", "run-forefoot"])
def test_a_running_foot_is_never_still_and_the_default_detector_still_finds_its_stances(kind):
    """Running stance keeps turning (heel rise and roll through the short foot flat): the foot flat's calmest rate
    lies above the fixed SHOE's ~17 deg/s gate in most strides, so that test misses most contacts, as on tracked
    real runs; nav's default (the anchored SHOE) finds at least 98 % of them with none merged."""
    from nav.metrics import stance_match
    from nav.pipeline import NavOptions, run

    scen = gait_walk({"kind": kind, "cadence_steps_per_min": 165.0}, length_m=60.0, sampling={"rate_hz": 200.0})
    rec = simulate_walk(scen)
    stance = rec.truth.stance  # the ground contact of a run
    ev = rec.events
    bounds = np.searchsorted(rec.t, np.column_stack([ev.t_ff, ev.t_ho]))[1:-1]  # foot flats, not the rests
    rate = np.degrees(np.linalg.norm(rec.gyr, axis=1))
    calmest = np.array([rate[a:b].min() for a, b in bounds])
    assert 17.0 < np.median(calmest) < 94.0  # deg/s: between the fixed gate and pyshoe's running gate
    fixed = stance_match(run(rec, NavOptions(detector="shoe"))[0].stationary, stance)
    default = stance_match(run(rec, NavOptions())[0].stationary, stance)
    assert fixed["found"] < 0.5 * fixed["true_stances"]
    assert default["found"] >= 0.98 * default["true_stances"] and default["merged"] == 0
