"""The twin's gait shape: events, pitch angles and rates fitted to a recording's stride-normalised pitch rate.

The foot's dominant motion is its pitch. Per stride (gyro onset to gyro onset, :mod:`gaitsim.loop.strides`),
the angular rate about the stride's dominant axis is averaged on a phase grid (:func:`stride_profile`) and its
integral gives the pitch. The simulator's pitch of a steady stride comes from
:func:`gaitsim.world.profile.pitch_profile` alone (no MuJoCo; a few ms), so it can be fitted:

1. **Events from features** (:func:`initial_guess`): heel strike at the impact peak of |a| late in the stride;
   the forefoot slap from the largest rocker rate after it to the quiet stance; heel off where the rate leaves
   the stance floor; toe off at the push-off rate peak (the rate reverses right after the toe leaves). Pitch
   and rate at each event are read off the measured profile.
2. **Least squares** (:func:`fit_pitch_profile`) from the better of that estimate and the given gait (the
   simulator's defaults at the recording's cadence), on the rate profile plus the stride's largest and
   smallest pitch (one degree weighs ``settings.ANGLE_WEIGHT`` deg/s). Combinations the scenario validation refuses
   cost a large penalty. A running twin (``settings.RUN_PITCH_FIT_BOUNDS``) fits the offset of the model's phase
   origin too: a running foot turns at 15-50 deg/s through its stance, so the recording's |w| onset does not
   fall where the model's pitch rate rises (on simulated runs the model at the true gait misfits by 135-200
   deg/s rms at the origin as cut and by 45-95 at its best offset); each start is judged at its best offset.
   The fitted values are scenario keys in their units (deg, deg/s, deg/s^2, s): the fit returns what a scenario
   file would say, and :func:`gaitsim.scenario.fill` converts it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from ..errors import ScenarioError
from ..scenario import fill, section_table, validate_gait
from ..world import path as paths
from ..world.gait import GaitParams, ImpactParams, MicroMotionParams, Walk, plan_stances
from ..world.profile import pitch_profile
from . import settings
from .signature import Signature
from .strides import dominant_axis, phase_resample


@dataclass
class StrideProfile:
    """Stride-normalised pitch of a recording (or of the model) on ``settings.PROFILE_POINTS`` phases from the gyro
    onset.

    Attributes
    ----------
    rate : (P,) deg/s, angular rate about the stride's dominant axis (positive: toes down).
    angle : (P,) deg, its integral from the onset, detrended to close over the stride.
    acc_norm : (P,) m/s^2, |specific force| (NaN for the model).
    period_s : s, median stride period.
    """

    rate: np.ndarray
    angle: np.ndarray
    acc_norm: np.ndarray
    period_s: float

    @property
    def phase(self) -> np.ndarray:
        return np.linspace(0.0, 1.0, len(self.rate), endpoint=False)


ORIGIN_SHIFT = "origin_shift"  # a fitted offset of the model's phase origin (stride share), not a scenario key


def _angle(rate: np.ndarray, period_s: float) -> np.ndarray:
    """Integral (deg) of a rate profile (deg/s) over the phase grid, a linear trend removed so it closes."""
    step = period_s / len(rate)
    angle = np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * step)])
    closing = angle[-1] + 0.5 * (rate[-1] + rate[0]) * step
    return angle - closing * np.arange(len(rate)) / len(rate)


def stride_profile(t: np.ndarray, acc: np.ndarray, gyr: np.ndarray, sig: Signature) -> StrideProfile:
    """Mean over the signature's strides of the rate about each stride's dominant axis and of |a|."""
    gyr_phases = phase_resample(t, np.degrees(gyr), sig.strides, settings.PROFILE_POINTS)  # (S, P, 3)
    axes = np.array([dominant_axis(gyr[s0:s1]) for s0, s1 in sig.strides])
    rate = np.einsum("spi,si->p", gyr_phases, axes) / len(axes)
    acc_norm = phase_resample(t, np.linalg.norm(acc, axis=1), sig.strides, settings.PROFILE_POINTS).mean(0)
    period = float(np.median(t[sig.strides[:, 1]] - t[sig.strides[:, 0]]))
    return StrideProfile(rate, _angle(rate, period), acc_norm, period)


def model_profile(gait: GaitParams, impact: ImpactParams) -> StrideProfile:
    """The simulator's pitch over one steady stride of ``gait`` / ``impact`` on the same phase grid (origin where
    |rate| last rose above ``settings.QUIET_RATE_DPS`` before mid foot flat)."""
    steady = dataclasses.replace(gait, stride_length_sd_m=0.0, cycle_sd_frac=0.0, pitch_sd=0.0,
                                 stand_start_s=settings.MIN_REST_S, stand_end_s=settings.MIN_REST_S)
    walk = Walk(path=paths.straight(4 * steady.stride_length_m, 0.0), gait=steady, impact=impact)
    plan = plan_stances(walk, np.random.default_rng(0))
    k = 2
    grid = np.linspace(plan.t_ic[k - 1], plan.t_ho[k + 1], 4000)
    angle, rate = np.degrees(pitch_profile(plan, steady, impact).stack(grid)[:2])
    loud = np.flatnonzero(np.abs(rate) >= settings.QUIET_RATE_DPS)
    onsets = []
    for j in (k, k + 1):  # like strides.gyro_onsets: the first quiet point after the last loud one
        before = loud[grid[loud] < 0.5 * (plan.t_ff[j] + plan.t_ho[j])]
        onsets.append(grid[before[-1] + 1] if len(before) else plan.t_ff[j])
    at = onsets[0] + np.linspace(0.0, 1.0, settings.PROFILE_POINTS, endpoint=False) * (onsets[1] - onsets[0])
    return StrideProfile(np.interp(at, grid, rate), np.interp(at, grid, angle) - np.interp(onsets[0], grid, angle),
                         np.full(settings.PROFILE_POINTS, np.nan), onsets[1] - onsets[0])


def initial_guess(measured: StrideProfile) -> dict:
    """Gait events, pitch angles and rates read off the measured profile (module docstring, step 1)."""
    phase, rate, angle = measured.phase, measured.rate, measured.angle
    late = phase > settings.HEEL_STRIKE_AFTER_PHASE
    i_ic = int(np.flatnonzero(late)[np.argmax(measured.acc_norm[late])]) if np.any(np.isfinite(measured.acc_norm)) \
        else int(np.flatnonzero(late)[np.argmin(angle[late])])
    early = phase < phase[i_ic] - settings.TOE_OFF_BEFORE_STRIKE_PHASE
    i_to = int(np.argmax(np.where(early, rate, -np.inf)))
    rising = np.flatnonzero((rate[:i_to] < settings.STANCE_FLOOR * rate[i_to]))
    i_ho = int(rising[-1]) if len(rising) else i_to // 2
    quiet = np.flatnonzero(np.abs(rate[:i_ho + 1]) < settings.STANCE_FLOOR * rate[i_to])
    i_ff = int(quiet[0]) if len(quiet) else 0
    rocker = np.r_[i_ic:settings.PROFILE_POINTS]
    i_slap = int(rocker[np.argmax(rate[rocker])])
    period = measured.period_s
    rocker_frac = 1.0 - phase[i_ic] + phase[i_ff]
    accel = np.gradient(rate, period / len(rate))
    return {
        "heel_rocker_frac": rocker_frac, "foot_flat_frac": phase[i_ho] - phase[i_ff],
        "push_off_frac": phase[i_to] - phase[i_ho],
        "pitch_heel_strike_deg": angle[i_ic], "pitch_rate_heel_strike_dps": rate[i_ic],
        "pitch_accel_heel_strike_dps2": accel[i_ic],
        "pitch_toe_off_deg": angle[i_to], "pitch_rate_toe_off_dps": rate[i_to], "pitch_accel_toe_off_dps2": accel[i_to],
        "slap_rate_dps": max(rate[i_slap], 0.0),
        "slap_duration_s": min((1.0 - phase[i_slap] + phase[i_ff]) * period,
                               settings.MAX_SLAP_ROCKER_SHARE * rocker_frac * period),
    }


def _apply(values: dict, gait: GaitParams, impact: ImpactParams) -> tuple[GaitParams, ImpactParams]:
    """``gait`` and ``impact`` with the fitted scenario keys ``values`` (their units) and the swing fraction."""
    values = {key: value for key, value in values.items() if key != ORIGIN_SHIFT}
    values["swing_frac"] = 1.0 - values["heel_rocker_frac"] - values["foot_flat_frac"] - values["push_off_frac"]
    impact_keys = {name for name, section, _, _ in settings.PITCH_FIT_BOUNDS if section == "impact"}
    return (fill(GaitParams, {k: v for k, v in values.items() if k not in impact_keys}, "<pitch fit> [gait]", gait),
            fill(ImpactParams, {k: v for k, v in values.items() if k in impact_keys}, "<pitch fit> [impact]", impact))


def fit_pitch_profile(measured: StrideProfile, gait: GaitParams, impact: ImpactParams,
                      micro: MicroMotionParams = MicroMotionParams(),
                      bounds: tuple = settings.PITCH_FIT_BOUNDS) -> tuple[dict, dict]:
    """Fit the events, pitch angles and rates and the slap (module docstring) for a gait of ``gait``'s cadence and
    the stance micro-motion ``micro`` (its pulses must fit the foot flat), the keys and their ranges ``bounds``
    ((scenario key, section, low, high) in the key's unit: the walking ranges, or ``settings.RUN_PITCH_FIT_BOUNDS``
    for a running twin).

    Returns
    -------
    changes : {"gait": {...}, "impact": {...}} to merge into a scenario document (swing_frac included).
    quality : rms rate misfit (deg/s) of the feature estimate and of the fit, and the fitted pitch extremes.
    """
    names = [name for name, _, _, _ in bounds]
    low = np.array([lo for _, _, lo, _ in bounds])
    high = np.array([hi for _, _, _, hi in bounds])
    inside = 1e-6 * (high - low)
    guess = {**initial_guess(measured), ORIGIN_SHIFT: 0.0}
    given = {"gait": section_table(gait), "impact": section_table(impact), "origin": {ORIGIN_SHIFT: 0.0}}
    starts = {"features": np.array([guess[n] for n in names], float),
              "given": np.array([given[sec][n] for n, sec, _, _ in bounds], float)}
    extremes = np.array([measured.angle.max(), measured.angle.min()])

    def rate_misfit(x, model: StrideProfile) -> np.ndarray:
        if ORIGIN_SHIFT not in names:
            return model.rate - measured.rate
        phase = measured.phase
        return np.interp(phase + x[names.index(ORIGIN_SHIFT)], phase, model.rate, period=1.0) - measured.rate

    def cost(x):
        g, i = _apply(dict(zip(names, x)), gait, impact)
        if g.swing_frac < settings.MIN_SWING_FRAC:
            return np.full(settings.PROFILE_POINTS + 2, 1e3 * (1.0 + settings.MIN_SWING_FRAC - g.swing_frac))
        try:
            validate_gait(g, i, micro, "<pitch fit>")
        except ScenarioError:
            return np.full(settings.PROFILE_POINTS + 2, 1e3)
        model = model_profile(g, i)
        return np.concatenate([rate_misfit(x, model),
                               settings.ANGLE_WEIGHT * (np.array([model.angle.max(), model.angle.min()]) - extremes)])

    costs = {}
    for label, x in starts.items():
        x = starts[label] = np.clip(x, low + inside, high - inside)
        if ORIGIN_SHIFT in names:  # each start judged at its best origin offset (grid over its range)
            k = names.index(ORIGIN_SHIFT)
            offsets = np.linspace(low[k] + inside[k], high[k] - inside[k], settings.ORIGIN_GRID_POINTS)
            x[k] = min(offsets, key=lambda o: float(np.sum(cost(np.r_[x[:k], o, x[k + 1:]]) ** 2)))
        costs[label] = float(np.sum(cost(x) ** 2))
    origin = min(costs, key=costs.get)
    found = least_squares(cost, starts[origin], bounds=(low, high), x_scale=high - low,
                          diff_step=settings.PITCH_FIT_DIFF_STEP,
                          max_nfev=settings.MAX_EVALUATIONS)
    best = found.x if np.sum(found.fun ** 2) <= costs[origin] else starts[origin]
    g, i = _apply(dict(zip(names, best)), gait, impact)
    changes = {"gait": {n: float(x) for (n, sec, _, _), x in zip(bounds, best) if sec == "gait"},
               "impact": {n: float(x) for (n, sec, _, _), x in zip(bounds, best) if sec == "impact"}}
    changes["gait"]["swing_frac"] = float(g.swing_frac)
    model = model_profile(g, i)
    quality = {"start": origin,
               "rms_misfit_at_starts": {k: float(np.sqrt(v / (settings.PROFILE_POINTS + 2))) for k, v in costs.items()},
               "rms_rate_misfit_fit_dps": float(np.sqrt(np.mean(rate_misfit(best, model) ** 2))),
               "origin_shift_s": float(best[names.index(ORIGIN_SHIFT)] * measured.period_s if ORIGIN_SHIFT in names
                                       else 0.0),
               "pitch_extremes_measured_deg": extremes.tolist(),
               "pitch_extremes_twin_deg": [float(model.angle.max()), float(model.angle.min())]}
    return changes, quality
