"""C4 joint trajectories of the kinematic foot from a stance plan.

The foot body's origin is the heel contact point; the toe contact point sits ``toe_length`` ahead on the foot's
x axis. Joints (MuJoCo chain, outermost first): slide x, y, z of the heel point in the world, then yaw (z),
pitch (y') and roll (x''), so the foot attitude is Rz(yaw) Ry(pitch) Rx(roll).

- Stance [t_ic, t_to]: the foot rolls on the ground without slipping (:class:`RollingSole`): the heel point is
  a function of the foot's pitch alone, about the heel contact in the heel rocker, over the sole while the foot
  is near level, about the toe contact in the push-off (and, after a forefoot strike, from the toe contact down
  to foot flat: the same function of pitch, run backwards). On top: heel-strike compression, the contact's creep
  (:class:`gaitsim.world.gait.MicroMotionParams`), impact ringing, the optional stance roll-over (roll about the
  heel-toe axis, which moves neither contact point) and the optional sustained roll and yaw (the yaw about a
  pivot on the heel-toe line; angles held through the push-off and returned over the swing).
- Pitch: a Hermite through knots at heel strike, the start of the forefoot slap, foot flat (level, rising at the
  heel-rise rate), heel off, toe off and, if set, the swing's pitch maximum (:func:`pitch_profile`).
- Push-off release: over its last ``toe_release_s`` the toe contact slides forward, its acceleration rising C4 to
  ``toe_release_accel_mps2`` at toe off, so the foot leaves the ground already moving forward.
- Swing [t_to, t_ic']: degree-9 Hermite of the heel point matching position and derivatives 1..4 at both ends,
  plus a C4 lift (height), a C4 lead along the walking direction (``swing_lead``: the heel's forward travel
  redistributed over the swing) and a sideways excursion; yaw turns to the next stance with a C4 smoothstep.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nav import quaternion as quat

from . import smooth
from .gait import GaitParams, ImpactParams, MicroMotionParams, StancePlan, Walk

JOINTS = ("x", "y", "z", "yaw", "pitch", "roll")


def _rot_z(yaw: float) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def heel_rise_rates(micro: MicroMotionParams, foot_flat: float, scale: float = 1.0) -> tuple[float, float]:
    """Pitch rates (rad/s) of a walking stance at foot flat and at heel off, ``foot_flat`` s later: the heel
    rise (times the stance's ``scale``) plus the sustained stance rotation's pitch; both zero for a still foot
    (``enabled`` False)."""
    if not micro.enabled:
        return 0.0, 0.0
    start = scale * micro.heel_rise_rate_start + micro.stance_rotation_rate[1]
    return start, start + scale * micro.heel_rise_growth * foot_flat**2


def swing_maximum(plan: StancePlan, gait: GaitParams) -> tuple[np.ndarray, np.ndarray]:
    """Times (s) and pitches (rad), (n,) each, of the pitch maximum of every swing (the one after stance k's toe
    off): where a steady deceleration at ``pitch_accel_to_swing_max`` (a < 0) stops the toe-off rate w,
    ``w / |a|`` after toe off and ``w^2 / (2 |a|)`` above the stance's toe-off pitch; empty without that knot
    (``pitch_accel_to_swing_max`` 0)."""
    if not gait.pitch_accel_to_swing_max < 0:
        return np.zeros(0), np.zeros(0)
    stop_s = gait.pitch_rate_toe_off / -gait.pitch_accel_to_swing_max
    return plan.t_to[:-1] + stop_s, plan.pitch_to[:-1] + 0.5 * gait.pitch_rate_toe_off * stop_s


def pitch_profile(plan: StancePlan, gait: GaitParams, impact: ImpactParams,
                  micro: MicroMotionParams = MicroMotionParams()) -> smooth.Piecewise:
    """Foot pitch (rad) of a walk: a Hermite through knots (value and derivatives 1..4).

    Knots of a walking stance: heel strike (its drawn pitch, ``pitch_rate_heel_strike``,
    ``pitch_accel_heel_strike``); start of the forefoot slap (``slap_rate``, the angle left to reach
    the foot-flat rate linearly); foot flat (level) and heel off, between which the pitch rate grows from the
    first to the second heel-rise rate of :func:`heel_rise_rates` with the square of the time since foot flat
    (a cubic pitch, given exactly by its derivatives at both knots); toe off (its drawn pitch,
    ``pitch_rate_toe_off``, ``pitch_accel_toe_off``); with ``pitch_accel_to_swing_max`` (a < 0) set, the
    swing's pitch maximum (:func:`swing_maximum`): zero rate, acceleration a and jerk a^2 / pitch_rate_toe_off,
    so the acceleration returns to zero in the time it took to stop the toe-off rotation (a flat maximum would be
    a still foot in mid-swing, which the stance detectors take for a stance). Derivatives not named are zero.
    Standing stances at the start and end are level and still. The slap turns the foot toward level: toes down
    after a heel strike, heel down after a forefoot strike."""
    n = plan.n_strides
    slap_rate = -impact.slap_rate if gait.forefoot_strike else impact.slap_rate
    strike = (gait.pitch_rate_heel_strike, gait.pitch_accel_heel_strike)
    toe_off = (gait.pitch_rate_toe_off, gait.pitch_accel_toe_off)
    t_max, pitch_max = swing_maximum(plan, gait)
    reversal = gait.pitch_accel_to_swing_max
    turn = (reversal, reversal**2 / gait.pitch_rate_toe_off) if t_max.size else ()  # relaxes as fast as it stopped
    knots = [(0.0, 0.0, 0.0, 0.0, 0.0)]
    for k in range(n + 1):
        flat = plan.t_ho[k] - plan.t_ff[k]
        start, end = heel_rise_rates(micro, flat, plan.rate_scale[k, 0]) if plan.walking[k] else (0.0, 0.0)
        jerk = 2.0 * (end - start) / flat**2  # third derivative of the cubic pitch
        if k > 0:
            slap = impact.slap_duration_s
            knots += [
                (plan.t_ic[k], plan.pitch_hs[k], *strike, 0.0),
                (plan.t_ff[k] - slap, -0.5 * (slap_rate + start) * slap, slap_rate, 0.0, 0.0),
                (plan.t_ff[k], 0.0, start, 0.0, jerk),
            ]
        if k < n:
            knots += [(plan.t_ho[k], (start + (end - start) / 3.0) * flat, end, jerk * flat, jerk),
                      (plan.t_to[k], plan.pitch_to[k], *toe_off, 0.0)]
            if t_max.size:
                knots.append((t_max[k], pitch_max[k], 0.0, *turn))
    knots.append((plan.t_end, 0.0, 0.0, 0.0, 0.0))
    kn = np.array(knots)
    keep = np.concatenate([[True], np.diff(kn[:, 0]) > 0])  # stance 0 starts at t = 0
    stacks = np.zeros((keep.sum(), smooth.NDER))
    stacks[:, :4] = kn[keep, 1:]
    return smooth.hermite(kn[keep, 0], stacks)


class RollingSole:
    """The foot's sagittal roll on level ground as a function of its pitch theta (rad, toes down positive).

    The sole is a convex curve from the heel contact to the toe contact (``toe_length`` L apart on the foot's
    x axis) that rolls on the ground without slipping. Its contact lies ``s'(theta)`` ahead of the heel point
    (horizontally), where ``s(theta)`` is the heel point's height: s = 0 (heel on the ground) for theta up to
    -b, s = L sin(theta) (toe on the ground) from +b, with b half of ``transfer_pitch``, and in between

        s'(theta) = L sigma(theta) cos(theta),   sigma = SMOOTHSTEP((theta + b) / (2 b)),

    so the contact moves from heel to toe as the foot pitches through +-b (the symmetric smoothstep puts the
    toe exactly on the ground at +b: the integral of sigma cos over [-b, b] is sin b). Rolling without slip
    moves the heel point forward by ``dX/dtheta = s + contact_radius``: the rolling centre sits
    ``contact_radius`` below the sole (compliance), so the sole's ground contact slides forward at pitch rate
    times that depth. On (-b, b) the cosine is its Taylor polynomial (degree ``TAYLOR_DEGREE``, exact to
    round-off for any b below 0.5 rad), so s and X are polynomials in ``u = (theta + b) / (2 b)``, integrated
    exactly and well conditioned; the joins at +-b are C4 (sigma's derivatives 1..4 vanish there).

    Parameters
    ----------
    toe_length : m, heel-to-toe contact distance L.
    transfer_pitch : rad, 2 b (> 0).
    contact_radius : m, depth of the rolling centre below the sole.
    """

    TAYLOR_DEGREE = 24

    def __init__(self, toe_length: float, transfer_pitch: float, contact_radius: float):
        self.length, self.half, self.radius = float(toe_length), 0.5 * float(transfer_pitch), float(contact_radius)
        b, span = self.half, float(transfer_pitch)
        poly = np.polynomial.polynomial
        # cos(theta) with theta = b (2 u - 1), as a polynomial in u
        cos_u = np.zeros(1)
        for n in range(0, self.TAYLOR_DEGREE + 1, 2):
            term = poly.polypow([-b, 2 * b], n) * (-1) ** (n // 2) / math.factorial(n)
            cos_u = poly.polyadd(cos_u, term)
        slope = self.length * poly.polymul(smooth.SMOOTHSTEP, cos_u)  # s'(theta) in u
        height = poly.polyint(slope) * span  # s in u (zero at u = 0: ds = s' dtheta = s' 2b du)
        travel = poly.polyint(height) * span  # integral of s from -b, in u
        # d^j/dtheta^j of s for j = 0..4, as polynomials in u (d/dtheta = d/du / 2b)
        height_derivatives = [height, slope]
        for _ in range(3):
            height_derivatives.append(poly.polyder(height_derivatives[-1]) / span)
        self._travel_end = float(poly.polyval(1.0, travel))
        # the six polynomials (s, its derivatives 1..4, X) as rows, zero-padded at the top: one Horner pass
        # of exactly numpy's polyval arithmetic (a zero top row keeps the running value +0)
        rows = [*height_derivatives, travel]
        self._rows = np.zeros((len(rows), max(len(c) for c in rows)))
        for i, c in enumerate(rows):
            self._rows[i, :len(c)] = c
        self._level = 0.0
        self._level = float(self._stacks(np.zeros(1))[0][0, 0])  # heel travel of the level foot

    def _stacks(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(5, N) each: the heel's forward travel X and height s (m) and their derivatives 1..4 with respect to
        the pitch, at pitch ``theta`` (rad); X is zero for the level foot."""
        theta = np.asarray(theta, float)
        b, length = self.half, self.length
        travel = np.zeros((smooth.NDER, theta.size))
        height = np.zeros((smooth.NDER, theta.size))
        mid = (theta > -b) & (theta < b)
        if mid.any():
            u = (theta[mid] + b) / (2 * b)
            value = self._rows[:, -1:] + u * 0  # numpy.polynomial.polynomial.polyval on every row
            for column in self._rows[:, -2::-1].T:  # value = column + value u, in place
                value *= u
                value += column[:, None]
            height[:, mid] = value[:-1]
            travel[0, mid] = value[-1]
        toe = theta >= b
        if toe.any():
            c, s = np.cos(theta[toe]), np.sin(theta[toe])
            height[:, toe] = length * np.stack([s, c, -s, -c, s])
            travel[0, toe] = self._travel_end + length * (np.cos(b) - c)
        travel[1:] = height[:-1]
        travel[0] += self.radius * theta - self._level
        travel[1] += self.radius
        return travel, height

    def heel(self, pitch: np.ndarray) -> np.ndarray:
        """(2, 5, N): forward travel X and height s (m) of the heel point relative to the level foot, with their
        time derivatives 1..4, from the derivative stack ``pitch`` (5, N) of the foot's pitch (rad)."""
        travel, height = self._stacks(pitch[0])
        return np.stack([smooth.compose(travel, pitch), smooth.compose(height, pitch)])

    def contact_offset(self, pitch: np.ndarray) -> np.ndarray:
        """(N,) m: horizontal distance from the heel point forward to the ground contact at pitch (rad)."""
        return self._stacks(np.asarray(pitch, float))[1][1]

    def heel_height(self, pitch: np.ndarray) -> np.ndarray:
        """(N,) m: height of the heel point above the ground contact at pitch (rad)."""
        return self._stacks(np.asarray(pitch, float))[1][0]


class StancePieces:
    """One function per listed stance, each added to the samples of its own stance only.

    Parameters
    ----------
    stances : (M,) int, the stances that have a function, increasing.
    functions : M :class:`smooth.Piecewise` of the same degree (packed in one :class:`smooth.PieceTable`), or
        M lists of other functions with a ``stack(t)`` method (e.g. :class:`smooth.Ringing`), evaluated one by
        one.
    """

    def __init__(self, stances, functions: list):
        self.stances = np.asarray(stances, int)
        self.functions = functions
        self.table = smooth.PieceTable(functions) if isinstance(functions[0], smooth.Piecewise) else None

    def add_to(self, out: np.ndarray, t: np.ndarray, stance: np.ndarray) -> None:
        """``out`` (5, N) += the stacks at increasing times ``t`` (N,) s of the functions of the stances
        ``stance`` (N,) int, non-decreasing; samples of a stance without a function are left alone."""
        start = np.searchsorted(stance, self.stances, side="left")
        stop = np.searchsorted(stance, self.stances, side="right")
        if self.table is not None:
            self.table.add_to(out, t, start, stop)
            return
        for a, b, pieces in zip(start, stop, self.functions):
            for piece in pieces:
                out[:, a:b] += piece.stack(t[a:b])


@dataclass
class StanceRotation:
    """Foot-flat roll and yaw of the walking stances: per axis, the kinds of pieces in the order added.

    Attributes
    ----------
    stances : (M,) int, the walking stances.
    t0, t1 : (M,) s, each stance's span, from its first piece's start to its last piece's end (disjoint).
    roll, yaw : lists of StancePieces (rad).
    """

    stances: np.ndarray
    t0: np.ndarray
    t1: np.ndarray
    roll: list[StancePieces]
    yaw: list[StancePieces]


class FootTrajectory:
    """Joint trajectories of one walk.

    The pieces of the same kind of all stances (or swings) are packed and evaluated together: every sample
    gets the same arithmetic as from its own stance's pieces one by one.

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
        self.frames = np.array([_rot_z(y) for y in self.walk_yaw])  # (n+1, 3, 3) walking frame -> world
        self.heading = np.array([[np.cos(y), np.sin(y)] for y in self.foot_yaw])  # (n+1, 2) foot's heading

        self.pitch = pitch_profile(plan, g, imp, mm)
        self.sole = RollingSole(toe_length, mm.contact_transfer_pitch, mm.contact_radius_m)

        # stance contact displacement (walking frame), per axis in the order added: heel-strike compression,
        # impact ringing (vertical), creep, toe release (forward)
        v_hs = np.asarray(imp.heel_strike_velocity_mps, float)
        self.compression = v_hs * imp.heel_strike_duration_s / 2
        strikes = np.arange(1, n + 1)
        self.contact: list[list[StancePieces]] = [[] for _ in range(3)]
        if n:
            for a in range(3):
                self.contact[a].append(StancePieces(strikes, [
                    smooth.hermite([plan.t_ic[k], plan.t_ic[k] + imp.heel_strike_duration_s],
                                   [[0, v_hs[a], 0, 0, 0], [self.compression[a], 0, 0, 0, 0]]) for k in strikes]))
            if imp.ringing_hz > 0 and imp.ringing_accel_mps2 != 0:
                self.contact[2].append(StancePieces(strikes, [
                    [smooth.Ringing(t_event, imp.ringing_hz, imp.ringing_damping, imp.ringing_accel_mps2)
                     for t_event in (plan.t_ic[k], plan.t_ff[k])] for k in strikes]))
        creeping = np.flatnonzero(plan.walking) if mm.enabled else np.zeros(0, int)
        if creeping.size:
            for a in np.flatnonzero(mm.creep_velocity_mps):
                self.contact[a].append(StancePieces(creeping, [
                    smooth.plateau_displacement(plan.t_ff[k], plan.t_ho[k], mm.creep_ramp_s,
                                                mm.creep_velocity_mps[a]) for k in creeping]))
        if n and g.toe_release_accel_mps2:  # forward in the walking frame, before each swing
            self.contact[0].append(StancePieces(np.arange(n), [
                smooth.release(plan.t_to[k], g.toe_release_s, g.toe_release_accel_mps2) for k in range(n)]))
        self.rotation = self._build_stance_rotation()
        self.heel_base = np.array([
            np.array([plan.pos[k, 0], plan.pos[k, 1], 0.0]) - (self.frames[k] @ self.compression if k > 0 else 0.0)
            for k in range(n + 1)
        ])
        # heel stacks at each stance's initial contact and toe off: (3, 5, 2 (n+1)), ic and to of each in turn
        t_ends = np.stack([plan.t_ic, plan.t_to], axis=1).ravel()
        ends = self._stance_heel(t_ends, self.pitch.stack(t_ends), np.repeat(np.arange(n + 1), 2))
        if n:
            self._build_swings(ends)
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

    def _build_stance_rotation(self) -> StanceRotation | None:
        """Roll and yaw of the foot flat of the walking stances: the pieces (rad) of roll (the pronation held
        through foot flat and the loading pulse, a left foot's mirrored for a right one, plus the sustained
        rotation's roll) and of yaw (the sustained rotation's), each ending with the return of the angle reached
        by heel off to zero over the following swing. (The sustained pitch is part of the heel rise:
        :func:`heel_rise_rates`.)"""
        plan, mm = self.plan, self.walk.micro
        mirror = -1.0 if mm.foot == "right" else 1.0
        roll, yaw = np.asarray(mm.stance_rotation_rate, float)[[0, 2]]
        if not (mm.enabled and (roll or yaw or mm.pronation_rate or mm.loading_roll_rate) and plan.walking.any()):
            return None
        ramp = mm.creep_ramp_s
        walking = np.flatnonzero(plan.walking)
        per_stance = []  # ([held roll, loading, return], [held yaw, return]) of each walking stance
        for k in walking:
            scale = mirror * plan.rate_scale[k, 1]
            held = [smooth.plateau_displacement(plan.t_ff[k] + ramp, plan.t_ho[k] - ramp, ramp, rate)
                    for rate in (roll + scale * mm.pronation_rate, yaw)]
            loading = smooth.pulse_displacement(plan.t_ff[k] - self.walk.impact.slap_duration_s, mm.loading_duration_s,
                                                scale * mm.loading_roll_rate)
            pieces = ([held[0], loading], [held[1]])
            swing = plan.t_ic[k + 1] - plan.t_to[k]
            for axis in pieces:
                axis.append(smooth.smoothstep(plan.t_to[k], swing, 0.0, -sum(p.after for p in axis)))
            per_stance.append(pieces)
        roll_pieces, yaw_pieces = ([StancePieces(walking, [s[a][i] for s in per_stance])
                                    for i in range(len(per_stance[0][a]))] for a in range(2))
        return StanceRotation(walking, np.array([min(p.t0 for axis in s for p in axis) for s in per_stance]),
                              np.array([max(p.t1 for axis in s for p in axis) for s in per_stance]),
                              roll_pieces, yaw_pieces)

    def _rotation_stack(self, t: np.ndarray, stance: np.ndarray) -> np.ndarray:
        """(2, 5, N) stacks at times ``t`` (N,) s of the foot-flat (roll, yaw) angles (rad) of the stances
        ``stance`` (N,) int: zero before the stance's foot flat, rising through it, held through the push-off,
        returned to zero over the following swing; zero for a stance without them."""
        out = np.zeros((2, smooth.NDER, t.size))
        for a, pieces in enumerate((self.rotation.roll, self.rotation.yaw) if self.rotation else ()):
            for piece in pieces:
                piece.add_to(out[a], t, stance)
        return out

    # -- pieces ---------------------------------------------------------------------------------------------

    def _stance_heel(self, t: np.ndarray, pitch: np.ndarray, stance: np.ndarray) -> np.ndarray:
        """(3, 5, N) heel point at times ``t`` (N,) s within [t_ic, t_to] of the stances ``stance`` (N,) int,
        non-decreasing, given the pitch stack (5, N) there: the contact displacement plus the roll on the sole
        along the foot's heading (:class:`RollingSole`); a sustained yaw turns that rolling offset about the
        vertical through the yaw pivot (a point on the level foot's heel-toe line, carried by the contact
        displacement)."""
        local = np.zeros((3, smooth.NDER, t.size))
        for a in range(3):
            for pieces in self.contact[a]:
                pieces.add_to(local[a], t, stance)
        frame = np.ascontiguousarray(self.frames[stance].transpose(1, 2, 0))  # (3, 3, N) walking frame -> world
        out = np.stack([frame[i, 0] * local[0] + frame[i, 1] * local[1] + frame[i, 2] * local[2] for i in range(3)])
        out[:, 0] += self.heel_base[stance].T
        travel, height = self.sole.heel(pitch)
        heading = self.heading[stance].T  # (2, N)
        rolled = heading[:, None, :] * travel
        out[2] += height
        if self.rotation is not None and self.walk.micro.stance_rotation_rate[2]:  # a yaw in the walking stances
            turned = np.isin(stance, self.rotation.stances)
            arm = self.walk.micro.stance_yaw_pivot_frac * self.toe_length * heading[:, turned]
            offset = rolled[:, :, turned]
            offset[:, 0] -= arm
            cos_y, sin_y = smooth.compose_trig(self._rotation_stack(t[turned], stance[turned])[1])
            offset = np.stack([smooth.product(cos_y, offset[0]) - smooth.product(sin_y, offset[1]),
                               smooth.product(sin_y, offset[0]) + smooth.product(cos_y, offset[1])])
            offset[:, 0] += arm
            rolled[:, :, turned] = offset
        out[:2] += rolled
        return out

    def _build_swings(self, ends: np.ndarray) -> None:
        """The swings' pieces, each kind packed in a :class:`smooth.PieceTable`: the heel point's Hermites
        (x, y, z), each from the heel's derivative stacks at toe off to those at the next initial contact
        (``ends`` (3, 5, 2 (n+1)): each stance's at initial contact and at toe off in turn), the lifts (raising
        the mid-swing heel to ``swing_height_m``), leads (``swing_lead``, along each swing's mean walking
        direction, in fractions of its horizontal travel) and sideways excursions (that direction turned left), and
        the foot's turns: yaw to the next stance, roll bump."""
        g, n, yaw = self.walk.gait, self.plan.n_strides, self.foot_yaw
        t0, t1 = self.plan.t_to[:-1], self.plan.t_ic[1:]
        self._swing_path = [smooth.PieceTable([smooth.hermite([t0[k], t1[k]], [ends[a, :, 2 * k + 1],
                                                                               ends[a, :, 2 * k + 2]])
                                               for k in range(n)]) for a in range(3)]
        z_mid = self._swing_path[2].stack(0.5 * (t0 + t1), np.arange(n))[0]
        self._swing_lift = smooth.PieceTable([smooth.lift(t0[k], t1[k] - t0[k], g.swing_height_m - z_mid[k])
                                              for k in range(n)])
        self._swing_side = smooth.PieceTable([smooth.lift(t0[k], t1[k] - t0[k], g.swing_lateral_m) for k in range(n)])
        travel = np.hypot(*(ends[:2, 0, 2::2] - ends[:2, 0, 1:-1:2]))  # (n,) m, each swing's horizontal travel
        self._swing_lead = smooth.PieceTable([
            smooth.lead(t0[k], t1[k] - t0[k], np.multiply(g.swing_lead, travel[k])) for k in range(n)
        ]) if any(g.swing_lead) else None
        mid_yaw = [0.5 * (self.walk_yaw[k] + self.walk_yaw[k + 1]) for k in range(n)]
        self._swing_sin = np.array([np.sin(y) for y in mid_yaw])
        self._swing_cos = np.array([np.cos(y) for y in mid_yaw])
        self._swing_yaw = smooth.PieceTable([smooth.smoothstep(t0[k], t1[k] - t0[k], 0.0, yaw[k + 1] - yaw[k])
                                             for k in range(n)])
        self._swing_roll = smooth.PieceTable([smooth.lift(t0[k], t1[k] - t0[k], g.swing_roll) for k in range(n)])

    def _swing_heel(self, t: np.ndarray, swing: np.ndarray) -> np.ndarray:
        """(3, 5, N) heel point at times ``t`` (N,) s within the swings ``swing`` (N,) int."""
        out = np.stack([path.stack(t, swing) for path in self._swing_path])
        out[2] += self._swing_lift.stack(t, swing)
        lateral = self._swing_side.stack(t, swing)
        out[0] -= self._swing_sin[swing] * lateral
        out[1] += self._swing_cos[swing] * lateral
        if self._swing_lead is not None:
            ahead = self._swing_lead.stack(t, swing)
            out[0] += self._swing_cos[swing] * ahead
            out[1] += self._swing_sin[swing] * ahead
        return out

    # -- public ---------------------------------------------------------------------------------------------

    def _heel(self, ts: np.ndarray, pitch: np.ndarray, out: np.ndarray) -> None:
        """Write into ``out`` (3, 5, N), zero on entry, the derivative stacks of the heel contact point (m, world)
        at increasing times ``ts`` (s), given the pitch stack (5, N) there."""
        plan = self.plan
        # stance k: [t_ic[k], t_to[k]) (the last to the end); swing k: [t_to[k], t_ic[k + 1])
        ic, to = np.searchsorted(ts, plan.t_ic), np.searchsorted(ts, plan.t_to)
        n = plan.n_strides
        rows = np.arange(ts.size)
        k = np.searchsorted(ic, rows, side="right") - 1  # the last stance begun by each sample
        stance = (k >= 0) & ((k == n) | (rows < to[np.minimum(k, n)]))
        swing = (k >= 0) & (k < n) & ~stance
        out[:, :, stance] = self._stance_heel(ts[stance], pitch[:, stance], k[stance])
        if swing.any():
            out[:, :, swing] = self._swing_heel(ts[swing], k[swing])

    def _angles(self, ts: np.ndarray, pitch: np.ndarray, out: np.ndarray) -> None:
        """Write into ``out`` (3, 5, N), zero on entry, the derivative stacks of (yaw, pitch, roll) in rad at
        increasing times ``ts`` (s), given the pitch stack (5, N) there; each piece is evaluated on its own
        window only."""
        plan = self.plan
        yaw, roll = out[0], out[2]
        roll_yaw = out[2::-2]  # a view of (roll, yaw)
        yaw[0] = self.foot_yaw[0]
        out[1] = pitch
        if plan.n_strides:
            smooth.accumulate(yaw, ts, plan.t_to[:-1], plan.t_ic[1:], self._swing_yaw.stack)
            smooth.accumulate(roll, ts, plan.t_to[:-1], plan.t_ic[1:], self._swing_roll.stack)
        if self.stance_roll is not None:
            smooth.accumulate(roll, ts, self.stance_roll.t0, self.stance_roll.t1,
                              lambda times, _: self.stance_roll.stack(times))
        if self.rotation is not None:
            smooth.accumulate(roll_yaw, ts, self.rotation.t0, self.rotation.t1,
                              lambda times, i: self._rotation_stack(times, self.rotation.stances[i]))

    def _sorted(self, t: np.ndarray, *parts) -> np.ndarray:
        """The stacks ``parts`` (methods of (ts, pitch, out) writing three joints' stacks) at times ``t`` (s) in
        any order, stacked: evaluated on the sorted times with one evaluation of the pitch, returned in the order
        of ``t``."""
        t = np.asarray(t, float).ravel()
        in_order = bool(np.all(t[1:] >= t[:-1]))  # a sampled record: no permutation
        order = None if in_order else np.argsort(t, kind="stable")
        ts = t if in_order else t[order]
        pitch = self.pitch.stack(ts)
        stacks = np.zeros((3 * len(parts), smooth.NDER, t.size))
        for i, part in enumerate(parts):
            part(ts, pitch, stacks[3 * i:3 * i + 3])
        if in_order:
            return stacks
        out = np.empty_like(stacks)
        out[:, :, order] = stacks
        return out

    def angles(self, t: np.ndarray) -> np.ndarray:
        """(3, 5, N) derivative stacks of (yaw, pitch, roll) in rad at times ``t`` (s)."""
        return self._sorted(t, self._angles)

    def joints(self, t: np.ndarray) -> np.ndarray:
        """(6, 5, N) derivative stacks of the joints (x, y, z, yaw, pitch, roll) at times ``t`` (s)."""
        return self._sorted(t, self._heel, self._angles)

    def point(self, t: np.ndarray, lever_arm: np.ndarray) -> np.ndarray:
        """(N, 3) m: world position at times ``t`` (s) of the foot point ``lever_arm`` (m, foot frame, from the
        heel contact)."""
        return foot_point(self.joints(np.asarray(t, float))[:, 0], lever_arm)

    def sample(self, t: np.ndarray, lever_arm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Joint stacks at times ``t`` (s) and the stance displacements of a foot point (the gait events are
        evaluated apart, so the samples, usually in order already, need no permutation).

        Returns
        -------
        joints : (6, 5, N) derivative stacks of the joints (:meth:`joints`).
        stance_displacement : (n+1, 3) m, exact displacement over each labelled stance (``GaitParams.
            labelled_stance``: the foot flat [t_ff, t_ho] or the contact [t_ic, t_to]) of the foot point
            ``lever_arm`` (m, foot frame; the IMU site's for the truth).
        """
        bounds = np.concatenate(self.plan.labelled(self.walk.gait.labelled_stance))
        start, end = np.split(foot_point(self.joints(bounds)[:, 0], lever_arm), 2)
        return self.joints(t), end - start


def foot_point(joints: np.ndarray, lever_arm: np.ndarray) -> np.ndarray:
    """(N, 3) m: world position of the foot point ``lever_arm`` (m, foot frame, from the heel contact) at joint
    values ``joints`` (6, N): x, y, z (m) of the heel point, yaw, pitch, roll (rad)."""
    rotation = quat.to_matrix(quat.from_euler_zyx(*joints[3:]))
    return joints[:3].T + rotation @ np.asarray(lever_arm, float)
