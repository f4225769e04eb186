"""`gaitsim nav`: files, keys, numbers equal to the Python API, atomic output on failure."""

import json

import numpy as np
import pytest
from nav_synthetic import synthetic_walk

from gaitsim import cli
from nav import pipeline
from nav.ekf import FilterConfig
from nav.recording import Recording, read_recording, write_recording
from nav.solution import SOLUTION_COLUMNS, read_solution_csv


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    folder = tmp_path_factory.mktemp("rec") / "walk"
    rec = synthetic_walk(strides=3)
    write_recording(rec, folder)
    return folder, rec


def test_nav_writes_solution_and_score(recording, tmp_path):
    folder, rec = recording
    out = tmp_path / "nav"
    code = cli.main(["nav", str(folder), "--out", str(out), "--threshold", "3e4", "--sigma-a", "0.01",
                     "--sigma-g-dps", "0.1", "--window", "3", "--states", "15", "--rts"])
    assert code == 0
    score = json.loads((out / "score.json").read_text())
    for key in ("along_track_error_m", "perpendicular_error_m", "final_error_m", "length_ratio",
                "heading_drift_deg_per_s", "detector", "threshold", "sigma_a_m_s2", "sigma_g_rad_s",
                "window_samples", "fs_hz"):
        assert key in score, key
    assert score["threshold"] == 3e4 and score["sigma_g_rad_s"] == pytest.approx(np.radians(0.1))
    table = read_solution_csv(out / "solution.csv")
    assert table.shape[1] == len(SOLUTION_COLUMNS)
    options = pipeline.NavOptions(filter=FilterConfig(states=15), rts=True)
    sol, expected = pipeline.run(read_recording(folder), options)  # the folder as stored (truth to 1e-12)
    np.testing.assert_allclose(table[:, 1:4], sol.pos[sol.start:], rtol=0, atol=1e-12)
    assert score["along_track_error_m"] == pytest.approx(expected["along_track_error_m"], abs=1e-12)


def test_bad_recording_writes_nothing(recording, tmp_path, capsys):
    _, rec = recording
    acc = rec.acc.copy()
    acc[3, 0] = np.nan
    bad = tmp_path / "bad"
    write_recording(Recording(rec.t, acc, rec.gyr, {}), bad)
    out = tmp_path / "nav"
    assert cli.main(["nav", str(bad), "--out", str(out)]) == 2
    assert "NaN" in capsys.readouterr().err
    assert not out.exists() and list(tmp_path.glob(".nav*")) == []


def test_the_default_detector_and_its_settings_reach_the_score(recording, tmp_path):
    folder, _ = recording
    out = tmp_path / "nav"
    assert cli.main(["nav", str(folder), "--out", str(out), "--anchor-span", "0.4", "--anchor-widen", "3",
                     "--anchor-cap", "20", "--anchor-calm", "0.03"]) == 0
    info = json.loads((out / "score.json").read_text())["info"]["detector"]
    assert info["detector"] == "anchored"
    assert info["adaptation"] == {"half_span_s": 0.4, "widen": 3.0, "cap": 20.0, "calm_s": 0.03}
