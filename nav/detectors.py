"""Zero-velocity (stance) detectors: SHOE/GLRT, ARE, MV, MAG and an oracle from true stance labels.

Statistics after Skog, Händel, Nilsson and Rantakokko (IEEE TBME 2010), with OpenShoe's window semantics: a
window of W samples starts at every sample k (step 1); if its statistic T(k) is below the threshold gamma, all W
samples k..k+W-1 are marked stationary. For a window with specific force y_a (m/s^2), angular rate y_w (rad/s),
window mean ybar_a and gravity magnitude g:

- SHOE: T = (1/W) sum_l [ |y_a,l - g ybar_a/|ybar_a| |^2 / sigma_a^2 + |y_w,l|^2 / sigma_g^2 ]
  (gravity direction from each window's own mean)
- ARE: T = (1/(sigma_g^2 W)) sum_l |y_w,l|^2
- MV:  T = (1/(sigma_a^2 W)) sum_l |y_a,l - ybar_a|^2
- MAG: T = (1/(sigma_a^2 W)) sum_l (|y_a,l| - g)^2

Window sums are sums of W shifted slices (vectorised, one pass per window offset, no loop over samples). They
are not taken as differences of a running cumulative sum: SHOE divides by sigma_a^2 ~ 1e-4, and the cumulative
sum's round-off grows with the recording's length, so differences of it would make T depend on where the
window sits. Every result carries its parameters (:class:`DetectorParams`): a threshold means nothing without
sigma_a, sigma_g, W, the sample rate and the window semantics. Different statistics have thresholds in different
units: :func:`threshold_for_fraction` gives a statistic the threshold that marks a given share of samples, to
compare detectors at one operating point.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._numba import detector as compiled_detector
from .compiled import kernel_array
from .constants import DEFAULT_GRAVITY, DEFAULT_SIGMA_A, DEFAULT_SIGMA_G, DEFAULT_THRESHOLD, DEFAULT_WINDOW

STATISTICS = ("shoe", "are", "mv", "mag")
DETECTORS = STATISTICS + ("anchored", "adaptive", "oracle")
SLIDING = "sliding window, step 1; all W samples of a window below the threshold are stationary (OpenShoe)"
BLOCKS = "non-overlapping blocks of W samples; a block below the threshold is stationary (pyshoe)"
WHOLE_RECORDING_GRAVITY = (
    "gravity direction from the mean of the whole recording; window mean of per-sample values, windows "
    "overlapping by half (gaitmap ShoeZuptDetector)"
)


@dataclass(frozen=True)
class DetectorParams:
    """The parameters that give a detector threshold its meaning.

    Attributes
    ----------
    name : one of ``DETECTORS``.
    threshold : gamma, dimensionless (the statistic is normalised by the sigmas). NaN for the oracle.
    sigma_a : m/s^2, accelerometer noise standard deviation used to normalise the statistic.
    sigma_g : rad/s, gyro noise standard deviation used to normalise the statistic.
    window : W, samples per window.
    fs : Hz, sample rate the window length refers to (median rate for irregular timestamps).
    gravity : m/s^2, gravity magnitude used by SHOE and MAG.
    semantics : how windows are laid out and marked.
    adaptation : how the threshold follows the gait, for the anchored SHOE (nav.calm_anchor) and the adaptive SHOE
        (nav.adaptive_detector), whose ``threshold`` is then the fixed gamma_0 or the floor; None for a fixed
        threshold.
    """

    name: str
    threshold: float
    sigma_a: float
    sigma_g: float
    window: int
    fs: float
    gravity: float = DEFAULT_GRAVITY
    semantics: str = SLIDING
    adaptation: dict | None = None

    def as_dict(self) -> dict:
        """The parameters as a JSON-ready dict (SI units; sigma_g also in deg/s for reading)."""
        out = {
            "detector": self.name, "threshold": self.threshold, "sigma_a_m_s2": self.sigma_a,
            "sigma_g_rad_s": self.sigma_g, "sigma_g_deg_s": math.degrees(self.sigma_g), "window_samples": self.window,
            "window_s": self.window / self.fs, "fs_hz": self.fs, "gravity_m_s2": self.gravity,
            "window_semantics": self.semantics,
        }
        if self.adaptation is not None:
            out["adaptation"] = dict(self.adaptation)
        return out


@dataclass(frozen=True)
class DetectorResult:
    """Output of a detector.

    Attributes
    ----------
    stationary : (N,) bool, samples marked as zero-velocity.
    statistic : (N - W + 1,) the test statistic T(k) of the window starting at k (empty for the oracle).
    params : DetectorParams used.
    threshold : (N - W + 1,) the threshold each window was compared with when it varies (adaptive SHOE); None
        when it is ``params.threshold`` throughout.
    """

    stationary: np.ndarray
    statistic: np.ndarray
    params: DetectorParams
    threshold: np.ndarray | None = None


def window_sum(x: np.ndarray, window: int) -> np.ndarray:
    """Sums over windows of ``window`` samples along axis -1, one per start index (length N - W + 1)."""
    n = x.shape[-1]
    out = x[..., : n - window + 1].copy()
    for j in range(1, window):
        out += x[..., j: n - window + 1 + j]
    return out


def spread_marks(below: np.ndarray, window: int) -> np.ndarray:
    """Mark all W samples of every window whose flag in ``below`` (..., N - W + 1) is set; returns (..., N)."""
    shape = below.shape[:-1] + (below.shape[-1] + window - 1,)
    marked = np.zeros(shape, bool)
    m = below.shape[-1]
    for j in range(window):
        marked[..., j: j + m] |= below
    return marked


def square_norm(x: np.ndarray) -> np.ndarray:
    """|x|^2 over the last axis (length 3), summed left to right: the order of the compiled SHOE statistic
    (:mod:`nav._numba.detector`), so that it and :func:`numpy_statistic` agree bit for bit (numpy's einsum sums three
    products in an order of its own, (x0^2 + x2^2) + x1^2 in numpy 2.0)."""
    return (x[..., 0] * x[..., 0] + x[..., 1] * x[..., 1]) + x[..., 2] * x[..., 2]


def statistic(name: str, acc: np.ndarray, gyr: np.ndarray, sigma_a: float, sigma_g: float, window: int,
              gravity: float = DEFAULT_GRAVITY) -> np.ndarray:
    """Detector statistic T(k) for every window start k.

    Parameters
    ----------
    name : "shoe", "are", "mv" or "mag".
    acc : (..., N, 3) m/s^2 specific force; gyr : (..., N, 3) rad/s angular rate (leading axes: runs).
    sigma_a : m/s^2; sigma_g : rad/s; window : samples; gravity : m/s^2.

    Returns
    -------
    (..., N - W + 1) dimensionless statistic: :func:`numpy_statistic`'s, the SHOE's from compiled code in one pass
    over the samples (:mod:`nav._numba.detector`, bit for bit numpy's; a fifth of its time or less).
    """
    if name != "shoe":
        return numpy_statistic(name, acc, gyr, sigma_a, sigma_g, window, gravity)
    shape = np.broadcast_shapes(np.shape(acc), np.shape(gyr))
    if len(shape) < 2 or shape[-1] != 3:
        raise ValueError(f"detector input of shape {shape} (acc {np.shape(acc)}, gyr {np.shape(gyr)}): allowed "
                         "(..., N, 3) samples of three axes")
    acc, gyr = kernel_array(acc, float, shape), kernel_array(gyr, float, shape)
    _check_window(window, shape[-2])
    runs = acc.reshape(-1, shape[-2], 3), gyr.reshape(-1, shape[-2], 3)
    out = np.empty((runs[0].shape[0], shape[-2] - window + 1))
    compiled_detector.shoe_statistic(*runs, int(window), sigma_a**2, sigma_g**2, gravity, out)
    return out.reshape(shape[:-2] + out.shape[-1:])


def numpy_statistic(name: str, acc: np.ndarray, gyr: np.ndarray, sigma_a: float, sigma_g: float, window: int,
                    gravity: float = DEFAULT_GRAVITY) -> np.ndarray:
    """:func:`statistic` in numpy: whole-array passes (the reference the compiled SHOE is tested against)."""
    acc = np.asarray(acc, float)
    gyr = np.asarray(gyr, float)
    _check_window(window, acc.shape[-2])
    w = float(window)
    if name in ("shoe", "mv"):
        mean_a = np.stack([window_sum(acc[..., i], window) for i in range(3)], -1) / w
        # sum |y_l - ybar|^2 = sum |y_l|^2 - W |ybar|^2 evaluated as sum |y_l - y_k|^2 - W |ybar - y_k|^2,
        # centred on the window's first sample to avoid cancellation against |y|^2 ~ g^2
        spread = np.zeros(mean_a.shape[:-1])
        n_win = mean_a.shape[-2]
        for j in range(window):
            spread += square_norm(acc[..., j: j + n_win, :] - acc[..., :n_win, :])
        spread -= w * square_norm(mean_a - acc[..., :n_win, :])
        spread = np.maximum(spread, 0.0)
        if name == "mv":
            return spread / (sigma_a**2 * w)
        # sum |y_l - g u|^2 = sum |y_l - ybar|^2 + W (|ybar| - g)^2 with u = ybar / |ybar|
        acc_term = spread + w * (np.sqrt(square_norm(mean_a)) - gravity) ** 2
        gyr_term = window_sum(square_norm(gyr), window)
        return (acc_term / sigma_a**2 + gyr_term / sigma_g**2) / w
    if name == "are":
        return window_sum(square_norm(gyr), window) / (sigma_g**2 * w)
    if name == "mag":
        return window_sum((np.sqrt(square_norm(acc)) - gravity) ** 2, window) / (sigma_a**2 * w)
    raise ValueError(f"detector statistic {name!r} is not one of {STATISTICS}")


def _check_window(window: int, samples: int) -> None:
    if window < 1 or window > samples:
        raise ValueError(f"detector window {window} samples is not in 1..{samples} (the recording length)")


def sample_rate(t: np.ndarray) -> float:
    """Median sample rate (Hz) of timestamps t (s), over all runs if t has a leading run axis."""
    return float(1.0 / np.median(np.diff(np.asarray(t, float), axis=-1)))


def detect(name: str, t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, threshold: float = DEFAULT_THRESHOLD,
           sigma_a: float = DEFAULT_SIGMA_A, sigma_g: float = DEFAULT_SIGMA_G, window: int = DEFAULT_WINDOW,
           gravity: float = DEFAULT_GRAVITY) -> DetectorResult:
    """Run a statistical detector with OpenShoe's sliding-window semantics.

    Parameters
    ----------
    name : "shoe", "are", "mv" or "mag" (for the oracle use :func:`oracle`, for the adaptive SHOE
        :func:`nav.adaptive_detector.detect_adaptive`).
    t : (N,) s; acc : (..., N, 3) m/s^2; gyr : (..., N, 3) rad/s.
    threshold : gamma (dimensionless); sigma_a : m/s^2; sigma_g : rad/s; window : samples; gravity : m/s^2.

    Returns
    -------
    DetectorResult with ``stationary`` of shape (..., N).
    """
    if not (sigma_a > 0 and sigma_g > 0 and threshold > 0):
        raise ValueError(f"detector sigmas and threshold must be positive: sigma_a={sigma_a} m/s^2, "
                         f"sigma_g={sigma_g} rad/s, threshold={threshold}")
    stat = statistic(name, acc, gyr, sigma_a, sigma_g, int(window), gravity)
    params = DetectorParams(name, float(threshold), float(sigma_a), float(sigma_g), int(window), sample_rate(t),
                            float(gravity))
    return DetectorResult(spread_marks(stat < threshold, int(window)), stat, params)


def marked_share(statistics: list[np.ndarray], window: int, threshold: float) -> float:
    """Share of all samples of the recordings whose statistics are ``statistics`` (each (N_i - W + 1,)) that a
    threshold ``threshold`` marks stationary with W = ``window`` (sliding-window marks as in :func:`detect`)."""
    total = sum(len(s) + window - 1 for s in statistics)
    return sum(int(spread_marks(s < threshold, window).sum()) for s in statistics) / total


def threshold_for_fraction(statistics: list[np.ndarray], window: int, fraction: float) -> float:
    """The smallest threshold at which a detector marks at least ``fraction`` of the samples stationary.

    Detectors with different statistics (SHOE, ARE, MV, MAG) have thresholds in different units; compared at
    one operating point, each gets the threshold that marks the same share of the same recordings as
    stationary. The marked share can only grow with the threshold and changes only where the threshold passes
    a value of the statistic, so the answer is found by bisection over the sorted statistic values.

    Parameters
    ----------
    statistics : the statistic T(k) of each recording (:func:`statistic`), each (N_i - W + 1,), dimensionless.
    window : W, samples (the windows' marks are spread as in :func:`detect`).
    fraction : target share of all samples of all recordings marked stationary, in (0, 1].

    Returns
    -------
    gamma, dimensionless: the next floating-point number above a statistic value (``T < gamma`` marks it).
    """
    if not 0.0 < fraction <= 1.0:
        raise ValueError(f"threshold_for_fraction: fraction = {fraction!r}; allowed: 0 < fraction <= 1")
    candidates = np.nextafter(np.unique(np.concatenate(statistics)), np.inf)
    low, high = 0, len(candidates) - 1  # marked_share at candidates[high] is 1 >= fraction
    while low < high:
        mid = (low + high) // 2
        if marked_share(statistics, window, candidates[mid]) >= fraction:
            high = mid
        else:
            low = mid + 1
    return float(candidates[low])


def oracle(t: np.ndarray, stance: np.ndarray) -> DetectorResult:
    """The "detector" that returns the recording's true stance labels (``Truth.stance``)."""
    stance = np.asarray(stance, bool)
    params = DetectorParams("oracle", math.nan, math.nan, math.nan, 1, sample_rate(t),
                            semantics="true stance labels (Truth.stance)")
    return DetectorResult(stance.copy(), np.empty(0), params)


# ------------------------------------------------------------------------------------------ threshold conversion
@dataclass(frozen=True)
class ShoeConvention:
    """How one code defines SHOE's normalisation and windows.

    Attributes
    ----------
    name : label for reports.
    sigma_a : m/s^2, the accelerometer noise std the statistic divides by (sqrt of a variance parameter).
    sigma_g : rad/s, the gyro noise std (a code working in deg/s is converted here, once).
    semantics : window layout and gravity direction (one of ``SLIDING``, ``BLOCKS``, ``WHOLE_RECORDING_GRAVITY``).
    """

    name: str
    sigma_a: float
    sigma_g: float
    semantics: str


def openshoe_convention(sigma_a: float = DEFAULT_SIGMA_A, sigma_g: float = DEFAULT_SIGMA_G) -> ShoeConvention:
    """OpenShoe (and this package): sigma_a m/s^2, sigma_g rad/s, sliding windows, per-window gravity."""
    return ShoeConvention("openshoe", sigma_a, sigma_g, SLIDING)


def pyshoe_convention(sigma_a: float = 0.01, sigma_g: float = math.radians(0.1)) -> ShoeConvention:
    """pyshoe: same statistic and units as OpenShoe, evaluated on non-overlapping blocks (W = 5 there)."""
    return ShoeConvention("pyshoe", sigma_a, sigma_g, BLOCKS)


def gaitmap_convention(acc_noise_variance: float = 3.5e-9, gyr_noise_variance: float = 1.3e-7) -> ShoeConvention:
    """gaitmap's ShoeZuptDetector: variances in (m/s^2)^2 and (deg/s)^2 (its gyro data are in deg/s).

    Defaults are gaitmap 2.x's; its default threshold is 2.31e9.
    """
    return ShoeConvention("gaitmap", math.sqrt(acc_noise_variance), math.radians(math.sqrt(gyr_noise_variance)),
                          WHOLE_RECORDING_GRAVITY)


@dataclass(frozen=True)
class ThresholdConversion:
    """A converted threshold and how far to trust it.

    Attributes
    ----------
    threshold : gamma in the target convention.
    exact : True when the statistic is the same function of the data in both conventions up to a scale.
    note : what is approximate, if anything.
    """

    threshold: float
    exact: bool
    note: str


def convert_threshold(threshold: float, source: ShoeConvention, target: ShoeConvention) -> ThresholdConversion:
    """Carry a SHOE threshold from one code's parameters to another's.

    Exact part: T is a weighted sum of an accelerometer and a gyro term divided by sigma_a^2 and sigma_g^2. If
    both conventions weight the two terms alike (same sigma_a/sigma_g), the statistic differs by the factor
    (sigma_source/sigma_target)^2 and the threshold converts exactly by that factor.

    Approximate part: if the ratios differ, the two statistics are not proportional; the conversion then keeps
    the gyro gate sigma_g*sqrt(gamma) fixed, because in walking the gyro term dominates at the stance edges
    (anchors §2). Different window semantics (sliding vs blocks, per-window vs whole-recording gravity, window
    length) change which samples are marked for the same T, so any such conversion is approximate too.

    Parameters
    ----------
    threshold : gamma in the source convention (dimensionless).
    source, target : the two conventions.
    """
    ratio_source = source.sigma_a / source.sigma_g
    ratio_target = target.sigma_a / target.sigma_g
    same_weighting = math.isclose(ratio_source, ratio_target, rel_tol=1e-12)
    new = threshold * (source.sigma_g / target.sigma_g) ** 2
    notes = []
    if not same_weighting:
        notes.append(
            f"sigma_a/sigma_g differ ({ratio_source:.4g} vs {ratio_target:.4g} (m/s^2)/(rad/s)): gyro gate "
            f"sigma_g*sqrt(gamma) = {math.degrees(source.sigma_g * math.sqrt(threshold)):.4g} deg/s kept, "
            "accelerometer weighting not preserved"
        )
    if source.semantics != target.semantics:
        notes.append(f"window semantics differ: {source.name}: {source.semantics}; {target.name}: {target.semantics}")
    return ThresholdConversion(new, not notes, "; ".join(notes) or "exact rescaling")
