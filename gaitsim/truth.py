"""Ground truth of a walk: plan the stances, build the C4 joint trajectories, sample MuJoCo's IMU-site sensors.

>>> from gaitsim.scenario import load_scenario
>>> from gaitsim.truth import simulate_walk
>>> rec = simulate_walk(load_scenario("scenarios/straight_100m.toml"), seed=1)   # doctest: +SKIP

The returned :class:`nav.recording.Recording` carries the truth, the per-stance events, and the IMU output: the
ideal sensor (the truth itself) unless the scenario has a [sensor] section.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from nav import quaternion as quat
from nav.recording import Events, Recording, Truth

from . import __version__
from .foot import FootModel
from .gait import StancePlan, plan_stances
from .profile import FootTrajectory
from .scenario import Scenario


def run_generators(seed: int, run: int = 0) -> tuple[np.random.Generator, np.random.Generator]:
    """Independent generators (gait variability, sensor errors) of run ``run`` of a scenario seeded ``seed``.

    The walk of a run does not depend on the sensor model and vice versa, so experiments can vary one alone.
    """
    ss = np.random.SeedSequence(entropy=seed, spawn_key=(run,))
    gait_ss, sensor_ss = ss.spawn(2)
    return np.random.default_rng(gait_ss), np.random.default_rng(sensor_ss)


def increments(t: np.ndarray, vel: np.ndarray, q: np.ndarray, gravity: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact (sculling- and coning-exact) increments over [t_k, t_k+1]; the last row is zero.

    Returns
    -------
    dv : (N, 3) m/s, ``C_k^T (v_{k+1} - v_k - g dt)`` with g = (0, 0, -gravity).
    dth : (N, 3) rad, rotation vector of ``q_k^* ⊗ q_{k+1}``.
    """
    dt = np.diff(t)[:, None]
    g = np.array([0.0, 0.0, -gravity])
    dv = np.zeros_like(vel)
    dth = np.zeros_like(vel)
    dv[:-1] = quat.rotate(quat.conjugate(q[:-1]), vel[1:] - vel[:-1] - g * dt)
    dth[:-1] = quat.to_rotvec(quat.multiply(quat.conjugate(q[:-1]), q[1:]))
    return dv, dth


def stance_labels(t: np.ndarray, plan: StancePlan) -> np.ndarray:
    """True where ``t_ff <= t < t_ho`` of some stance (the last stance includes its end)."""
    idx = np.searchsorted(plan.t_ff, t, side="right") - 1
    ok = idx >= 0
    inside = np.zeros(t.size, bool)
    inside[ok] = t[ok] < plan.t_ho[idx[ok]]
    inside[t >= plan.t_ff[-1]] = True
    return inside


def simulate_truth(scenario: Scenario, gait_rng: np.random.Generator) -> tuple[Truth, Events, FootTrajectory]:
    """Truth and events of one walk of ``scenario`` (its stride variability drawn from ``gait_rng``)."""
    foot = FootModel(scenario.mount, scenario.gravity)
    plan = plan_stances(scenario.walk, gait_rng)
    traj = FootTrajectory(scenario.walk, plan, foot.toe_length)
    n = int(np.floor(plan.t_end * scenario.rate_hz + 1e-9)) + 1
    t = np.arange(n) / scenario.rate_hz
    joints = traj.joints(t)
    s = foot.sample(joints[:, 0].T, joints[:, 1].T, joints[:, 2].T)
    dv, dth = increments(t, s.vel, s.quat, scenario.gravity)
    truth = Truth(t=t, pos=s.pos, vel=s.vel, quat=s.quat, gyr=s.gyr, acc=s.acc, dv=dv, dth=dth,
                  stance=stance_labels(t, plan))
    events = Events(t_ic=plan.t_ic, t_ff=plan.t_ff, t_ho=plan.t_ho, t_to=plan.t_to,
                    stance_displacement=traj.stance_displacement(foot.lever_arm))
    return truth, events, traj


def describe(scenario: Scenario, seed: int, run: int) -> dict:
    """meta.json content of a simulated recording (the sensor part is added by the caller)."""
    w = scenario.walk
    return {
        "generator": f"gaitsim {__version__}",
        "scenario": scenario.name,
        "scenario_file": scenario.source,
        "seed": seed,
        "run": run,
        "frames": {
            "world": "ENU, z up, flat non-rotating earth",
            "body": "IMU sensor axes; with the default mount x toward the toes, y left, z up when the foot is flat",
            "quaternion": "(w, x, y, z), body to world",
        },
        "sampling": {"rate_hz": scenario.rate_hz, "gravity_mps2": scenario.gravity},
        "path": scenario.path_table,
        "gait": dataclasses.asdict(w.gait),
        "impact": dataclasses.asdict(w.impact),
        "micromotion": dataclasses.asdict(w.micro),
        "mount": dataclasses.asdict(scenario.mount),
        "stance_label": "foot flat: t_ff <= t < t_ho (events.csv)",
    }


def simulate_walk(scenario: Scenario, seed: int | None = None, run: int = 0) -> Recording:
    """One run of ``scenario``: truth, events and the sensor output, deterministic from (seed, run).

    Parameters
    ----------
    scenario : Scenario
    seed : base seed; default the scenario's.
    run : run index; each run draws its own stride variability and sensor errors.
    """
    seed = scenario.seed if seed is None else seed
    gait_rng, sensor_rng = run_generators(seed, run)
    truth, events, _ = simulate_truth(scenario, gait_rng)
    meta = describe(scenario, seed, run)
    if scenario.sensor is None:
        t, acc, gyr = truth.t.copy(), truth.acc.copy(), truth.gyr.copy()
        meta["sensor"] = {"name": "ideal", "withheld": False, "note": "imu.csv holds the exact truth (no sensor model)"}
    else:
        from .imu.model import apply_sensor

        t, acc, gyr = apply_sensor(scenario.sensor, truth.t, truth.acc, truth.gyr, sensor_rng)
        meta["sensor"] = scenario.sensor.declared()
    return Recording(t=t, acc=acc, gyr=gyr, meta=meta, truth=truth, events=events)
