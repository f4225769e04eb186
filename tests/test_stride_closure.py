"""Stride closure (nav.closure) and its two callers, the input check (nav.checks) and the loop residual
(gaitsim.loop.closure): laws on a still sensor, and both callers' numbers on measured data frozen from the code
before their two closure computations became one."""

import warnings

import numpy as np
import pytest

from conftest import DATA, needs_data
from gaitsim.loop.closure import closure_between_stances
from gaitsim.measured import load_dataset
from nav.checks import check_recording, closure_between_rests
from nav.closure import stride_closure

G = 9.81
FS = 800.0


def still(n, acc=(0.0, 0.0, G), gyr=(0.0, 0.0, 0.0)):
    t = np.arange(n) / FS
    return t, np.tile(acc, (n, 1)).astype(float), np.tile(gyr, (n, 1)).astype(float)


def test_gyro_bias_tilts_the_carried_gravity_by_rate_times_time_and_subtracting_it_closes():
    # A roll rate b on a still, level sensor turns it by b T about x: the carried up (0, sin bT, cos bT) against
    # the read (0, 0, 1) gives tilt (sin bT, 0, 0); gravity's wrong projection gives v_y = -g (1 - cos bT) / b.
    b, n = 0.02, 1601
    t, acc, gyr = still(n, gyr=(b, 0.0, 0.0))
    windows = dict(level=[[0, 100]], start=[0], end=[[n - 1, n]], read=[[n - 100, n]])
    found = stride_closure(t, acc, gyr, gravity=G, **windows)
    bt = b * t[-1]
    np.testing.assert_allclose(found.tilt, [[np.sin(bt), 0.0, 0.0]], atol=1e-12)
    np.testing.assert_allclose(found.angle, [bt], rtol=1e-9)
    np.testing.assert_allclose(found.velocity, [[0.0, -G * (1 - np.cos(bt)) / b, G * (np.sin(bt) / b - t[-1])]],
                               rtol=1e-7, atol=1e-12)
    closed = stride_closure(t, acc, gyr, gravity=G, gyro_bias=np.array([b, 0.0, 0.0]), **windows)
    assert np.max(np.abs(closed.velocity)) < 1e-12 and np.max(np.abs(closed.tilt)) < 1e-15
    assert closed.angle[0] < 1e-15


def test_levelling_absorbs_a_horizontal_force_and_the_velocity_is_the_mean_over_the_end_window():
    # Levelled on f = (0.3, 0, g), the attitude takes the horizontal force for tilt: only |f| - g is left, upward,
    # integrated from the start sample; the velocity is its mean over the end window.
    t, acc, gyr = still(2001, acc=(0.3, 0.0, G))
    found = stride_closure(t, acc, gyr, level=[[0, 50]], start=[400], end=[[1500, 1700]], read=[[1500, 1700]],
                           gravity=G)
    excess = np.hypot(0.3, G) - G
    np.testing.assert_allclose(found.velocity, [[0.0, 0.0, excess * np.mean(t[1500:1700] - t[400])]], atol=1e-12)
    assert found.angle[0] < 1e-12


FROZEN_REST_SPEED = [0.17065778752607236, 0.37423899305495917, 0.25483535687066944, 0.47118765152916847,
                     0.37144436069739756, 0.16836542424810444]  # m/s
FROZEN_REST_TILT = [0.03974860676826205, 0.03792565725330982, 0.030217745761816933, 0.06159982313591325,
                    0.03115992928698404, 0.02485072639251811]  # rad
FROZEN_COUNTS = {  # check_recording's closure counts: strides, strides off, median speed m/s, median tilt deg
    ("gaitmap-healthy", "left"): (32, 0, 0.25483036587680263, 2.0602120192071878),
    ("gaitmap-healthy", "right"): (32, 0, 0.3616178041190504, 2.3007193654017772),
    ("ucr-fgo", "left"): (80, 0, 0.29674926799116597, 1.7818844015037685),
    ("ucr-fgo", "right"): (79, 0, 0.3317567696267259, 2.6328439941009454),
    ("xio-ngimu", "short_walk"): (16, 0, 0.4320174614552805, 3.785767601884361),
    ("xio-ngimu", "long_walk"): (37, 0, 0.4600075397900508, 4.992108969899888),
}


def measured(dataset, recording):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the loader's data-quality counts are in meta
        return {rec.meta["recording"]: rec for rec in load_dataset(dataset, DATA)}[recording]


@needs_data("gaitmap-healthy")
def test_rest_closure_on_measured_data_is_the_one_before_the_shared_computation():
    rec = measured("gaitmap-healthy", "left")
    n = int(np.searchsorted(rec.t, rec.t[0] + 8.0))  # 1639 samples, 6 strides between rests
    speed, tilt = closure_between_rests(rec.t[:n], rec.acc[:n], rec.gyr[:n], rec.gravity)
    np.testing.assert_allclose(speed, FROZEN_REST_SPEED, rtol=0, atol=1e-12)
    np.testing.assert_allclose(tilt, FROZEN_REST_TILT, rtol=0, atol=1e-12)


@needs_data()
@pytest.mark.parametrize("dataset, recording", sorted(FROZEN_COUNTS))
def test_check_closure_counts_on_every_shared_recording_are_the_ones_before(dataset, recording):
    rec = measured(dataset, recording)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the check's own data-quality warnings
        counts = check_recording(rec, rec.gravity).counts
    strides, off, speed, tilt = FROZEN_COUNTS[(dataset, recording)]
    assert (counts["closure_strides"], counts["closure_strides_off"]) == (strides, off)
    assert counts["closure_speed_median_mps"] == pytest.approx(speed, rel=0, abs=1e-12)
    assert counts["closure_tilt_median_deg"] == pytest.approx(tilt, rel=0, abs=1e-12)


STANCES = np.array([[0, 178], [483, 530], [698, 753], [918, 973], [1142, 1193], [1359, 1412], [1573, 1623]])
FROZEN_VELOCITY = [[0.5982057275437739, -0.17352189179852723, -0.02710929909044682],
                   [0.008701418126092382, 0.16481468337617852, 0.07354767989176104],
                   [0.2930988581837744, 0.1509340784525258, -0.05857877153505758],
                   [0.4321166783202531, -0.12189227632530007, -0.28269153628298227],
                   [-0.15184278304940615, -0.19258144899276247, 0.09287446833032507],
                   [0.22498492349548244, -0.19607038108690647, -0.12594325195960812]]  # m/s
FROZEN_TILT_DEG = [[-0.3077384502365882, 2.149344266800789], [0.6411155432445175, 0.9703197290109692],
                   [0.2689852904347867, 1.2959548235056095], [-0.8694798885874676, -0.00824625145624265],
                   [0.9448288853775417, 1.1139082568451046], [0.2615434077019149, 1.2319086723808184]]


@needs_data("gaitmap-healthy")
def test_stance_closure_on_measured_data_is_the_one_before_the_shared_computation():
    # the first 8 s of gaitmap's left foot; stances as SHOE detected them there, gyro bias from the first
    rec = measured("gaitmap-healthy", "left")
    t, acc, gyr = rec.t[:1639], rec.acc[:1639], rec.gyr[:1639]
    found = closure_between_stances(t, acc, gyr, STANCES[:-1], STANCES[1:], rec.gravity,
                                    gyr[slice(*STANCES[0])].mean(0))
    np.testing.assert_allclose(found.velocity, FROZEN_VELOCITY, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.degrees(found.tilt[:, :2]), FROZEN_TILT_DEG, rtol=0, atol=1e-12)
