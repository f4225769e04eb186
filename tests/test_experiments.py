"""The paper reproduction in quick mode: files, compensation laws, determinism, Dask equals local."""

import csv
import json

import numpy as np
import pytest

from gaitsim.experiments.reproduce import reproduce


def _table(path):
    with open(path) as fh:
        return {row["variant"]: {k: float(v) for k, v in row.items() if k != "variant"} for row in csv.DictReader(fh)}


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("quick")
    summary = reproduce(out, quick=True, workers=2, progress=False)
    return out, summary


def test_report_tables_and_figures_exist(quick):
    out, _ = quick
    table = _table(out / "compensation.csv")
    assert list(table) == ["before", "calibration", "stance_velocity", "both"]
    for name in ("fig2_3_velocity.png", "fig4_shoe.png", "fig5_length_vs_threshold.png", "fig6_heading.png",
                 "fig9_10_compensation.png", "README.md", "ablation.csv", "error_budget.csv", "sensitivity.csv",
                 "calibration.json"):
        assert (out / name).stat().st_size > 200, name


def test_each_compensation_step_removes_its_error(quick):
    _, s = quick
    comp = s["compensation"]
    drift = {v: abs(comp[v]["heading_drift_deg_per_s"]["mean"]) for v in comp}
    along = {v: comp[v]["along_track_error_m"]["mean"] for v in comp}
    # step 1 removes the g-sensitivity heading drift (paper's G_g: ~0.02-0.03 deg/s)
    assert drift["before"] > 0.01 and drift["calibration"] < 0.3 * drift["before"]
    # step 2 removes most of the stance-velocity length loss (the rolling foot's in-window motion loses ~0.25 %
    # of the 14 m quick walk)
    assert along["before"] > 0.02 and abs(along["stance_velocity"]) < 0.5 * along["before"]
    # on a 14 m quick walk the noise floor is a larger share than on 99.6 m (full run: 9x)
    assert comp["both"]["final_error_m"]["mean"] < 0.6 * comp["before"]["final_error_m"]["mean"]


def test_g_sensitivity_alone_drifts_at_the_g_times_f_rate(quick):
    _, s = quick
    assert 0.015 < abs(s["heading"]["heading_drift_deg_per_s"]) < 0.035  # paper 0.028 deg/s


def test_rerun_resumes_and_reproduces_identically(quick, tmp_path):
    out, s = quick
    again = reproduce(out, quick=True, workers=1, progress=False)  # all runs stored: nothing recomputed
    assert json.dumps(again["compensation"], sort_keys=True) == json.dumps(s["compensation"], sort_keys=True)


def test_dask_cluster_gives_identical_numbers(quick, tmp_path):
    distributed = pytest.importorskip("distributed")
    _, s = quick
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        dask = reproduce(tmp_path / "dask", quick=True, scheduler=cluster.scheduler_address, progress=False)
    assert json.dumps(dask["compensation"], sort_keys=True) == json.dumps(s["compensation"], sort_keys=True)
    assert dask["threshold_sweep"] == s["threshold_sweep"]


def test_fig5_rise_allows_a_fall_within_its_standard_error_only():
    from gaitsim.experiments.report import fig5_rises

    walks = np.random.default_rng(3).normal(0.0, 0.01, 10)
    rising = {1e4: walks + 0.50, 2e4: walks + 0.60, 3e4: walks + 0.70}
    assert fig5_rises(rising)
    flat = np.random.default_rng(4).normal(0.0, 0.01, 10)
    assert fig5_rises({**rising, 3e4: rising[2e4] + flat - flat.mean() - 0.5 * flat.std(ddof=1) / np.sqrt(10)})
    assert not fig5_rises({**rising, 3e4: walks + 0.55})  # a fall of 0.05 m on identical walks
