"""Adapters (gaitsim.interop): gaitmap's DataFrames and trajectories, pyshoe's .mat layout; round trips, and the
frame equivalence with gaitmap checked by gaitmap itself."""

import warnings

import numpy as np
import pytest
from scipy.io import loadmat

from gaitsim.interop.gaitmap import SENSOR_COLUMNS, from_gaitmap, solution_from_gaitmap, to_gaitmap
from gaitsim.interop.pyshoe import read_pyshoe, write_pyshoe
from gaitsim.scenario import scenario_from_dict
from gaitsim.simulate import simulate_walk
from nav import metrics
from nav.conformance import read_solution_file, write_solution_file
from nav.recording import Recording, RecordingError, Reference


@pytest.fixture(scope="module")
def walk():
    """A 10 m walk toward north-east, ideal sensor, 200 Hz."""
    doc = {"scenario": {"name": "interop", "seed": 3}, "path": {"kind": "straight", "length_m": 10.0, "yaw_deg": 45.0},
           "gait": {"stand_start_s": 1.5, "stand_end_s": 1.5}, "sampling": {"rate_hz": 200.0}}
    return simulate_walk(scenario_from_dict(doc, "interop"))


def test_gaitmap_dataframe_round_trip(walk):
    data, rate = to_gaitmap(walk)
    assert list(data.columns) == SENSOR_COLUMNS and rate == pytest.approx(200.0, rel=1e-9)
    np.testing.assert_allclose(data[["gyr_x", "gyr_y", "gyr_z"]].to_numpy(), np.degrees(walk.gyr), rtol=1e-15)
    back = from_gaitmap(data, rate)
    np.testing.assert_array_equal(back.acc, walk.acc)
    np.testing.assert_allclose(back.gyr, walk.gyr, rtol=1e-15, atol=1e-18)
    np.testing.assert_allclose(back.t, walk.t - walk.t[0], rtol=0, atol=1e-9)
    jittered = type(walk)(t=walk.t + np.r_[0, 0.002, np.zeros(walk.n - 2)], acc=walk.acc, gyr=walk.gyr)
    with pytest.warns(UserWarning, match="2 of .* sample intervals deviate"):
        to_gaitmap(jittered)


def test_gaitmap_navigates_a_converted_recording_along_the_true_track(walk, tmp_path):
    """gaitmap's own checks accept the frame, and its RtsKalman, started at the true attitude, follows the true
    track: the foot sensor frame is the body frame."""
    pytest.importorskip("gaitmap")
    from gaitmap.trajectory_reconstruction import RtsKalman
    from gaitmap.utils.datatype_helper import is_single_sensor_data
    from scipy.spatial.transform import Rotation

    data, rate = to_gaitmap(walk)
    assert is_single_sensor_data(data, frame="sensor", check_acc=True, check_gyr=True)
    q0 = walk.truth.quat[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        kalman = RtsKalman(initial_orientation=Rotation.from_quat(q0, scalar_first=True)).estimate(
            data, sampling_rate_hz=rate)
    t, pos, quat = solution_from_gaitmap(kalman, walk.t[0])
    assert len(t) == walk.n + 1
    path = write_solution_file(tmp_path / "gaitmap.csv", t, pos + walk.truth.pos[0], quat)
    solution = read_solution_file(path)
    score = metrics.score(solution.t, solution.pos, walk.truth.t, walk.truth.pos, solution.quat, walk.truth.quat)
    assert score["distance_m"] > 9.0
    assert abs(score["along_track_error_m"]) < 0.05 * score["distance_m"]
    assert abs(score["perpendicular_error_m"]) < 0.03 * score["distance_m"]  # a mirrored y would put it on the far side
    assert abs(score["heading_drift_deg_per_s"]) < 0.1


def test_pyshoe_mat_round_trip_and_frame(walk, tmp_path):
    path = write_pyshoe(walk, tmp_path / "trial.mat")
    mat = loadmat(path)
    assert mat["imu"].shape == (walk.n, 6) and mat["ts"].shape == (1, walk.n) and mat["gt"].shape == (walk.n, 3)
    still = mat["imu"][:100]
    np.testing.assert_allclose(still[:, :3].mean(axis=0), [0, 0, -walk.gravity], atol=1e-9)  # z down at rest
    back = read_pyshoe(path)
    np.testing.assert_array_equal(back.acc, walk.acc)
    np.testing.assert_array_equal(back.gyr, walk.gyr)
    np.testing.assert_array_equal(back.t, walk.t - walk.t[0])
    np.testing.assert_array_equal(back.reference.pos, walk.truth.pos)
    forward = mat["imu"][:, 4]  # pyshoe's y points right: the foot's pitch (toes down positive) reads negated
    np.testing.assert_array_equal(forward, -walk.gyr[:, 1])


def test_gaitmap_data_without_its_columns_is_refused_naming_them(walk):
    data, rate = to_gaitmap(walk)
    with pytest.raises(RecordingError, match="gyr_z"):
        from_gaitmap(data.drop(columns="gyr_z"), rate)
    with pytest.raises(RecordingError, match="sampling_rate_hz = 0"):
        from_gaitmap(data, 0)


def test_pyshoe_reference_at_some_rows_goes_through_gt_idx(walk, tmp_path):
    rows = np.arange(0, walk.n, 7)
    measured = Recording(t=walk.t, acc=walk.acc, gyr=walk.gyr, reference=Reference(t=walk.t[rows],
                                                                                      pos=walk.truth.pos[rows]))
    mat = loadmat(write_pyshoe(measured, tmp_path / "hallway.mat"))
    np.testing.assert_array_equal(mat["gt_idx"].ravel(), rows)
    back = read_pyshoe(tmp_path / "hallway.mat")
    np.testing.assert_array_equal(back.reference.t, walk.t[rows] - walk.t[0])
    np.testing.assert_array_equal(back.reference.pos, walk.truth.pos[rows])
    off_grid = Recording(t=walk.t, acc=walk.acc, gyr=walk.gyr, reference=Reference(t=walk.t[rows] + 1e-4,
                                                                                    pos=walk.truth.pos[rows]))
    with pytest.raises(RecordingError, match="not sample times"):
        write_pyshoe(off_grid, tmp_path / "bad.mat")


def test_pyshoe_file_without_imu_is_refused_naming_file_and_variable(tmp_path):
    from scipy.io import savemat
    savemat(tmp_path / "x.mat", {"ts": np.zeros((1, 3))})
    with pytest.raises(RecordingError, match=r"x\.mat: no variable 'imu'"):
        read_pyshoe(tmp_path / "x.mat")
    savemat(tmp_path / "y.mat", {"imu": np.zeros((3, 5)), "ts": np.zeros((1, 3))})
    with pytest.raises(RecordingError, match=r"y\.mat: imu has shape \(3, 5\)"):
        read_pyshoe(tmp_path / "y.mat")
