"""Steps 2-3 of the wobble study: the stance study's twin with a synthetic foot-flat rate wobble.

The wobble is what :mod:`studies.wobble_spectrum` measures on the same recording, in the foot-flat frame (the
twin's sensor axes are its foot axes): per axis, Gaussian noise (seeded) shaped by the measured PSD shape
(:func:`shaped_noise`), times the measured rms envelope through the foot flat (ten phase bins, interpolated
between bin centres, held to the ends), times a taper that takes it to zero over the first and last ``EDGE`` of
each foot flat (smoothstep). The foot flats are the committed twin's detected ones, the recipe the envelope was
measured with on the recording (the twin's labelled heel off lies 34-59 ms before its detected one). The angle
reached over a foot flat returns over the following swing (:func:`studies.mount_turn.swing_return`, scaled so that
the trapezoid integral of the sampled rate, the angle the twin is turned by, is zero again at the swing's end).

Variants:

- ``committed``: no wobble;
- ``wobble_s1..3`` (noise seeds 1-3): a rotation of the sensor about its own centre
  (:func:`studies.mount_turn.apply_turn`: gyro = C^T w_foot + w_m, accelerometer = C^T f_foot, site unchanged);
- on gaitmap, ``wobble_s1_z``: seed 1 plus the measured constant out-of-foot z turn (:mod:`studies.mount_turn`'s
  ``z`` variant);
- on gaitmap, ``foot_wobble_s1``: seed 1 as a rotation of the foot about the contact the Vicon wobble gives
  (:func:`foot_wobble_truth`: the site moves by w x r).

``python3 -m studies.stance_wobble OUT.json [DATASET]`` from the repository root (default gaitmap-healthy) sweeps
them like :mod:`studies.mount_turn` (bootstrap 400); ``python3 -m studies.mount_table OUT.json`` prints the
tables. ``python3 -m studies.stance_wobble --shares [DATASET ...]`` prints a table: per recording and twin the
foot-flat shares below each gate, abs(w)'s 10/50/90 % quantiles, the SHOE statistic's accelerometer term (median,
90 % quantile) over the same samples, and the wobble re-measured by :mod:`studies.wobble_spectrum` (foot-frame
rms, the site velocity's rms, f50, f90).
"""

from __future__ import annotations

import dataclasses
import json
import sys
import warnings

import numpy as np

from nav import quaternion as quat
from gaitsim.scenario import scenario_from_dict
from gaitsim.simulate import sense, simulate_world
from gaitsim.stance.command import SENSORS, SITES, load_recordings
from gaitsim.stance.twin import TWIN_SEED, TwinSpec, match_timing, measure_gait

from .mount_rate import foot_flats, gaitmap_feet, gaitmap_rates
from .mount_shoe import shoe_terms
from .mount_turn import DATA, _smoothstep, apply_turn, study, swing_return, turn_truth
from .wobble_spectrum import BINS, measure, vicon_check

EDGE = 0.025  # share of the foot flat over which the wobble tapers to zero at each end
SEEDS = (1, 2, 3)


def shaped_noise(n: int, rate_hz: float, freq: np.ndarray, shape: np.ndarray, rng) -> np.ndarray:
    """(n, A) unit-variance Gaussian noise whose PSD follows ``shape`` (F, A) on ``freq`` (F,) Hz (zero beyond)."""
    white = np.fft.rfft(rng.standard_normal((n, shape.shape[1])), axis=0)
    f = np.fft.rfftfreq(n, 1.0 / rate_hz)
    gain = np.stack([np.sqrt(np.interp(f, freq, shape[:, i], right=0.0)) for i in range(shape.shape[1])], -1)
    noise = np.fft.irfft(white * gain, n, axis=0)
    return noise / noise.std(axis=0)


def envelope(u: np.ndarray, measured: dict) -> np.ndarray:
    """(n, 3) rad/s: the measured rms through the foot flat at phases ``u``, tapered to zero at both ends."""
    centres = 0.5 * (BINS[1:] + BINS[:-1])
    rms = np.radians(measured["envelope_dps"])
    taper = _smoothstep(np.clip(u / EDGE, 0, 1)) * _smoothstep(np.clip((1 - u) / EDGE, 0, 1))
    return np.stack([np.interp(u, centres, rms[:, i]) for i in range(3)], -1) * taper[:, None]


def wobble_rate(t: np.ndarray, events, flats: np.ndarray, measured: dict, seed: int) -> np.ndarray:
    """(N, 3) rad/s: the wobble over every foot flat ``flats`` (K, 2) s and its return over the swing from the
    next labelled toe off to the initial contact after it."""
    rate_hz = 1.0 / np.median(np.diff(t))
    noise = shaped_noise(len(t), rate_hz, np.asarray(measured["psd_freq_hz"]), np.asarray(measured["psd"]),
                         np.random.default_rng(seed))
    rate = np.zeros((len(t), 3))
    for ff, ho in flats:
        to = events.t_to[np.searchsorted(events.t_to, ho)]
        ic_next = events.t_ic[np.searchsorted(events.t_ic, to)]
        flat = (t >= ff) & (t < ho)
        rate[flat] = noise[flat] * envelope((t[flat] - ff) / (ho - ff), measured)
        swing, back = swing_return(t, to, ic_next, 1.0)
        end = np.flatnonzero(swing)[-1] + 2
        drift = np.trapezoid(rate[:end], t[:end], axis=0)  # the angle at the swing's end without a return
        rate[swing] = back[:, None]
        unit = drift - np.trapezoid(rate[:end], t[:end], axis=0)  # the sampled return's own integral
        rate[swing] = back[:, None] * drift / unit
    return rate


def wobble_angle(truth, events, flats: np.ndarray, measured: dict, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(rotation vector theta (N, 3) rad, its rate (N, 3) rad/s) of the wobble (:func:`wobble_rate`); theta is
    the trapezoid integral of the rate (small angles: the rate is the body rate to 0.5 |theta| |rate|)."""
    rate = wobble_rate(truth.t, events, flats, measured, seed)
    dt = np.diff(truth.t)[:, None]
    return np.concatenate([np.zeros((1, 3)), np.cumsum(0.5 * (rate[1:] + rate[:-1]) * dt, axis=0)]), rate


def wobble_truth(truth, events, flats: np.ndarray, measured: dict, seed: int):
    """The truth with its sensor wobbling about its own centre (module docstring); returns (truth, |theta|)."""
    theta, rate = wobble_angle(truth, events, flats, measured, seed)
    return apply_turn(truth, theta, rate), np.linalg.norm(theta, axis=1)


def foot_wobble_truth(truth, events, flats: np.ndarray, measured: dict, seed: int, lever: np.ndarray):
    """The truth with its foot (and the sensor on it) wobbling about a contact ``lever`` (3,) m behind the sensor
    point (foot frame, r = site - contact): the sensor frame turns as in :func:`wobble_truth` and the site moves
    by R_foot (R(theta) - I) r; its velocity and the extra specific force are the sampled derivatives
    (np.gradient) of that displacement. Returns (truth, |theta|)."""
    theta, rate = wobble_angle(truth, events, flats, measured, seed)
    turned = apply_turn(truth, theta, rate)
    shift = np.einsum("nij,nj->ni", quat.to_matrix(truth.quat),
                      np.einsum("nij,j->ni", quat.to_matrix(quat.from_rotvec(theta)), lever) - lever)
    velocity = np.gradient(shift, truth.t, axis=0)
    force = np.einsum("nji,nj->ni", quat.to_matrix(turned.quat), np.gradient(velocity, truth.t, axis=0))
    return dataclasses.replace(turned, pos=truth.pos + shift, vel=truth.vel + velocity,
                               acc=turned.acc + force), np.linalg.norm(theta, axis=1)


def committed_twin(dataset: str, label: str, rec):
    """The stance study's twin of ``rec``: (scenario, truth, events, meta, sensed twin recording)."""
    gait = measure_gait(rec, rec.reference.t, rec.reference.pos)
    doc = match_timing(gait, TwinSpec(mount=SITES[dataset][0], micromotion={"foot": label}, sensor=SENSORS[dataset]))
    scenario = scenario_from_dict(doc, "<stance twin>")
    truth, events, meta = simulate_world(scenario, TWIN_SEED)
    return scenario, truth, events, meta, sense(truth, events, meta, scenario.sensor, TWIN_SEED)


def variants(dataset: str, label: str, rec, rates: dict, levers: dict) -> dict:
    """The wobbled twins of one recording (module docstring); ``rates``: :func:`studies.mount_rate.gaitmap_rates`,
    ``levers``: side -> the measured contact lever (m, marker frame, :func:`studies.wobble_spectrum.contact_lever`)."""
    measured = measure(rec)["foot"]
    flats = foot_flats(committed_twin(dataset, label, rec)[-1])

    def wobbled(seed):
        return lambda truth, events, context: wobble_truth(truth, events, flats, measured, seed)

    out = {f"wobble_s{s}": wobbled(s) for s in SEEDS}
    if dataset == "gaitmap-healthy":
        z_rate = np.radians(np.median(np.degrees(rates[label]["strides"]["out_of_foot"]), axis=0) * [0, 0, 1])
        out["wobble_s1_z"] = lambda truth, events, context: turn_truth(
            wobble_truth(truth, events, flats, measured, SEEDS[0])[0], events, z_rate)
        out["foot_wobble_s1"] = lambda truth, events, context: foot_wobble_truth(
            truth, events, flats, measured, SEEDS[0], np.asarray(levers[label]))
    return out


def measured_levers() -> dict:
    """Gaitmap side -> the contact lever (m, marker frame) the Vicon wobble gives (:mod:`studies.wobble_spectrum`)."""
    return {side: vicon_check(side, rec, pose, t_mocap, markers)["contact"]["lever_marker_m"]
            for side, rec, pose, t_mocap, markers in gaitmap_feet()}


def shares(dataset: str) -> None:
    """Print, per recording and twin, a table row: the foot-flat shares (%) below each gate, abs(w)'s 10/50/90 %
    quantiles (deg/s), the SHOE accelerometer term's median and 90 % quantile, and the wobble re-measured
    (foot-frame rms deg/s, site-velocity rms mm/s, f50, f90 Hz)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        recs = load_recordings(dataset, DATA)
        rates = gaitmap_rates() if dataset == "gaitmap-healthy" else {}
        levers = measured_levers() if dataset == "gaitmap-healthy" else {}
    for label, rec in recs:
        scenario, truth, events, meta, _ = committed_twin(dataset, label, rec)
        twins = {"real": rec}
        for name, turn in {"committed": lambda truth, events, context: (truth, None),
                           **variants(dataset, label, rec, rates, levers)}.items():
            twins[name] = sense(turn(truth, events, {})[0], events, meta, scenario.sensor, TWIN_SEED)
        for name, r in twins.items():
            terms = shoe_terms(r)
            track = (r.reference.t, r.reference.pos) if name == "real" else (r.truth.t, r.truth.pos)
            m = measure(r, *track) if name != "real" or SITES[dataset][1] else measure(r)
            cells = ["/".join(f"{100 * b:.0f}" for b in terms["below"]),
                     "/".join(f"{q:.1f}" for q in terms["w_p10_50_90"]),
                     f"{terms['acc_term']:.0f}/{terms['acc_term_p90']:.0f}",
                     m["foot"]["rms_dps"], m.get("site_velocity_rms_mmps", "-"),
                     [round(f, 1) for f in m["foot"]["f50_hz"]], [round(f, 1) for f in m["foot"]["f90_hz"]]]
            print(f"| {dataset}/{label} | {name} | " + " | ".join(str(c) for c in cells) + " |")


if __name__ == "__main__":
    if sys.argv[1] == "--shares":
        print("| recording | twin | below gates 1e4..5e4 (%) | abs(w) p10/50/90 (deg/s) | SHOE accelerometer term "
              "median/p90 | wobble rms x/y/z (deg/s) "
              "| site velocity wobble (mm/s) | f50 (Hz) | f90 (Hz) |\n" + "|---" * 9 + "|")
        for ds in sys.argv[2:] or ("gaitmap-healthy", "ucr-fgo"):
            shares(ds)
        sys.exit(0)
    dataset = sys.argv[2] if len(sys.argv) > 2 else "gaitmap-healthy"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        recs = load_recordings(dataset, DATA)
        rates = gaitmap_rates() if dataset == "gaitmap-healthy" else {}
        levers = measured_levers() if dataset == "gaitmap-healthy" else {}
    results = {f"{dataset}/{label}": study(dataset, label, rec, variants(dataset, label, rec, rates, levers))
               for label, rec in recs}
    with open(sys.argv[1], "w") as fh:
        json.dump(results, fh, indent=1, default=float)
