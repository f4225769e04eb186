"""Gait parameters and the stance plan: when each gait event happens and where each stance is placed.

One foot is simulated. A walk is: standing (foot flat) -> for each stride: heel off, push-off (rotation about
the toe contact), toe off, swing, initial contact (heel strike), heel rocker (rotation about the heel contact),
foot flat -> standing at the end. Phase durations are fractions of the gait cycle (one stride of one foot).

A forefoot strike (``forefoot_strike``) lands on the forefoot, toes down, and rotates about the toe contact until
the heel comes down at foot flat (a toe rocker in place of the heel rocker). Stop-and-go (``stop_every_strides``)
turns every n-th stance into a stop: the foot stands exactly still for ``stop_duration_s`` more (no micro-motion;
``StancePlan.walking`` is False for it, as for the standing at both ends). The labelled stance
(``labelled_stance``, :data:`LABELLED_STANCES`) is the foot flat [t_ff, t_ho) of a walk, the only phase in which
a walking foot, and so an IMU anywhere on it, is nearly at rest; a running foot is never at rest, and its labelled
stance is the ground contact [t_ic, t_to), from initial contact (heel or forefoot) to toe off.
Speed-dependent defaults of each gait are in :mod:`gaitsim.world.gaits`.

Angles: foot pitch is the rotation about the foot's left (y) axis, positive when the toes point down; the foot
pitch at heel strike is therefore negative (toes up) and at toe off positive (heel up). Every parameter is SI
(angles in rad, rates in rad/s); scenario files give them in degrees (:mod:`gaitsim.scenario` converts).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .gaits import SWING_RELEASE_S
from .path import Path

# what the truth's stance label and events.csv's displacement cover, per ``GaitParams.labelled_stance``
LABELLED_STANCES = {"foot_flat": "foot flat: t_ff <= t < t_ho (events.csv)",
                    "contact": "ground contact, initial contact to toe off: t_ic <= t < t_to (events.csv)"}


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
    pitch_accel_to_swing_max : rad/s^2, at most 0: mean pitch acceleration from toe off to the swing's pitch
        maximum. A negative value adds a knot to the swing at that maximum (zero rate, acceleration ``a``), reached
        ``pitch_rate_toe_off / |a|`` after toe off, ``pitch_rate_toe_off^2 / (2 |a|)`` above the toe-off pitch:
        where a steady deceleration at ``a`` stops the toe-off rotation
        (:func:`gaitsim.world.profile.swing_maximum`); the running kinds use it (:mod:`gaitsim.world.gaits`).
        Default 0: no knot, the swing pitch is one Hermite from toe off to initial contact.
    swing_height_m : m, heel height at mid-swing. Default 0.08.
    toe_release_accel_mps2 : m/s^2, forward acceleration of the toe contact at toe off. Over the last
        ``toe_release_s`` of the push-off the contact slides forward, its acceleration rising C4 from zero
        (:func:`gaitsim.world.smooth.release`): the foot leaves the ground moving forward at ``a d / 2`` m/s,
        ``3 a d^2 / 22`` m ahead of where it pivoted. It stands for the forefoot rolling off over the flexing toes,
        which a rigid foot pivoting on a fixed toe cannot do: on gaitmap-healthy's Vicon the heel sensor moves
        forward at 2.1-2.6 m/s while the toe is still down, against 0.4-0.6 m/s for the fixed toe. Default 0 (a
        fixed toe until toe off, the seed walk as it was); the walking kind sets the value fitted to gaitmap's
        Vicon (:func:`gaitsim.world.gaits.toe_release_accel`).
    toe_release_s : s, duration d of that release. Default 0.04.
    swing_lead : (3,) dimensionless, how far the heel runs ahead of the swing's degree-9 Hermite at a quarter, half
        and three quarters of the swing, in fractions of the swing's horizontal travel
        (:func:`gaitsim.world.smooth.lead`). The Hermite alone, fixed by the stance at both ends, packs the travel
        into the middle of the swing (peak speed ~2.4 times the mean; 7.2-7.7 m/s against the Vicon's 4.2-4.4 on
        gaitmap's walks); a lag in the middle spreads it. Default (0, 0, 0): the Hermite alone (fitted with the
        release on gaitmap: -0.035, -0.140, -0.073; why no kind uses it yet: :mod:`gaitsim.world.gaits`).
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
    labelled_stance : which part of each stance the truth labels stance (``truth.csv``'s ``stance`` column, the
        displacement in ``events.csv``; :data:`LABELLED_STANCES`): ``"foot_flat"`` [t_ff, t_ho), where a walking
        foot is nearly still (what a zero-velocity detector should find), or ``"contact"`` [t_ic, t_to), the
        whole ground contact from initial contact (heel, or forefoot for a forefoot strike) to toe off: the
        stance of running gait analysis, whose foot is never still. Default ``"foot_flat"``; the running kinds
        set ``"contact"`` (:mod:`gaitsim.world.gaits`).
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
    pitch_accel_to_swing_max: float = 0.0
    swing_height_m: float = 0.08
    toe_release_accel_mps2: float = 0.0
    toe_release_s: float = SWING_RELEASE_S
    swing_lead: tuple = (0.0, 0.0, 0.0)
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
    labelled_stance: str = "foot_flat"

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
    """The foot in stance: a rolling, compliant foot from initial contact to toe off.

    The foot's pitch never stops in stance: after the forefoot lands (foot flat, the heel-toe line level) the
    heel keeps rising slowly (ankle rocker), at a pitch rate ``heel_rise_rate_start + heel_rise_growth tau^2``
    with tau the time since foot flat: the heel rise accelerates into the push-off the longer the foot has been
    loaded (a slow walker's long foot flat ends at a faster heel rise than a fast walker's short one). As the
    forefoot is loaded the foot rolls and turns (pronation, a pulse of roll and yaw rate), and it keeps
    rolling and turning slowly through foot flat; the rates vary from stride to stride. The foot rolls on the
    ground without slipping (:class:`gaitsim.world.profile.RollingSole`): about the heel contact while its pitch is below
    ``-contact_transfer_pitch / 2`` (heel rocker), about the toe contact above ``+contact_transfer_pitch / 2``
    (forefoot rocker), and in between on a convex sole whose contact moves from heel to toe as the foot pitches.
    A compliant contact (``contact_radius_m``) rolls as if the instantaneous centre of rotation sat that deep
    below the sole, and the contact creeps forward (``creep_velocity_mps``). A point of the foot at height z
    above the ground therefore moves forward at ``pitch rate * (z + contact_radius_m) + creep``, so the velocity
    of a foot IMU in stance follows its angular rate. Standing at the start and end of a walk is exactly still.

    Defaults: fitted jointly to four tracked feet (gaitmap-healthy left and right, Vicon three-marker pose at
    the sensor's lever arm, 204.8 Hz; ucr-fgo left and right, 60 Hz) by ``gaitsim stance --fit``
    (:mod:`gaitsim.stance.fit`: foot-flat profiles of the angular rate, its sagittal part and, on gaitmap, the
    IMU site's forward and vertical velocity; results/stance/fit.json). The fit put the contact radius and
    the creep at zero: on these feet the site's velocity in foot flat is the rolling foot's, pitch rate times
    height. ``stance_rate_sd_frac`` is measured, not fitted: the stride-to-stride coefficient of variation of
    the mean core-stance angular rate is 0.27 to 0.32 on all four feet.

    Attributes
    ----------
    enabled : switch; False gives a still foot flat (level, no heel rise, creep, roll or yaw) for ablation.
        Default True.
    heel_rise_rate_start : rad/s, foot pitch rate (toes down = heel up) at foot flat. Default 3.0 deg/s.
    heel_rise_growth : rad/s^3, growth of the pitch rate with the square of the time since foot flat.
        Default 13 deg/s^3 (gaitmap's 0.38 s foot flat ends at 4.9 deg/s, UCR's 0.78 s one at 11 deg/s).
    contact_transfer_pitch : rad, pitch range over which the contact rolls from the heel to the toe (the
        flatter the sole, the smaller); centred on the level foot. Default 9.4 deg (a sole of radius
        toe_length / 0.164 rad, 1.2 m for the 0.2 m foot).
    contact_radius_m : m, depth of the rolling centre below the sole (compliant heel pad, sole and forefoot):
        the sole's ground contact slides forward at pitch rate times this. Default 0.
    loading_roll_rate : rad/s, peak roll rate of the foot as the forefoot is loaded (subtalar pronation), a
        pulse (shape 256 s^4 (1-s)^4) over ``loading_duration_s`` from the start of the forefoot slap. Given for
        a left foot (``foot``). Default 29 deg/s.
    loading_duration_s : s, duration of that pulse. Default 0.13.
    pronation_rate : rad/s, roll rate held through foot flat (C4 ramps of ``creep_ramp_s`` inside it): the
        loaded foot keeps rolling slowly; the roll reached is held through the push-off and returned over the
        swing. Roll turns about the heel-toe axis and moves neither contact: a sensor at height h moves
        sideways at roll rate times h, not forward. Given for a left foot. Default 4.5 deg/s.
    foot : "left" or "right": the roll above is a left foot's (positive = eversion) and is mirrored (negated)
        for a right foot. Default "left". (Gaitmap's IMUs read a core-stance rate about their z axis of 5-6
        deg/s, mirrored between the feet, but the Vicon markers on the same shoes turn by under 1 deg/s about
        the vertical: the sensor turns on the shoe, the foot does not; the model has no stance yaw of its own.)
    stance_rate_sd_frac : relative stride-to-stride standard deviation of the stance model's rates: each
        walking stance scales its heel rise (pitch) and its roll rates by independent factors
        ``max(0, 1 + stance_rate_sd_frac * N(0, 1))`` drawn with the stride variability. Default 0.3.
    creep_velocity_mps : m/s, (forward, left, up) slide of the contact in the walking frame during foot flat.
        Default (0, 0, 0).
    creep_ramp_s : s, C4 ramps of the creep (outside foot flat) and of the held rates (inside it).
        Default 0.05.
    stance_roll_rate : rad/s, stance roll-over (pronation, then supination) about the heel-toe axis: the
        roll rate is +rate at foot flat, falls linearly through zero at mid foot-flat to -rate at heel off, and
        rises from / returns to zero over the heel rocker / push-off (C4). Rolling about the contact axis moves
        neither contact point. Core-stance mean |rate| is rate/2. Default 0.
    stance_rotation_rate : rad/s, (roll, pitch, yaw) rates of a sustained rotation of the foot during foot flat
        (the loop's effect, on top of the model's own rates and not mirrored). The pitch adds to the heel-rise
        rate; roll and yaw each ramp up (C4, over ``creep_ramp_s``) after foot flat, hold, and ramp down to
        zero at heel off; the angle is held through the push-off and returned over the swing. The rates equal
        the body rates about the foot's x (toes), y (left), z (up) axes to first order in the (few-degree)
        stance angles. Default (0, 0, 0). ``gaitsim loop`` (results/loop/) fitted a heel rise (pitch) of 5-6
        deg/s on every measured foot, and roll and yaw that depend on the side, about (+4, 5, -5) for a left
        foot and (-4, 5, +6) for a right one, against the simulator's earlier still foot flat.
    stance_yaw_pivot_frac : where the foot-flat yaw turns the foot, a fraction of the way from the heel contact
        (0) to the toe contact (1) on the level foot. Default 0 (about the heel, as gaitmap's Vicon markers
        show: the heel-side sensor moves sideways at under 0.006 m/s while the foot yaws at 6 deg/s).
    """

    enabled: bool = True
    heel_rise_rate_start: float = math.radians(3.0)
    heel_rise_growth: float = math.radians(13.0)
    contact_transfer_pitch: float = math.radians(9.4)
    contact_radius_m: float = 0.0
    loading_roll_rate: float = math.radians(29.0)
    loading_duration_s: float = 0.13
    pronation_rate: float = math.radians(4.5)
    foot: str = "left"
    stance_rate_sd_frac: float = 0.3
    creep_velocity_mps: tuple[float, float, float] = (0.0, 0.0, 0.0)
    creep_ramp_s: float = 0.05
    stance_roll_rate: float = 0.0
    stance_rotation_rate: tuple[float, float, float] = (0.0, 0.0, 0.0)
    stance_yaw_pivot_frac: float = 0.0


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
    rate_scale : (n+1, 2) factors of the stance model's (pitch, roll) rates in each stance.
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
    rate_scale: np.ndarray

    @property
    def n_strides(self) -> int:
        return len(self.t_ic) - 1

    def labelled(self, labelled_stance: str) -> tuple[np.ndarray, np.ndarray]:
        """(start, end) s of each stance's labelled part (``GaitParams.labelled_stance``): [t_ff, t_ho) for
        ``"foot_flat"``, [t_ic, t_to) for ``"contact"``."""
        if labelled_stance not in LABELLED_STANCES:
            raise ValueError(f"labelled_stance = {labelled_stance!r} is not allowed; allowed: "
                             f"{', '.join(LABELLED_STANCES)}")
        return (self.t_ff, self.t_ho) if labelled_stance == "foot_flat" else (self.t_ic, self.t_to)


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
                          np.zeros((1, 2)), z.copy(), z.copy(), z.copy(), np.zeros(1, bool), walk.duration_s,
                          np.ones((1, 2)))
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
    rate_scale = np.maximum(0.0, 1.0 + walk.micro.stance_rate_sd_frac * rng.standard_normal((n + 1, 2)))
    return StancePlan(
        t_ic, t_ff, t_ho, t_to, pos, yaw,
        g.pitch_heel_strike + pitch_noise[0],
        g.pitch_toe_off + pitch_noise[1],
        walking, float(t_end), rate_scale,
    )
