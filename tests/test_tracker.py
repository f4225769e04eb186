"""The simulated tracker: resolution, rate, and velocity by differentiation."""

import numpy as np

from gaitsim.experiments.tracker import TrackerSpec, track, velocity_within
from nav.recording import Truth


def _line_truth(speed=0.5, rate=800.0, duration=5.0):
    t = np.arange(0, duration, 1 / rate)
    pos = np.column_stack([speed * t, 0.3 + 0 * t, 0 * t])
    vel = np.tile([speed, 0.0, 0.0], (t.size, 1))
    z = np.zeros((t.size, 3))
    return Truth(t=t, pos=pos, vel=vel, quat=np.tile([1.0, 0, 0, 0], (t.size, 1)), gyr=z, acc=z, dv=z, dth=z,
                 stance=np.zeros(t.size, bool))


def test_tracker_quantises_to_its_resolution_at_its_rate():
    tr = track(_line_truth(), TrackerSpec(rate_hz=60.0, resolution_m=0.001, noise_m=0.0), np.random.default_rng(0))
    assert np.allclose(np.diff(tr.t), 1 / 60)
    np.testing.assert_allclose(tr.pos / 0.001, np.round(tr.pos / 0.001), atol=1e-9)
    # quantisation error of a uniform motion is bounded by half the resolution
    assert np.abs(tr.pos[:, 0] - 0.5 * tr.t).max() <= 0.0005 + 1e-12


def test_tracked_velocity_of_a_uniform_motion_is_unbiased_with_the_expected_spread():
    noise = 0.0005
    tr = track(_line_truth(duration=60.0), TrackerSpec(60.0, 0.0, noise), np.random.default_rng(1))
    inner = tr.vel[1:-1, 0]
    assert abs(inner.mean() - 0.5) < 1e-3
    # central difference of white noise: sd = noise * sqrt(2) / (2 dt)
    np.testing.assert_allclose(np.std(inner), noise * np.sqrt(2) * 60 / 2, rtol=0.05)


def test_stance_velocity_within_ignores_the_swing_a_central_difference_straddles():
    # creep at 3 mm/s in [1.0, 1.4] s, leaving with 20 m/s^2 after it (a heel-off): the plain central difference
    # at the stance's last sample averages in the swing, the differences inside the stance do not
    rate = 800.0
    t = np.arange(0, 2.0, 1 / rate)
    after = np.clip(t - 1.4, 0, None)
    vel = np.column_stack([0.003 + 20.0 * after, 0 * t, 0 * t])
    pos = np.column_stack([0.003 * t + 10.0 * after ** 2, 0 * t, 0 * t])
    z = np.zeros((t.size, 3))
    truth = Truth(t=t, pos=pos, vel=vel, quat=np.tile([1.0, 0, 0, 0], (t.size, 1)), gyr=z, acc=z, dv=z, dth=z,
                  stance=np.zeros(t.size, bool))
    tr = track(truth, TrackerSpec(60.0, 0.0, 0.0), np.random.default_rng(0))
    stance = t[(t >= 1.0) & (t <= 1.4)]
    plain_end = np.interp(stance[-1], tr.t, tr.vel[:, 0])
    assert plain_end > 0.03  # > 10 x the creep: the bias that made the fitted pseudo-velocity overshoot
    np.testing.assert_allclose(velocity_within(tr, stance)[:, 0], 0.003, atol=1e-9)
    assert velocity_within(tr, stance[stance < 1.0 + 1.9 / 60]) is None  # shorter than two tracker periods
