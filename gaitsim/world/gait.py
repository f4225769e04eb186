"""Gait parameters and the stance plan: when each gait event happens and where each stance is placed.

One foot is simulated. A walk is: standing (foot flat) -> for each stride: heel off, push-off (rotation about
the toe contact), toe off, swing, initial contact (heel strike), heel rocker (rotation about the heel contact),
foot flat -> standing at the end. Phase durations are fractions of the gait cycle (one stride of one foot).

A forefoot strike (``forefoot_strike``) lands on the forefoot, toes down, and rotates about the toe contact until
the heel comes down at foot flat (a toe rocker in place of the heel rocker). Stop-and-go (``stop_every_strides``)
turns every n-th stance into a stop: the foot stands exactly still for ``stop_duration_s`` more (no micro-motion;
``StancePlan.walking`` is False for it, as for the standing at both ends). The labelled stance of every gait is
the foot flat [t_ff, t_ho]: the only phase in which the whole foot, and so an IMU anywhere on it, is at rest.
Speed-dependent defaults of each gait are in :mod:`gaitsim.world.gaits`.

Angles: foot pitch is the rotation about the foot's left (y) axis, positive when the toes point down; the foot
pitch at heel strike is therefore negative (toes up) and at toe off positive (heel up). Every parameter is SI
(angles in rad, rates in rad/s); scenario files give them in degrees (:mod:`gaitsim.scenario` converts).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .path import Path


@dataclass(frozen=True)
class GaitParams:
    """Spatio-temporal gait parameters of one foot.

    Attributes
    ----------
    cadence_steps_per_min : steps/min (two steps per stride of one foot). Default 84, the seed paper's pace.
    stride_length_m : m, nominal heel-contact to heel-contact distance of one foot. Default 1.4 (~0.98 m/s).
    heel_rocker_frac, foot_flat_frac, push_off_frac, swing_frac : fractions of the gait cycle, summing to 1.
        Defaults 0.15 / 0.30 / 0.17 / 0.38: stance 62 % (anchors §7), foot flat from 15 % to 45 %.
    pitch_heel_strike : rad, foot pitch at initial contact: negative (toes up) for a heel strike, positive (toes
        down) for a forefoot strike. Default -20 deg.
    pitch_rate_heel_strike : rad/s, pitch rate at initial contact. Default 60 deg/s (forefoot starting down).
    pitch_accel_heel_strike : rad/s^2, pitch acceleration at initial contact. Default 0.
    pitch_toe_off : rad, foot pitch at toe off (heel up). Default 45 deg.
    pitch_rate_toe_off : rad/s, pitch rate at toe off. Default 150 deg/s.
    pitch_accel_toe_off : rad/s^2, pitch acceleration at toe off; measured feet reverse their push-off
        rotation right after toe off (gaitmap: about -8000 deg/s^2), which a zero here cannot show. Default 0.
    swing_height_m : m, heel height at mid-swing. Default 0.08.
    swing_lateral_m : m, sideways excursion of the heel at mid-swing, positive to the left. Default 0.01.
    swing_roll : rad, foot roll at mid-swing (positive: rotation about the toe axis x). Default 3 deg.
    toe_out : rad, foot yaw relative to the walking direction during stance (positive: toes to the left).
        Default 0.
    stride_length_sd_m : m, stride-to-stride standard deviation of the stride length. Default 0.02.
    cycle_sd_frac : relative stride-to-stride standard deviation of the cycle time. Default 0.01.
    pitch_sd : rad, stride-to-stride standard deviation of the heel-strike and toe-off pitch. Default 1 deg.
    stand_start_s, stand_end_s : s, standing (foot flat, still) at the start and end. Default 2.0 each.
    forefoot_strike : land on the forefoot and rotate about the toe contact down to foot flat. Default False.
    stop_every_strides : every n-th stance of the walk is a stop (0: none). Default 0.
    stop_duration_s : s, how much longer a stop stands (still) than a walking stance's foot flat. Default 3.0.
    """

    cadence_steps_per_min: float = 84.0
    stride_length_m: float = 1.4
    heel_rocker_frac: float = 0.15
    foot_flat_frac: float = 0.30
    push_off_frac: float = 0.17
    swing_frac: float = 0.38
    pitch_heel_strike: float = math.radians(-20.0)
    pitch_rate_heel_strike: float = math.radians(60.0)
    pitch_accel_heel_strike: float = 0.0
    pitch_toe_off: float = math.radians(45.0)
    pitch_rate_toe_off: float = math.radians(150.0)
    pitch_accel_toe_off: float = 0.0
    swing_height_m: float = 0.08
    swing_lateral_m: float = 0.01
    swing_roll: float = math.radians(3.0)
    toe_out: float = 0.0
    stride_length_sd_m: float = 0.02
    cycle_sd_frac: float = 0.01
    pitch_sd: float = math.radians(1.0)
    stand_start_s: float = 2.0
    stand_end_s: float = 2.0
    forefoot_strike: bool = False
    stop_every_strides: int = 0
    stop_duration_s: float = 3.0

    @property
    def cycle_s(self) -> float:
        """Nominal gait-cycle duration (s): two steps."""
        return 120.0 / self.cadence_steps_per_min


@dataclass(frozen=True)
class ImpactParams:
    """Heel strike and forefoot slap.

    Attributes
    ----------
    heel_strike_velocity_mps : (forward, left, up) m/s, heel velocity at initial contact in the walking frame;
        it is brought to zero over ``heel_strike_duration_s`` (heel-pad compression). Default (0.25, 0, -0.3).
    heel_strike_duration_s : s, sharpness of the heel strike. Default 0.012.
    slap_rate : rad/s, forefoot pitch rate when the forefoot meets the ground. Default 250 deg/s.
    slap_duration_s : s, time in which the forefoot stops at foot flat (sharpness of the slap). Default 0.025.
    ringing_hz : Hz, natural frequency of a damped vertical oscillation of the foot (shoe/mount ringing) excited
        at each heel strike and forefoot slap. Default 0 (off).
    ringing_damping : damping ratio of that oscillation, in (0, 1). Default 0.15.
    ringing_accel_mps2 : m/s^2, its nominal peak acceleration (displacement amplitude times (2 pi f)^2).
        Default 0.
    """

    heel_strike_velocity_mps: tuple[float, float, float] = (0.25, 0.0, -0.3)
    heel_strike_duration_s: float = 0.012
    slap_rate: float = math.radians(250.0)
    slap_duration_s: float = 0.025
    ringing_hz: float = 0.0
    ringing_damping: float = 0.15
    ringing_accel_mps2: float = 0.0


@dataclass(frozen=True)
class MicroMotionParams:
    """Foot motion during stance: velocities of the contact point in the walking frame (forward, left, up).

    The profile of one stance is the sum of a creep plateau over foot flat (C4 ramps of ``creep_ramp_s``
    outside it), a settling pulse starting at foot flat and a heel-off pulse centred on heel off (pulse
    shape 256 s^4 (1-s)^4, peak at mid-pulse). Standing at the start and end of a walk is exactly still.

    Attributes
    ----------
    enabled : switch. Default True.
    creep_velocity_mps : m/s during foot flat. Default (0.01, 0, 0) (seed paper Fig. 3, anchors §7).
    creep_ramp_s : s. Default 0.05.
    settle_velocity_mps : m/s, peak of the pulse after foot flat. Default (0.02, 0, 0).
    settle_duration_s : s. Default 0.08.
    heel_off_velocity_mps : m/s, peak of the pulse around heel off. Default (0.02, 0, 0.005).
    heel_off_duration_s : s. Default 0.10.
    stance_roll_rate : rad/s, stance roll-over (pronation, then supination) about the heel-toe axis: the
        roll rate is +rate at foot flat, falls linearly through zero at mid foot-flat to -rate at heel off, and
        rises from / returns to zero over the heel rocker / push-off (C4). Rolling about the contact axis moves
        neither contact point. Core-stance mean |rate| is rate/2. Default 0 (a still foot flat).
    stance_rotation_rate : rad/s, (roll, pitch, yaw) rates of a sustained rotation of the foot during foot flat:
        each rate ramps up (C4, over ``creep_ramp_s``) after foot flat, holds, and ramps down to zero at heel
        off, so the foot turns by rate * (foot flat - creep_ramp_s) during the stance; the angle is held through
        the push-off and returned over the swing. The rates are ZYX Euler-angle rates on top of the gait's
        angles, equal to the body rates about the foot's x (toes), y (left), z (up) axes to first order in the
        (few-degree) stance angles. Measured foot IMUs show it in every recording (gaitmap, x-io, UCR:
        core-stance rates of 2-6 deg/s per axis, signs mirrored in roll and yaw between left and right foot:
        pronation, heel rise, internal rotation). Default (0, 0, 0). Fitted by ``gaitsim loop``
        (results/loop/): a heel rise (pitch) of 5-6 deg/s on every measured foot, and roll and yaw that depend
        on the side, about (+4, 5, -5) for a left foot and (-4, 5, +6) for a right one. The default stays off
        because switching the pitch on changes the paper reproduction (along-track loss 0.93 -> 1.25 m) and
        the blind bandwidth case (see the loop's README).
    stance_rotation_pivot_frac : (pitch, yaw) pivots of the sustained rotation, each a fraction of the way from
        the heel contact (0) to the toe contact (1): the foot yaws about the vertical axis through the yaw pivot,
        then pitches about the lateral axis through the pitch pivot; roll turns about the heel-toe line and
        moves no contact point. Default (1, 0): the heel rises about the forefoot and the foot turns about
        the heel, as gaitmap's Vicon markers show (the heel-side sensor moves up at pitch rate x 0.20-0.23 m
        and sideways at under 0.006 m/s while the foot yaws at 6 deg/s).
    """

    enabled: bool = True
    creep_velocity_mps: tuple[float, float, float] = (0.01, 0.0, 0.0)
    creep_ramp_s: float = 0.05
    settle_velocity_mps: tuple[float, float, float] = (0.02, 0.0, 0.0)
    settle_duration_s: float = 0.08
    heel_off_velocity_mps: tuple[float, float, float] = (0.02, 0.0, 0.005)
    heel_off_duration_s: float = 0.10
    stance_roll_rate: float = 0.0
    stance_rotation_rate: tuple[float, float, float] = (0.0, 0.0, 0.0)
    stance_rotation_pivot_frac: tuple[float, float] = (1.0, 0.0)


@dataclass(frozen=True)
class Walk:
    """Everything that defines one walk's kinematics (before the sensor model)."""

    path: Path | None  # None: standing still for ``duration_s``
    gait: GaitParams = field(default_factory=GaitParams)
    impact: ImpactParams = field(default_factory=ImpactParams)
    micro: MicroMotionParams = field(default_factory=MicroMotionParams)
    duration_s: float = 0.0  # only for standing still


@dataclass
class StancePlan:
    """Event times (s), placements and per-stance pitch of every stance, stance 0 being the initial standing.

    Attributes
    ----------
    t_ic, t_ff, t_ho, t_to : (n+1,) s. Stance 0 has t_ic = t_ff = 0; the last has t_ho = t_to = t_end.
    pos : (n+1, 2) m, heel contact after heel-strike compression (before stance micro-motion).
    yaw : (n+1,) rad, walking direction of each stance.
    pitch_hs, pitch_to : (n+1,) rad, pitch at the stance's heel strike / toe off.
    walking : (n+1,) bool, True for full gait stances (micro-motion applies), False for standing (both ends and
        the stops of stop-and-go).
    t_end : s, end of the recording.
    """

    t_ic: np.ndarray
    t_ff: np.ndarray
    t_ho: np.ndarray
    t_to: np.ndarray
    pos: np.ndarray
    yaw: np.ndarray
    pitch_hs: np.ndarray
    pitch_to: np.ndarray
    walking: np.ndarray
    t_end: float

    @property
    def n_strides(self) -> int:
        return len(self.t_ic) - 1


def plan_stances(walk: Walk, rng: np.random.Generator) -> StancePlan:
    """Place the stances of ``walk`` along its path with seeded stride-to-stride variability.

    The stride count is ``round(path length / stride length)`` (at least 1); the drawn stride lengths are
    rescaled to end exactly at the path's end. With ``stop_every_strides = m > 0``, stances m, 2m, ... (not the
    last) are stops: their foot flat lasts ``stop_duration_s`` longer and they do not walk.
    """
    g = walk.gait
    if walk.path is None:
        z = np.zeros(1)
        return StancePlan(z, z, np.full(1, walk.duration_s), np.full(1, walk.duration_s),
                          np.zeros((1, 2)), z.copy(), z.copy(), z.copy(), np.zeros(1, bool), walk.duration_s)
    n = max(1, int(round(walk.path.length / g.stride_length_m)))
    strides = 1.0 + rng.standard_normal(n) * g.stride_length_sd_m / g.stride_length_m
    s = np.concatenate([[0.0], np.cumsum(strides)]) * walk.path.length / strides.sum()
    pos, yaw = walk.path.at(s)
    cycles = g.cycle_s * (1.0 + g.cycle_sd_frac * rng.standard_normal(n))
    pitch_noise = g.pitch_sd * rng.standard_normal((2, n + 1))

    walking = np.ones(n + 1, bool)
    walking[[0, n]] = False
    if g.stop_every_strides > 0:
        walking[g.stop_every_strides:n:g.stop_every_strides] = False
    stop_s = np.where(walking, 0.0, g.stop_duration_s)
    t_ic = np.zeros(n + 1)
    t_ff = np.zeros(n + 1)
    t_ho = np.zeros(n + 1)
    t_to = np.zeros(n + 1)
    t_ho[0] = g.stand_start_s
    t_to[0] = t_ho[0] + g.push_off_frac * cycles[0]
    for k in range(1, n + 1):
        c = cycles[k - 1]
        t_ic[k] = t_to[k - 1] + g.swing_frac * c
        t_ff[k] = t_ic[k] + g.heel_rocker_frac * c
        t_ho[k] = t_ff[k] + g.foot_flat_frac * c + (stop_s[k] if k < n else 0.0)
        t_to[k] = t_ho[k] + g.push_off_frac * (cycles[k] if k < n else c)
    t_end = t_ff[n] + g.stand_end_s
    t_ho[n] = t_to[n] = t_end
    return StancePlan(
        t_ic, t_ff, t_ho, t_to, pos, yaw,
        g.pitch_heel_strike + pitch_noise[0],
        g.pitch_toe_off + pitch_noise[1],
        walking, float(t_end),
    )
