"""The loop: navigate the recording, fit its twin, rank residuals, attribute them to effects, add, repeat.

:func:`run_loop` does, for one recording:

1. navigate it with the shared filter (:data:`gaitsim.loop.settings.NAV_OPTIONS`) and score it against its
   reference; compute its signature (:mod:`gaitsim.loop.signature`);
2. fit the twin (:mod:`gaitsim.loop.twin`), simulate it, treat the simulation as a measured recording (IMU
   samples and a position reference only) and do the same;
3. residuals = recording - twin: the signature residuals plus the navigation residuals ``nav_length_ratio``
   (stride length ratio against a continuous reference, :func:`nav.metrics.stride_length_ratio`, else the
   start-to-end length ratio), ``nav_heading_drift``
   (deg/s) and ``nav_final_error`` (m). Every residual's uncertainty includes what the twin fit alone gets
   wrong, measured on a twin of the twin (:func:`comparison_noise`); a navigation residual's also the
   standard deviation of the twin's value over ``settings.NAV_REPEATS`` re-simulations with other seeds (gait
   variability and sensor noise), at least its ``settings.NAV_FLOOR``;
4. rank the residuals by ``|value| / uncertainty`` (z). The largest significant one (z > ``settings.NOISE_LEVEL``) not
   yet acted on is tried against every effect of the library that moves it. The navigation residuals come
   after every signature residual, whatever their z: they are the outcome the loop predicts, and many effects
   move them, so they are acted on only when no diagnostic of one effect is left (an effect found there must
   still leave every signature residual it moves at the noise level). Never acted on (but reported, and used
   in the fits of effects that move them): ``settings.DERIVED`` residuals (``stance_shoe`` is a function of the stance
   gyro and accelerometer residuals).
   Each effect's magnitude is fitted by minimising ``Q = sum z_i^2`` over the residuals the effect moves,
   with a grid of ``settings.GRID_POINTS`` values plus a bounded Brent refinement, re-simulating the twin each time
   (with its noise re-matched to the recording's static noise, :func:`gaitsim.loop.twin.match_noise`).
   The fraction of the acted residual an effect explains is ``1 - |value after| / |value before|``;
5. the effect explaining the most is added to the twin when it explains at least ``settings.EXPLAINED_FRACTION``,
   lowers Q, and does no harm: no other residual, navigation included, may grow by more than
   ``settings.NOISE_LEVEL`` in z to above it (an effect that trades one residual for another is not what the recording
   shows). An effect that moves only navigation residuals (``g_sensitivity``) is fitted and reported as a
   candidate but never named: a single navigation number is closed by any effect that moves it.
   Otherwise the residual is reported ``"unexplained"`` (with the best candidate for the record).
   Steps 4-5 repeat for at most ``settings.MAX_ROUNDS`` residuals.

The predicted-versus-measured navigation discrepancy is ``|twin - recording|`` of each navigation metric,
reported for the twin before any effect and after all accepted ones.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize_scalar

from nav import pipeline
from nav.recording import Recording, RecordingError

from ..measured.reference import as_measured, reference_track
from . import effects as fx
from . import residuals, settings
from . import twin as tw
from .residuals import Residual
from .signature import Signature, signature

NAV_UNITS = {"nav_length_ratio": "1", "nav_heading_drift": "deg/s", "nav_final_error": "m"}


@dataclass
class Side:
    """One recording as the loop sees it: the recording, its signature and its navigation metrics."""

    recording: Recording
    signature: Signature
    nav: dict
    solution: object = None


@dataclass
class LoopResult:
    """Everything the report needs (see :mod:`gaitsim.loop.report`)."""

    measured: Side
    twin_before: tw.Twin
    twin_after: tw.Twin
    before: Side
    after: Side
    residuals_before: dict
    residuals_after: dict
    attributions: list
    noise: dict
    context: dict = field(default_factory=dict)

    def navigation_summary(self) -> dict:
        """Per navigation metric: measured, twin before/after and the discrepancy |twin - measured| before/after."""
        out = {}
        for key, m in self.measured.nav.items():
            b, a = self.before.nav.get(key, math.nan), self.after.nav.get(key, math.nan)
            if not math.isfinite(m):
                continue
            out[key] = {"unit": NAV_UNITS[key], "measured": m, "twin_before": b, "twin_after": a,
                        "discrepancy_before": abs(b - m), "discrepancy_after": abs(a - m)}
        return out


def navigation_metrics(rec: Recording) -> tuple[dict, object]:
    """Navigate ``rec`` and return (metrics, solution): nav_length_ratio, nav_heading_drift, nav_final_error."""
    sol, score = pipeline.run(rec, settings.NAV_OPTIONS)
    ratio = score.get("stride_length_ratio" if len(rec.reference.t) > 2 else "length_ratio", math.nan)
    drift = score.get("heading_drift_deg_per_s", math.nan)
    metrics = {"nav_length_ratio": float(ratio) if ratio is not None else math.nan,
               "nav_heading_drift": float(drift) if drift is not None else math.nan,
               "nav_final_error": float(score.get("final_error_m", math.nan))}
    return metrics, sol


def measure(rec: Recording, with_nav: bool = True) -> Side:
    """Signature (with the continuous reference's track, its detector at the recording's gravity,
    :attr:`nav.recording.Recording.gravity`) and, optionally, navigation metrics of ``rec``."""
    pos_t, pos = reference_track(rec)
    sig = signature(rec.t, rec.acc, rec.gyr, pos_t, pos, rec.gravity)
    if not with_nav:
        return Side(rec, sig, {})
    nav, sol = navigation_metrics(rec)
    return Side(rec, sig, nav, sol)


def simulate_side(simulate: tw.TwinSimulator, twin: tw.Twin, measured: Side, with_nav: bool,
                  seed: int | None = None) -> Side:
    """Simulate the twin and measure it like the recording (same kind of reference)."""
    sim = as_measured(simulate(twin, seed))
    if reference_track(measured.recording)[0] is None:  # start and end only, inside the IMU's span (a
        # time skew drops samples at both ends)
        inside = np.flatnonzero((sim.reference.t >= sim.t[0]) & (sim.reference.t <= sim.t[-1]))[[0, -1]]
        sim.reference.t, sim.reference.pos = sim.reference.t[inside], sim.reference.pos[inside]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # input checks on candidate twins (e.g. clipping) are expected
        return measure(sim, with_nav)


def compare(measured: Side, twin: Side, noise: dict) -> dict:
    """All residuals measured - twin (signature residuals, plus navigation ones when both sides have them), with
    the comparison's own uncertainty ``noise`` (:func:`comparison_noise`)."""
    out = residuals.compare(measured.signature, twin.signature, noise)
    for key, m in measured.nav.items():
        w = twin.nav.get(key, math.nan)
        if math.isfinite(m) and math.isfinite(w):
            out[key] = Residual(key, NAV_UNITS[key], m, w, m - w, noise.get(key, 0.0))
    return out


def comparison_noise(simulate: tw.TwinSimulator, twin: tw.Twin, measured: Side) -> dict:
    """What a comparison with this twin is uncertain by beyond the stride-to-stride scatter (name -> value).

    - **Fit floor** of every residual: the twin is simulated with another seed and treated as a recording
      (``settings.TWIN_OF_TWIN_SEED``), a twin is fitted to it the same way, and the residuals between the two are what
      the fit alone gets wrong (both sides come from the same model, so nothing else differs); the floor is
      their rms over ``settings.TWIN_OF_TWIN_REPEATS`` such pairs.
    - **Navigation**: the standard deviation of the twin's navigation metrics over ``settings.NAV_REPEATS`` seeds
      combined with their fit floor, at least ``settings.NAV_FLOOR``.
    """
    squares = {}
    for k in range(settings.TWIN_OF_TWIN_REPEATS):
        pseudo = simulate_side(simulate, twin, measured, True, twin.seed + settings.TWIN_OF_TWIN_SEED + k)
        refit = tw.fit_twin(pseudo.recording, pseudo.signature, pseudo.solution, simulate)
        for name, r in compare(pseudo, simulate_side(simulate, refit, measured, True), {}).items():
            if math.isfinite(r.value):
                squares.setdefault(name, []).append(r.value ** 2)
    floors = {name: float(math.sqrt(np.mean(v))) for name, v in squares.items()}
    values = [simulate_side(simulate, twin, measured, True, twin.seed + 1 + k).nav
              for k in range(settings.NAV_REPEATS)]
    for key, least in settings.NAV_FLOOR.items():
        spread = np.nanstd([v[key] for v in values], ddof=1)
        floors[key] = float(max(math.hypot(np.nan_to_num(spread), floors.get(key, 0.0)), least))
    return floors


def _q(res: dict, names) -> float:
    return float(sum(res[n].z ** 2 for n in names if n in res and math.isfinite(res[n].z)))


@dataclass
class Fit:
    """One effect fitted against one residual."""

    effect: fx.Effect
    magnitude: float
    changes: dict
    residuals: dict
    side: Side
    q_before: float
    q_after: float
    fraction: float
    harmed: tuple = ()

    def summary(self) -> dict:
        return {"effect": self.effect.name, "magnitude": self.magnitude, "unit": self.effect.unit,
                "fraction_explained": self.fraction, "q_before": self.q_before, "q_after": self.q_after,
                "made_worse": list(self.harmed), "identifiable": self.identifiable}

    @property
    def identifiable(self) -> bool:
        """An effect that moves navigation residuals only can close one whatever caused it: it is fitted and
        reported as a candidate but never named."""
        return any(not name.startswith("nav_") for name in self.effect.moves)

    @property
    def acceptable(self) -> bool:
        return (self.identifiable and self.fraction >= settings.EXPLAINED_FRACTION and self.q_after < self.q_before
                and not self.harmed)


def fit_effect(simulate: tw.TwinSimulator, effect: fx.Effect, twin: tw.Twin, measured: Side, base: dict,
               acted: str, ctx: dict, noise: dict, context_of=None) -> Fit:
    """Fit ``effect``'s magnitude (module docstring, step 4) and measure what it explains of ``acted`` (one of
    the residuals it moves: the fit itself does not depend on which).

    An effect whose direction comes from the residuals (``Effect.refine``) is fitted again with the context
    ``context_of(scenario, signature)`` of its first fit, and the better of the two fits is kept."""
    fit = _fit_magnitude(simulate, effect, twin, measured, base, ctx, noise)
    if effect.refine and context_of is not None and fit.side is not None:
        refined = context_of(twin.with_changes(fit.changes).scenario, fit.side.signature)
        again = _fit_magnitude(simulate, effect, twin, measured, base, refined, noise)
        fit = again if again.q_after < fit.q_after else fit
    return judged(fit, base, acted)


def _fit_magnitude(simulate: tw.TwinSimulator, effect: fx.Effect, twin: tw.Twin, measured: Side, base: dict,
                   ctx: dict, noise: dict) -> Fit:
    """One magnitude search of ``effect`` in context ``ctx``: grid, then bounded Brent around the best point."""
    use_nav = any(name.startswith("nav_") for name in effect.moves)
    names = [n for n in base if n in effect.moves]
    low, high = effect.search_bounds(ctx)
    cache = {}

    def evaluate(m: float, with_nav: bool = use_nav):
        key = (round(float(m), 12), with_nav)
        if key not in cache:
            try:
                changed = tw.match_noise(twin.with_changes(effect.changes(float(m), ctx)), simulate)
                side = simulate_side(simulate, changed, measured, with_nav)
            except (ValueError, RecordingError):  # e.g. the twin no longer shows regular strides
                cache[key] = (math.inf, {}, None)
            else:
                res = compare(measured, side, noise)
                cache[key] = (_q(res, names), res, side)
        return cache[key]

    to_axis = (np.log if effect.log_scale else (lambda x: x))
    from_axis = (np.exp if effect.log_scale else (lambda x: x))
    axis = np.linspace(to_axis(low), to_axis(high), settings.GRID_POINTS)
    guess = effect.first_guess(base, ctx)
    if guess is not None and math.isfinite(guess) and low < guess < high:
        axis = np.sort(np.append(axis, to_axis(guess)))
    costs = [evaluate(from_axis(a))[0] for a in axis]
    i = int(np.argmin(costs))
    lo_a, hi_a = axis[max(i - 1, 0)], axis[min(i + 1, len(axis) - 1)]
    if hi_a > lo_a and math.isfinite(costs[i]):
        found = minimize_scalar(lambda a: evaluate(from_axis(a))[0], bounds=(lo_a, hi_a), method="bounded",
                                options={"maxiter": settings.BRENT_ITERATIONS, "xatol": (hi_a - lo_a) * settings.BRENT_TOLERANCE})
        best = found.x if found.fun <= costs[i] else axis[i]
    else:
        best = axis[i]
    magnitude = float(from_axis(best))
    q_after, res, side = evaluate(magnitude, True)  # navigated, so that no harm to navigation goes unseen
    changes = effect.changes(magnitude, ctx)
    return Fit(effect, magnitude, changes, res, side, _q(base, names), q_after, 0.0)


def judged(fit: Fit, base: dict, acted: str) -> Fit:
    """``fit`` with the fraction of ``acted`` it explains and the other residuals it makes worse."""
    res = fit.residuals
    before, after = abs(base[acted].value), abs(res[acted].value) if acted in res else math.inf
    fraction = 1.0 - after / before if before > 0 else 0.0
    harmed = tuple(n for n in res if n != acted and n in base
                   and res[n].z > settings.NOISE_LEVEL and res[n].z > base[n].z + settings.NOISE_LEVEL)
    return dataclasses.replace(fit, fraction=float(fraction), harmed=harmed)


def _record(acted: Residual, best: Fit | None, accepted: bool, candidates: list) -> dict:
    after = best.residuals.get(acted.name) if (best is not None and accepted) else None
    return {
        "residual": acted.name, "unit": acted.unit, "z_before": acted.z,
        "effect": best.effect.name if accepted else "unexplained",
        "scenario_key": best.effect.key if accepted else None,
        "scenario_changes": best.changes if accepted else None,
        "magnitude": best.magnitude if accepted else None,
        "magnitude_unit": best.effect.unit if accepted else None,
        "residual_before": acted.value, "uncertainty_before": acted.uncertainty,
        "residual_after": after.value if after is not None else acted.value,
        "uncertainty_after": after.uncertainty if after is not None else acted.uncertainty,
        "at_noise_level_after": bool(after.at_noise_level) if after is not None else bool(acted.at_noise_level),
        "fraction_explained": best.fraction if (best is not None and accepted) else
        (max(0.0, best.fraction) if best is not None else 0.0),
        "best_candidate": best.summary() if best is not None else None,
        "candidates": [c.summary() for c in candidates],
    }


def run_loop(rec: Recording, library: tuple = fx.LIBRARY, max_rounds: int = settings.MAX_ROUNDS,
             log=lambda message: None) -> LoopResult:
    """The whole loop on one recording (module docstring). ``log`` receives progress lines."""
    simulate = tw.TwinSimulator()
    measured = measure(rec)
    log(f"navigated the recording: {measured.nav}")
    base_twin = tw.fit_twin(rec, measured.signature, measured.solution, simulate)
    noise = comparison_noise(simulate, base_twin, measured)
    before = simulate_side(simulate, base_twin, measured, True)
    current_twin, current_side = base_twin, before
    current = compare(measured, before, noise)
    first = dict(current)
    attributions, acted_names, used = [], set(), set()
    fitted = {}  # effect name -> its fit to the current twin (an effect's fit depends on the twin, not on the
    # residual acted on: fitted once per twin)
    ctx = fx.context(rec, base_twin.scenario, measured.signature, before.signature)
    for _ in range(max_rounds):
        ranked = sorted((r for r in current.values() if r.name not in acted_names
                         and r.name not in settings.DERIVED and r.z > settings.NOISE_LEVEL),
                        key=lambda r: (r.name.startswith("nav_"), -r.z))
        if not ranked:
            break
        acted = ranked[0]
        acted_names.add(acted.name)
        ctx = fx.context(rec, current_twin.scenario, measured.signature, current_side.signature)
        candidates = [e for e in library if acted.name in e.moves and e.name not in used and fx.applicable(e, ctx)]
        fits = []
        for e in candidates:
            if e.name not in fitted:
                fitted[e.name] = fit_effect(simulate, e, current_twin, measured, current, acted.name, ctx, noise,
                                            lambda scenario, sig: fx.context(rec, scenario, measured.signature, sig))
            fits.append(judged(fitted[e.name], current, acted.name))
        ranked_fits = sorted(fits, key=lambda f: (f.acceptable, f.fraction, -f.q_after), reverse=True)
        best = ranked_fits[0] if ranked_fits else None
        accepted = best is not None and best.acceptable
        attributions.append(_record(acted, best, accepted, fits))
        log(f"{acted.name} (z = {acted.z:.1f}): " + (f"{best.effect.name} = {best.magnitude:.4g} {best.effect.unit}, "
                                                     f"explains {best.fraction:.0%}" if accepted else "unexplained"))
        if accepted:
            used.add(best.effect.name)
            fitted = {}
            current_twin = tw.match_noise(current_twin.with_changes(best.changes), simulate)
            current_side = simulate_side(simulate, current_twin, measured, True)
            current = compare(measured, current_side, noise)
    return LoopResult(measured, base_twin, current_twin, before, current_side, first, current, attributions,
                      noise, ctx)
