"""The MuJoCo foot model, driven kinematically: prescribe qpos, qvel, qacc and read the sensors via mj_inverse.

``mj_inverse`` evaluates every sensor at exactly the prescribed state (anchors §8); ``mj_forward`` would
overwrite qacc. The accelerometer sensor gives specific force in the site frame (+9.81 on the up axis at rest).

The model (the site's place and axes on the foot, gravity) is MuJoCo's; :meth:`FootModel.kinematics` evaluates
the same site quantities with the rigid-body formulas of its joint chain for all samples at once, and
:meth:`FootModel.check` holds them against MuJoCo's own sensors on chosen samples.
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
    """Sensor quantities of the IMU site at each sample (MuJoCo's own sensors, or the same from the rigid-body
    formulas).

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
        self.imu_site = imu  # MuJoCo id of the IMU site
        self._slices = {}
        for name in ("acc", "gyr", "pos", "quat", "vel"):
            sid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SENSOR, f"imu_{name}")
            adr, dim = m.sensor_adr[sid], m.sensor_dim[sid]
            self._slices[name] = slice(adr, adr + dim)

    def kinematics(self, qpos: np.ndarray, qvel: np.ndarray, qacc: np.ndarray) -> SiteSamples:
        """The IMU site's sensor quantities at N prescribed states (each (N, 6): joints x, y, z, yaw, pitch,
        roll; m, rad and their rates), from the rigid-body formulas of the joint chain, vectorised.

        The attitude is R = Rz(yaw) Ry(pitch) Rx(roll); the angular velocity is the sum of the joint rates about
        their axes, w = yaw' e_z + pitch' e_y' + roll' e_x'' (e_y' = Rz e_y, e_x'' = Rz Ry e_x), and its rate adds
        the turning of those axes. The site at lever r = R r_foot from the heel point p moves at p' + w x r and
        accelerates at p'' + w' x r + w x (w x r); the accelerometer reads R_site^T (a - g), the gyro R_site^T w.
        Equal to :meth:`sample` to round-off (:meth:`check`).
        """
        m = self.model
        yaw, pitch, roll = np.asarray(qpos, float)[:, 3:].T
        vel, ang_rate = np.asarray(qvel, float)[:, :3], np.asarray(qvel, float)[:, 3:]
        acc, ang_acc = np.asarray(qacc, float)[:, :3], np.asarray(qacc, float)[:, 3:]
        cz, sz, cy, sy = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
        axes = np.zeros((3, yaw.size, 3))
        axes[0, :, 2] = 1.0  # yaw axis e_z
        axes[1, :, 0], axes[1, :, 1] = -sz, cz  # pitch axis e_y' = Rz e_y
        axes[2, :, 0], axes[2, :, 1], axes[2, :, 2] = cz * cy, sz * cy, -sy  # roll axis e_x'' = Rz Ry e_x
        w_yaw_pitch = ang_rate[:, :1] * axes[0] + ang_rate[:, 1:2] * axes[1]
        w = w_yaw_pitch + ang_rate[:, 2:] * axes[2]
        axes_rate = np.stack([cross(ang_rate[:, :1] * axes[0], axes[1]), cross(w_yaw_pitch, axes[2])])
        w_dot = (np.einsum("nj,jni->ni", ang_acc, axes) + ang_rate[:, 1:2] * axes_rate[0]
                 + ang_rate[:, 2:] * axes_rate[1])
        body = quat.from_euler_zyx(yaw, pitch, roll)
        site = self.imu_site
        lever = quat.rotate(body, np.broadcast_to(m.site_pos[site], w.shape))
        q = continuous_sign(quat.multiply(body, np.broadcast_to(m.site_quat[site], body.shape)))
        site_to_world = quat.to_matrix(q)
        world_acc = acc + cross(w_dot, lever) + cross(w, cross(w, lever))
        return SiteSamples(pos=np.asarray(qpos, float)[:, :3] + lever, vel=vel + cross(w, lever), quat=q,
                           gyr=np.einsum("nji,nj->ni", site_to_world, w),
                           acc=np.einsum("nji,nj->ni", site_to_world, world_acc - m.opt.gravity))

    def check(self, qpos: np.ndarray, qvel: np.ndarray, qacc: np.ndarray, samples: SiteSamples, rows: np.ndarray,
              rel_tol: float = 1e-9) -> None:
        """Raise if ``samples`` (:meth:`kinematics` at the N states) differ on ``rows`` from MuJoCo's sensors
        (:meth:`sample`) by more than ``rel_tol`` times each quantity's largest magnitude there (quaternions up
        to sign)."""
        rows = np.asarray(rows)
        mujoco_samples = self.sample(qpos[rows], qvel[rows], qacc[rows])
        for name in ("pos", "vel", "quat", "gyr", "acc"):
            ours, theirs = getattr(samples, name)[rows], getattr(mujoco_samples, name)
            if name == "quat":
                ours = ours * np.sign(np.einsum("ij,ij->i", ours, theirs))[:, None]
            error = np.abs(ours - theirs).max(axis=1)
            # the tolerance's scale: the quantity's range on these rows, floored for rows that barely move
            scale = max(np.abs(theirs).max(), 1.0 if name in ("pos", "quat") else 1e-3)
            worst = int(np.argmax(error))
            if error[worst] > rel_tol * scale:
                raise RuntimeError(f"IMU-site {name}: the rigid-body formulas differ from MuJoCo's sensors by "
                                   f"{error[worst]:.3g} at state row {int(rows[worst])} (allowed {rel_tol:g} x "
                                   f"{scale:.3g}); the foot model and the formulas no longer describe the same foot")

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


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of (N, 3) arrays: numpy's arithmetic (``a1 b2 - a2 b1``, ...) without its
    broadcasting machinery."""
    a0, a1, a2 = a.T
    b0, b1, b2 = b.T
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def continuous_sign(q: np.ndarray) -> np.ndarray:
    """Flip quaternion signs so consecutive samples lie in the same hemisphere, the first with w >= 0."""
    flips = np.concatenate([[q[0, 0] < 0], np.einsum("ij,ij->i", q[1:], q[:-1]) < 0])
    return q * np.where(np.cumsum(flips) % 2 == 1, -1.0, 1.0)[:, None]
