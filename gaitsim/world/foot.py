"""The MuJoCo foot model, driven kinematically: prescribe qpos, qvel, qacc and read the sensors via mj_inverse.

``mj_inverse`` evaluates every sensor at exactly the prescribed state (anchors §8); ``mj_forward`` would
overwrite qacc. The accelerometer sensor gives specific force in the site frame (+9.81 on the up axis at rest).
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources

import mujoco
import numpy as np

from nav import quaternion as quat
from nav.constants import DEFAULT_GRAVITY

MOUNTS = ("toes", "instep", "heel")


@dataclass(frozen=True)
class Mount:
    """Where and how the IMU sits on the foot.

    Attributes
    ----------
    site : one of ``MOUNTS``; the nominal mount point on the foot model. Default "toes" (the seed paper's).
    offset_m : (3,) m, added to the mount point, foot frame.
    rpy : (3,) rad, (roll, pitch, yaw) of the sensor axes relative to the foot axes, R = Rz Ry Rx.
    """

    site: str = "toes"
    offset_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass
class SiteSamples:
    """Sensor readings of the IMU site at each sample (MuJoCo's own sensors).

    Attributes
    ----------
    pos : (N, 3) m, world.   vel : (N, 3) m/s, world.   quat : (N, 4) site->world (w, x, y, z).
    gyr : (N, 3) rad/s, site frame.   acc : (N, 3) m/s^2, specific force, site frame.
    """

    pos: np.ndarray
    vel: np.ndarray
    quat: np.ndarray
    gyr: np.ndarray
    acc: np.ndarray


class FootModel:
    """The shipped MJCF foot with the IMU site placed at a mount.

    Parameters
    ----------
    mount : Mount
    gravity : m/s^2, magnitude of gravity along -z. Default nav's DEFAULT_GRAVITY (9.81).
    """

    def __init__(self, mount: Mount = Mount(), gravity: float = DEFAULT_GRAVITY):
        if mount.site not in MOUNTS:
            raise ValueError(f"mount site {mount.site!r} is not one of {MOUNTS}")
        xml = resources.files("gaitsim.world").joinpath("assets/foot.xml").read_text()
        self.model = mujoco.MjModel.from_xml_string(xml)
        self.model.opt.gravity[:] = (0.0, 0.0, -gravity)
        self.data = mujoco.MjData(self.model)
        m = self.model
        site = lambda name: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, name)  # noqa: E731
        self.toe_length = float(m.site_pos[site("toe_contact")][0] - m.site_pos[site("heel_contact")][0])
        imu = site("imu")
        m.site_pos[imu] = m.site_pos[site(f"mount_{mount.site}")] + np.asarray(mount.offset_m, float)
        roll, pitch, yaw = mount.rpy
        m.site_quat[imu] = quat.from_euler_zyx(yaw, pitch, roll)
        m.site_sameframe[imu] = 0  # the compiler flagged it as coinciding with the body frame; it no longer does
        self.mount = mount
        self.lever_arm = np.array(m.site_pos[imu])  # m, IMU site in the foot frame (from the heel contact)
        self._slices = {}
        for name in ("acc", "gyr", "pos", "quat", "vel"):
            sid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SENSOR, f"imu_{name}")
            adr, dim = m.sensor_adr[sid], m.sensor_dim[sid]
            self._slices[name] = slice(adr, adr + dim)

    def sample(self, qpos: np.ndarray, qvel: np.ndarray, qacc: np.ndarray) -> SiteSamples:
        """Evaluate the IMU site's sensors at N prescribed states (each (N, 6): joints x, y, z, yaw, pitch, roll)."""
        m, d = self.model, self.data
        out = np.empty((len(qpos), m.nsensordata))
        # the per-sample loop is bound to MjData's own buffers (views), looked up once
        pos, vel, acc, sensors, inverse = d.qpos, d.qvel, d.qacc, d.sensordata, mujoco.mj_inverse
        for k, (p, v, a) in enumerate(zip(np.ascontiguousarray(qpos), np.ascontiguousarray(qvel),
                                          np.ascontiguousarray(qacc))):
            pos[:] = p
            vel[:] = v
            acc[:] = a
            inverse(m, d)
            out[k] = sensors
        s = self._slices
        q = out[:, s["quat"]]
        q = continuous_sign(q)
        return SiteSamples(pos=out[:, s["pos"]], vel=out[:, s["vel"]], quat=q, gyr=out[:, s["gyr"]], acc=out[:, s["acc"]])


def continuous_sign(q: np.ndarray) -> np.ndarray:
    """Flip quaternion signs so consecutive samples lie in the same hemisphere, the first with w >= 0."""
    flips = np.concatenate([[q[0, 0] < 0], np.einsum("ij,ij->i", q[1:], q[:-1]) < 0])
    return q * np.where(np.cumsum(flips) % 2 == 1, -1.0, 1.0)[:, None]
