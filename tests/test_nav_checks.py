"""Bad input (nav.checks and the pipeline): each problem is a clear error or a counted warning."""

import numpy as np
import pytest
from nav_synthetic import synthetic_walk

from nav import pipeline
from nav.checks import check_recording
from nav.recording import Recording, RecordingError


@pytest.fixture(scope="module")
def walk():
    return synthetic_walk(strides=3)


def variant(rec, t=None, acc=None, gyr=None):
    return Recording(rec.t if t is None else t, rec.acc if acc is None else acc, rec.gyr if gyr is None else gyr, {})


def test_clean_recording_passes_without_warnings(walk):
    report = check_recording(walk)
    assert report.warnings == []
    assert report.counts["static_specific_force"] == pytest.approx(9.81, rel=1e-9)


def test_nan_and_inf_samples_are_counted_per_column(walk):
    acc = walk.acc.copy()
    acc[[5, 9], 1] = np.nan
    acc[7, 2] = np.inf
    expected = r"3 NaN/inf cells \(per column \{'acc_y': 2, 'acc_z': 1\}; first in data row 6"
    with pytest.raises(RecordingError, match=expected):
        check_recording(variant(walk, acc=acc))


def test_repeated_and_decreasing_timestamps_are_errors(walk):
    t = walk.t.copy()
    t[10] = t[9]
    t[20] = t[18]
    with pytest.raises(RecordingError, match="1 repeated and 1 decreasing timestamps .first at row 10"):
        check_recording(variant(walk, t=t))


def test_irregular_intervals_are_a_counted_warning(walk):
    t = walk.t.copy()
    t[100:] += 0.0006  # one interval 48 % longer than the others
    with pytest.warns(UserWarning, match="1 of"):
        report = check_recording(variant(walk, t=t))
    assert report.counts["irregular_intervals"] == 1


def test_accelerometer_in_g_is_an_error(walk):
    with pytest.raises(RecordingError, match="looks like it reports g"):
        check_recording(variant(walk, acc=walk.acc / 9.81))


def test_gyro_in_deg_per_s_is_an_error(walk):
    with pytest.raises(RecordingError, match="deg/s"):
        check_recording(variant(walk, gyr=np.degrees(walk.gyr) * 3))  # peak ~ 2.4 rad/s -> 410 deg/s


def test_static_gyro_offset_too_large_for_rad_s_warns(walk):
    with pytest.warns(UserWarning, match="at rest"):
        check_recording(variant(walk, gyr=walk.gyr + np.degrees(0.01)))


def test_too_short_to_align_and_no_stance_are_errors(walk):
    short = variant(walk, t=walk.t[:10], acc=walk.acc[:10], gyr=walk.gyr[:10])
    with pytest.raises(RecordingError, match="too short or never at rest"):
        pipeline.navigate(short, pipeline.NavOptions(detector="shoe"))
    with pytest.raises(RecordingError, match="no stance found"):
        noisy = walk.acc + np.random.default_rng(0).normal(0, 0.01, walk.acc.shape)  # T ~ 1 at rest
        pipeline.navigate(variant(walk, acc=noisy), pipeline.NavOptions(detector="shoe", threshold=1e-3))


def test_oracle_and_increments_need_truth(walk):
    bare = variant(walk)
    with pytest.raises(RecordingError, match="oracle"):
        pipeline.navigate(bare, pipeline.NavOptions(detector="oracle"))
    with pytest.raises(RecordingError, match="increments"):
        pipeline.navigate(bare, pipeline.NavOptions(method="increments"))


def _saturate_every_swing(rec, gyr):
    """The gyro clipped at 60 % of its peak rate about y: a flat top in every swing (numpy only)."""
    limit = 0.6 * np.abs(gyr[:, 1]).max()
    out = gyr.copy()
    out[:, 1] = np.clip(out[:, 1], -limit, limit)
    return out


def test_a_gyro_scaled_wrong_is_refused_but_not_when_saturation_spoils_every_stride():
    rec = synthetic_walk(strides=6)
    with pytest.raises(RecordingError, match="gyro against accelerometer"):
        check_recording(variant(rec, gyr=rec.gyr * 3.0))
    # clipped in every swing: the closure cannot tell a scale from saturation, so it is not judged (a warning)
    clipped = variant(rec, gyr=_saturate_every_swing(rec, rec.gyr * 3.0))
    with pytest.warns(UserWarning, match="not judged: 6 of 6 strides hold clipped samples"):
        report = check_recording(clipped)
    assert report.counts["closure_strides"] == 0 and report.counts["closure_strides_clipped"] == 6
    assert report.counts["clipped_samples"]["gyr_y"] > 0


def test_strides_without_clipping_are_still_judged():
    rec = synthetic_walk(strides=6)
    gyr = rec.gyr * 3.0
    swing = ~rec.truth.stance
    first_two = swing & (rec.t < rec.t[np.flatnonzero(swing)[0]] + 2 * 1.4)  # the swings of the first two strides
    limit = np.abs(gyr[~first_two, 1]).max()  # the range: the other strides peak at it, these two beyond
    gyr[first_two, 1] = np.clip(1.2 * gyr[first_two, 1], -limit, limit)
    with pytest.raises(RecordingError, match="4 of 4 strides end faster"):
        check_recording(variant(rec, gyr=gyr))


def test_one_axis_saturated_at_2000_deg_per_s_is_not_deg_per_s():
    rec = synthetic_walk(strides=3)
    gyr = rec.gyr.copy()
    burst = slice(2000, 2400)  # 0.5 s: 10 % of the samples
    gyr[burst, 1] = np.radians(1999.0)
    gyr[burst, 2] = 3.0  # rad/s on another axis: the norm exceeds 35 rad/s, no single axis does
    with pytest.warns(UserWarning):
        report = check_recording(variant(rec, gyr=gyr), allow=("closure",))
    assert report.counts["samples_above_walking_rate"] == 0
    with pytest.raises(RecordingError, match="reports deg/s"):
        check_recording(variant(rec, gyr=np.degrees(rec.gyr)))


def test_a_mirrored_frame_is_refused_and_named():
    rec = synthetic_walk(strides=6)
    flip = np.diag([1.0, -1.0, 1.0])  # the y axis of both sensors reversed: a left-handed frame
    with pytest.raises(RecordingError, match="times -1 closes them.*mirrored sensor frame"):
        check_recording(variant(rec, acc=rec.acc @ flip, gyr=rec.gyr @ flip))
    with pytest.raises(RecordingError, match="times 0.333 closes them.*wrong gyro scale"):
        check_recording(variant(rec, gyr=rec.gyr * 3.0))


def test_strides_that_end_fast_at_every_gyro_scale_are_flagged_not_refused():
    """An accelerometer error, not the gyro: a kick of 1.5 m/s along the axis the foot turns about (y), mid-swing
    (numpy only), ends every stride fast whatever the gyro's scale, and the recording's own scale closes best (as
    on a simulated consumer sensor's run, whose foot is never still at its rests: README, the input checks)."""
    rec = synthetic_walk(strides=6)
    acc = rec.acc.copy()
    swing = np.flatnonzero(~rec.truth.stance)
    starts = swing[np.flatnonzero(np.diff(swing, prepend=-2) > 1)]
    rate = 1.0 / np.median(np.diff(rec.t))
    for s in starts:
        middle = slice(s + int(0.15 * rate), s + int(0.35 * rate))  # 0.2 s at 7.5 m/s^2
        acc[middle, 1] += 7.5
    with pytest.warns(UserWarning, match="not the gyro's scale or frame"):
        report = check_recording(variant(rec, acc=acc))
    assert report.counts["closure_speed_median_mps"] > 1.0
    assert report.counts["closure_best_gyro_scale"] == 1.0
