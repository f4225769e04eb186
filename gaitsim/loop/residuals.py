"""Stride-normalised signatures of a foot-IMU recording and the residuals between two of them.

A *signature* (:func:`signature`) summarises one recording with the same recipe whether it is measured or
simulated, so two signatures can be compared number by number:

1. Stance is detected from the IMU alone (SHOE with the shared filter's defaults, :mod:`nav.detectors`); runs of
   stance closer than ``MERGE_GAP_S`` are merged. A stride runs from one stance onset to the next, the onset
   being where the angular rate last fell below ``QUIET_RATE_DPS`` before the stance centre (a gyro-only
   event, so accelerometer-side effects that move the SHOE onset do not shift the phase grid); strides whose
   period is not within 0.6..1.5 times the median (rest at the ends, missed stances) are dropped.
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
                                         the Nyquist frequency exceeds 1.25 times the band edge)
   onset_hf                    m/s^2     rms of |a| high-passed at ONSET_HF_EDGE_HZ over the first
                                         ONSET_WINDOW_S of the stance (impact ringing lives here)
   acc_gyro_lag                ms        shift of the stride's cross-correlation curve of |a| with |dw/dt|
                                         (band-passed, +-LAG_WINDOW_S) against the twin's mean curve; set by
                                         :func:`compare` (the twin's strides against their own mean give its
                                         spread), so a pure relative delay of the gyro shows as its value
   swing_axis_yaw              deg       atan2(x, y) of the stride's dominant rotation axis (angular
                                         momentum direction of the gyro, sign so that y > 0)
   stance_velocity             m/s       forward velocity of the position track (reference or truth) over
                                         the middle third of the stance; forward = this stride's direction
   ==========================  ========  ===============================================================

   plus ``rest_acc_norm`` (m/s^2, |mean specific force| over the first detected rest, uncertainty its sample
   standard deviation / sqrt(samples)) and the phase profiles: each stride's six channels resampled onto
   ``PHASE_POINTS`` points of the normalised gait phase (0 = stance onset), with per-phase mean and standard
   error.
3. Residuals (:func:`compare`): for a scalar, ``measured - twin`` with uncertainty
   ``sqrt(se_measured^2 + se_twin^2 + floor^2)``; for a profile ``profile_<channel>``, the rms over the phase
   grid of the mean difference, with the rms of the combined standard error (and the floor) as its
   uncertainty (pure noise then gives a ratio near 1, not 0). The floor is what the twin fit itself is off by
   (measured by the loop on a twin of its own twin). A residual is at the noise level when
   ``|value| <= NOISE_LEVEL * uncertainty``.

Navigation residuals (length ratio, heading drift) are added by :mod:`gaitsim.loop.attribution`, which runs
the filter.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from nav import detectors
from nav.alignment import stationary_runs

PHASE_POINTS = 64
MERGE_GAP_S = 0.04  # s, stance runs closer than this are one stance
MIN_STANCE_S = 0.06  # s, shorter stance runs are ignored
MAX_STRIDE_S = 3.0  # s, longer "strides" contain rest
LAG_WINDOW_S = 0.06  # s, half-width of the |a| x |dw/dt| cross-correlation curve
LAG_BAND_HZ = (8.0, 45.0)
ONSET_HF_EDGE_HZ = 30.0
ONSET_WINDOW_S = 0.1  # s, from the stride's gyro onset
LAG_UPSAMPLE = 16  # the curves are compared on a grid this much finer than the samples
QUIET_RATE_DPS = 40.0  # deg/s, the stride's phase origin is where |w| last fell below this before mid-stance
UNCERTAINTY_FLOOR = {"stance_velocity": 0.0005, "swing_axis_yaw": 0.05}  # reference / axis resolution
NOISE_LEVEL = 3.0  # a residual with |value| <= NOISE_LEVEL * uncertainty is at the noise level
CHANNELS = ("acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z")
UNITS = {
    "stance_gyro": "deg/s", **{f"stance_rate_{a}": "deg/s" for a in "xyz"}, "stance_acc_spread": "m/s^2", "stance_duration": "s", "stance_shoe": "log10",
    "acc_peak": "m/s^2", "gyr_peak": "deg/s", "hf40": "%", "hf80": "%", "onset_hf": "m/s^2", "acc_gyro_lag": "ms",
    "swing_axis_yaw": "deg", "stance_velocity": "m/s", "rest_acc_norm": "m/s^2",
    **{f"profile_{c}": ("m/s^2" if c.startswith("acc") else "deg/s") for c in CHANNELS},
}


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
    lag_curves : (n, L) per-stride |a| x |dw/dt| cross-correlation curves (for ``acc_gyro_lag``).
    """

    scalars: dict
    profiles: dict
    strides: np.ndarray
    stances: np.ndarray
    rate_hz: float
    spectrum: tuple
    lag_curves: np.ndarray


@dataclass
class Residual:
    """One compared number: measured, twin, their difference and its uncertainty (units in ``unit``)."""

    name: str
    unit: str
    measured: float
    twin: float
    value: float
    uncertainty: float

    @property
    def z(self) -> float:
        """|value| / uncertainty (inf when the uncertainty is zero and the value is not)."""
        if not math.isfinite(self.value):
            return math.nan
        if self.uncertainty <= 0:
            return 0.0 if self.value == 0 else math.inf
        return abs(self.value) / self.uncertainty

    @property
    def at_noise_level(self) -> bool:
        return bool(self.z <= NOISE_LEVEL)

    def as_dict(self) -> dict:
        return {"name": self.name, "unit": self.unit, "measured": self.measured, "twin": self.twin,
                "value": self.value, "uncertainty": self.uncertainty, "z": self.z}


def stance_intervals(t: np.ndarray, stationary: np.ndarray) -> np.ndarray:
    """(m, 2) sample indices [start, end) of detected stances after merging gaps < MERGE_GAP_S and dropping
    runs shorter than MIN_STANCE_S; ``t`` in s."""
    starts, ends = stationary_runs(stationary)
    if len(starts) == 0:
        return np.empty((0, 2), int)
    merged = [[starts[0], ends[0]]]
    for s, e in zip(starts[1:], ends[1:]):
        if t[s] - t[merged[-1][1] - 1] < MERGE_GAP_S:
            merged[-1][1] = e
        else:
            merged.append([s, e])
    out = np.array(merged, int)
    keep = t[out[:, 1] - 1] - t[out[:, 0]] >= MIN_STANCE_S
    return out[keep]


def gyro_onsets(gyr: np.ndarray, stances: np.ndarray) -> np.ndarray:
    """Sample index where |w| last rose above QUIET_RATE_DPS before each stance's centre, plus one."""
    loud = np.degrees(np.linalg.norm(gyr, axis=1)) >= QUIET_RATE_DPS
    loud_index = np.flatnonzero(loud)
    centres = (stances[:, 0] + stances[:, 1]) // 2
    before = np.searchsorted(loud_index, centres) - 1
    return np.where(before >= 0, loud_index[np.maximum(before, 0)] + 1, stances[:, 0])


def _strides(t: np.ndarray, gyr: np.ndarray, stances: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Stride [start, end) sample indices (gyro onset to next onset) and their stances, regular ones only."""
    if len(stances) < 2:
        return np.empty((0, 2), int), np.empty((0, 2), int)
    onsets = gyro_onsets(gyr, stances)
    periods = t[onsets[1:]] - t[onsets[:-1]]
    usable = periods < MAX_STRIDE_S
    if not usable.any():
        return np.empty((0, 2), int), np.empty((0, 2), int)
    median = np.median(periods[usable])
    keep = usable & (periods > 0.6 * median) & (periods < 1.5 * median)
    # a stance that lasts longer than the stride's own period is rest, not gait
    keep &= (t[stances[:-1, 1] - 1] - t[onsets[:-1]]) < 0.8 * periods
    strides = np.column_stack([onsets[:-1], onsets[1:]])[keep]
    return strides, stances[:-1][keep]


def phase_resample(t: np.ndarray, x: np.ndarray, strides: np.ndarray, points: int = PHASE_POINTS) -> np.ndarray:
    """(S, P, ...) the signal ``x`` (N, ...) resampled linearly on ``points`` equal phases of each stride
    [s0, s1] (sample indices; phase 0 at s0, the last phase one step before s1)."""
    phase = np.linspace(0.0, 1.0, points, endpoint=False)
    x = np.asarray(x, float)
    flat = x.reshape(len(x), -1)
    out = []
    for s0, s1 in strides:
        grid = t[s0] + phase * (t[s1] - t[s0])
        out.append(np.stack([np.interp(grid, t[s0:s1 + 1], flat[s0:s1 + 1, i]) for i in range(flat.shape[1])], -1))
    return np.array(out).reshape((len(strides), points) + x.shape[1:])


def _mean_se(samples) -> Scalar:
    x = np.asarray(samples, float)
    x = x[np.isfinite(x)]
    if len(x) == 0:
        return Scalar(math.nan, math.nan, x)
    se = float(np.std(x, ddof=1) / math.sqrt(len(x))) if len(x) > 1 else math.nan
    return Scalar(float(np.mean(x)), se, x)


def _band_share(x: np.ndarray, rate_hz: float, edge_hz: float) -> float:
    """Share (%) of the variance of ``x`` above ``edge_hz``."""
    power = np.abs(np.fft.rfft(x - x.mean())) ** 2
    freq = np.fft.rfftfreq(len(x), 1.0 / rate_hz)
    total = power[1:].sum()
    return float(100.0 * power[freq > edge_hz].sum() / total) if total > 0 else math.nan


def _band_pass(x: np.ndarray, rate_hz: float, band: tuple = LAG_BAND_HZ) -> np.ndarray:
    """Zero-phase FFT band pass of ``x`` (band in Hz, upper edge at most 0.45 rate), mean removed."""
    spec = np.fft.rfft(x - x.mean())
    freq = np.fft.rfftfreq(len(x), 1.0 / rate_hz)
    spec[(freq < band[0]) | (freq > min(band[1], 0.45 * rate_hz))] = 0.0
    return np.fft.irfft(spec, len(x))


def _xcorr_curve(gyr: np.ndarray, acc_norm: np.ndarray, rate_hz: float) -> np.ndarray:
    """Normalised cross-correlation of band-passed |a| with band-passed |dw/dt| at lags -L..L samples."""
    a = _band_pass(acc_norm, rate_hz)
    g = _band_pass(np.linalg.norm(np.gradient(gyr, axis=0), axis=1) * rate_hz, rate_hz)
    max_lag = max(2, int(round(LAG_WINDOW_S * rate_hz)))
    n = len(a)
    if n <= 2 * max_lag + 4:
        return np.full(2 * max_lag + 1, math.nan)
    corr = np.array([np.dot(a[max_lag:n - max_lag], g[max_lag + k:n - max_lag + k])
                     for k in range(-max_lag, max_lag + 1)])
    scale = np.linalg.norm(a) * np.linalg.norm(g)
    return corr / scale if scale > 0 else corr


def curve_shift_ms(curves: np.ndarray, template: np.ndarray, rate_hz: float) -> np.ndarray:
    """Shift (ms) of each curve (n, L) against ``template`` (L,) by least squares on an upsampled grid;
    positive: the gyro feature comes later relative to the accelerometer feature than in the template."""
    lags = np.arange(len(template)) - len(template) // 2
    fine = np.linspace(lags[0], lags[-1], (len(lags) - 1) * LAG_UPSAMPLE + 1)
    inner = np.abs(fine) <= lags[-1] / 2
    shifts = fine[inner]
    tmpl = np.interp(fine, lags, template)
    shifted = np.interp((fine[inner][None, :] - shifts[:, None]).ravel(), fine, tmpl).reshape(len(shifts), -1)
    out = np.full(len(curves), math.nan)
    for k, c in enumerate(curves):
        if np.all(np.isfinite(c)):
            cost = np.sum((np.interp(fine, lags, c)[inner][None, :] - shifted) ** 2, axis=1)
            out[k] = shifts[int(np.argmin(cost))]
    return 1000.0 * out / rate_hz


def dominant_axis(gyr: np.ndarray) -> np.ndarray:
    """Unit principal axis of the angular rate (N, 3) over a stride, signed so that its y component is >= 0."""
    _, vectors = np.linalg.eigh(gyr.T @ gyr)
    return vectors[:, -1] * (1.0 if vectors[1, -1] >= 0 else -1.0)


def _swing_axis_yaw(gyr: np.ndarray) -> float:
    """atan2(x, y) (deg) of the stride's dominant rotation axis."""
    axis = dominant_axis(gyr)
    return float(np.degrees(np.arctan2(axis[0], axis[1])))


def _stance_velocity(t: np.ndarray, pos_t: np.ndarray, pos: np.ndarray, strides: np.ndarray,
                     stances: np.ndarray) -> np.ndarray:
    """Per stride, mean forward velocity (m/s) of a position track over the middle third of the stance."""
    ok = np.all(np.isfinite(pos), axis=1)
    if ok.sum() < 10:
        return np.full(len(strides), math.nan)
    pt, pp = pos_t[ok], pos[ok]
    out = np.full(len(strides), math.nan)
    for k, ((s0, s1), (c0, c1)) in enumerate(zip(strides, stances)):
        t_mid = 0.5 * (t[c0] + t[c1 - 1])
        t_next = t_mid + (t[s1] - t[s0])
        if t_next > pt[-1] or t[c0] < pt[0]:
            continue
        here = np.array([np.interp(t_mid, pt, pp[:, i]) for i in range(2)])
        there = np.array([np.interp(t_next, pt, pp[:, i]) for i in range(2)])
        step = there - here
        if np.hypot(*step) < 0.2:
            continue
        forward = step / np.hypot(*step)
        third = (t[c1 - 1] - t[c0]) / 3.0
        ta, tb = t[c0] + third, t[c1 - 1] - third
        if tb - ta <= 0:
            continue
        xa = np.array([np.interp(ta, pt, pp[:, i]) for i in range(2)])
        xb = np.array([np.interp(tb, pt, pp[:, i]) for i in range(2)])
        out[k] = float((xb - xa) @ forward / (tb - ta))
    return out


def signature(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, pos_t: np.ndarray | None = None,
              pos: np.ndarray | None = None, gravity: float = 9.81) -> Signature:
    """Stride-normalised signature of one recording (module docstring).

    Parameters
    ----------
    t : (N,) s.  acc : (N, 3) m/s^2 specific force.  gyr : (N, 3) rad/s.
    pos_t, pos : optional position track (M,) s and (M, 3) m on the same clock (a reference or the truth);
        needed for ``stance_velocity``.
    gravity : m/s^2, for the SHOE detector.

    Raises
    ------
    ValueError when fewer than 3 regular strides are found.
    """
    t = np.asarray(t, float)
    acc = np.asarray(acc, float)
    gyr = np.asarray(gyr, float)
    rate = detectors.sample_rate(t)
    result = detectors.detect("shoe", t, acc, gyr, gravity=gravity)
    stances_all = stance_intervals(t, result.stationary)
    strides, stances = _strides(t, gyr, stances_all)
    if len(strides) < 3:
        raise ValueError(f"signature: only {len(strides)} regular strides found (need 3); stance runs: "
                         f"{len(stances_all)}")
    acc_norm = np.linalg.norm(acc, axis=1)
    gyr_norm = np.linalg.norm(gyr, axis=1)
    log_stat = np.log10(np.maximum(result.statistic, 1e-12))
    per = {k: [] for k in ("stance_gyro", "stance_rate_x", "stance_rate_y", "stance_rate_z", "stance_acc_spread", "stance_duration", "stance_shoe", "acc_peak",
                           "gyr_peak", "hf40", "hf80", "onset_hf", "swing_axis_yaw")}
    curves = []
    spectra = []
    n_fft = int(2 ** np.ceil(np.log2(np.median(strides[:, 1] - strides[:, 0]))))
    for (s0, s1), (c0, c1) in zip(strides, stances):
        third = (c1 - c0) // 3
        core = slice(c0 + third, c1 - third) if c1 - c0 >= 6 else slice(c0, c1)
        per["stance_gyro"].append(np.degrees(gyr_norm[core].mean()))
        for axis, mean_rate in zip("xyz", np.degrees(gyr[core].mean(0))):
            per[f"stance_rate_{axis}"].append(mean_rate)
        per["stance_acc_spread"].append(float(np.sqrt(np.mean(np.sum((acc[core] - acc[core].mean(0)) ** 2, 1)))))
        per["stance_duration"].append(t[c1 - 1] - t[c0])
        inside = log_stat[c0:min(c1, len(log_stat))]
        per["stance_shoe"].append(float(np.median(inside)) if inside.size else math.nan)
        per["acc_peak"].append(acc_norm[s0:s1].max())
        per["gyr_peak"].append(np.degrees(gyr_norm[s0:s1].max()))
        for edge, key in ((40.0, "hf40"), (80.0, "hf80")):
            per[key].append(_band_share(acc_norm[s0:s1], rate, edge) if rate / 2 > 1.25 * edge else math.nan)
        if rate / 2 > 1.25 * ONSET_HF_EDGE_HZ:
            high = _band_pass(acc_norm[s0:s1], rate, (ONSET_HF_EDGE_HZ, np.inf))
            per["onset_hf"].append(float(np.sqrt(np.mean(high[:max(2, int(ONSET_WINDOW_S * rate))] ** 2))))
        curves.append(_xcorr_curve(gyr[s0:s1], acc_norm[s0:s1], rate))
        per["swing_axis_yaw"].append(_swing_axis_yaw(gyr[s0:s1]))
        seg = acc_norm[s0:s1] - acc_norm[s0:s1].mean()
        spec = np.abs(np.fft.rfft(seg, n_fft)) ** 2
        spectra.append(spec / max(spec[1:].sum(), 1e-30))
    scalars = {k: _mean_se(v) for k, v in per.items()}
    if pos is not None and pos_t is not None:
        scalars["stance_velocity"] = _mean_se(_stance_velocity(t, np.asarray(pos_t, float), np.asarray(pos, float),
                                                               strides, stances))
    rest = stances_all[0]
    rest_acc = acc[rest[0]:rest[1]]
    norm_samples = np.linalg.norm(rest_acc, axis=1)
    scalars["rest_acc_norm"] = Scalar(float(np.linalg.norm(rest_acc.mean(0))),
                                      float(max(norm_samples.std(ddof=1), 1e-4) / math.sqrt(len(rest_acc))),
                                      norm_samples)
    resampled = phase_resample(t, np.column_stack([acc, np.degrees(gyr)]), strides)  # (S, P, 6), CHANNELS order
    profiles = {}
    for i, c in enumerate(CHANNELS):
        x = resampled[:, :, i]
        profiles[c] = Profile(x.mean(0), x.std(0, ddof=1) / math.sqrt(len(x)), x)
    spectrum = (np.fft.rfftfreq(n_fft, 1.0 / rate), np.mean(spectra, axis=0))
    return Signature(scalars, profiles, strides, stances, rate, spectrum, np.array(curves))


def compare(measured: Signature, twin: Signature, floors: dict | None = None) -> dict:
    """Residuals measured - twin for every number both signatures have (name -> :class:`Residual`).

    ``floors`` (name -> value in the residual's unit) adds, in quadrature, what the comparison itself is
    uncertain by beyond the stride-to-stride scatter (the twin fit's own error, see
    :func:`gaitsim.loop.attribution.comparison_noise`); ``UNCERTAINTY_FLOOR`` is the least uncertainty."""
    floors = floors or {}

    def uncertainty(name: str, *parts: float) -> float:
        combined = math.sqrt(sum(float(np.nan_to_num(x)) ** 2 for x in (*parts, floors.get(name, 0.0))))
        return max(combined, UNCERTAINTY_FLOOR.get(name, 0.0))

    out = {}
    for name, m in measured.scalars.items():
        w = twin.scalars.get(name)
        if w is None or not (math.isfinite(m.value) and math.isfinite(w.value)):
            continue
        out[name] = Residual(name, UNITS[name], m.value, w.value, m.value - w.value, uncertainty(name, m.se, w.se))
    if measured.lag_curves.shape[1:] == twin.lag_curves.shape[1:]:
        template = np.nanmean(twin.lag_curves, axis=0)
        m = _mean_se(curve_shift_ms(measured.lag_curves, template, measured.rate_hz))
        w = _mean_se(curve_shift_ms(twin.lag_curves, template, twin.rate_hz))
        if math.isfinite(m.value) and math.isfinite(w.value):
            out["acc_gyro_lag"] = Residual("acc_gyro_lag", UNITS["acc_gyro_lag"], m.value, w.value,
                                           m.value - w.value, uncertainty("acc_gyro_lag", m.se, w.se))
    for c in CHANNELS:
        m, w = measured.profiles[c], twin.profiles[c]
        name = f"profile_{c}"
        rms = float(np.sqrt(np.mean((m.mean - w.mean) ** 2)))
        out[name] = Residual(name, UNITS[name], float(np.sqrt(np.mean(m.mean**2))), float(np.sqrt(np.mean(w.mean**2))),
                             rms, uncertainty(name, float(np.sqrt(np.mean(m.se**2 + w.se**2)))))
    return out
