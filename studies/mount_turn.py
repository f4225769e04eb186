"""Steps 2-3 of the mount-yaw study: the stance study's twin of a recording with its sensor turning on the foot.

The twin is exactly the one ``gaitsim stance`` compares (:func:`gaitsim.stance.command.study_recording`: the
recording's gait, rate, site and sensor class, seeded). Its sensor frame is then rotated relative to the foot
about a fixed axis ``a`` (sensor frame) by the angle theta(t) (:func:`mount_angle`): the rate ``w_m`` held over
each labelled foot flat [t_ff, t_ho), ramped in over the heel rocker and out over the push-off (smoothstep), and
theta returned to zero over the following swing (rate -Theta 2 sin^2(pi u) / T_swing). theta is C2, periodic
per stride; the sensor's position is unchanged (it turns about its own centre). With C = R(a, theta):

    gyro  = C^T w_foot + theta' a        accelerometer = C^T f_foot        attitude = q_foot (x) q(a, theta)

The sensor model (BMI160 class) is then applied with the twin's sensor seed, and the result swept with
:func:`gaitsim.stance.sweep.sweep` against the twin's true site track, exactly like the committed twin.

Variants (:func:`variants`): ``committed`` (no turn), on gaitmap the out-of-foot rate of
:func:`studies.mount_rate.gaitmap_rates` as measured (``full``: the median vector over strides; ``z``: its z
component; ``full_strides`` / ``z_strides``: each stride's own core mean, twin stride k taking real stride k mod K;
``z_signal``: the real sensor's z rate itself, less the Vicon foot's median core z, stride by stride at the same
foot-flat phase, :func:`signal_turn_truth`, over the core u 0.1..0.9; ``z_signal_flat``: the same over u
0.025..0.975, into the loading tail, where the Vicon's own z is larger than its core median); on ucr-fgo, which has no pose, ``z_gap``: the core z rate the real
sensor reads and the committed twin's does not.

Run from the repository root: ``python3 -m studies.mount_turn OUT.json [DATASET]`` (default gaitmap-healthy);
``python3 -m studies.mount_table OUT.json`` prints the tables.
"""

from __future__ import annotations

import dataclasses
import json
import sys
import warnings

import numpy as np

from nav import pipeline, quaternion as quat
from gaitsim.scenario import scenario_from_dict
from gaitsim.simulate import sense, simulate_world
from gaitsim.stance.command import SENSORS, SITES, compare, load_recordings
from gaitsim.stance.profiles import foot_flat_profiles
from gaitsim.stance.sweep import nav_options, sweep
from gaitsim.stance.twin import TWIN_SEED, TwinSpec, match_timing, measure_gait

from .mount_rate import foot_flats, gaitmap_rates, summary as rate_summary

DATA = "../shared/data"
BOOTSTRAP = 400


def _smoothstep(x):
    return 3 * x**2 - 2 * x**3


def mount_angle(t: np.ndarray, events, rate: float) -> tuple[np.ndarray, np.ndarray]:
    """(theta (N,) rad, theta' (N,) rad/s) of the mount turn (module docstring) for every stance whose four
    events and the next initial contact are known; zero elsewhere."""
    theta, dtheta = np.zeros(len(t)), np.zeros(len(t))
    for k in range(len(events.t_ic) - 1):
        ic, ff, ho, to, ic_next = (events.t_ic[k], events.t_ff[k], events.t_ho[k], events.t_to[k],
                                   events.t_ic[k + 1])
        if not np.all(np.isfinite([ic, ff, ho, to, ic_next])) or not ic < ff < ho < to < ic_next:
            continue
        d1, d2, d3, dsw = ff - ic, ho - ff, to - ho, ic_next - to
        total = rate * (0.5 * d1 + d2 + 0.5 * d3)
        for lo, hi, fn in (
                (ic, ff, lambda x: (rate * d1 * (x**3 - x**4 / 2), rate * _smoothstep(x))),
                (ff, ho, lambda x: (rate * (0.5 * d1 + x * d2), np.full_like(x, rate))),
                (ho, to, lambda x: (rate * (0.5 * d1 + d2 + d3 * (x - x**3 + x**4 / 2)),
                                    rate * (1 - _smoothstep(x)))),
                (to, ic_next, lambda x: (total * (1 - x + np.sin(2 * np.pi * x) / (2 * np.pi)),
                                         -total * 2 * np.sin(np.pi * x) ** 2 / dsw))):
            sel = (t >= lo) & (t < hi)
            theta[sel], dtheta[sel] = fn((t[sel] - lo) / (hi - lo))
    return theta, dtheta


def apply_turn(truth, phi: np.ndarray, dphi: np.ndarray):
    """The truth with its sensor frame turned on the foot by the rotation vector ``phi`` (N, 3) rad (sensor frame,
    about an axis fixed within each stride, so its body rate is ``dphi`` (N, 3) rad/s); increments left out
    (NaN: the RK4 path does not read them)."""
    q_m = quat.from_rotvec(phi)
    c_t = np.swapaxes(quat.to_matrix(q_m), -1, -2)  # turned sensor <- untuned sensor
    return dataclasses.replace(
        truth, quat=quat.multiply(truth.quat, q_m), gyr=np.einsum("nij,nj->ni", c_t, truth.gyr) + dphi,
        acc=np.einsum("nij,nj->ni", c_t, truth.acc), dv=np.full_like(truth.dv, np.nan),
        dth=np.full_like(truth.dth, np.nan))


def turn_truth(truth, events, rate_vec: np.ndarray):
    """The truth with its sensor frame turned on the foot about ``rate_vec`` (rad/s, sensor frame) at its
    magnitude (module docstring), and theta (N,) rad. ``rate_vec`` (3,) holds for every stride; (K, 3) gives
    stride k (initial contact k to k+1) row k mod K."""
    rate_vec = np.atleast_2d(np.asarray(rate_vec, float))
    if not np.any(rate_vec):
        return truth, np.zeros(len(truth.t))
    unit_theta, unit_dtheta = mount_angle(truth.t, events, 1.0)
    stride = np.clip(np.searchsorted(events.t_ic, truth.t, side="right") - 1, 0, None)
    per_sample = rate_vec[stride % len(rate_vec)]
    phi = unit_theta[:, None] * per_sample  # rotation vector of the mount turn, sensor frame
    return apply_turn(truth, phi, unit_dtheta[:, None] * per_sample), np.linalg.norm(phi, axis=1)


def _core_window(u: np.ndarray, edge: float = 0.1) -> np.ndarray:
    """0 outside u in [edge, 1 - edge], smoothstep up over [edge, 2 edge] and down over [1 - 2 edge, 1 - edge],
    1 between."""
    return (_smoothstep(np.clip((u - edge) / edge, 0, 1))
            * (1 - _smoothstep(np.clip((u - 1 + 2 * edge) / edge, 0, 1))))


def swing_return(t: np.ndarray, to: float, ic_next: float, total: float) -> tuple[np.ndarray, np.ndarray]:
    """(swing mask (N,), rate over the swing (n,)): the rate that turns the angle ``total`` back over the swing
    [to, ic_next) s, -total 2 sin^2(pi u) / T_swing (in the unit of ``total`` per s)."""
    swing = (t >= to) & (t < ic_next)
    return swing, -total * 2 * np.sin(np.pi * (t[swing] - to) / (ic_next - to)) ** 2 / (ic_next - to)


def signal_turn_truth(truth, events, real_t: np.ndarray, real_rate: np.ndarray, real_flats: np.ndarray,
                      edge: float = 0.1):
    """The truth with its sensor turned about its z axis by a measured rate signal: twin stride k's foot flat
    takes real stride (k mod K)'s ``real_rate`` (N_r,) rad/s at the same foot-flat phase u (``real_flats`` (K, 2)
    s: FF and HO), weighted by :func:`_core_window` (``edge``); the angle so reached returns over the swing (rate
    -Theta 2 sin^2(pi u) / T_swing). theta is the trapezoid integral of that rate (it returns to within 0.03 deg
    of zero at the initial contacts); returns (truth, |theta| (N,) rad)."""
    t = truth.t
    rate = np.zeros(len(t))
    for k in range(len(events.t_ic) - 1):
        ic, ff, ho, to, ic_next = (events.t_ic[k], events.t_ff[k], events.t_ho[k], events.t_to[k],
                                   events.t_ic[k + 1])
        if not ic < ff < ho < to < ic_next:
            continue
        a, b = real_flats[k % len(real_flats)]
        flat = (t >= ff) & (t < ho)
        u = (t[flat] - ff) / (ho - ff)
        rate[flat] = _core_window(u, edge) * np.interp(a + u * (b - a), real_t, real_rate)
        fine = np.linspace(0, 1, 2001)
        total = (np.trapezoid(_core_window(fine, edge) * np.interp(a + fine * (b - a), real_t, real_rate), fine)
                 * (ho - ff))
        swing, back = swing_return(t, to, ic_next, total)
        rate[swing] = back
    theta = np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(t))])
    axis = np.array([0.0, 0.0, 1.0])
    return apply_turn(truth, theta[:, None] * axis, rate[:, None] * axis), np.abs(theta)


def heading_check(rec, threshold: float) -> dict:
    """Filter yaw minus the true sensor yaw (deg) at the true foot-flat middles (first, last, mean, sd), and
    the start-to-end underestimate (%) of the horizontal distance between the first and last of them."""
    sol = pipeline.navigate(rec, nav_options(threshold, method="rk4"))
    ev, tr = rec.events, rec.truth
    mids = 0.5 * (ev.t_ff + ev.t_ho)
    mids = mids[np.isfinite(mids) & (mids > sol.t[sol.start] + 0.5)]
    idx = np.searchsorted(sol.t, mids)
    yaw_est = quat.to_euler_zyx(sol.quat[idx])[0]
    yaw_true = quat.to_euler_zyx(tr.quat[idx])[0]
    err = np.degrees(np.angle(np.exp(1j * (yaw_est - yaw_true))))
    est_len = np.linalg.norm(sol.pos[idx[-1], :2] - sol.pos[idx[0], :2])
    true_len = np.linalg.norm(tr.pos[idx[-1], :2] - tr.pos[idx[0], :2])
    return {"yaw_error_first_deg": float(err[0]), "yaw_error_last_deg": float(err[-1]),
            "yaw_error_mean_deg": float(err.mean()), "yaw_error_sd_deg": float(err.std()),
            "start_to_end_underestimate_pct": float(100 * (1 - est_len / true_len))}


def study(dataset: str, label: str, rec, variants: dict) -> dict:
    """The real sweep and, per variant (name -> f(truth, events, context) -> (turned truth, |theta|)), the
    turned twin's sweep, comparison, profiles, core rates and heading check; ``context`` holds the real and the
    committed twin's core rates (deg/s), so "committed" (no turn) runs first."""
    site, _ = SITES[dataset]
    ref = rec.reference
    gait = measure_gait(rec, ref.t, ref.pos)
    doc = match_timing(gait, TwinSpec(mount=site, micromotion={"foot": label}, sensor=SENSORS[dataset]))
    scenario = scenario_from_dict(doc, "<stance twin>")
    truth, events, meta = simulate_world(scenario, TWIN_SEED)
    real = sweep(rec, ref.t, ref.pos, bootstrap=BOOTSTRAP)
    out = {"gait": gait.as_dict(), "real": real.as_dict(),
           "real_profile": foot_flat_profiles(rec, ref.t, ref.pos).as_dict(),
           "real_rates": rate_summary(np.asarray(rec.t), rec.gyr, foot_flats(rec)), "twins": {}}
    context = {"real_core_dps": out["real_rates"]["core_median_dps"]}
    for name, turn in {"committed": lambda truth, events, context: (truth, np.zeros(len(truth.t))),
                       **variants}.items():
        turned, theta = turn(truth, events, context)
        twin = sense(turned, events, meta, scenario.sensor, TWIN_SEED)
        flats = foot_flats(twin)
        tw = sweep(twin, twin.truth.t, twin.truth.pos, bootstrap=BOOTSTRAP, method="rk4")
        out["twins"][name] = {
            "mount_rate_core_dps": rate_summary(twin.t, turned.gyr - np.einsum(
                "nji,nj->ni", quat.to_matrix(quat.multiply(quat.conjugate(truth.quat), turned.quat)), truth.gyr),
                flats)["core_median_dps"],
            "max_mount_angle_deg": float(np.degrees(theta.max())),
            "mount_angle_at_contacts_deg": float(np.degrees(np.interp(events.t_ic, truth.t, theta).max())),
            "sweep": tw.as_dict(), "comparison": compare(real, tw),
            "profile": foot_flat_profiles(twin, twin.truth.t, twin.truth.pos).as_dict(),
            "rates": rate_summary(twin.t, twin.gyr, flats),
            "heading": {f"{th:.0e}": heading_check(twin, th) for th in (1e4, 5e4)}}
        if name == "committed":
            context["twin_core_dps"] = out["twins"][name]["rates"]["core_median_dps"]
        print(dataset, label, name, "done", file=sys.stderr)
    return out


def constant(rate_dps):
    """A turn at ``rate_dps`` (3,) deg/s every stride, or (K, 3) deg/s stride by stride (:func:`turn_truth`)."""
    return lambda truth, events, context: turn_truth(truth, events, np.radians(rate_dps))


def variants(dataset: str, label: str, rec, rates: dict) -> dict:
    """The turns studied on one recording (module docstring); ``rates``: :func:`studies.mount_rate.gaitmap_rates`."""
    if dataset != "gaitmap-healthy":
        return {"z_gap": lambda truth, events, context: turn_truth(
            truth, events, np.radians([0.0, 0.0, context["real_core_dps"][2] - context["twin_core_dps"][2]]))}
    strides = np.degrees(rates[label]["strides"]["out_of_foot"])
    full = np.median(strides, axis=0)
    vicon_z = np.median(rates[label]["strides"]["vicon_foot"][:, 2])
    return {"full": constant(full), "z": constant(full * [0, 0, 1]), "full_strides": constant(strides),
            "z_strides": constant(strides * [0, 0, 1]),
            "z_signal": lambda truth, events, context: signal_turn_truth(
                truth, events, np.asarray(rec.t), rec.gyr[:, 2] - vicon_z, foot_flats(rec)),
            "z_signal_flat": lambda truth, events, context: signal_turn_truth(
                truth, events, np.asarray(rec.t), rec.gyr[:, 2] - vicon_z, foot_flats(rec), edge=0.025)}


if __name__ == "__main__":
    dataset = sys.argv[2] if len(sys.argv) > 2 else "gaitmap-healthy"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        recs = load_recordings(dataset, DATA)
        rates = gaitmap_rates() if dataset == "gaitmap-healthy" else {}
    results = {f"{dataset}/{label}": study(dataset, label, rec, variants(dataset, label, rec, rates))
               for label, rec in recs}
    with open(sys.argv[1], "w") as fh:
        json.dump(results, fh, indent=1, default=float)
