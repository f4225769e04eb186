"""ucr-fgo loader: units, 60 Hz clock, zero-velocity labels and the z-down reference made right-handed z-up."""

import warnings

import numpy as np
import pytest

from gaitsim.measured import load_dataset, ucr_zero_velocity_labels
from gaitsim.measured.quality import DataQualityWarning
from conftest import DATA, needs_data

pytestmark = needs_data("ucr-fgo")


@pytest.fixture(scope="module")
def recordings():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DataQualityWarning)
        return {rec.meta["recording"]: rec for rec in load_dataset("ucr-fgo", DATA)}


def test_units_are_si_in_the_first_still_second(recordings):
    for rec in recordings.values():
        first = rec.t < 1.0  # the walk starts standing (authors' label: zero velocity)
        assert ucr_zero_velocity_labels(rec.meta["recording"], DATA)[first].all()
        # 1.5 %: the left accelerometer reads 9.91 m/s^2 at rest (a ~1 % sensor error, not a unit error)
        assert np.linalg.norm(rec.acc[first], axis=1).mean() == pytest.approx(9.81, rel=0.015)
        assert np.sqrt(np.mean(np.sum(rec.gyr[first] ** 2, axis=1))) < 0.05


def test_clock_is_the_sample_counter_at_60_hz(recordings):
    for rec in recordings.values():
        assert rec.t[-1] == pytest.approx(7200 / 60.0)
        np.testing.assert_allclose(np.diff(rec.t), 1 / 60.0, rtol=1e-9)
        np.testing.assert_array_equal(rec.reference.t, rec.t)


def test_zero_velocity_label_count_matches_the_file(recordings):
    for side, name in (("left", "imuMeasLeft.csv"), ("right", "imuMeasRight.csv")):
        raw = np.loadtxt(DATA / "ucr-fgo" / name, delimiter=",", skiprows=1)
        labels = ucr_zero_velocity_labels(side, DATA)
        assert labels.sum() == int(raw[:, 7].sum())
        assert recordings[side].meta["data_quality"]["zero_velocity_label"]["samples"] == int(raw[:, 7].sum())


def test_reference_is_z_up_the_foot_rises_in_swing(recordings):
    raw = np.loadtxt(DATA / "ucr-fgo" / "positionGt.csv", delimiter=",", skiprows=1)
    for k, (side, rec) in enumerate(recordings.items()):
        stance = ucr_zero_velocity_labels(side, DATA)
        z = rec.reference.pos[:, 2]
        assert np.percentile(z[~stance], 90) - np.median(z[stance]) > 0.03  # swing clearance, upward
        stored_z = raw[:, 3 + 3 * k]
        assert np.percentile(stored_z[~stance], 10) - np.median(stored_z[stance]) < -0.03  # the file: z down


def test_reference_is_right_handed_it_turns_the_way_the_gyro_does(recordings):
    for rec in recordings.values():
        turns = rec.meta["frames"]["turn_check_rad"]
        # ~6 counter-clockwise laps seen by both; a mirrored (z-negated only) frame would turn the other way
        assert turns["reference_heading_change"] > 30.0
        assert turns["reference_heading_change"] == pytest.approx(turns["imu_integrated_gyro_z"], rel=0.25)
        checks = rec.meta["frames"]["imu_checks"]
        assert checks["dominant_gyro_axis"] == 1 and checks["forward_is_plus_x"]
