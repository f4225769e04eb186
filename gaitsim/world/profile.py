"""C4 joint trajectories of the kinematic foot from a stance plan.

The foot body's origin is the heel contact point; the toe contact point sits ``toe_length`` ahead on the foot's
x axis. Joints (MuJoCo chain, outermost first): slide x, y, z of the heel point in the world, then yaw (z),
pitch (y') and roll (x''), so the foot attitude is Rz(yaw) Ry(pitch) Rx(roll).

- Heel rocker [t_ic, t_ff]: rotation about the heel contact (fixed but for heel-strike compression and stance
  micro-motion). Its last ``slap_duration_s`` stop the forefoot: pitch rate ``slap_rate * (1 - smoothstep)``.
  A forefoot strike rotates about the toe contact instead (toe rocker), and its last ``slap_duration_s`` stop
  the heel coming down: pitch rate ``-slap_rate * (1 - smoothstep)``.
- Foot flat [t_ff, t_ho]: still, but for micro-motion, the optional stance roll-over (roll about the
  heel-toe axis, which moves neither contact point) and the optional sustained stance rotation (about a pivot
  on the heel-toe line; its angles are held through the push-off and returned over the swing).
- Push-off [t_ho, t_to]: rotation about the toe contact, whose position follows the micro-motion.
- Swing [t_to, t_ic']: degree-9 Hermite of the heel point matching position and derivatives 1..4 at both ends,
  plus a C4 lift (height) and sideways excursion; yaw turns to the next stance with a C4 smoothstep.
"""

from __future__ import annotations

import numpy as np

from nav import quaternion as quat

from . import smooth
from .gait import GaitParams, ImpactParams, StancePlan, Walk

JOINTS = ("x", "y", "z", "yaw", "pitch", "roll")


def _rot_z(yaw: float) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def pitch_profile(plan: StancePlan, gait: GaitParams, impact: ImpactParams) -> smooth.Piecewise:
    """Foot pitch (rad) of a walk: a Hermite through knots (value, rate, acceleration, 0, 0) at each stance's
    heel strike (its drawn pitch, ``pitch_rate_heel_strike``, ``pitch_accel_heel_strike``), start of the
    forefoot slap (``slap_rate``, with the angle left to stop at that rate), foot flat and heel off (level and
    still) and toe off (its drawn pitch, ``pitch_rate_toe_off``, ``pitch_accel_toe_off``); level at the start
    and the end. The slap turns the foot toward level: toes down after a heel strike, heel down after a forefoot
    strike."""
    n = plan.n_strides
    slap_rate = -impact.slap_rate if gait.forefoot_strike else impact.slap_rate
    strike = (gait.pitch_rate_heel_strike, gait.pitch_accel_heel_strike)
    toe_off = (gait.pitch_rate_toe_off, gait.pitch_accel_toe_off)
    knots = [(0.0, 0.0, 0.0, 0.0)]
    for k in range(n + 1):
        if k > 0:
            knots += [
                (plan.t_ic[k], plan.pitch_hs[k], *strike),
                (plan.t_ff[k] - impact.slap_duration_s, -0.5 * slap_rate * impact.slap_duration_s, slap_rate, 0.0),
                (plan.t_ff[k], 0.0, 0.0, 0.0),
            ]
        if k < n:
            knots += [(plan.t_ho[k], 0.0, 0.0, 0.0), (plan.t_to[k], plan.pitch_to[k], *toe_off)]
    knots.append((plan.t_end, 0.0, 0.0, 0.0))
    kn = np.array(knots)
    keep = np.concatenate([[True], np.diff(kn[:, 0]) > 0])  # stance 0 starts at t = 0
    stacks = np.zeros((keep.sum(), smooth.NDER))
    stacks[:, :3] = kn[keep, 1:]
    return smooth.hermite(kn[keep, 0], stacks)


class FootTrajectory:
    """Joint trajectories of one walk.

    Parameters
    ----------
    walk : Walk
    plan : StancePlan
    toe_length : m, heel-to-toe contact distance of the foot model.
    """

    def __init__(self, walk: Walk, plan: StancePlan, toe_length: float):
        self.walk, self.plan, self.toe_length = walk, plan, toe_length
        g, imp, mm = walk.gait, walk.impact, walk.micro
        n = plan.n_strides
        self.walk_yaw = np.unwrap(plan.yaw)
        self.foot_yaw = self.walk_yaw + g.toe_out
        self.frames = [_rot_z(y) for y in self.walk_yaw]

        self.pitch = pitch_profile(plan, g, imp)

        # stance contact displacement (walking frame): heel-strike compression + micro-motion
        v_hs = np.asarray(imp.heel_strike_velocity_mps, float)
        self.compression = v_hs * imp.heel_strike_duration_s / 2
        self.contact: list[list[list[smooth.Piecewise]]] = []  # [stance][axis] -> pieces
        for k in range(n + 1):
            axes: list[list[smooth.Piecewise]] = [[], [], []]
            if k > 0:
                t0, t1 = plan.t_ic[k], plan.t_ic[k] + imp.heel_strike_duration_s
                for a in range(3):
                    axes[a].append(smooth.hermite([t0, t1], [[0, v_hs[a], 0, 0, 0], [self.compression[a], 0, 0, 0, 0]]))
            if k > 0 and imp.ringing_hz > 0 and imp.ringing_accel_mps2 != 0:
                axes[2] += [smooth.Ringing(t_event, imp.ringing_hz, imp.ringing_damping, imp.ringing_accel_mps2)
                            for t_event in (plan.t_ic[k], plan.t_ff[k])]
            if plan.walking[k] and mm.enabled:
                for a in range(3):
                    axes[a] += [
                        smooth.plateau_displacement(plan.t_ff[k], plan.t_ho[k], mm.creep_ramp_s, mm.creep_velocity_mps[a]),
                        smooth.pulse_displacement(plan.t_ff[k], mm.settle_duration_s, mm.settle_velocity_mps[a]),
                        smooth.pulse_displacement(plan.t_ho[k] - mm.heel_off_duration_s / 2, mm.heel_off_duration_s,
                                                  mm.heel_off_velocity_mps[a]),
                    ]
            self.contact.append(axes)
        self.rotation = self._build_stance_rotation()
        self.heel_base = [
            np.array([plan.pos[k, 0], plan.pos[k, 1], 0.0]) - (self.frames[k] @ self.compression if k > 0 else 0.0)
            for k in range(n + 1)
        ]
        self._contact_at_heel_off = [self._contact_stack(k, np.array([plan.t_ho[k]]))[:, 0, :] for k in range(n)]
        self._toe_at_heel_off = [
            self._stance_heel(k, np.array([plan.t_ho[k]]))[:, 0, 0] + self._toe_vector(k) for k in range(n)
        ]
        self._swings = [self._build_swing(k) for k in range(n)]
        self.stance_roll = self._build_stance_roll()

    def _build_stance_roll(self) -> smooth.Piecewise | None:
        """Roll-over of the walking stances: rate +w at t_ff falling linearly to -w at t_ho (a quadratic angle),
        joined C4 to zero at t_ic and t_to."""
        plan, mm = self.plan, self.walk.micro
        rate = mm.stance_roll_rate
        if not (mm.enabled and rate and plan.walking.any()):
            return None
        knots, stacks = [], []
        for k in np.flatnonzero(plan.walking):
            flat = plan.t_ho[k] - plan.t_ff[k]
            edge = rate * (plan.t_ff[k] - plan.t_ic[k]) / 2  # roll reached at foot flat
            knots += [plan.t_ic[k], plan.t_ff[k], plan.t_ho[k], plan.t_to[k]]
            stacks += [[0, 0, 0, 0, 0], [edge, rate, -2 * rate / flat, 0, 0],
                       [edge, -rate, -2 * rate / flat, 0, 0], [0, 0, 0, 0, 0]]
        return smooth.hermite(np.array(knots), np.array(stacks, float))

    def _build_stance_rotation(self) -> dict | None:
        """Sustained stance rotation per walking stance k: (roll, pitch, yaw) angle pieces (rad) of the rate
        plateau inside foot flat, and the angles (3,) rad reached at heel off."""
        plan, mm = self.plan, self.walk.micro
        rates = np.asarray(mm.stance_rotation_rate, float)
        if not (mm.enabled and np.any(rates) and plan.walking.any()):
            return None
        ramp = mm.creep_ramp_s
        return {int(k): ([smooth.plateau_displacement(plan.t_ff[k] + ramp, plan.t_ho[k] - ramp, ramp, r) for r in rates],
                         rates * (plan.t_ho[k] - plan.t_ff[k] - ramp))
                for k in np.flatnonzero(plan.walking)}

    def _rotation_of(self, k: int, t: np.ndarray) -> np.ndarray:
        """(3, 5, N) stacks of stance k's sustained-rotation angles (roll, pitch, yaw), rad: zero before its foot
        flat, rising through it, held through the push-off, returned to zero over the following swing."""
        out = np.zeros((3, smooth.NDER, t.size))
        if self.rotation is None or k not in self.rotation:
            return out
        pieces, held = self.rotation[k]
        swing = self.plan.t_ic[k + 1] - self.plan.t_to[k]
        for a in range(3):
            out[a] = pieces[a].stack(t) + smooth.smoothstep_stack(t, self.plan.t_to[k], swing, 0.0, -held[a])
        return out

    # -- pieces ---------------------------------------------------------------------------------------------

    @staticmethod
    def _x_axis(yaw: np.ndarray, pitch: np.ndarray) -> np.ndarray:
        """(3, 5, N) stack of the foot's x axis in the world, (cos p cos y, cos p sin y, -sin p), from the
        stacks of yaw and pitch (roll does not move it)."""
        cos_y, sin_y = smooth.compose_trig(yaw)
        cos_p, sin_p = smooth.compose_trig(pitch)
        return np.stack([smooth.product(cos_p, cos_y), smooth.product(cos_p, sin_y), -sin_p])

    def _held_angles(self, k: int) -> np.ndarray:
        """(roll, pitch, yaw) rad of stance k's sustained rotation from heel off to toe off (zero without it)."""
        return self.rotation[k][1] if self.rotation is not None and k in self.rotation else np.zeros(3)

    def _toe_vector(self, k: int) -> np.ndarray:
        """Heel-to-toe contact vector (m, world) at stance k's heel off."""
        _, pitch, yaw = self._held_angles(k)
        c = np.cos(pitch)
        return self.toe_length * np.array([c * np.cos(self.foot_yaw[k] + yaw), c * np.sin(self.foot_yaw[k] + yaw),
                                           -np.sin(pitch)])

    def _contact_stack(self, k: int, t: np.ndarray) -> np.ndarray:
        """(3, 5, N) world-frame derivative stacks of the stance-k contact displacement."""
        local = np.zeros((3, smooth.NDER, t.size))
        for a in range(3):
            for piece in self.contact[k][a]:
                local[a] += piece.stack(t)
        return np.einsum("ij,jdn->idn", self.frames[k], local)

    def _stance_heel(self, k: int, t: np.ndarray) -> np.ndarray:
        """(3, 5, N) heel point during [t_ic, t_ho] of stance k.

        After a forefoot strike the foot turns about its toe contact until foot flat (the gait's pitch is zero
        from there to heel off): heel += L (u0 - x_axis(pitch)), u0 the level heel-to-toe direction.

        A sustained stance rotation first yaws the heel-toe line about the yaw pivot (a fraction f_y of the way
        to the toe), turning its horizontal direction from u0 to u, then pitches it about the pitch pivot (f_p):
        heel += L (f_y (u0 - u) + f_p (u - x_axis)), L the heel-toe length."""
        out = self._contact_stack(k, t)
        out[:, 0] += self.heel_base[k][:, None]
        if self.walk.gait.forefoot_strike and k > 0:
            yaw = np.zeros((smooth.NDER, t.size))
            yaw[0] = self.foot_yaw[k]
            level = self._x_axis(yaw, np.zeros_like(yaw))
            out += self.toe_length * (level - self._x_axis(yaw, self.pitch.stack(t)))
        if self.rotation is not None and k in self.rotation:
            _, pitch, yaw = self._rotation_of(k, t)
            yaw[0] += self.foot_yaw[k]
            u = self._x_axis(yaw, np.zeros_like(pitch))
            u0 = np.zeros((3, smooth.NDER, 1))
            u0[:, 0, 0] = np.cos(self.foot_yaw[k]), np.sin(self.foot_yaw[k]), 0.0
            f_pitch, f_yaw = self.walk.micro.stance_rotation_pivot_frac
            out += self.toe_length * (f_yaw * (u0 - u) + f_pitch * (u - self._x_axis(yaw, pitch)))
        return out

    def _push_off_heel(self, k: int, t: np.ndarray) -> np.ndarray:
        """(3, 5, N) heel point during [t_ho, t_to]: rotation about the (micro-moving) toe contact."""
        out = self._contact_stack(k, t)
        out[:, 0] -= self._contact_at_heel_off[k]
        _, held_pitch, held_yaw = self._held_angles(k)
        pitch = self.pitch.stack(t)
        pitch[0] += held_pitch
        yaw = np.zeros_like(pitch)
        yaw[0] = self.foot_yaw[k] + held_yaw
        out -= self.toe_length * self._x_axis(yaw, pitch)
        out[:, 0] += self._toe_at_heel_off[k][:, None]
        return out

    def _build_swing(self, k: int) -> list[smooth.Piecewise]:
        t0, t1 = self.plan.t_to[k], self.plan.t_ic[k + 1]
        start = self._push_off_heel(k, np.array([t0]))[:, :, 0]
        end = self._stance_heel(k + 1, np.array([t1]))[:, :, 0]
        return [smooth.hermite([t0, t1], [start[a], end[a]]) for a in range(3)]

    def _swing_heel(self, k: int, t: np.ndarray) -> np.ndarray:
        plan, g = self.plan, self.walk.gait
        t0, t1 = plan.t_to[k], plan.t_ic[k + 1]
        out = np.stack([p.stack(t) for p in self._swings[k]])
        z_mid = self._swings[k][2].stack(np.array([0.5 * (t0 + t1)]))[0, 0]
        out[2] += smooth.lift(t, t0, t1 - t0, g.swing_height_m - z_mid)
        mid_yaw = 0.5 * (self.walk_yaw[k] + self.walk_yaw[k + 1])
        side = smooth.lift(t, t0, t1 - t0, g.swing_lateral_m)
        out[0] -= np.sin(mid_yaw) * side
        out[1] += np.cos(mid_yaw) * side
        return out

    # -- public ---------------------------------------------------------------------------------------------

    def heel(self, t: np.ndarray) -> np.ndarray:
        """(3, 5, N) derivative stacks of the heel contact point (m, world) at times ``t`` (s)."""
        t = np.asarray(t, float)
        plan = self.plan
        out = np.zeros((3, smooth.NDER, t.size))
        for k in range(plan.n_strides + 1):
            m = (t >= plan.t_ic[k]) & (t < plan.t_ho[k]) if k < plan.n_strides else t >= plan.t_ic[k]
            if m.any():
                out[:, :, m] = self._stance_heel(k, t[m])
            if k < plan.n_strides:
                m = (t >= plan.t_ho[k]) & (t < plan.t_to[k])
                if m.any():
                    out[:, :, m] = self._push_off_heel(k, t[m])
                m = (t >= plan.t_to[k]) & (t < plan.t_ic[k + 1])
                if m.any():
                    out[:, :, m] = self._swing_heel(k, t[m])
        return out

    def angles(self, t: np.ndarray) -> np.ndarray:
        """(3, 5, N) derivative stacks of (yaw, pitch, roll) in rad at times ``t`` (s)."""
        t = np.asarray(t, float)
        plan, g = self.plan, self.walk.gait
        yaw = np.zeros((smooth.NDER, t.size))
        yaw[0] = self.foot_yaw[0]
        roll = np.zeros((smooth.NDER, t.size))
        pitch = self.pitch.stack(t)
        for k in range(plan.n_strides):
            dur = plan.t_ic[k + 1] - plan.t_to[k]
            yaw += smooth.smoothstep_stack(t, plan.t_to[k], dur, 0.0, self.foot_yaw[k + 1] - self.foot_yaw[k])
            roll += smooth.lift(t, plan.t_to[k], dur, g.swing_roll)
        if self.stance_roll is not None:
            roll += self.stance_roll.stack(t)
        for k in (self.rotation or {}):
            d_roll, d_pitch, d_yaw = self._rotation_of(k, t)
            roll += d_roll
            pitch += d_pitch
            yaw += d_yaw
        return np.stack([yaw, pitch, roll])

    def joints(self, t: np.ndarray) -> np.ndarray:
        """(6, 5, N) derivative stacks of the joints (x, y, z, yaw, pitch, roll) at times ``t`` (s)."""
        return np.concatenate([self.heel(t), self.angles(t)])

    def point(self, t: np.ndarray, lever_arm: np.ndarray) -> np.ndarray:
        """(N, 3) m: world position at times ``t`` (s) of the foot point ``lever_arm`` (m, foot frame, from the
        heel contact)."""
        t = np.asarray(t, float)
        yaw, pitch, roll = self.angles(t)[:, 0]
        rotation = quat.to_matrix(quat.from_euler_zyx(yaw, pitch, roll))
        return self.heel(t)[:, 0, :].T + rotation @ np.asarray(lever_arm, float)

    def stance_displacement(self, lever_arm: np.ndarray = np.zeros(3)) -> np.ndarray:
        """(n+1, 3) m: exact displacement over foot flat [t_ff, t_ho] of the foot point ``lever_arm`` (m, foot
        frame; the IMU site's for the truth)."""
        p = self.plan
        return self.point(p.t_ho, lever_arm) - self.point(p.t_ff, lever_arm)
