"""Ground truth of a walk: plan the stances, build the C4 joint trajectories, evaluate the IMU site's kinematics.

The site's kinematics come from the rigid-body formulas of the MuJoCo foot model, for all samples at once, and
are checked against MuJoCo's own sensors (``mj_inverse``) on every ``CHECK_EVERY``-th sample and the samples at
every gait event.

The world knows nothing of sensors or scenario files: :mod:`gaitsim.simulate` turns a scenario into the inputs
of :func:`simulate_truth` and puts the sensor model on its output.
"""

from __future__ import annotations

import numpy as np

from nav import quaternion as quat
from nav.recording import Events, Truth

from .foot import FootModel, Mount
from .gait import StancePlan, Walk, plan_stances
from .profile import FootTrajectory

CHECK_EVERY = 100  # every how many samples the rigid-body kinematics are checked against MuJoCo's sensors


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


def within_intervals(t: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """(N,) bool: True where ``start[k] <= t < end[k]`` for some k (intervals sorted by start, not overlapping)."""
    idx = np.searchsorted(start, t, side="right") - 1
    ok = idx >= 0
    inside = np.zeros(t.size, bool)
    inside[ok] = t[ok] < end[idx[ok]]
    return inside


def stance_labels(t: np.ndarray, plan: StancePlan, labelled_stance: str) -> np.ndarray:
    """True where ``start <= t < end`` of some stance's labelled part (:meth:`StancePlan.labelled`; the last
    stance includes its end)."""
    start, end = plan.labelled(labelled_stance)
    inside = within_intervals(t, start, end)
    inside[t >= start[-1]] = True
    return inside


def check_rows(t: np.ndarray, plan: StancePlan) -> np.ndarray:
    """Sample rows on which the kinematics are checked against MuJoCo: every ``CHECK_EVERY``-th, the last,
    and those at or just after each gait event (heel strike, foot flat, heel off, toe off)."""
    events = np.concatenate([plan.t_ic, plan.t_ff, plan.t_ho, plan.t_to])
    at_events = np.minimum(np.searchsorted(t, events), t.size - 1)
    return np.unique(np.concatenate([np.arange(0, t.size, CHECK_EVERY), [t.size - 1], at_events]))


def simulate_truth(walk: Walk, mount: Mount, rate_hz: float, gravity: float,
                   gait_rng: np.random.Generator) -> tuple[Truth, Events]:
    """Truth and events of one walk sampled at ``rate_hz`` (Hz) under ``gravity`` (m/s^2), the IMU at ``mount``
    (its stride variability drawn from ``gait_rng``)."""
    foot = FootModel(mount, gravity)
    plan = plan_stances(walk, gait_rng)
    traj = FootTrajectory(walk, plan, foot.toe_length)
    n = int(np.floor(plan.t_end * rate_hz + 1e-9)) + 1
    t = np.arange(n) / rate_hz
    joints, displacement = traj.sample(t, foot.lever_arm)
    qpos, qvel, qacc = joints[:, 0].T, joints[:, 1].T, joints[:, 2].T
    s = foot.kinematics(qpos, qvel, qacc)
    foot.check(qpos, qvel, qacc, s, check_rows(t, plan))
    dv, dth = increments(t, s.vel, s.quat, gravity)
    truth = Truth(t=t, pos=s.pos, vel=s.vel, quat=s.quat, gyr=s.gyr, acc=s.acc, dv=dv, dth=dth,
                  stance=stance_labels(t, plan, walk.gait.labelled_stance))
    events = Events(t_ic=plan.t_ic, t_ff=plan.t_ff, t_ho=plan.t_ho, t_to=plan.t_to,
                    stance_displacement=displacement)
    return truth, events
