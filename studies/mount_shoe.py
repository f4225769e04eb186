"""Why a twin's foot flat is or is not marked at 1e4: the SHOE statistic's two terms inside the foot flats of a
recording and of the stance twin with and without the mount turn (studies.mount_turn).

``python3 -m studies.mount_shoe``: per recording and twin, the share of foot-flat samples (u in 0.1..0.9) whose
statistic is below each threshold 1e4..5e4, and the median over those samples of the gyro term (|w|^2 mean / sigma_g^2), the
accelerometer term, and of |w| (deg/s) with its 10/90 % quantiles; the per-stride rms of each gyro axis about
its linear trend over the core (u 0.2..0.8), median over strides, of the raw gyro and of the gyro low-passed
20 Hz (zero phase).
"""

from __future__ import annotations

import warnings

import numpy as np

from nav import detectors
from gaitsim.measured import mocap
from gaitsim.scenario import scenario_from_dict
from gaitsim.simulate import sense, simulate_world
from gaitsim.stance.command import SENSORS, SITES, load_recordings
from gaitsim.stance.sweep import SIGMA_A, SIGMA_G, THRESHOLDS, WINDOW
from gaitsim.stance.twin import TWIN_SEED, TwinSpec, match_timing, measure_gait

from .mount_rate import foot_flats, gaitmap_rates
from .mount_turn import DATA, variants


def _core_wiggle(t: np.ndarray, gyr: np.ndarray, flats: np.ndarray) -> list:
    """deg/s: per stride the rms of each gyro axis about its linear trend over the core (u 0.2..0.8), median over
    strides."""
    wiggle = []
    for t_ff, t_ho in flats:
        d = t_ho - t_ff
        sel = (t >= t_ff + 0.2 * d) & (t <= t_ff + 0.8 * d)
        fit = np.polynomial.polynomial.polyfit(t[sel] - t_ff, gyr[sel], 1)
        wiggle.append(np.sqrt(np.mean((gyr[sel] - np.polynomial.polynomial.polyval(t[sel] - t_ff, fit).T) ** 2, 0)))
    return np.degrees(np.median(wiggle, axis=0)).round(2).tolist()


def shoe_terms(rec) -> dict:
    """The SHOE statistic's terms inside the foot flats of ``rec`` (module docstring)."""
    t = np.asarray(rec.t, float)
    acc_only = detectors.statistic("shoe", rec.acc, 0 * rec.gyr, SIGMA_A, SIGMA_G, WINDOW)
    total = detectors.statistic("shoe", rec.acc, rec.gyr, SIGMA_A, SIGMA_G, WINDOW)
    inside = np.zeros(len(total), bool)
    for t_ff, t_ho in foot_flats(rec):
        d = t_ho - t_ff
        inside |= (t[:len(total)] >= t_ff + 0.1 * d) & (t[:len(total)] < t_ho - 0.1 * d)
    w = np.degrees(np.linalg.norm(rec.gyr[:len(total)], axis=1))[inside]
    rate_hz = 1.0 / np.median(np.diff(t))
    wiggle = {name: _core_wiggle(t, gyr, foot_flats(rec)) for name, gyr in
              (("core_wiggle_rms_dps", rec.gyr), ("core_wiggle_rms_below_20hz_dps", mocap.lowpass(rec.gyr, 20.0, rate_hz)))}
    return {"below": [round(float(np.mean(total[inside] < th)), 3) for th in THRESHOLDS], "gyro_term": float(np.median((total - acc_only)[inside])),
            "acc_term": float(np.median(acc_only[inside])), "acc_term_p90": float(np.quantile(acc_only[inside], 0.9)),
            "w_p10_50_90": np.quantile(w, [0.1, 0.5, 0.9]).round(1).tolist(),
            **wiggle}


if __name__ == "__main__":
    for dataset in ("gaitmap-healthy", "ucr-fgo"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            recs = load_recordings(dataset, DATA)
            rates = gaitmap_rates() if dataset == "gaitmap-healthy" else {}
        for label, rec in recs:
            print(dataset, label, "real", shoe_terms(rec))
            gait = measure_gait(rec, rec.reference.t, rec.reference.pos)
            doc = match_timing(gait, TwinSpec(mount=SITES[dataset][0], micromotion={"foot": label},
                                              sensor=SENSORS[dataset]))
            scenario = scenario_from_dict(doc, "<stance twin>")
            truth, events, meta = simulate_world(scenario, TWIN_SEED)
            turns = variants(dataset, label, rec, rates) if dataset == "gaitmap-healthy" else {}
            for name, turn in {"committed": lambda truth, events, context: (truth, None), **turns}.items():
                turned, _ = turn(truth, events, {})
                print(dataset, label, name, shoe_terms(sense(turned, events, meta, scenario.sensor, TWIN_SEED)))
