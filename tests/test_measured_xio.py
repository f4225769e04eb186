"""xio-ngimu loader: repeated rows dropped and counted, jitter kept and reported, units, loop-closure reference."""

import warnings

import numpy as np
import pytest

from gaitsim.measured import load_dataset
from gaitsim.measured.quality import DataQualityWarning
from conftest import DATA, needs_data

pytestmark = needs_data("xio-ngimu")


@pytest.fixture(scope="module")
def recordings():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DataQualityWarning)
        return {rec.meta["recording"]: rec for rec in load_dataset("xio-ngimu", DATA)}


@pytest.fixture(scope="module")
def raw_tables():
    return {walk: np.loadtxt(DATA / "xio-ngimu" / f"{walk}.csv", delimiter=",", skiprows=1)
            for walk in ("short_walk", "long_walk")}


def test_repeated_rows_are_dropped_and_counted(recordings, raw_tables):
    for walk, raw in raw_tables.items():
        rec = recordings[walk]
        repeated = int(np.count_nonzero(np.diff(raw[:, 0]) <= 0))
        quality = rec.meta["data_quality"]
        assert quality["dropped_rows"] == repeated
        assert 0.005 < repeated / len(raw) < 0.02  # the README's ~1 % of repeated packets
        assert rec.n == len(raw) - repeated
        assert np.all(np.diff(rec.t) > 0)


def test_dropped_rows_and_jitter_are_reported_as_warnings(raw_tables):
    with pytest.warns(DataQualityWarning) as caught:
        load_dataset("xio-ngimu", DATA)
    messages = [str(w.message) for w in caught]
    for walk, raw in raw_tables.items():
        repeated = int(np.count_nonzero(np.diff(raw[:, 0]) <= 0))
        assert any(m.startswith(f"{walk}.csv: dropped {repeated} of {len(raw)} rows") for m in messages)
        assert any(m.startswith(f"{walk}.csv: timestamp jitter") for m in messages)


def test_timestamps_are_kept_and_their_jitter_reported(recordings, raw_tables):
    for walk, raw in raw_tables.items():
        rec = recordings[walk]
        kept = np.unique(raw[:, 0])
        np.testing.assert_allclose(rec.t, kept - kept[0], atol=1e-12)  # no resampling onto a nominal grid
        jitter = rec.meta["data_quality"]["jitter"]
        dt = np.diff(kept)
        assert jitter["dt_std"] == pytest.approx(dt.std(), rel=1e-9)
        assert jitter["gaps"] == int(np.count_nonzero(dt > 1.5 * np.median(dt)))
        assert 0.05 < jitter["jitter_rel"] < 0.3  # the README's ~15 %


def test_units_are_si_in_still_windows(recordings):
    for rec in recordings.values():
        n = int(round(1 / np.median(np.diff(rec.t))))
        gyr_ms = np.convolve(np.sum(rec.gyr**2, axis=1), np.ones(n) / n, mode="valid")
        k = int(np.flatnonzero(gyr_ms < 0.05**2)[0])  # first second still by the gyro
        assert np.linalg.norm(rec.acc[k:k + n], axis=1).mean() == pytest.approx(9.81, rel=0.01)
        first = rec.t < 1.0  # the walks start standing
        assert np.sqrt(np.mean(np.sum(rec.gyr[first] ** 2, axis=1))) < 0.05


def test_frame_gravity_up_pitch_about_y_x_forward(recordings):
    for rec in recordings.values():
        checks = rec.meta["frames"]["imu_checks"]
        assert checks["still_acc_mean"][2] > 0.8 * 9.81
        assert checks["dominant_gyro_axis"] == 1
        assert checks["pitch_excursion_deg"] > 30.0


def test_reference_is_a_loop_closure(recordings):
    for rec in recordings.values():
        assert rec.meta["reference"]["kind"] == "loop_closure"
        np.testing.assert_array_equal(rec.reference.t, [rec.t[0], rec.t[-1]])
        np.testing.assert_array_equal(rec.reference.pos[0], rec.reference.pos[-1])
