"""Gait kinds and their speed-dependent defaults: walking from 60 to 130 steps/min, running from 150 to 180 steps/min
with a rearfoot or a forefoot strike.

A scenario chooses a kind with ``[gait] kind`` (:mod:`gaitsim.scenario`); the kind's defaults follow from the
cadence and every key the file writes overrides them. Kind ``"custom"`` (the default) keeps the fixed defaults of
:class:`gaitsim.world.gait.GaitParams`, :class:`~gaitsim.world.gait.ImpactParams` and
:class:`~gaitsim.world.gait.MicroMotionParams` (the seed paper's 84 steps/min walk), so existing scenarios do not
change. Stop-and-go is not a kind: it is a property of any walk (``stop_every_strides``, ``stop_duration_s``).

The defaults are TOML-shaped tables (scenario keys in their units), so a preset reads like a scenario file.

Walking (``"walk"``), c in steps/min, anchored at the seed walk (84 steps/min, 1.4 m strides, 62 % stance,
-20 / +45 deg at heel strike / toe off: :class:`~gaitsim.world.gait.GaitParams`):

- step length 0.70 + 0.0035 (c - 84) m: 0.62 m (0.62 m/s) at 60 and 0.86 m (1.87 m/s) at 130 steps/min, the
  usual span from slow to fast walking (Perry & Burnfield, Gait Analysis, 2nd ed., ch. 2: free walking
  ~1.37 m/s at ~113 steps/min, slow walking below 0.8 m/s; the step length grows less than in proportion to the
  cadence, so the walk ratio falls from 0.0103 to 0.0066 m min/step);
- stance 62 - 0.11 (c - 84) % of the cycle: 64.6 % at 60 and 56.9 % at 130 steps/min (stance shortens with speed:
  Hebenstreit et al., Human Movement Science 43:118-124, 2015, about 65 % slow to 59 % fast); heel rocker, foot
  flat and push-off keep their seed shares of the stance (15 : 30 : 17);
- pitch at heel strike -(20 + 0.12 (c - 84)) deg (-22.3 deg at 103: the recordings' twins give -22 to -25) and
  at toe off 45 + 0.67 (c - 84) deg, with the pitch reversal after toe off of the recordings' twins (see
  ``WALK_TOE_OFF_*``); the shared recordings (UCR's slow shuffle aside) cover 97-108 steps/min, the slopes
  carry the fit to the ends of the range;
- the pitch rates at heel strike and toe off, and the forefoot slap rate, scale with the cadence (a faster cycle
  turns the same angles faster); the heel's touchdown velocity scales with the walking speed;
- the push-off's toe release as gaitmap-healthy's Vicon shows it (``SWING_*``, `python3 -m studies.swing_fit`):
  the toe contact accelerating to 51 m/s^2 at toe off over the push-off's last 40 ms at 110 steps/min (scaled
  with the cadence squared), so the foot leaves the ground moving forward. A fixed toe starts the swing's Hermite
  from rest and packs the travel into its middle: on the twins of gaitmap's walks the IMU site peaks at 7.2-7.7
  m/s where the Vicon shows 4.2-4.4. Fitted on both feet, the twins' median profiles around the toe-off reversal
  misfit by 1.37 / 1.63 m/s in speed instead of 1.68 / 2.13 and by 19.8 / 26.3 m/s^2 in specific force along x
  instead of 29.9 / 41.6 (fitted on one foot, the other, held out, improves alike). The swing lead fitted with it
  (``swing_lead`` -0.035 / -0.140 / -0.073) halves the misfit again at 110 steps/min, but at 60 the same fractions
  make the late swing glide at 2.3 m/s with the pitch rate crossing zero, which nav's anchored SHOE took for a
  stance in every stride (117 % error): it stays a scenario key, not a default, until a slower walk is fitted.
  The running kinds keep a fixed toe (no running recording to fit).

Running (``"run-rearfoot"``, ``"run-forefoot"``), c from 150 to 180 steps/min:

- step length 1.2 m (3.0-3.6 m/s over the range; recreational runners at 154-169 steps/min);
- duty factor (stance share of the cycle) 37 - 0.2 (c - 165) %: 40 % at 150 and 34 % at 180 steps/min, a
  flight phase throughout (published measurements of recreational runners gathered for issue 17: contact
  271-284 ms, duty factor 35-39 % at 154-169 steps/min);
- rearfoot strike: heel first at -15 deg (foot strike angle > 8 deg for a rearfoot strike: Altman & Davis, Gait
  & Posture 35:298-300, 2012), a short heel rocker; forefoot strike: toes first at +8 deg, rotation about the
  toe contact until the heel comes down (Lieberman et al., Nature 463:531-535, 2010: forefoot strikers land on
  the ball of the foot, then the heel lowers);
- toe off at 70 deg at 1000 deg/s, with no angular acceleration there (the rotation peaks at toe off); the
  touchdown velocity (0.4 m/s forward, 0.8 m/s down, stopped in 15 ms) and the rocker rate at contact
  (200 deg/s toward level) are set so that the simulated peaks reach the published ones below (no measured
  running recording to fit). An earlier reversal of -25000 deg/s^2 at toe off made the push-off pitch dip
  below level (to -11 deg at 150 steps/min: the heel under the ground, an 80 g spike once the sole rolls);
  without it the push-off pitch stays above level at every running cadence (tests/test_gaits.py); swing height
  0.15 m; the stance micro-motion's ramps and pulses shortened to fit a ~0.06 s foot flat;
- after toe off the foot keeps turning toes down until a swing pitch maximum stops it
  (``pitch_accel_to_swing_max_dps2``, :func:`gaitsim.world.profile.swing_maximum`): the toe-off rate brought to zero by
  a steady deceleration at the walking recordings' reversal (``WALK_TOE_OFF_ACCEL``, -6350 deg/s^2 at 103 steps/min)
  scaled with the cadence squared as for the walking kinds (-13500 / -16300 / -19400 deg/s^2 at 150 / 165 / 180
  steps/min). The maximum comes 74 / 61 / 52 ms after toe off (15 / 13 / 12 % of the swing) at 37 / 31 / 26 deg above
  the toe-off pitch: 107 / 100 / 95 deg (median; 94-109 over strides and cadences), toes down and pointing slightly
  back, the sole facing backward. The same law puts the walking kinds' own swing maximum, made by their toe-off
  reversal, within 0.5 ms and 0.01 deg (tests/test_gaits.py). No publication giving the running foot-segment angle
  through swing was found to check it against (searched: foot segment / foot-to-ground angle in running swing, foot-IMU
  pitch in running; the running studies found report the angle at contact only: Falbriard et al., Front Bioeng
  Biotechnol 8:65, 2020; foot strike angle: Altman & Davis above): an extrapolation of a walking measurement by the
  walking kinds' cadence law, not a running fit. The knot keeps the deceleration (zero rate, acceleration a, jerk a^2 /
  toe-off rate: the acceleration relaxes in the time it took to stop the rotation); a flat maximum (zero acceleration)
  was a still foot in mid-swing that nav's default detector took for a stance (10-16 false updates per 60 m at 800 Hz).
  Before this knot the swing pitch was one Hermite from toe off to contact and rose to 164-185 deg (toes pointing
  backward, sole up), which gave the rearfoot strike its 1335-1374 deg/s by sweeping ~185 deg back before its heel
  strike. Both strikes now peak at their toe-off rate, 1000-1040 deg/s (30 m runs at 150, 165 and 180 steps/min), below
  the published ~1500: a known miss (strict xfails in tests/test_gaits.py); the peak specific force stays 13.8-15.0 g. A
  faster rotation at toe off or a return that reverses before contact would raise it, but no measurement found gives
  either for these runners: forefoot strikers land with the ankle plantarflexed and the shank more vertical, their
  plantarflexors switched on earlier (Ahn et al., J Sport Health Sci 3:102-112, 2014), with less tibialis anterior and
  more gastrocnemius activity than rearfoot strikers in terminal swing (Yong, Silder & Delp, J Biomech 47:3593-3597,
  2014); and no published foot-IMU peak rate of forefoot strikers alone was found (the ~1500 deg/s below pools running
  up to 6.4 m/s). Measured running feet disagree with the swing above and with the toe-off rate: the heel and
  first-metatarsal markers of one treadmill runner of the RBDS dataset at 2.5 / 3.5 / 4.5 m/s (repository
  regifukuchi/BMC-RIC-running-biomechanics, data/RBDS0041runT252.txt, ...T352, ...T452: 150 Hz, two strides each, 158 /
  163 / 177 steps/min; read for issue 17, foot pitch from the heel-to-MT1 line, unfiltered) land at 21 / 27 / 27 deg
  toes up, roll over at up to 480-560 / 640 / 690-780 deg/s, leave the ground (MT1 5 mm up) at 41 / 43 / 46 deg toes
  down turning at 350-370 / 530-540 / 690-740 deg/s (push-off peaks 460-480 / 650-660 / 810-830 deg/s 13-27 ms before),
  reach their swing maximum of 87-91 / 105-114 / 120-124 deg at 58-61 % of the stride (~175 ms after toe off), and
  return toes up at up to 580-620 / 650-680 / 750-780 deg/s 100-190 ms before contact: the sagittal peak is 620-830
  deg/s, in late swing or at push-off, and the swing maximum grows with speed where this model's shrinks with cadence. A
  filtered trace of a Running Injury Clinic runner (same repository, data/L_foot_angle_mat.txt, ~185 steps/min) agrees
  in shape (83 deg maximum at 61 %, late-swing peak 620-640 deg/s). One subject, markers on the shoe (toe flexion
  unseen): not fitted here yet;
- a running foot is never still: it pitches (heel rise from 30 deg/s) and rolls (25 deg/s held) through its
  short foot flat, so the stance's calmest rate is ~28 deg/s (median over strides; 15-49 deg/s with the
  stride-to-stride variation of the stance rates). The value is bounded by measurements, not fitted to one: the
  shared filter's fixed SHOE (a gate of ~17 deg/s at 3e4, 0.1 deg/s) missed stances on tracked real runs
  (issue 17), while pyshoe's running threshold (35e7 with its sigmas and 5-sample window: a window-mean rate of
  ~94 deg/s, 6x its walking gate; utiasSTARS/pyshoe, Wagstaff et al., IPIN 2017/2018) found them; the rates sit
  near the low end of that span. A foot still in foot flat (the earlier running default, calmest rate ~3 deg/s)
  passed the fixed SHOE in every stride and hid the failure measured on real runs.

Measured foot-IMU peaks the kinds are checked against (``PUBLISHED_PEAKS``; a test asserts them from the
simulated truth within 20 %): walking at the seed pace 600-1000 deg/s and 5-15 g (anchors §7: the shared
recordings and the seed paper's VN-200 walk); running about 1500 deg/s and 15 g at the foot (issue 17; the
saturation of the accelerometer or gyro of some IMU designs in running, up to 6.4 m/s, spoils ZUPT gait parameters:
Potter et al., Sensors 19(11):2601, 2019). The same study bounds the rate from both sides: a gyro range cut from
2000 to 1500 or 1000 deg/s left the speed dependence of its ZUPT stride metrics as it was (slope differences 0.00
and +0.05 %/(m/s), p 0.99 and 0.81, its appendix A), a cut to 750 deg/s did not (-0.40, p < 0.05): feet above 750
deg/s long enough to matter, above 1000 too briefly to. The simulated 1000-1040 deg/s lie in that band; the test
keeps the issue's ~1500 as the figure to reach. Where the running peak falls: the foot's pitch-rate extremes mark
toe off and foot contact (Falbriard et al., Front. Physiol. 9:610, 2018), as here (the peak is the toe-off rate). Not
reproduced: the rearfoot strikers' heel-to-toe rollover, whose peak sagittal rate is 846 deg/s (the mean
for the shoe of medium midsole bending stiffness, the lowest of the five shoes' means; Braeuer et al., Sensors
21(15):5010, 2021) against 250 / 265 / 424 deg/s here at 150 / 165 / 180 steps/min (median over strides): it
would take a heel rocker of about 30 ms instead of 73 ms at 165 steps/min, which the stance timing above does not
give. (The motion-captured runners above roll over at 340-360 and 480-780 deg/s.)
"""

from __future__ import annotations

import math

KINDS = ("custom", "walk", "run-rearfoot", "run-forefoot")
CADENCE_SPAN = {"walk": (60.0, 130.0), "run-rearfoot": (150.0, 180.0), "run-forefoot": (150.0, 180.0)}  # steps/min
DEFAULT_CADENCE = {"walk": 84.0, "run-rearfoot": 165.0, "run-forefoot": 165.0}  # steps/min

SEED_CADENCE = 84.0  # steps/min, the walk GaitParams' fixed defaults describe
SEED_STEP_M = 0.70
WALK_STEP_SLOPE = 0.0035  # m per step/min
SEED_STANCE = 0.62
WALK_STANCE_SLOPE = -0.0011  # stance share per step/min
SEED_SHARES = (0.15, 0.30, 0.17)  # heel rocker, foot flat, push-off (cycle fractions at the seed pace)
# fitted by `gaitsim loop` to the shared walking recordings (results/loop/*/attribution.json: gaitmap left/right,
# x-io long/short walk at 97-108 steps/min): toe-off pitch 49-65 deg, its reversal -5600..-7400 deg/s^2
WALK_FIT_CADENCE = 103.0  # steps/min, their mean cadence
WALK_TOE_OFF_SLOPE = 0.67  # deg per step/min: from the seed's 45 deg at 84 to their mean 57.7 deg at 103
WALK_TOE_OFF_ACCEL = -6350.0  # deg/s^2 at WALK_FIT_CADENCE, their mean; scales with the cadence squared

# the walking push-off's toe release, fitted by `python3 -m studies.swing_fit` to the IMU site's speed and specific
# force around toe off on gaitmap-healthy's Vicon (both feet, 109-110 steps/min; ../shared/data): its acceleration
# at toe off, scaled with the cadence squared as the pitch accelerations, over a fixed duration
SWING_FIT_CADENCE = 109.7  # steps/min, the two twins' mean cadence
SWING_TOE_RELEASE = 51.0  # m/s^2 at SWING_FIT_CADENCE
SWING_RELEASE_S = 0.04  # s, fixed (0.04-0.10 s fit alike; the loop's push-off lag, read over 0.12 s after
# each stance on a fixed toe, stays clear of it up to 115 steps/min: tests/test_loop_push_off.py)

RUN_CADENCE = 165.0  # steps/min, the middle of the running span
RUN_STEP_M = 1.2
RUN_DUTY = 0.37
RUN_DUTY_SLOPE = -0.002  # per step/min
RUN_SHARES = (0.10, 0.09, 0.18)  # heel (or toe) rocker, foot flat, push-off at RUN_DUTY
RUN_HEEL_RISE_DPS = 30.0  # deg/s, pitch rate at the start of the running foot flat (see the module docstring)
RUN_PRONATION_DPS = 25.0  # deg/s, roll rate held through it

# peak |specific force| (g) and |rate| (deg/s) at the foot measured per gait (see the module docstring)
PUBLISHED_PEAKS = {"walk": {"accel_g": (5.0, 15.0), "gyro_dps": (600.0, 1000.0)},
                   "run": {"accel_g": (15.0, 15.0), "gyro_dps": (1500.0, 1500.0)}}


def toe_release_accel(cadence: float) -> float:
    """m/s^2, the walking toe release's acceleration at toe off at ``cadence`` steps/min (:data:`SWING_TOE_RELEASE`
    scaled with the cadence squared)."""
    return SWING_TOE_RELEASE * (cadence / SWING_FIT_CADENCE) ** 2


def _phases(stance: float, shares: tuple[float, float, float]) -> dict:
    """Phase fractions of the cycle: the stance split in the proportions of ``shares``, the rest swing."""
    total = sum(shares)
    rocker, flat, push = (stance * s / total for s in shares)
    return {"heel_rocker_frac": rocker, "foot_flat_frac": flat, "push_off_frac": push,
            "swing_frac": 1.0 - rocker - flat - push}


def walk_tables(cadence: float) -> dict[str, dict]:
    """Scenario tables of walking at ``cadence`` steps/min (see the module docstring)."""
    pace = cadence / SEED_CADENCE
    step = SEED_STEP_M + WALK_STEP_SLOPE * (cadence - SEED_CADENCE)
    speed_ratio = step * cadence / (SEED_STEP_M * SEED_CADENCE)
    gait = {"cadence_steps_per_min": cadence, "stride_length_m": 2 * step,
            **_phases(SEED_STANCE + WALK_STANCE_SLOPE * (cadence - SEED_CADENCE), SEED_SHARES),
            "pitch_heel_strike_deg": -(20.0 + 0.12 * (cadence - SEED_CADENCE)),
            "pitch_toe_off_deg": 45.0 + WALK_TOE_OFF_SLOPE * (cadence - SEED_CADENCE),
            "pitch_rate_heel_strike_dps": 60.0 * pace, "pitch_rate_toe_off_dps": 150.0 * pace,
            "pitch_accel_toe_off_dps2": WALK_TOE_OFF_ACCEL * (cadence / WALK_FIT_CADENCE) ** 2,
            "toe_release_accel_mps2": toe_release_accel(cadence)}
    impact = {"heel_strike_velocity_mps": [0.25 * speed_ratio, 0.0, -0.3 * speed_ratio],
              "slap_rate_dps": 250.0 * pace}
    return {"gait": gait, "impact": impact, "micromotion": {}}


def run_tables(cadence: float, forefoot: bool) -> dict[str, dict]:
    """Scenario tables of running at ``cadence`` steps/min, rearfoot or forefoot strike (see the module
    docstring)."""
    duty = RUN_DUTY + RUN_DUTY_SLOPE * (cadence - RUN_CADENCE)
    gait = {"cadence_steps_per_min": cadence, "stride_length_m": 2 * RUN_STEP_M,
            **_phases(duty, RUN_SHARES), "forefoot_strike": forefoot, "labelled_stance": "contact",
            "pitch_heel_strike_deg": 8.0 if forefoot else -15.0,
            "pitch_rate_heel_strike_dps": -200.0 if forefoot else 200.0,
            "pitch_toe_off_deg": 70.0, "pitch_rate_toe_off_dps": 1000.0, "pitch_accel_toe_off_dps2": 0.0,
            "pitch_accel_to_swing_max_dps2": WALK_TOE_OFF_ACCEL * (cadence / WALK_FIT_CADENCE) ** 2,
            "swing_height_m": 0.15, "stride_length_sd_m": 0.04}
    impact = {"heel_strike_velocity_mps": [0.4, 0.0, -0.8], "heel_strike_duration_s": 0.015,
              "slap_rate_dps": 250.0, "slap_duration_s": 0.02}
    micro = {"creep_ramp_s": 0.02, "loading_duration_s": 0.04, "heel_rise_rate_start_dps": RUN_HEEL_RISE_DPS,
             "pronation_rate_dps": RUN_PRONATION_DPS}
    return {"gait": gait, "impact": impact, "micromotion": micro}


def kind_tables(kind: str, cadence: float | None) -> dict[str, dict]:
    """Default scenario tables ({section: {key: value}}, keys in their units) of gait ``kind`` at ``cadence``
    steps/min (None: the kind's default cadence); empty tables for ``"custom"``.

    Raises
    ------
    ValueError
        for an unknown kind, or a cadence outside the span the kind's defaults are documented for (the message
        names the key and the value; the scenario reader adds the file).
    """
    if kind not in KINDS:
        raise ValueError(f"kind = {kind!r} is not allowed; allowed: {', '.join(KINDS)}")
    if kind == "custom":
        return {"gait": {}, "impact": {}, "micromotion": {}}
    cadence = DEFAULT_CADENCE[kind] if cadence is None else cadence
    low, high = CADENCE_SPAN[kind]
    if not (math.isfinite(cadence) and low <= cadence <= high):
        raise ValueError(f"cadence_steps_per_min = {cadence!r} is not allowed with kind = {kind!r}; its "
                            f"defaults hold for {low:g}-{high:g} steps/min (kind = 'custom' and explicit keys "
                            "for other paces)")
    if kind == "walk":
        return walk_tables(cadence)
    return run_tables(cadence, forefoot=kind == "run-forefoot")
