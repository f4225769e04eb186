"""The stride-normalised signature of a foot-IMU recording.

A *signature* (:func:`signature`) summarises one recording with the same recipe whether it is measured or
simulated, so two signatures can be compared number by number:

1. Strides from the IMU alone (:mod:`gaitsim.loop.strides`: the shared filter's default detector, a stride
   from one gyro-quiet stance onset to the next, irregular ones dropped).
2. Per stride (n strides, each statistic's uncertainty is its stride-to-stride standard deviation / sqrt(n)):

   ==========================  ========  ===============================================================
   name                        unit      per-stride statistic
   ==========================  ========  ===============================================================
   stance_gyro                 deg/s     mean |angular rate| over the middle third of the detected stance
   stance_rate_x, _y, _z       deg/s     mean angular rate per sensor axis there (signed: a sustained
                                         rotation of the standing foot shows here, a symmetric rocking not)
   stance_acc_spread           m/s^2     rms deviation of the specific force from its mean there (3 axes)
   stance_duration             s         detected stance length (at the detector's threshold)
   stance_shoe                 log10     median log10 of the SHOE statistic inside the detected stance
   acc_peak                    m/s^2     largest |specific force| of the stride
   gyr_peak                    deg/s     largest |angular rate| of the stride
   hf40, hf80                  %         share of the stride's |a| variance above 40 / 80 Hz (only when
                                         the Nyquist frequency exceeds HF_NYQUIST_MARGIN times the edge)
   onset_hf                    m/s^2     rms of |a| high-passed at ONSET_HF_EDGE_HZ over the first
                                         ONSET_WINDOW_S of the stance (impact ringing lives here)
   acc_gyro_lag                ms        the gyro's lag behind the accelerometer read from the push-off, a
                                         turn about the still toe contact (:mod:`gaitsim.loop.push_off`; > 0: the
                                         gyro's samples come later), jackknife error over the stances
   swing_axis_yaw              deg       atan2(x, y) of the stride's dominant rotation axis (angular
                                         momentum direction of the gyro, sign so that y > 0)
   stance_velocity             m/s       forward velocity of the position track (reference or truth) over
                                         the middle third of the stance; forward = this stride's direction

   closure_forward, _left, _up  m/s       stride closure (:mod:`gaitsim.loop.closure`): velocity the unaided
                                         strapdown carries from this stride's stance to the next one
   closure_roll, _pitch        deg       stride closure: gyro-carried minus accelerometer-read tilt there;
                                         uncertainty also the gyro bias's error x the stride duration
   ==========================  ========  ===============================================================

   plus ``rest_acc_norm`` (m/s^2, |mean specific force| over the first detected rest, uncertainty its sample
   standard deviation / sqrt(samples)), ``rest_gyro_change`` (deg/s) and ``rest_acc_change`` (m/s^2): the
   length of the change of the mean angular rate and specific force from the first to the last detected rest
   (at least ``settings.QUIET_REST_S`` each; absent without two such rests), a drift no constant sensor error
   makes, uncertainty from the samples' spread; ``rest_acc_noise_lag1``, ``rest_acc_noise_lag2``,
   ``rest_gyro_noise_lag1`` and ``rest_gyro_noise_lag2`` (1): the autocorrelation at lags 1 and 2 of each sensor's
   first difference at rest, per channel over blocks of ``settings.REST_NOISE_BLOCK`` samples of every rest of at
   least ``settings.QUIET_REST_S`` (mean over the sensor's three channels and the blocks, uncertainty the blocks'
   scatter). White noise reads -0.5 and 0 (a little above -0.5 in blocks this short, in recording and twin alike);
   a low-pass in the sensor correlates neighbouring samples, and the pair tells its form: a first-order stage
   without zeros, ``y[k] = b y[k-1] + (1 - b) x[k]``, reads ``-(1 - b) / 2`` and ``-b (1 - b) / 2`` (b = 0.46 at a
   cutoff of an eighth of the sample rate: -0.27 and -0.12), a digital Butterworth with the same lag 1 reads lag 2
   below -0.35 (its zero at the Nyquist frequency). Differences, less their straight line in each block, take out
   the slow motion of a foot that is not quite still (a motion at frequency f keeps (2 pi f / rate)^2 of its
   variance in the difference); and the phase profiles: each stride's six channels
   resampled onto ``PHASE_POINTS`` points of the normalised gait phase (0 = stance onset), with per-phase mean
   and standard error. Capitalised names are :mod:`gaitsim.loop.settings`.

   Every mean over a rest (these, and the gyro bias the stride closure subtracts) is taken over its core
   (:func:`rest_core`): a detected rest reaches into the heel off, where the gyro already reads tens of deg/s,
   and whether its last sample does depends on the sample boundary the detector's statistic crosses.

The residuals between two signatures are :mod:`gaitsim.loop.residuals`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from nav import detectors
from nav.constants import DEFAULT_GRAVITY
from nav.series import resample

from . import settings
from .closure import closure_between_stances, following, middle_thirds
from .push_off import push_off_lag
from .strides import detect_stances, dominant_axis, phase_resample, regular_strides

CHANNELS = ("acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z")
CLOSURE = ("closure_forward", "closure_left", "closure_up", "closure_roll", "closure_pitch")
PER_STRIDE = ("stance_gyro", "stance_rate_x", "stance_rate_y", "stance_rate_z", "stance_acc_spread", "stance_duration",
              "stance_shoe", "acc_peak", "gyr_peak", "hf40", "hf80", "onset_hf", "swing_axis_yaw")  # scalars per stride


@dataclass
class Scalar:
    """A signature number: value, standard error and the per-stride samples it came from."""

    value: float
    se: float
    samples: np.ndarray = field(default_factory=lambda: np.empty(0))


@dataclass
class Profile:
    """Per-phase mean (P,) and standard error (P,) of one channel; ``strides`` (n, P) the resampled strides."""

    mean: np.ndarray
    se: np.ndarray
    strides: np.ndarray


@dataclass
class Signature:
    """Stride-normalised summary of one recording (see the module docstring).

    Attributes
    ----------
    scalars : name -> Scalar.
    profiles : channel -> Profile (acc in m/s^2, gyr in deg/s).
    strides : (n, 2) int, sample indices of each used stride's start and end.
    stances : (n, 2) int, sample indices of each used stride's detected stance (start, end).
    rate_hz : median sample rate.
    spectrum : (frequencies Hz, mean power of |a| per stride, normalised to unit total) for figures.
    stationary : (N,) bool, the zero-velocity detection the strides were cut from (nav's default, the anchored
        SHOE: :func:`gaitsim.loop.strides.detect_stances`).
    gravity : m/s^2, the gravity that detection assumed (the recording's).
    stance_runs : (m, 2) int, every detected stance [start, end), the rests included (the twin fit re-uses them).
    """

    scalars: dict
    profiles: dict
    strides: np.ndarray
    stances: np.ndarray
    rate_hz: float
    spectrum: tuple
    stationary: np.ndarray
    gravity: float
    stance_runs: np.ndarray


def mean_se(samples) -> Scalar:
    x = np.asarray(samples, float)
    x = x[np.isfinite(x)]
    if len(x) == 0:
        return Scalar(math.nan, math.nan, x)
    se = float(np.std(x, ddof=1) / math.sqrt(len(x))) if len(x) > 1 else math.nan
    return Scalar(float(np.mean(x)), se, x)


def _spectrum_of(x: np.ndarray, rate_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """(rfft of ``x`` less its mean, its frequencies in Hz)."""
    return np.fft.rfft(x - x.mean()), np.fft.rfftfreq(len(x), 1.0 / rate_hz)


def _band_share(spec: np.ndarray, freq: np.ndarray, edge_hz: float) -> float:
    """Share (%) of the variance above ``edge_hz`` of a series with the spectrum ``spec`` at ``freq`` (Hz;
    :func:`_spectrum_of`)."""
    power = np.abs(spec) ** 2
    total = power[1:].sum()
    return float(100.0 * power[freq > edge_hz].sum() / total) if total > 0 else math.nan


def _band_pass(spec: np.ndarray, freq: np.ndarray, n: int, rate_hz: float, band: tuple) -> np.ndarray:
    """Zero-phase FFT band pass (band in Hz, upper edge at most ``settings.BAND_TOP_SHARE`` times the rate) of the
    ``n`` samples with the spectrum ``spec`` at ``freq`` (:func:`_spectrum_of`: mean removed)."""
    spec = np.where((freq < band[0]) | (freq > min(band[1], settings.BAND_TOP_SHARE * rate_hz)), 0.0, spec)
    return np.fft.irfft(spec, n)


def _swing_axis_yaw(gyr: np.ndarray) -> float:
    """atan2(x, y) (deg) of the stride's dominant rotation axis."""
    axis = dominant_axis(gyr)
    return float(np.degrees(np.arctan2(axis[0], axis[1])))


def _stance_velocity(t: np.ndarray, pos_t: np.ndarray, pos: np.ndarray, strides: np.ndarray,
                     stances: np.ndarray) -> np.ndarray:
    """Per stride, mean forward velocity (m/s) of a position track over the middle third of the stance."""
    ok = np.all(np.isfinite(pos), axis=1)
    if ok.sum() < settings.MIN_TRACK_SAMPLES:
        return np.full(len(strides), math.nan)
    pt, pp = pos_t[ok], pos[ok, :2]
    (s0, s1), (c0, c1) = np.asarray(strides).T, np.asarray(stances).T
    t_mid = 0.5 * (t[c0] + t[c1 - 1])
    step = resample(t_mid + (t[s1] - t[s0]), pt, pp) - resample(t_mid, pt, pp)
    length = np.hypot(step[:, 0], step[:, 1])
    third = (t[c1 - 1] - t[c0]) / 3.0
    ta, tb = t[c0] + third, t[c1 - 1] - third
    valid = ((t_mid + (t[s1] - t[s0]) <= pt[-1]) & (t[c0] >= pt[0]) & (length >= settings.MIN_TRACK_STRIDE_M)
             & (tb - ta > 0))
    with np.errstate(divide="ignore", invalid="ignore"):
        along = np.einsum("ij,ij->i", resample(tb, pt, pp) - resample(ta, pt, pp), step / length[:, None])
        velocity = along / (tb - ta)
    return np.where(valid, velocity, math.nan)


def signature(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, pos_t: np.ndarray | None = None,
              pos: np.ndarray | None = None, gravity: float = DEFAULT_GRAVITY) -> Signature:
    """Stride-normalised signature of one recording (module docstring).

    Parameters
    ----------
    t : (N,) s.  acc : (N, 3) m/s^2 specific force.  gyr : (N, 3) rad/s.
    pos_t, pos : optional position track (M,) s and (M, 3) m on the same clock (a reference or the truth);
        needed for ``stance_velocity``.
    gravity : m/s^2, for the zero-velocity detector.

    Raises
    ------
    ValueError when fewer than 3 regular strides are found.
    """
    t = np.asarray(t, float)
    acc = np.asarray(acc, float)
    gyr = np.asarray(gyr, float)
    rate = detectors.sample_rate(t)
    result, stances_all = detect_stances(t, acc, gyr, gravity)
    strides, stances = regular_strides(t, gyr, stances_all)
    if len(strides) < 3:
        raise ValueError(f"signature: only {len(strides)} regular strides found (need 3); stance runs: "
                         f"{len(stances_all)}")
    acc_norm = np.linalg.norm(acc, axis=1)
    log_stat = np.log10(np.maximum(result.statistic, 1e-12))
    per = {k: [] for k in PER_STRIDE}
    for stride, stance in zip(strides, stances):
        for key, value in {**_stance_statistics(t, acc, gyr, log_stat, stance),
                           **_stride_statistics(acc_norm, gyr, rate, stride)}.items():
            per[key].append(value)
    scalars = {k: mean_se(v) for k, v in per.items()}
    if pos is not None and pos_t is not None:
        scalars["stance_velocity"] = mean_se(_stance_velocity(t, np.asarray(pos_t, float), np.asarray(pos, float),
                                                               strides, stances))
    first_rest = rest_core(t, stances_all[0])
    scalars["rest_acc_norm"] = _rest_acc_norm(acc[first_rest])
    scalars.update(_rest_changes(t, acc, gyr, stances_all))
    scalars.update(_rest_noise_correlation(t, acc, gyr, stances_all))
    closing = closure_between_stances(t, acc, gyr, stances, following(stances, stances_all), gravity,
                                      rest_gyro_bias(t, gyr, stances_all, scalars.get("rest_gyro_change")))
    for name, column in zip(CLOSURE, np.column_stack([closing.velocity, np.degrees(closing.tilt[:, :2])]).T):
        scalars[name] = mean_se(column)
    stride_s = float(np.mean(t[strides[:, 1] - 1] - t[strides[:, 0]]))
    common = np.degrees(_rest_mean_se(gyr[first_rest])) * stride_s  # the bias's error, the same every stride
    for axis, name in enumerate(("closure_roll", "closure_pitch")):
        spread = scalars[name]
        scalars[name] = Scalar(spread.value, float(np.hypot(spread.se, common[axis])), spread.samples)
    scalars["acc_gyro_lag"] = Scalar(*push_off_lag(t, acc, gyr, stances), np.empty(0))
    return Signature(scalars, _profiles(t, acc, gyr, strides), strides, stances, rate,
                     _spectrum(acc_norm, strides, rate), result.stationary, float(gravity), stances_all)


def _stance_statistics(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, log_stat: np.ndarray,
                       stance: np.ndarray) -> dict:
    """The stance statistics of one stride (module docstring) over its detected stance [c0, c1)."""
    c0, c1 = stance
    core = slice(*middle_thirds(stance)[0])
    rates = np.degrees(gyr[core].mean(0))
    inside = log_stat[c0:min(c1, len(log_stat))]
    return {"stance_gyro": np.degrees(np.linalg.norm(gyr[core], axis=1).mean()),
            "stance_rate_x": rates[0], "stance_rate_y": rates[1], "stance_rate_z": rates[2],
            "stance_acc_spread": float(np.sqrt(np.mean(np.sum((acc[core] - acc[core].mean(0)) ** 2, 1)))),
            "stance_duration": t[c1 - 1] - t[c0],
            "stance_shoe": float(np.median(inside)) if inside.size else math.nan}


def _stride_statistics(acc_norm: np.ndarray, gyr: np.ndarray, rate: float, stride: np.ndarray) -> dict:
    """The whole-stride statistics of one stride [s0, s1) (module docstring); the high-frequency ones only where
    the sample rate resolves their band."""
    s0, s1 = stride
    a = acc_norm[s0:s1]
    spec, freq = _spectrum_of(a, rate)
    out = {"acc_peak": a.max(), "gyr_peak": np.degrees(np.linalg.norm(gyr[s0:s1], axis=1).max())}
    for edge, key in zip(settings.HF_EDGES_HZ, ("hf40", "hf80")):
        out[key] = _band_share(spec, freq, edge) if rate / 2 > settings.HF_NYQUIST_MARGIN * edge else math.nan
    if rate / 2 > settings.HF_NYQUIST_MARGIN * settings.ONSET_HF_EDGE_HZ:
        high = _band_pass(spec, freq, len(a), rate, (settings.ONSET_HF_EDGE_HZ, np.inf))
        out["onset_hf"] = float(np.sqrt(np.mean(high[:max(2, int(settings.ONSET_WINDOW_S * rate))] ** 2)))
    out["swing_axis_yaw"] = _swing_axis_yaw(gyr[s0:s1])
    return out


def _rest_acc_norm(rest_acc: np.ndarray) -> Scalar:
    """|mean specific force| (m/s^2) over the first detected rest; its uncertainty the samples' spread (at least
    ``settings.REST_ACC_NORM_SD_FLOOR``) / sqrt(samples)."""
    norm_samples = np.linalg.norm(rest_acc, axis=1)
    spread = max(norm_samples.std(ddof=1), settings.REST_ACC_NORM_SD_FLOOR)
    return Scalar(float(np.linalg.norm(rest_acc.mean(0))), float(spread / math.sqrt(len(rest_acc))), norm_samples)


def rest_core(t: np.ndarray, rest) -> slice:
    """The samples of a detected rest [start, end) less ``settings.REST_MARGIN_S`` at both ends (at most a quarter
    of the rest each, so a short rest keeps its middle half).

    A detected rest ends where the detector's statistic crosses its threshold, which can take in a heel off's
    first samples: on a 200 Hz simulated walk the first rest's last sample reads ~20 deg/s or not depending on
    which side of a sample the crossing falls, and a mean over that rest moved the gyro bias on y by 0.03 deg/s
    and the stride closure's pitch by 0.045 deg (a jump of 3 standard errors between twins a fraction of a
    millimetre apart in sensor position). Over the core the same mean is continuous in the data."""
    start, end = int(rest[0]), int(rest[1])
    step = (t[end - 1] - t[start]) / max(end - start - 1, 1)
    margin = min(int(round(settings.REST_MARGIN_S / step)) if step > 0 else 0, (end - start) // 4)
    return slice(start + margin, end - margin)


def _rest_mean_se(core: np.ndarray) -> np.ndarray:
    """(3,) standard error of the mean of the samples ``core`` (N, 3) of a rest's core (spread / sqrt(samples)).

    The stride closure subtracts the first rest's mean rate as the gyro bias; its error turns every stride's tilt
    by about the same angle (error x stride duration), which the strides' scatter does not show. On a 200 Hz
    simulated walk that is ~0.003 deg/s (0.004 deg per stride), on the 60 Hz ucr-fgo recordings, whose first
    rests are 0.7-1.6 s of a foot that is not quite still (1-2.7 deg/s spread), 0.16-0.27 deg/s."""
    return core.std(axis=0, ddof=1) / math.sqrt(len(core)) if len(core) > 1 else np.full(core.shape[1], math.nan)


def _long_rests(t: np.ndarray, stances: np.ndarray) -> list:
    """The detected stances [start, end) lasting at least ``settings.QUIET_REST_S``."""
    return [(a, b) for a, b in stances if t[b - 1] - t[a] >= settings.QUIET_REST_S]


def rest_gyro_bias(t: np.ndarray, gyr: np.ndarray, stances: np.ndarray, change: Scalar | None) -> np.ndarray:
    """(N, 3) rad/s, the gyro bias the stride closure subtracts: the mean rate over the core (:func:`rest_core`) of
    the first detected stance (the initial rest). When the bias changed significantly between the first and the
    last long rest (``change``, the ``rest_gyro_change`` scalar, beyond ``settings.NOISE_LEVEL`` times its
    standard error) the means of those two rests' cores are interpolated linearly in time between their centres
    instead (held constant outside): a drifting bias is outside the effect library, and it must not leak into the
    closure, where it would read as a scale or time error of the sensor. Below that level the last rest only adds
    its noise."""
    long = _long_rests(t, stances)
    if change is None or change.value <= settings.NOISE_LEVEL * change.se:
        return np.broadcast_to(gyr[rest_core(t, stances[0])].mean(0), gyr.shape)
    (a0, a1), (b0, b1) = long[0], long[-1]
    centres = [0.5 * (t[a0] + t[a1 - 1]), 0.5 * (t[b0] + t[b1 - 1])]
    means = np.array([gyr[rest_core(t, long[0])].mean(0), gyr[rest_core(t, long[-1])].mean(0)])
    return np.column_stack([np.interp(t, centres, means[:, i]) for i in range(3)])


def _rest_changes(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, stances: np.ndarray) -> dict:
    """``rest_gyro_change`` (deg/s) and ``rest_acc_change`` (m/s^2) between the first and the last rest of at
    least ``settings.QUIET_REST_S`` (module docstring); empty without two such rests."""
    long = _long_rests(t, stances)
    if len(long) < 2:
        return {}
    first, last = rest_core(t, long[0]), rest_core(t, long[-1])
    out = {}
    for name, x, scale in (("rest_gyro_change", gyr, math.degrees(1.0)), ("rest_acc_change", acc, 1.0)):
        change = scale * (x[last].mean(0) - x[first].mean(0))
        spread = scale * np.hypot(_rest_mean_se(x[first]), _rest_mean_se(x[last]))
        out[name] = Scalar(float(np.linalg.norm(change)), float(np.linalg.norm(spread)), change)
    return out


def _rest_noise_correlation(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, stances: np.ndarray) -> dict:
    """``rest_acc_noise_lag1`` ... ``rest_gyro_noise_lag2`` (1) over the long rests (module docstring); a sensor's
    pair is absent with fewer than two blocks. Each block's first difference loses its straight line (the foot's
    slow motion at a rest's edges, up to a quadratic in the samples); a channel whose first difference does not
    vary (a quantised reading stuck on one value) is left out of its block."""
    block = settings.REST_NOISE_BLOCK
    ramp = np.arange(block - 1) - (block - 2) / 2.0
    cores = [rest_core(t, rest) for rest in _long_rests(t, stances)]
    out = {}
    for sensor, x in (("acc", acc), ("gyro", gyr)):
        lags = []
        for core in cores:
            for start in range(core.start, core.stop - block + 1, block):
                d = np.diff(x[start:start + block], axis=0)
                d -= d.mean(0) + np.outer(ramp, ramp @ d) / (ramp @ ramp)  # a quadratic motion's straight line
                power = np.sum(d * d, axis=0)
                moving = power > 0
                if moving.any():
                    lags.append([np.mean(np.sum(d[lag:] * d[:-lag], axis=0)[moving] / power[moving])
                                 for lag in (1, 2)])
        if len(lags) >= 2:
            out.update({f"rest_{sensor}_noise_lag{lag}": mean_se(column)
                        for lag, column in zip((1, 2), np.array(lags).T)})
    return out


def _profiles(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, strides: np.ndarray) -> dict:
    """Channel -> :class:`Profile` of the six channels (acc m/s^2, gyr deg/s) on the stride phase grid."""
    resampled = phase_resample(t, np.column_stack([acc, np.degrees(gyr)]), strides)  # (S, P, 6), CHANNELS order
    profiles = {}
    for i, c in enumerate(CHANNELS):
        x = resampled[:, :, i]
        profiles[c] = Profile(x.mean(0), x.std(0, ddof=1) / math.sqrt(len(x)), x)
    return profiles


def _spectrum(acc_norm: np.ndarray, strides: np.ndarray, rate: float) -> tuple[np.ndarray, np.ndarray]:
    """(frequencies Hz, mean over strides of the |a| power spectrum, each stride's normalised to unit total)."""
    n_fft = int(2 ** np.ceil(np.log2(np.median(strides[:, 1] - strides[:, 0]))))
    spectra = []
    for s0, s1 in strides:
        seg = acc_norm[s0:s1] - acc_norm[s0:s1].mean()
        spec = np.abs(np.fft.rfft(seg, n_fft)) ** 2
        spectra.append(spec / max(spec[1:].sum(), 1e-30))
    return np.fft.rfftfreq(n_fft, 1.0 / rate), np.mean(spectra, axis=0)
