"""Every tuning constant of the sim-to-real loop, with its unit and what it decides.

The modules of :mod:`gaitsim.loop` read these by name (``settings.NOISE_LEVEL``); none keeps a number of its own.
"""

from __future__ import annotations

import math

from nav import pipeline

# -- strides (gaitsim.loop.strides) --------------------------------------------------------------------------
MERGE_GAP_S = 0.04  # s, detected stance runs closer than this are one stance
MIN_STANCE_S = 0.06  # s, shorter stance runs are ignored
MAX_STRIDE_S = 3.0  # s, a longer "stride" contains rest
STRIDE_PERIOD_BAND = (0.6, 1.5)  # 1, a regular stride's period lies within these multiples of the median
REST_STANCE_SHARE = 0.8  # 1, a stance lasting longer than this share of its stride's period is rest, not gait
QUIET_RATE_DPS = 40.0  # deg/s, a stride's phase origin is where |w| last fell below this before mid-stance
PHASE_POINTS = 64  # points of the normalised gait phase the profiles are resampled on

# -- sensor frame (gaitsim.loop.frame) ----------------------------------------------------------------------
MIRROR_CLOSURE_RATIO = 3.0  # 1, the data are mirrored when mirroring them back closes the strides this much better
MIN_FRAME_STRIDES = 3  # strides between detected stances needed to check the frame

# -- signature (gaitsim.loop.signature) ----------------------------------------------------------------------
HF_EDGES_HZ = (40.0, 80.0)  # Hz, band edges of the hf40 / hf80 shares of |a| variance
HF_NYQUIST_MARGIN = 1.25  # 1, a band share is computed only when the Nyquist frequency exceeds edge x this
PUSH_OFF_S = 0.12  # s, window after each detected stance in which acc_gyro_lag fits the turn about the toe
LAG_RANGE_MS = 15.0  # ms, acc_gyro_lag is searched over +- this
LAG_STEP_MS = 1.0  # ms, grid step of that search (refined by a parabola)
OUTLIER_SIGMAS = 3.0  # 1, the push-off height leaves out stances whose own height lies this many robust sigmas off
ONSET_HF_EDGE_HZ = 30.0  # Hz, high-pass edge of |a| for onset_hf
ONSET_WINDOW_S = 0.1  # s, from the stride's gyro onset, over which onset_hf is taken
BAND_TOP_SHARE = 0.45  # 1, a band pass or searched frequency stays below this share of the sample rate
REST_ACC_NORM_SD_FLOOR = 1e-4  # m/s^2, least sample spread of |f| at rest (a quantised sensor can read one value)
QUIET_REST_S = 1.0  # s, least length of the first and last rest compared by rest_gyro_change / rest_acc_change
REST_NOISE_BLOCK = 32  # samples, blocks of a long rest's core giving the rest_*_noise_lag* residuals (their scatter: the se)
MIN_TRACK_SAMPLES = 10  # finite position-track samples needed for stance_velocity
MIN_TRACK_STRIDE_M = 0.2  # m, a stride whose track moves less than this gives no forward direction (no stance_velocity)

# -- residuals (gaitsim.loop.residuals) ----------------------------------------------------------------------
NOISE_LEVEL = 3.0  # 1, a residual with |value| <= NOISE_LEVEL x uncertainty is at the noise level
PROFILE_SPREAD_FACTOR = 2.0  # 1, the twin's profile should lie within this x the recording's stride-to-stride sd
FIG5_BOOTSTRAP = 200  # block-bootstrap draws of the Fig. 5 residuals (gaitsim.loop.fig5; the stance study uses 1000)
FIG5_THRESHOLDS = (1.0e4, 3.0e4, 5.0e4)  # SHOE thresholds of the loop's sweeps (the stance study's five cost 1.8x)
UNCERTAINTY_FLOOR = {"stance_velocity": 0.0005, "swing_axis_yaw": 0.05}  # m/s, deg: reference / axis resolution

# -- twin fit (gaitsim.loop.twin) ----------------------------------------------------------------------------
TWIN_SEED = 7  # seed of the twin's simulations
FIT_ITERATIONS = 2  # rounds of cadence and clearance matching by simulation
PATH_TOLERANCE_M = 0.3  # m, Ramer-Douglas-Peucker tolerance of the twin's path through the stance centres
HAIRPIN_TURN = math.radians(120.0)  # rad, a sharper corner of the path is walked as a hairpin
CORNER_RADII_M = (1.0, 0.75, 0.5)  # m, corner radii tried in turn (then half a stride) for the twin's polyline
RADIUS_MARGIN_M = 0.001  # m, added to the half-stride corner radius (the scenario requires at least one step)
STRAIGHT_MIN_SPAN_M = 0.5  # m, a straight twin walks toward the track's end only when that end is this far away
DEFAULT_STRIDE_LENGTH_M = 1.4  # m, the twin's stride length when the track gives no stance-to-stance step
WALK_RUN_SPEED_MPS = 2.0  # m/s, a recording at least this fast (stride length x stride rate) gets a running twin:
# the preferred walk-run transition speed of adults, 2.0-2.1 m/s (Hreljac, Med Sci Sports Exerc 25:1158-1162, 1993;
# a Froude number v^2 / (g L) of ~0.5 at a 0.9 m leg length)
MAX_CYCLE_SD_FRAC = 0.1  # 1, largest stride-to-stride spread of the cycle time the twin is given
MIN_REST_S = 0.5  # s, least standing time at either end of the twin (the filter aligns on it)
QUIET_WINDOW_S = 0.5  # s, length of the quietest window (noise, tilt) and least length of a rest for the gyro bias
REST_MARGIN_S = 0.25  # s, trimmed from both ends of a detected rest before a mean is taken over it (its core)
MIN_ACC_SD_MPS2 = 1e-5  # m/s^2, least quiet-window accelerometer spread (a twin's noise density from it)
MIN_GYR_SD_RAD_S = 1e-6  # rad/s, least quiet-window gyro spread
SWING_HEIGHT_BOUNDS_M = (0.01, 0.3)  # m, range of the twin's swing height after matching the clearance
NAV_OPTIONS = pipeline.NavOptions(method="rk4")  # both sides are navigated from their IMU samples
TRUTH_CACHE_MB = 64.0  # MB of simulated walks (ideal sensor) kept per loop process, the ones used last (at least
# two): effects on the sensor re-use them, and a round's twin outlives the ~15 walks of one effect's search
# (a 40 s twin at 205 Hz is 1.4 MB)

# -- gait shape fit (gaitsim.loop.gait_fit) ------------------------------------------------------------------
PROFILE_POINTS = 128  # phase grid of the pitch profiles
ANGLE_WEIGHT = 10.0  # deg/s of rate misfit per degree of pitch-extreme misfit
MAX_EVALUATIONS = 600  # least-squares evaluations of the pitch fit
MIN_SWING_FRAC = 0.25  # 1, smallest swing share of the gait cycle the fit may reach
STANCE_FLOOR = 0.1  # 1, heel off: where the rate first exceeds this share of the push-off peak
HEEL_STRIKE_AFTER_PHASE = 0.6  # 1, the heel strike is looked for after this share of the stride (from the onset)
TOE_OFF_BEFORE_STRIKE_PHASE = 0.15  # 1, the toe off is looked for at least this share of the stride before it
MAX_SLAP_ROCKER_SHARE = 0.7  # 1, the first guess of the forefoot slap lasts at most this share of the heel rocker
PITCH_FIT_DIFF_STEP = 1e-3  # 1, relative finite-difference step of the pitch fit's Jacobian
# (scenario key, section, low, high in the key's unit): what the pitch fit varies; swing_frac = 1 - the stance
# fractions
PITCH_FIT_BOUNDS = (("heel_rocker_frac", "gait", 0.04, 0.3), ("foot_flat_frac", "gait", 0.05, 0.5),
                    ("push_off_frac", "gait", 0.05, 0.35), ("pitch_heel_strike_deg", "gait", -45.0, -2.0),
                    ("pitch_rate_heel_strike_dps", "gait", -300.0, 700.0), ("pitch_toe_off_deg", "gait", 5.0, 85.0),
                    ("pitch_rate_toe_off_dps", "gait", -300.0, 900.0),
                    ("pitch_accel_toe_off_dps2", "gait", -4e4, 1e4),
                    ("pitch_accel_heel_strike_dps2", "gait", -2e4, 2e4), ("slap_rate_dps", "impact", 0.0, 900.0),
                    ("slap_duration_s", "impact", 0.005, 0.15))
# a running twin's pitch fit (gaitsim.world.gaits' running kinds: a forefoot strike lands toes down, the foot
# leaves the ground turning at ~1000 deg/s); the other bounds as for walking. A running foot turns at 15-50 deg/s
# through its stance (|w| near QUIET_RATE_DPS), so the recording's |w| onset, the phase origin of its profile, does
# not fall where the model's pitch rate rises: the origin's offset (a share of the stride) is fitted as well
RUN_PITCH_FIT_BOUNDS = tuple((name, section, *{"pitch_heel_strike_deg": (-45.0, 30.0),
                                                "pitch_rate_heel_strike_dps": (-700.0, 700.0),
                                                "pitch_rate_toe_off_dps": (-300.0, 1800.0)}.get(name, (low, high)))
                             for name, section, low, high in PITCH_FIT_BOUNDS)
RUN_PITCH_FIT_BOUNDS += (("origin_shift", "origin", -0.1, 0.1),)  # the origin's offset, a share of the stride
ORIGIN_GRID_POINTS = 41  # offsets tried for each start of a fit with a fitted origin (every 0.5 % of the stride)

# -- sensor position on the foot (gaitsim.loop.mount_fit) ----------------------------------------------------
PROBE_M = 0.1  # m, how far each probe moves the IMU site
YAW_ITERATIONS = 2  # steps of the twin's mount-yaw fit (mount_fit.fit_yaw)
YAW_BOUND_DEG = 45.0  # deg, largest mount yaw; beyond it an axis of the frame check (frame.py) changes
SITE_BOUNDS_M = ((-0.08, -0.07, 0.0), (0.25, 0.07, 0.12))  # m, foot frame from the heel contact

# -- effects (gaitsim.loop.effects) --------------------------------------------------------------------------
RINGING_BAND_HZ = 20.0  # Hz, lowest ringing frequency searched in the residual spectrum
RINGING_SMOOTHING_HZ = 10.0  # Hz, width of the moving average applied to both spectra before their log ratio
MIN_RINGING_HZ = 5.0  # Hz, the ringing effect is tried only from this frequency up
CLIP_BAND = 0.01  # 1, a clipped sample lies within this share of the recording's largest accelerometer reading
MIN_CLIPPED_RUNS = 2  # runs of >= 2 consecutive such samples needed before saturation is tried

# -- attribution (gaitsim.loop.attribution) ------------------------------------------------------------------
NAV_REPEATS = 3  # re-simulations of the twin with other seeds; their pairs calibrate the comparison noise
TWIN_OF_TWIN_SEED = 100  # seed offset of those re-simulations
NAV_FLOOR = {"nav_length_ratio": 0.003, "nav_heading_drift": 0.01, "nav_final_error": 0.05}  # 1, deg/s, m
HARM_FACTOR = 2.0  # 1, an effect harms a residual at the noise level that it pushes beyond this x NOISE_LEVEL
EXPLAINED_FRACTION = 0.5  # 1, least share of the acted residual an accepted effect explains
DERIVED = ("stance_shoe",)  # residuals never acted on (functions of others)
REFITTED = ("swing_axis_yaw",)  # residuals the twin's own fit closes again after each added effect (the sensor's
# yaw on the foot, twin.refit_yaw): never acted on, outside the misfit, harmed by no effect
MAX_EFFECTS = 6  # effects added to a twin per recording at most (a residual left unexplained costs none)
GRID_POINTS = 7  # grid of each effect's magnitude search before the Brent refinement
BRENT_ITERATIONS = 8  # iterations of the bounded Brent refinement
BRENT_TOLERANCE = 1e-3  # 1, Brent's magnitude tolerance as a share of its bracket
JOINT_SIZE = 3  # linear sensor effects fitted together at most (attribution.fit_joint)
JOINT_STEP_SHARE = 0.05  # 1, finite-difference step of a linear effect, as a share of its search range
JOINT_SUBSETS = 3  # best sets of the linearised fit refined by simulation
JOINT_ITERATIONS = 3  # Gauss-Newton iterations of each refinement
JOINT_BOUND_SHARE = 1e-3  # 1, a refined magnitude this close to its search range's edge (a share of the range) is
# on the edge: no estimate

# -- blind tests (gaitsim.loop.blind) ------------------------------------------------------------------------
BLIND_WALK_LENGTH_M = 20.0  # m, straight walk of every blind case
BLIND_RUN_LENGTH_M = 40.0  # m, straight run of the running blind cases (16 strides of 2.4 m)
BLIND_RATE_HZ = 200.0  # Hz, its IMU rate
BLIND_REFERENCE_RATE_HZ = 100.0  # Hz, its position reference (like a motion tracker)
BLIND_SEED = 11  # seed of the blind recordings
BLIND_EFFECTS = 4  # effects added per blind recording on a simulated sensor at most
BLIND_MAGNITUDE_TOLERANCE = 0.25  # 1, a blind effect is found when its magnitude is within this share of the truth
