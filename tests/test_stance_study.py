"""The stance study (gaitsim.stance): detected stances and gait events, the threshold sweep's definitions on
simulated walks with known truth, the acceptance comparison, and the committed results still reproduced."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from gaitsim.scenario import scenario_from_dict
from gaitsim.stance import command, sweep as sweeps, twin as twins
from gaitsim.stance.events import MERGE_GAP_S, RATE_EVENT, gait_events, group_stances
from gaitsim.simulate import simulate_walk
from nav import detectors

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
STILL = {"heel_rise_rate_start_dps": 0.0, "heel_rise_growth_dps3": 0.0, "loading_roll_rate_dps": 0.0,
         "pronation_rate_dps": 0.0, "stance_rate_sd_frac": 0.0}


def walk(micromotion=None, strides=6, rate=204.8):
    doc = {"path": {"kind": "straight", "length_m": 1.3 * strides}, "gait": {"stride_length_m": 1.3},
           "sampling": {"rate_hz": rate}, "micromotion": micromotion or {}}
    return simulate_walk(scenario_from_dict(doc, "test"), seed=3)


@pytest.fixture(scope="module")
def default_walk():
    return walk()


def test_runs_closer_than_the_merge_gap_are_one_stance():
    t = np.arange(200) * 0.01
    flags = np.zeros(200, bool)
    flags[10:20] = flags[20 + int(MERGE_GAP_S / 0.01) - 2:40] = True  # gap shorter than the merge gap
    flags[100:120] = True  # far away: a stance of its own
    stances = group_stances(t, flags)
    assert stances.bounds.tolist() == [[10, 40], [100, 120]]
    assert stances.detected_samples().tolist() == [10 + 40 - (20 + int(MERGE_GAP_S / 0.01) - 2), 20]


def test_gait_events_sit_on_the_sagittal_rate_crossings(default_walk):
    rec = default_walk
    stationary = detectors.detect("shoe", rec.t, rec.acc, rec.gyr, 5e4, sweeps.SIGMA_A, sweeps.SIGMA_G,
                                  sweeps.WINDOW).stationary
    stances = group_stances(rec.t, stationary)
    ev = gait_events(rec.gyr, stances)
    ok = np.flatnonzero(ev.complete())
    assert len(ok) >= len(rec.events.t_ic) - 3
    rate = rec.gyr[:, 1]
    for k in ok:
        assert rate[ev.ic[k] - 1] < 0 <= rate[ev.ic[k]] and rate[ev.to[k]] >= 0 > rate[ev.to[k] + 1]
        assert rate[ev.ff[k] - 1] >= RATE_EVENT > rate[ev.ff[k]] and rate[ev.ho[k] - 1] < RATE_EVENT <= rate[ev.ho[k]]
        # forefoot contact and heel off lie within 30 / 60 ms of the simulator's foot flat and heel off
        j = int(np.argmin(np.abs(rec.events.t_ff - rec.t[ev.ff[k]])))
        assert -0.03 < rec.t[ev.ff[k]] - rec.events.t_ff[j] <= 0.0
        assert 0.0 <= rec.t[ev.ho[k]] - rec.events.t_ho[j] < 0.06


def test_windows_widen_and_the_site_speeds_up_with_the_threshold(default_walk):
    """The rolling foot's law: a higher threshold admits faster samples at the window edges, where the heel
    rise is faster, so the mean in-window velocity grows with the window."""
    rec = default_walk
    stats = []
    for threshold in sweeps.THRESHOLDS:
        flags = detectors.detect("shoe", rec.t, rec.acc, rec.gyr, threshold, sweeps.SIGMA_A, sweeps.SIGMA_G,
                                 sweeps.WINDOW).stationary
        w = sweeps.windows(rec.t, flags, rec.truth.t, rec.truth.pos)
        stats.append((w.window[w.walking].mean(), w.displacement[w.walking].sum() / w.duration[w.walking].sum()))
    stats = np.array(stats)
    assert np.all(np.diff(stats[:, 0]) > 0)
    assert stats[-1, 1] > 1.05 * stats[0, 1] and 0.0 < stats[0, 1] < 0.01


def test_in_window_velocity_of_a_creeping_still_foot_is_its_creep():
    creep = 0.005
    rec = walk({**STILL, "creep_velocity_mps": [creep, 0.0, 0.0]})
    w = sweeps.windows(rec.t, detectors.detect("shoe", rec.t, rec.acc, rec.gyr, 3e4, sweeps.SIGMA_A, sweeps.SIGMA_G,
                                               sweeps.WINDOW).stationary, rec.truth.t, rec.truth.pos)
    v = w.displacement[w.walking].sum() / w.duration[w.walking].sum()
    assert v == pytest.approx(creep, rel=0.05)  # the windows' edges reach into the slap and push-off a little


def test_with_the_true_in_window_velocity_an_ideal_sensor_loses_nothing(default_walk):
    rec = default_walk
    r, = sweeps.run_thresholds(rec, rec.truth.t, rec.truth.pos, [3e4])
    assert r.underestimate_pct() > 0.05  # the foot's motion in the windows shortens the track ...
    # ... and only that: the run-mean pseudo-velocity removes most of it (what is left is the velocity's
    # variation inside each run)
    assert abs(r.underestimate_pct(track_pseudo=True)) < 0.25 * r.underestimate_pct()


def test_bootstrap_curves_are_deterministic_and_bounded(default_walk):
    rec = default_walk
    a = sweeps.sweep(rec, rec.truth.t, rec.truth.pos, thresholds=(1e4, 5e4), bootstrap=40)
    b = sweeps.sweep(rec, rec.truth.t, rec.truth.pos, thresholds=(1e4, 5e4), bootstrap=40)
    assert json.dumps(a.as_dict()) == json.dumps(b.as_dict())
    c = a.curves["underestimate_pct"]
    assert np.all(c.sd > 0) and c.slope == pytest.approx(c.value[-1] - c.value[0])


def test_comparison_takes_the_real_uncertainty_as_the_bound_where_it_is_larger():
    curve = lambda v, sd: sweeps.Curve(np.array(v), np.array(sd), v[-1] - v[0], 0.05, float(np.mean(v)), 0.05)  # noqa: E731
    real = sweeps.Sweep(np.array([1e4, 5e4]), {"underestimate_pct": curve([1.0, 1.4], [0.1, 0.5]),
                                               "in_window_velocity_mps": curve([0.002, 0.004], [0.001, 0.001]),
                                               "window_s": curve([0.2, 0.3], [0.01, 0.1])}, 10)
    twin = sweeps.Sweep(np.array([1e4, 5e4]), {"underestimate_pct": curve([1.3, 1.8], [0.0, 0.0]),
                                               "in_window_velocity_mps": curve([0.006, 0.004], [0.0, 0.0]),
                                               "window_s": curve([0.2, 0.39], [0.0, 0.0])}, 10)
    out = command.compare(real, twin)
    assert [r["within"] for r in out["underestimate_pct"]] == [False, True]
    assert out["underestimate_pct"][1]["bound_is_real_sd"] and out["underestimate_pct"][1]["bound"] == 0.5
    assert [r["within"] for r in out["in_window_velocity_mps"]] == [False, True]
    assert [r["within"] for r in out["window_s"]] == [True, True]  # 0.39 vs 0.3: the 0.1 s sd is the bound
    assert out["slope"]["within"] and out["slope"]["same_sign"]


@pytest.mark.skipif(not (DATA / "gaitmap-healthy").is_dir(), reason="shared gaitmap data not found")
def test_committed_results_still_match_a_small_run():
    """gaitmap's left foot re-run in part (the smallest and largest threshold, few bootstrap draws): the measured
    gait, the twin's scenario and the real curves equal the committed ones."""
    committed = json.loads((ROOT / "results/stance/gaitmap-healthy/left/fig5.json").read_text())
    label, rec = command.load_recordings("gaitmap-healthy", DATA)[0]
    site, _ = command.SITES["gaitmap-healthy"]
    gait = twins.measure_gait(rec, rec.reference.t, rec.reference.pos)
    spec = twins.TwinSpec(mount=site, micromotion={"foot": label}, sensor=command.SENSORS["gaitmap-healthy"])
    assert json.loads(json.dumps(twins.match_timing(gait, spec))) == committed["twin_scenario"]
    real = sweeps.sweep(rec, rec.reference.t, rec.reference.pos, thresholds=(1e4, 5e4), bootstrap=10)
    for name in ("underestimate_pct", "in_window_velocity_mps", "window_s"):
        np.testing.assert_allclose(real.curves[name].value, np.array(committed["real"][name]["value"])[[0, -1]],
                                   rtol=1e-6, atol=1e-9)
    assert math.isclose(gait.stride_period_s, committed["gait"]["stride_period_s"], rel_tol=1e-9)
