"""Fixtures for other implementations: a suite built, its manifest and determinism, and ``gaitsim score``.

Acceptance: a small independent ZUPT-aided EKF written here (OpenShoe-style SHOE detector, trapezoidal
mechanisation, 9-state error-state Kalman filter; nothing imported from ``nav`` but the file reader's contract)
navigates a fixture, writes a solution file, and ``gaitsim score`` passes it; the same solution made 10 % short
fails; without attitude the attitude heading drift is reported as not scored.
"""

import json
import math

import numpy as np
import pytest
from numpy.lib.stride_tricks import sliding_window_view

from gaitsim.cli import main
from gaitsim.fixtures.build import MANIFEST_FILE, build_suite
from gaitsim.fixtures.suite import suite_from_dict
from nav import storage
from nav.conformance import (REFERENCE_FOLDER, TOLERANCES_FILE, read_solution_file, write_solution_file)
from nav.recording import read_recording

SUITE = {
    "suite": {"name": "test-fixtures", "version": 1, "seed": 11, "monte_carlo_runs": 8, "tolerance_sigmas": 3.0,
              "floors": {"m": 0.001, "1": 0.0001, "deg/s": 0.0001}},
    "gait": {"stand_start_s": 1.5, "stand_end_s": 1.5},
    "walks": {"straight": {"kind": "straight", "length_m": 8.0, "yaw_deg": 30.0}},
    "sensors": {"ideal": {}, "vn200": {"preset": "vn200"}},
    "sampling": {"rates_hz": [200.0]},
}
FIXTURE = "straight-vn200-200hz"


@pytest.fixture(scope="module")
def suite_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("suite") / "fixtures"
    build_suite(suite_from_dict(SUITE, "test"), out, workers=1)
    return out


def test_manifest_lists_every_fixture_with_the_hashes_of_its_files(suite_dir):
    manifest = json.loads((suite_dir / MANIFEST_FILE).read_text())
    assert [f["name"] for f in manifest["fixtures"]] == ["straight-ideal-200hz", FIXTURE]
    for entry in manifest["fixtures"]:
        folder = suite_dir / entry["name"]
        on_disk = sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file())
        assert sorted(entry["files"]) == on_disk
        assert all(storage.sha256(folder / name) == digest for name, digest in entry["files"].items())
        tolerances = json.loads((folder / TOLERANCES_FILE).read_text())
        for name, metric in tolerances["metrics"].items():
            assert metric["monte_carlo_runs"] == 8
            assert metric["tolerance"] == pytest.approx(max(3.0 * metric["monte_carlo_std"], metric["floor"]))
    assert manifest["version"] == 1 and manifest["definition"] == SUITE


def test_a_rebuild_gives_the_same_bytes(suite_dir, tmp_path):
    again = build_suite(suite_from_dict(SUITE, "test"), tmp_path / "again", workers=1)
    first = json.loads((suite_dir / MANIFEST_FILE).read_text())
    assert [f["files"] for f in again["fixtures"]] == [f["files"] for f in first["fixtures"]]


def test_the_reference_solution_passes_its_fixture(suite_dir, tmp_path, capsys):
    folder = suite_dir / FIXTURE
    solution = next((folder / REFERENCE_FOLDER).glob("solution.*"))
    assert main(["score", str(solution), str(folder), "--json", str(tmp_path / "score.json")]) == 0
    doc = json.loads((tmp_path / "score.json").read_text())
    assert doc["passed"] and doc["has_attitude"] and doc["has_zupt"]
    assert all(m["status"] == "pass" for m in doc["metrics"].values())
    assert doc["difference_from_reference_solution"]["rms_horizontal_m"] < 1e-6  # stored to 1 um
    assert f"fixture {FIXTURE}: PASS" in capsys.readouterr().out


# ----- an independent implementation, written for this test ------------------------------------------------------

def skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rotation(phi):
    """Rotation matrix of a rotation vector (Rodrigues)."""
    angle = np.linalg.norm(phi)
    if angle < 1e-12:
        return np.eye(3) + skew(phi)
    k = skew(phi / angle)
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


def shoe_detector(acc, gyr, g, sigma_a=0.01, sigma_g=math.radians(0.1), window=3, gamma=3e4):
    """OpenShoe's SHOE test: a window is stationary when its statistic is below gamma; every sample of a
    stationary window is marked."""
    a = sliding_window_view(acc, window, axis=0)  # (n - W + 1, 3, W)
    w = sliding_window_view(gyr, window, axis=0)
    mean = a.mean(axis=2, keepdims=True)
    up = g * mean / np.linalg.norm(mean, axis=1, keepdims=True)
    statistic = (np.sum((a - up) ** 2, axis=(1, 2)) / sigma_a**2 + np.sum(w**2, axis=(1, 2)) / sigma_g**2) / window
    zupt = np.zeros(len(acc), bool)
    for k in np.flatnonzero(statistic < gamma):
        zupt[k:k + window] = True
    return zupt


def independent_ekf(t, acc, gyr, start, pos0, heading, g):
    """9-state error-state EKF (errors true - estimate in position, velocity and attitude, C_true = (I + [phi x])
    C_est), trapezoidal strapdown (mean rate over the interval, mean of the specific force rotated at both ends),
    ZUPT on every detected stationary sample. Returns (pos, quat, zupt) from ``start``."""
    zupt = shoe_detector(acc, gyr, g)
    f0 = acc[start:start + 20].mean(axis=0)
    roll, pitch = math.atan2(f0[1], f0[2]), math.atan2(-f0[0], math.hypot(f0[1], f0[2]))
    c = rotation([0, 0, heading]) @ rotation([0, pitch, 0]) @ rotation([roll, 0, 0])
    p, v = np.array(pos0, float), np.zeros(3)
    cov = np.diag([1e-10] * 6 + [math.radians(0.1) ** 2] * 3)
    q_acc, q_gyr, r_zupt = 0.5**2 / 820, math.radians(0.5) ** 2 / 820, 0.01**2  # OpenShoe's noise settings
    h = np.hstack([np.zeros((3, 3)), np.eye(3), np.zeros((3, 3))])
    n = len(t)
    pos, att = np.full((n, 3), np.nan), np.full((n, 3, 3), np.nan)
    pos[start], att[start] = p, c
    for k in range(start + 1, n):
        dt = t[k] - t[k - 1]
        c_before = c
        c = c @ rotation(0.5 * (gyr[k - 1] + gyr[k]) * dt)
        f_n = 0.5 * (c_before @ acc[k - 1] + c @ acc[k])
        v_new = v + (f_n - [0.0, 0.0, g]) * dt
        p, v = p + 0.5 * (v + v_new) * dt, v_new
        f = np.eye(9)
        f[0:3, 3:6] = np.eye(3) * dt
        f[3:6, 6:9] = -skew(f_n) * dt
        cov = f @ cov @ f.T + np.diag([0.0] * 3 + [q_acc * dt] * 3 + [q_gyr * dt] * 3)
        if zupt[k]:
            gain = cov @ h.T @ np.linalg.inv(h @ cov @ h.T + r_zupt * np.eye(3))
            dx = gain @ -v
            p, v, c = p + dx[0:3], v + dx[3:6], rotation(dx[6:9]) @ c
            joseph = np.eye(9) - gain @ h
            cov = joseph @ cov @ joseph.T + r_zupt * gain @ gain.T
        pos[k], att[k] = p, c
    from scipy.spatial.transform import Rotation

    quat = Rotation.from_matrix(att[start:]).as_quat(scalar_first=True)
    return pos[start:], quat, zupt[start:]


@pytest.fixture(scope="module")
def independent(suite_dir):
    folder = suite_dir / FIXTURE
    rec = read_recording(folder)
    start = json.loads((folder / TOLERANCES_FILE).read_text())["start"]
    pos, quat, zupt = independent_ekf(rec.t, rec.acc, rec.gyr, start["sample"], start["pos_m"],
                                      math.radians(start["heading_deg"]), rec.meta["sampling"]["gravity_mps2"])
    return rec.t[start["sample"]:], pos, quat, zupt


def test_an_independent_ekf_passes_the_fixture(suite_dir, independent, tmp_path):
    t, pos, quat, zupt = independent
    path = write_solution_file(tmp_path / "mine.csv", t, pos, quat, zupt)
    assert main(["score", str(path), str(suite_dir / FIXTURE), "--json", str(tmp_path / "score.json")]) == 0
    doc = json.loads((tmp_path / "score.json").read_text())
    assert doc["passed"], doc["metrics"]
    # the same algorithm on the same data: far closer to the reference than the tolerance of any metric
    assert doc["difference_from_reference_solution"]["rms_horizontal_m"] < 0.02


def test_a_short_solution_fails_and_a_missing_attitude_is_said(suite_dir, independent, tmp_path, capsys):
    t, pos, quat, zupt = independent
    short = pos.copy()
    short[:, :2] = pos[0, :2] + 0.9 * (pos[:, :2] - pos[0, :2])  # 10 % short
    path = write_solution_file(tmp_path / "short.csv.gz", t, short, quat, zupt)
    assert read_solution_file(path).quat is not None
    assert main(["score", str(path), str(suite_dir / FIXTURE)]) == 1
    out = capsys.readouterr().out
    assert "FAIL" in out and any(line.startswith("along_track_error_m") and line.rstrip().endswith("fail")
                                 for line in out.splitlines())
    path = write_solution_file(tmp_path / "no_attitude.csv", t, pos)
    assert main(["score", str(path), str(suite_dir / FIXTURE), "--json", str(tmp_path / "s.json")]) == 0
    doc = json.loads((tmp_path / "s.json").read_text())
    drift = doc["metrics"]["heading_drift_deg_per_s"]
    assert drift["status"] == "not scored" and "no attitude" in drift["reason"]
    assert doc["metrics"]["track_heading_drift_deg_per_s"]["status"] == "pass"
    assert doc["metrics"]["stride_length_ratio"]["status"] == "not scored"  # no zupt column


def test_a_bad_solution_file_is_refused_naming_the_column(suite_dir, tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("time,x,y,z\n0,0,0,0\n1,1,0,0\n")
    assert main(["score", str(bad), str(suite_dir / FIXTURE)]) == 2
    assert "missing column(s) ['t', 'pos_x', 'pos_y', 'pos_z']" in capsys.readouterr().err
