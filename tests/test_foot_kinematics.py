"""The vectorised rigid-body kinematics of the IMU site equal MuJoCo's sensors, and the check says when not."""

import numpy as np
import pytest

from gaitsim.world.foot import FootModel, Mount


def random_states(n, seed=0):
    rng = np.random.default_rng(seed)
    qpos = rng.normal(size=(n, 6)) * [1.0, 1.0, 0.1, 2.0, 0.8, 0.5]
    return qpos, rng.normal(size=(n, 6)) * 3.0, rng.normal(size=(n, 6)) * 50.0


@pytest.mark.parametrize("mount", [Mount(), Mount("heel", (0.01, -0.02, 0.005), (0.1, -0.2, 0.3))])
def test_kinematics_equal_mujoco_sensors(mount):
    foot = FootModel(mount, gravity=9.8)
    qpos, qvel, qacc = random_states(500)
    ours, theirs = foot.kinematics(qpos, qvel, qacc), foot.sample(qpos, qvel, qacc)
    for name in ("pos", "vel", "quat", "gyr", "acc"):
        np.testing.assert_allclose(getattr(ours, name), getattr(theirs, name), rtol=0,
                                   atol=1e-12 * np.abs(getattr(theirs, name)).max(), err_msg=name)
    foot.check(qpos, qvel, qacc, ours, np.arange(500))


def test_check_raises_when_the_model_moves_the_site():
    foot = FootModel()
    qpos, qvel, qacc = random_states(50, seed=1)
    samples = foot.kinematics(qpos, qvel, qacc)
    foot.model.site_pos[foot.imu_site][2] += 1e-6  # the MJCF site moved after the formulas were evaluated
    with pytest.raises(RuntimeError, match="IMU-site pos"):
        foot.check(qpos, qvel, qacc, samples, np.arange(0, 50, 7))
