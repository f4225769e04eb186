"""The sensor frame, checked on the data before anything is fitted: a frame error is never absorbed by a mount fit.

The loop works in the body frame x toes, y left, z up. Three laws of a walking foot fix that frame from the data
alone, whatever the logger did:

1. **Handedness.** Stride closure (:mod:`gaitsim.loop.closure`) is invariant under a proper rotation of the
   sensor axes, but a mirrored (left-handed) frame turns gravity the wrong way while the foot pitches: the
   velocity carried from one stance to the next misses zero by metres per second instead of centimetres. The
   data are mirrored when mirroring them back closes the strides ``settings.MIRROR_CLOSURE_RATIO`` times better.
2. **Up.** At rest (every detected stance) the specific force points up: the axis holding most of it, with its
   sign, is z.
3. **Left.** The foot's dominant rotation while walking is its pitch; the axis of the largest angular-rate rms
   is y, signed so that the largest pitch excursion of each swing (the toes going down after heel off) is
   positive about it (median over swings). x completes the right-handed triad.

The check returns the axis map (:mod:`gaitsim.measured.axes`) that brings the data into the body frame;
:func:`require_body_frame` refuses a recording whose map is not the identity and names the ``--axes`` option
that corrects it. The same tolerance that keeps a tilted mount's gravity on z (the largest component) applies:
a sensor turned by less than 45 degrees on the foot is a mount, fitted later; beyond that it is a frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nav.recording import Recording, RecordingError

from ..measured import axes
from . import settings
from .closure import closure_between_stances
from .strides import detect_stances

MIRROR = np.diag([-1.0, 1.0, 1.0])


class FrameError(RecordingError):
    """The recording's sensor frame is not the body frame (the message names the ``--axes`` map to use)."""


@dataclass
class FrameCheck:
    """What the frame laws found (module docstring).

    Attributes
    ----------
    axes : (3, 3) signed permutation bringing the data into the body frame (identity when it already is).
    findings : human-readable statements with the numbers behind them.
    numbers : the numbers (closure m/s, mean rest specific force m/s^2, rate rms rad/s, excursion deg).
    """

    axes: np.ndarray
    findings: list
    numbers: dict

    @property
    def is_body_frame(self) -> bool:
        return bool(np.array_equal(self.axes, np.eye(3)))


def _median_closure(rec: Recording, matrix: np.ndarray, pairs: np.ndarray) -> float:
    """Median |stride closure velocity| (m/s) of the data mapped by ``matrix``."""
    acc, gyr = rec.acc @ matrix.T, rec.gyr @ matrix.T
    rest = slice(*pairs[0, 0])
    found = closure_between_stances(rec.t, acc, gyr, pairs[:, 0], pairs[:, 1], rec.gravity, gyr[rest].mean(0))
    return float(np.median(np.linalg.norm(found.velocity, axis=1)))


def _swing_excursions(t: np.ndarray, rate: np.ndarray, stances: np.ndarray) -> np.ndarray:
    """Signed largest excursion (rad) of the integral of ``rate`` (rad/s) over each swing between stances."""
    out = []
    for (_, end), (start, _) in zip(stances[:-1], stances[1:]):
        if t[start] - t[end - 1] > settings.MAX_STRIDE_S:
            continue
        angle = np.cumsum(rate[end - 1:start] * np.diff(t[end - 1:start + 1]))
        if angle.size:
            out.append(angle[np.argmax(np.abs(angle))])
    return np.array(out)


def check_frame(rec: Recording) -> FrameCheck:
    """The axis map that brings ``rec`` into the body frame, found from its data (module docstring).

    Raises
    ------
    RecordingError
        when the recording has too few stances to tell (fewer than ``settings.MIN_FRAME_STRIDES`` strides).
    """
    found, stances = detect_stances(rec.t, rec.acc, rec.gyr, rec.gravity)
    gaps = rec.t[stances[1:, 0]] - rec.t[stances[:-1, 1] - 1] if len(stances) > 1 else np.empty(0)
    pairs = np.stack([stances[:-1], stances[1:]], axis=1)[gaps < settings.MAX_STRIDE_S] if len(gaps) else gaps
    if len(pairs) < settings.MIN_FRAME_STRIDES:
        raise RecordingError(f"frame check: {len(pairs)} strides between detected stances (need "
                             f"{settings.MIN_FRAME_STRIDES}); {len(stances)} stances detected")
    numbers, findings = {}, []
    as_is, mirrored = _median_closure(rec, np.eye(3), pairs), _median_closure(rec, MIRROR, pairs)
    numbers["median_stride_closure_mps"] = {"as_recorded": as_is, "mirrored": mirrored}
    flip = mirrored * settings.MIRROR_CLOSURE_RATIO < as_is
    if flip:
        findings.append(f"the frame is mirrored (left-handed): strides close to {as_is:.3g} m/s as recorded and to "
                        f"{mirrored:.3g} m/s mirrored")
    first = MIRROR if flip else np.eye(3)
    acc, gyr = rec.acc @ first.T, rec.gyr @ first.T
    rest = acc[found.stationary].mean(0)
    up = int(np.argmax(np.abs(rest)))
    numbers["rest_specific_force_mps2"] = rest.tolist()
    rms = np.sqrt(np.mean(gyr[~found.stationary] ** 2, axis=0))
    rms[up] = -np.inf
    left = int(np.argmax(rms))
    numbers["walking_rate_rms_rad_s"] = np.sqrt(np.mean(gyr[~found.stationary] ** 2, axis=0)).tolist()
    excursion = float(np.degrees(np.median(_swing_excursions(rec.t, gyr[:, left], stances))))
    numbers["median_swing_excursion_deg"] = excursion
    mirrored_back = " (after mirroring back)" if flip else ""
    z_row = np.eye(3)[up] * np.sign(rest[up])
    y_row = np.eye(3)[left] * (1.0 if excursion > 0 else -1.0)
    proper = np.array([np.cross(y_row, z_row), y_row, z_row])
    if up != 2 or rest[up] < 0:
        findings.append(f"gravity at rest is on {'-' if rest[up] < 0 else '+'}{axes.AXES[up]} (mean specific force "
                        f"{np.round(rest, 2).tolist()} m/s^2){mirrored_back}, not +z")
    if left != 1 or excursion <= 0:
        findings.append(f"the pitch axis (largest walking rate, toes-down swing excursion positive) is "
                        f"{'-' if excursion <= 0 else '+'}{axes.AXES[left]} (rms {np.round(rms[left], 2)} rad/s, "
                        f"median swing excursion {excursion:.0f} deg){mirrored_back}, not +y")
    return FrameCheck(proper @ first, findings, numbers)


def require_body_frame(rec: Recording, axis_map: str | None = None) -> tuple[Recording, FrameCheck]:
    """``rec`` mapped by ``axis_map`` (``--axes`` text, None for none) once its frame passes :func:`check_frame`.

    Raises
    ------
    FrameError
        naming what failed and the ``--axes`` map that brings the recording into the body frame.
    """
    given = axes.parse_axis_map(axis_map) if axis_map is not None else np.eye(3)
    mapped = axes.remapped(rec, given) if axis_map is not None else rec
    check = check_frame(mapped)
    if not check.is_body_frame:
        advice = axes.axis_map_text(check.axes @ given)
        after = f" after --axes {axis_map}" if axis_map is not None else ""
        raise FrameError(f"sensor frame{after} is not x toes, y left, z up: {'; '.join(check.findings)}; "
                         f"rerun with --axes {advice}")
    return mapped, check
