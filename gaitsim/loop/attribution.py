"""The loop: navigate the recording, fit its twin, rank residuals, attribute them to effects, add, repeat.

:func:`run_loop` does, for one recording:

0. check it (:func:`nav.checks.check_recording`: NaN, timestamps, units) and its sensor frame
   (:mod:`gaitsim.loop.frame`, after an optional ``--axes`` map): a bad input is an error, never fitted;
1. navigate it with the shared filter (:data:`gaitsim.loop.settings.NAV_OPTIONS`) and score it against the
   reference it has (:mod:`gaitsim.loop.navigation`: a track, start and end, a walked distance, or none);
   compute its signature (:mod:`gaitsim.loop.signature`);
2. fit the twin (:mod:`gaitsim.loop.twin`), simulate it, treat the simulation as a measured recording (IMU
   samples and a position reference only) and do the same;
3. residuals = recording - twin: the signature residuals plus the navigation residuals its reference allows
   (:mod:`gaitsim.loop.navigation`: ``nav_length_ratio``, ``nav_heading_drift`` deg/s, ``nav_final_error`` m). Every residual's uncertainty includes what the twin fit alone gets
   wrong, measured on a twin of the twin (:func:`comparison_noise`); a navigation residual's also the
   standard deviation of the twin's value over ``settings.NAV_REPEATS`` re-simulations with other seeds (gait
   variability and sensor noise), at least its ``settings.NAV_FLOOR``;
4. rank the residuals by ``|value| / uncertainty`` (z). The largest significant one (z > ``settings.NOISE_LEVEL``) not
   yet acted on is tried against every effect of the library that moves it. The navigation residuals come
   after every signature residual, whatever their z: they are the outcome the loop predicts, and many effects
   move them, so they are acted on only when no diagnostic of one effect is left (an effect found there must
   still leave every signature residual it moves at the noise level). Never acted on (but reported, and used
   in the fits of effects that move them): ``settings.DERIVED`` residuals (``stance_shoe`` is a function of the stance
   gyro and accelerometer residuals) and ``settings.REFITTED`` ones, which the twin's own fit closes again after
   every added effect (``swing_axis_yaw``: the sensor's yaw on the foot, :func:`gaitsim.loop.twin.refit_yaw`;
   a change of the foot's stance motion turns the swing axis too), so that no effect harms them either.
   Each effect's magnitude is fitted by minimising ``Q = sum z_i^2`` over the residuals the effect moves,
   with a grid of ``settings.GRID_POINTS`` values plus a bounded Brent refinement, re-simulating the twin each time
   (with its noise re-matched to the recording's static noise, :func:`gaitsim.loop.twin.match_noise`).
   The fraction of the acted residual an effect explains is ``1 - |value after| / |value before|``;
5. of the candidates, the one that leaves the smallest misfit over all signature residuals
   (:func:`gaitsim.loop.residuals.signature_misfit`) is added to the twin when it lowers that misfit and its
   own Q, explains at least ``settings.EXPLAINED_FRACTION`` of the acted residual or brings it to the noise
   level by moving it toward zero by at least its uncertainty (a residual just above the noise level that an
   effect nudges below it, or that reads at the noise level only because the twin's spread grew, is not
   explained), lies inside its search range (a magnitude on the range's edge is no estimate: the minimum was not
   bracketed), and does no harm: no other residual, navigation included, that was at the noise level may end
   beyond ``settings.HARM_FACTOR`` times it (an effect that trades one residual for another is not what the
   recording shows). Its magnitude is searched on the signature residuals it moves (navigation and the Fig. 5
   residuals, :mod:`gaitsim.loop.fig5`, are checked at the fitted magnitude; the Fig. 5 residuals are searched
   on by an effect marked ``Effect.sweeps``), unless navigation is all it moves. An effect that moves only navigation residuals (``g_sensitivity``) is fitted and reported as a
   candidate but never named: a single navigation number is closed by any effect that moves it.
   Otherwise the residual is reported ``"unexplained"`` (with the best candidate for the record). The other
   acceptable candidates whose misfit lies within ``settings.NOISE_LEVEL ** 2`` of the named one's (less than
   one residual at the noise level adds) are reported with it as ``"equivalent"``: the recording does not tell
   them apart (e.g. the low-pass forms, which differ most above a fifth of the sample rate, where the
   comparison's noise is largest), and the named magnitude holds for the named form only.
5b. the sensor's linear errors (``Effect.linear``: scales, accelerometer biases, the skew, the g-sensitivity) are
   also fitted together (:func:`fit_joint`), when one of them moves the acted residual and two or more effects
   are left in the budget: a real sensor has several at once, and one alone can stand in for a pair the
   recording shows (a consumer accelerometer's offsets along x and z read as a z scale error, the x offset
   hidden in the mount pitch the twin reads at rest; the greedy rounds then name proxies). One
   forward-difference probe of each effect gives the slopes of the signed z of the scalar signature residuals
   (not the phase profiles, whose residual is an rms: :func:`_joint_names`); the linearised least squares keeps
   the sets of up to ``settings.JOINT_SIZE`` effects that hold an effect moving the acted residual and in which
   every member earns its place: the set's misfit lies more than ``settings.NOISE_LEVEL ** 2`` below that of each
   set without one of its members (:func:`linear_sets`). The best few are refined by Gauss-Newton on the
   simulated twin and judged as a single effect is (step 5); of the acceptable sets and the best single effect,
   the one with the lowest misfit plus ``settings.NOISE_LEVEL ** 2`` per member beyond the first is named (a
   larger set must fit better by one residual at the noise level per added member). Each member gets its own
   record (``joint_with`` the others); acceptable sets and single effects within the margin of step 5 are
   reported as equivalent.
   Steps 4-5 repeat, each significant residual acted on once, until none is left or
   ``settings.MAX_EFFECTS`` effects have been added. A residual left unexplained does not count against that
   budget: it says what the twin cannot reproduce, and must not keep a smaller residual that an effect of the
   library does explain from being acted on (a candidate's fit to the current twin is kept, so acting on
   another residual re-fits only effects not tried on that twin yet). A significant residual that no effect of
   the library moves (``rest_gyro_change``: a drifting bias) is reported unexplained before the rounds
   (:func:`unmovable`).

The predicted-versus-measured navigation discrepancy is ``|twin - recording|`` of each navigation metric,
reported for the twin before any effect and after all accepted ones.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import dataclasses
import itertools
import math
import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize_scalar

from nav.checks import check_recording
from nav.recording import Recording, RecordingError

from ..measured.reference import as_measured, reference_track
from . import effects as fx
from . import fig5, residuals, settings
from . import twin as tw
from .frame import FrameCheck, require_body_frame
from .navigation import NAV_UNITS, NavReference, nav_reference, navigation_metrics, same_kind
from .progress import Progress
from .residuals import Residual
from .signature import Signature, signature


@dataclass
class Side:
    """One recording as the loop sees it: the recording, its reference kind, its signature and its navigation
    metrics (those the reference kind allows)."""

    recording: Recording
    reference: NavReference
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
    frame: FrameCheck | None = None

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


def measure(rec: Recording, ref: NavReference, with_nav: bool = True, with_fig5: bool | None = None) -> Side:
    """Signature (with the continuous reference's track, its detector at the recording's gravity,
    :attr:`nav.recording.Recording.gravity`) and, optionally, the navigation metrics ``ref`` allows. The Fig. 5
    numbers (:mod:`gaitsim.loop.fig5`) join the signature's scalars when ``with_fig5`` (default: ``with_nav``)
    and the reference is a track."""
    pos_t, pos = reference_track(rec) if ref.kind == "track" else (None, None)
    sig = signature(rec.t, rec.acc, rec.gyr, pos_t, pos, rec.gravity)
    if (with_nav if with_fig5 is None else with_fig5) and pos is not None:
        sig.scalars.update(fig5.fig5_scalars(rec, pos_t, pos))
    if not with_nav:
        return Side(rec, ref, sig, {})
    nav, sol = navigation_metrics(rec, ref)
    return Side(rec, ref, sig, nav, sol)


def simulate_side(simulate: tw.TwinSimulator, twin: tw.Twin, measured: Side, with_nav: bool,
                  seed: int | None = None, with_fig5: bool | None = None) -> Side:
    """Simulate the twin and measure it like the recording (same kind of reference; :func:`measure`)."""
    sim = same_kind(as_measured(simulate(twin, seed)), measured.reference)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # input checks on candidate twins (e.g. clipping) are expected
        return measure(sim, measured.reference, with_nav, with_fig5)


def compare(measured: Side, twin: Side, noise: dict) -> dict:
    """All residuals measured - twin (signature residuals, plus navigation ones when both sides have them), with
    the comparison's own uncertainty ``noise`` (:func:`comparison_noise`)."""
    out = residuals.compare(measured.signature, twin.signature, noise)
    for key, m in measured.nav.items():
        w = twin.nav.get(key, math.nan)
        if math.isfinite(m) and math.isfinite(w):
            out[key] = Residual(key, NAV_UNITS[key], m, w, m - w, noise.get(key, 0.0))
    return out


def _twin_of_twin(simulate: tw.TwinSimulator, twin: tw.Twin, measured: Side, seed: int) -> tuple[Side, dict, dict]:
    """One seed of :func:`comparison_noise`: the twin simulated with ``seed`` and measured like the recording, its
    own twin's residuals against it, and the navigation discrepancies between the two (metric -> value)."""
    side = simulate_side(simulate, twin, measured, True, seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        own = tw.fit_twin(side.recording, side.signature, side.solution, simulate)
    again = simulate_side(simulate, own, side, True)
    gaps = {key: side.nav.get(key, math.nan) - again.nav.get(key, math.nan) for key in measured.nav}
    return side, residuals.compare(side.signature, again.signature), gaps


def comparison_noise(workers: "Workers", twin: tw.Twin, measured: Side, progress: Progress) -> dict:
    """What a comparison with this twin is uncertain by beyond the stride-to-stride scatter (name -> value),
    calibrated on the twin itself: it is simulated with ``settings.NAV_REPEATS`` other seeds; every pair of
    those simulations is compared as recording and twin would be (same model, so only chance differs), and
    each simulation gets a twin of its own, fitted by the recipe that fitted this one, and is compared with it
    (a *twin of the twin*: what the fit itself gets wrong, on a recording whose model the fit can reach).

    - **Signature residuals**: the floor is what those residuals show beyond their own stride scatter,
      ``sqrt(max(0, mean(value^2 - se^2)))`` (``se`` the combined standard error), the larger of the pairs' and
      the twins of the twin's: the part of the difference between a recording and its twin that the per-stride
      standard errors miss (a profile averaged over few, unevenly cut strides; a swing peak the gait-shape fit
      does not reach). With it, a residual's z is ~1 between a simulation and its own twin.
    - **Navigation**: the standard deviation of the twin's navigation metrics over those seeds, the rms of the
      twins of the twin's navigation discrepancies, and ``settings.NAV_FLOOR``, whichever is largest.

    The seeds are independent tasks of ``workers`` (:class:`Workers`).
    """
    progress.stage("calibrating the comparison noise on the twin and twins of the twin", settings.NAV_REPEATS)
    seeds = [twin.seed + settings.TWIN_OF_TWIN_SEED + k for k in range(settings.NAV_REPEATS)]
    sides, fitted, nav_gaps = [], [], {}
    for side, own_residuals, gaps in workers.map(_twin_of_twin, [twin] * len(seeds), [measured] * len(seeds), seeds):
        sides.append(side)
        fitted.append(own_residuals)
        for key, gap in gaps.items():
            nav_gaps.setdefault(key, []).append(gap)
        progress.step("simulations of the twin with other seeds, each with a twin of its own fitted")
    pairs = [residuals.compare(sides[i].signature, sides[j].signature)
             for i in range(len(sides)) for j in range(i + 1, len(sides))]
    floors = {}
    for group in (pairs, fitted):
        excess = {}
        for compared in group:
            for name, r in compared.items():
                if math.isfinite(r.value):
                    excess.setdefault(name, []).append(r.value ** 2 - r.uncertainty ** 2)
        for name, v in excess.items():
            floors[name] = max(floors.get(name, 0.0), float(math.sqrt(max(0.0, np.mean(v)))))
    for key in measured.nav:
        spread = np.nanstd([s.nav.get(key, math.nan) for s in sides], ddof=1)
        gap = np.sqrt(np.nanmean(np.square(nav_gaps[key]))) if np.isfinite(nav_gaps[key]).any() else 0.0
        floors[key] = float(max(np.nan_to_num(spread), gap, settings.NAV_FLOOR[key]))
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
    total_before: float = math.nan
    total_after: float = math.nan
    closes_acted: bool = False  # brings the acted residual to the noise level, moved by >= its uncertainty
    at_bound: bool = False

    def summary(self) -> dict:
        return {"effect": self.effect.name, "magnitude": self.magnitude, "unit": self.effect.unit,
                **_judgement(self), "identifiable": self.identifiable}

    def named(self) -> tuple:
        """(effect, magnitude, scenario changes) of what naming this fit adds to the twin."""
        return ((self.effect, self.magnitude, self.changes),)

    @property
    def identifiable(self) -> bool:
        """An effect that moves navigation residuals only can close one whatever caused it: it is fitted and
        reported as a candidate but never named."""
        return any(not name.startswith("nav_") for name in self.effect.moves)

    @property
    def acceptable(self) -> bool:
        return _acceptable(self)


@dataclass
class JointFit:
    """Linear sensor effects fitted together (:func:`fit_joint`): ``members`` are (effect, magnitude) pairs added
    to the twin in order, ``changes`` their scenario changes, each in the context of the twin before it. Judged
    like a :class:`Fit` (:func:`judged`)."""

    members: tuple
    changes: tuple
    residuals: dict
    q_before: float
    q_after: float
    fraction: float = 0.0
    harmed: tuple = ()
    total_before: float = math.nan
    total_after: float = math.nan
    closes_acted: bool = False
    at_bound: bool = False
    identifiable = True  # every linear effect moves signature residuals

    def summary(self) -> dict:
        return {"effect": " + ".join(e.name for e, _ in self.members),
                "members": [{"effect": e.name, "magnitude": m, "unit": e.unit} for e, m in self.members],
                **_judgement(self), "identifiable": True}

    def named(self) -> tuple:
        return tuple((e, m, c) for (e, m), c in zip(self.members, self.changes))

    @property
    def acceptable(self) -> bool:
        return _acceptable(self)


def _judgement(fit) -> dict:
    """What :func:`judged` found of a fit, as reported."""
    return {"fraction_explained": fit.fraction, "q_before": fit.q_before, "q_after": fit.q_after,
            "misfit_before": fit.total_before, "misfit_after": fit.total_after, "made_worse": list(fit.harmed),
            "at_search_bound": fit.at_bound}


def _acceptable(fit) -> bool:
    """Step 5's rule (module docstring) for a :class:`Fit` or a :class:`JointFit` after :func:`judged`."""
    return (fit.identifiable and (fit.fraction >= settings.EXPLAINED_FRACTION or fit.closes_acted)
            and fit.q_after < fit.q_before and fit.total_after < fit.total_before and not fit.harmed
            and not fit.at_bound)


def fit_effect(simulate: tw.TwinSimulator, effect: fx.Effect, twin: tw.Twin, measured: Side, base: dict, ctx: dict,
               noise: dict) -> Fit:
    """Fit ``effect``'s magnitude to the twin (module docstring, step 4); :func:`judged` then measures what it
    explains of the residual acted on (the fit itself does not depend on which).

    An effect whose direction comes from the residuals (``Effect.refine``) is fitted again with the context
    (:func:`gaitsim.loop.effects.context`) of its first fit, and the better of the two fits is kept."""
    fit = _fit_magnitude(simulate, effect, twin, measured, base, ctx, noise)
    if effect.refine and fit.side is not None:
        refined = fx.context(measured.recording, twin.with_changes(fit.changes).scenario, measured.signature,
                             fit.side.signature)
        again = _fit_magnitude(simulate, effect, twin, measured, base, refined, noise)
        fit = again if again.q_after < fit.q_after else fit
    return fit


def _fit_magnitude(simulate: tw.TwinSimulator, effect: fx.Effect, twin: tw.Twin, measured: Side, base: dict,
                   ctx: dict, noise: dict) -> Fit:
    """One magnitude search of ``effect`` in context ``ctx``: grid, then bounded Brent around the best point."""
    use_nav = all(name.startswith("nav_") for name in effect.moves)  # navigated only when that is all it moves
    names = [n for n in base if n in effect.moves and (use_nav or not n.startswith("nav_"))
             and (effect.sweeps or n not in fig5.NUMBERS)]
    low, high = effect.search_bounds(ctx)
    cache = {}

    def evaluate(m: float, with_nav: bool = use_nav):
        key = (round(float(m), 12), with_nav)
        if key not in cache:
            try:
                changed = tw.match_noise(twin.with_changes(effect.changes(float(m), ctx)), simulate)
                side = simulate_side(simulate, changed, measured, with_nav, with_fig5=effect.sweeps or with_nav)
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
    edge = settings.BRENT_TOLERANCE * (axis[-1] - axis[0])
    return Fit(effect, magnitude, changes, res, side, _q(base, names), q_after, 0.0,
               at_bound=bool(best <= axis[0] + edge or best >= axis[-1] - edge))


def judged(fit: Fit | JointFit, base: dict, acted: str) -> Fit | JointFit:
    """``fit`` with the fraction of ``acted`` it explains, whether it closes ``acted`` (to the noise level, moved
    toward zero by at least its uncertainty) and the other residuals it makes worse: at the noise level before,
    beyond ``settings.HARM_FACTOR`` times it after (a residual that was already off may move either way while
    another effect remains to be found)."""
    res = fit.residuals
    before, after = abs(base[acted].value), abs(res[acted].value) if acted in res else math.inf
    fraction = 1.0 - after / before if before > 0 else 0.0
    harmed = tuple(n for n in res if n != acted and n in base and n not in settings.REFITTED
                   and base[n].z <= settings.NOISE_LEVEL < res[n].z / settings.HARM_FACTOR)
    return dataclasses.replace(fit, fraction=float(fraction), harmed=harmed,
                               closes_acted=bool(acted in res and res[acted].at_noise_level
                                                 and before - after >= base[acted].uncertainty),
                               total_before=residuals.signature_misfit(base),
                               total_after=residuals.signature_misfit(res))


def equivalent(best: Fit | JointFit, fits: list) -> list:
    """The acceptable fits other than ``best`` whose signature misfit after lies within
    ``settings.NOISE_LEVEL ** 2`` of ``best``'s, smallest misfit first (module docstring, step 5)."""
    margin = best.total_after + settings.NOISE_LEVEL ** 2
    return sorted((f for f in fits if f is not best and f.acceptable and f.total_after <= margin),
                  key=lambda f: f.total_after)


def add_effects(twin: tw.Twin, effects, measured: Side, simulate: tw.TwinSimulator,
                twin_signature: Signature | None = None, refit: bool = True) -> tuple[tw.Twin, tuple]:
    """``twin`` with the (effect, magnitude) ``effects`` added in order, each in the context of the twin with the
    ones before it (:func:`gaitsim.loop.effects.context`), and the scenario changes each added. With ``refit`` an
    effect is added as the loop adds it (:func:`gaitsim.loop.twin.with_effect`: the yaw re-fitted, the noise
    re-matched), without it only its changes (as a magnitude search tries it). The context's twin signature is
    ``twin_signature`` for every effect, or, when None, the twin so far simulated again before each (an effect
    whose context holds a simulated number, a stance rotation's direction, needs it; a linear effect's does not)."""
    added = []
    for effect, magnitude in effects:
        signature_now = (simulate_side(simulate, twin, measured, False).signature if twin_signature is None
                         else twin_signature)
        change = effect.changes(float(magnitude), fx.context(measured.recording, twin.scenario, measured.signature,
                                                             signature_now))
        twin = tw.with_effect(twin, change, measured.signature, simulate) if refit else twin.with_changes(change)
        added.append(change)
    return twin, tuple(added)


def _signed_z(res: dict, names: list) -> np.ndarray:
    """value / uncertainty of each residual of ``names`` (NaN where it is missing)."""
    return np.array([res[n].value / res[n].uncertainty if n in res and math.isfinite(res[n].value)
                     and res[n].uncertainty > 0 else np.nan for n in names])


def _joint_names(base: dict) -> list:
    """The residuals a joint fit works on: the scalar ones :func:`gaitsim.loop.residuals.signature_misfit` sums,
    whose signed values a linear model can follow. Left to the simulated check of each refined set: the phase
    profiles (each residual an rms over the phases, never negative; fitted phase by phase, the shape the twin's
    gait misses was taken up by sensor errors the recording does not have) and the Fig. 5 residuals (a threshold
    sweep of every probe would cost ~5x its signature)."""
    return [name for name, r in base.items() if not name.startswith(("nav_", "profile_")) and name not in fig5.NUMBERS
            and name not in settings.DERIVED + settings.REFITTED and math.isfinite(r.z)]


def _probe(simulate: tw.TwinSimulator, twin: tw.Twin, measured: Side, noise: dict, names: list, members,
           twin_signature: Signature) -> np.ndarray | None:
    """:func:`_signed_z` of ``names`` for ``twin`` with ``members`` added as a magnitude search tries them (None
    when that twin shows no regular strides)."""
    try:
        changed, _ = add_effects(twin, members, measured, simulate, twin_signature, refit=False)
        side = simulate_side(simulate, tw.match_noise(changed, simulate), measured, False)
    except (ValueError, RecordingError):
        return None
    return _signed_z(compare(measured, side, noise), names)


def _refine(simulate: tw.TwinSimulator, twin: tw.Twin, measured: Side, noise: dict, names: list, effects: list,
            start, steps, bounds, twin_signature: Signature) -> tuple[float, list, np.ndarray]:
    """Gauss-Newton on the simulated residuals from the linearised magnitudes ``start`` of ``effects`` (each
    iteration a forward difference of ``steps`` per effect, every magnitude held inside its ``bounds``), at most
    ``settings.JOINT_ITERATIONS`` steps, a step that does not lower the misfit halved once; then every member must
    still earn its place in the simulation: while leaving one out (the others at their magnitudes) raises the
    misfit by less than ``settings.NOISE_LEVEL ** 2``, the one that costs least is left out. Returns (misfit,
    effects kept, their magnitudes); residuals a probe lacks count as zero."""
    low, high = np.array(bounds, float).T

    def misfit(chosen, m):
        z = _probe(simulate, twin, measured, noise, names, tuple(zip(chosen, m)), twin_signature)
        return (math.inf, None) if z is None else (float(np.nansum(z ** 2)), np.nan_to_num(z))

    def slopes(m, z):
        columns = []
        for i, h in enumerate(steps):
            moved = m.copy()
            moved[i] += h
            z_i = misfit(effects, moved)[1]
            if z_i is None:
                return None
            columns.append((z_i - z) / h)
        return np.stack(columns, axis=1)

    m = np.asarray(start, float)
    q, z = misfit(effects, m)
    for _ in range(settings.JOINT_ITERATIONS):
        jacobian = None if z is None else slopes(m, z)
        if jacobian is None:
            break
        step, *_ = np.linalg.lstsq(jacobian, -z, rcond=None)
        for share in (1.0, 0.5):
            trial = np.clip(m + share * step, low, high)
            q_trial, z_trial = misfit(effects, trial)
            if q_trial < q:
                m, q, z = trial, q_trial, z_trial
                break
        else:
            break
    kept = list(range(len(effects)))
    while len(kept) > 1 and math.isfinite(q):
        without = [misfit([effects[j] for j in kept if j != i], [m[j] for j in kept if j != i])[0] for i in kept]
        cheapest = int(np.argmin(without))
        if without[cheapest] - q >= settings.NOISE_LEVEL ** 2:
            break
        q = without[cheapest]
        kept.pop(cheapest)
    return q, [effects[j] for j in kept], m[kept]


def linear_sets(columns: dict, z0: np.ndarray, bounds: list, size: int, required: set) -> list:
    """The sets of the linearised fit worth refining. Every set of 2 to ``size`` of the effects whose slopes are
    ``columns`` (index -> slopes of the residuals' signed z per unit magnitude) is fitted by least squares to close
    ``z0``; a set qualifies when it holds an effect of ``required``, every magnitude lies inside its ``bounds``,
    and every member earns its place: the set's misfit ``|z|^2`` lies more than ``settings.NOISE_LEVEL ** 2``
    below that of each set without one of its members (one residual at the noise level). Returns (misfit,
    indices, magnitudes) of the ``settings.JOINT_SUBSETS`` qualifying sets with the lowest misfit plus
    ``settings.NOISE_LEVEL ** 2`` per member beyond the first (the score the loop names by), best first."""
    fitted = {}
    for k in range(1, size + 1):
        for combo in itertools.combinations(sorted(columns), k):
            slopes = np.stack([columns[i] for i in combo], axis=1)
            m, *_ = np.linalg.lstsq(slopes, -z0, rcond=None)
            left = z0 + slopes @ m
            fitted[combo] = (float(left @ left), m)
    qualifying = []
    for combo, (misfit, m) in fitted.items():
        if len(combo) < 2 or not required & set(combo):
            continue
        without = min(fitted[tuple(i for i in combo if i != j)][0] for j in combo)
        if misfit < without - settings.NOISE_LEVEL ** 2 and all(bounds[i][0] < mi < bounds[i][1]
                                                               for i, mi in zip(combo, m)):
            qualifying.append((misfit, combo, m))
    return sorted(qualifying, key=lambda f: f[0] + (len(f[1]) - 1) * settings.NOISE_LEVEL ** 2)[:settings.JOINT_SUBSETS]


def fit_joint(workers: "Workers", effects: list, twin: tw.Twin, measured: Side, base: dict, ctx: dict,
              noise: dict, size: int, twin_signature: Signature, acted: str, cache: dict) -> list:
    """The sensor's linear errors fitted together (module docstring, step 5b): one forward-difference probe of
    each of ``effects`` (linear, ``settings.JOINT_STEP_SHARE`` of its search range) gives the slopes of the
    residuals' signed z (:func:`_joint_names`; only those every probe has); :func:`linear_sets` picks the sets of
    up to ``size`` effects the data support, each holding an effect that moves ``acted``; each is refined by
    Gauss-Newton on the simulated twin, its members pruned to those that earn their place there (:func:`_refine`),
    and simulated once more with navigation, as a :class:`Fit` is (a set pruned to one effect is left to the
    single fits, one pruned of every effect that moves ``acted`` is dropped). Returns those fits (to be :func:`judged`), best misfit first. Probes and refinements are
    independent tasks of ``workers``; ``cache`` keeps them for the same twin (a later round on it)."""
    names = _joint_names(base)
    if size < 2 or len(effects) < 2 or not names:
        return []
    bounds = [e.search_bounds(ctx) for e in effects]
    steps = [settings.JOINT_STEP_SHARE * (high - low) for low, high in bounds]
    if "probes" not in cache:
        n = len(effects) + 1  # the twin as it is first: its noise re-matched as every probe's is
        cache["probes"] = list(workers.map(_probe, [twin] * n, [measured] * n, [noise] * n, [names] * n,
                                           [()] + [((e, h),) for e, h in zip(effects, steps)], [twin_signature] * n))
    z0, *probes = cache["probes"]
    if z0 is None:
        return []
    kept = np.all([np.isfinite(z) for z in [z0] + [p for p in probes if p is not None]], axis=0)
    columns = {i: (z[kept] - z0[kept]) / steps[i] for i, z in enumerate(probes) if z is not None}
    required = {i for i, e in enumerate(effects) if acted in e.moves}
    sets = linear_sets(columns, z0[kept], bounds, size, required)
    new = [(combo, m) for _, combo, m in sets if combo not in cache]
    k = len(new)
    for (combo, _), (_, kept, magnitudes) in zip(new, workers.map(
            _refine, [twin] * k, [measured] * k, [noise] * k, [names] * k,
            [[effects[i] for i in combo] for combo, _ in new], [m for _, m in new],
            [[steps[i] for i in combo] for combo, _ in new], [[bounds[i] for i in combo] for combo, _ in new],
            [twin_signature] * k)):
        cache[combo] = None if len(kept) < 2 or not any(acted in e.moves for e in kept) else _joint_fit(
            workers.simulate, kept, magnitudes, [bounds[effects.index(e)] for e in kept], twin, measured, base,
            noise, twin_signature)
    fits = [cache[combo] for _, combo, _ in sets if cache[combo] is not None]
    return sorted(fits, key=lambda f: residuals.signature_misfit(f.residuals))


def _joint_fit(simulate: tw.TwinSimulator, effects: list, magnitudes, bounds: list, twin: tw.Twin, measured: Side,
               base: dict, noise: dict, twin_signature: Signature) -> JointFit | None:
    """The refined set simulated with navigation and compared (None when that twin shows no regular strides)."""
    members = tuple(zip(effects, (float(m) for m in magnitudes)))
    try:
        changed, changes = add_effects(twin, members, measured, simulate, twin_signature, refit=False)
        side = simulate_side(simulate, tw.match_noise(changed, simulate), measured, True)
    except (ValueError, RecordingError):
        return None
    res = compare(measured, side, noise)
    moved = [name for name in base if any(name in e.moves for e in effects) and not name.startswith("nav_")
             and name not in fig5.NUMBERS]
    edges = [settings.JOINT_BOUND_SHARE * (high - low) for low, high in bounds]
    at_bound = any(not low + edge < m < high - edge for (_, m), (low, high), edge in zip(members, bounds, edges))
    return JointFit(members, changes, res, _q(base, moved), _q(res, moved), at_bound=at_bound)


def _records(acted: Residual, best: Fit | JointFit | None, accepted: bool, candidates: list,
             applied: tuple = ()) -> list:
    """The attribution records of one round: one per effect named, with the scenario changes ``applied`` to the
    twin (a joint fit names several, each record saying which others it was fitted with), or one
    ``"unexplained"``."""
    after = best.residuals.get(acted.name) if (best is not None and accepted) else None
    named = best.named() if accepted else ((None, None, None),)
    return [{
        "residual": acted.name, "unit": acted.unit, "z_before": acted.z,
        "effect": effect.name if accepted else "unexplained",
        "scenario_key": effect.key if accepted else None,
        "scenario_changes": changes if accepted else None,
        "magnitude": magnitude if accepted else None,
        "magnitude_unit": effect.unit if accepted else None,
        **({"joint_with": [e.name for e, _, _ in named if e is not effect]} if len(named) > 1 else {}),
        "residual_before": acted.value, "uncertainty_before": acted.uncertainty,
        "residual_after": after.value if after is not None else acted.value,
        "uncertainty_after": after.uncertainty if after is not None else acted.uncertainty,
        "at_noise_level_after": bool(after.at_noise_level) if after is not None else bool(acted.at_noise_level),
        "fraction_explained": best.fraction if (best is not None and accepted) else
        (max(0.0, best.fraction) if best is not None else 0.0),
        "best_candidate": best.summary() if best is not None else None,
        "equivalent": _equivalent_entries(best, candidates) if accepted else [],
        "candidates": [c.summary() for c in candidates],
    } for (effect, magnitude, _), changes in zip(named, applied or (None,) * len(named))]


def _equivalent_entries(best: Fit | JointFit, candidates: list) -> list:
    """The candidates reported as fitting as well as ``best`` (:func:`equivalent`), a joint set one entry per
    member (``with``: the other members of its set)."""
    out = []
    for fit in equivalent(best, candidates):
        summary = fit.summary()
        out += [summary] if isinstance(fit, Fit) else [
            {**member, "with": [m["effect"] for m in summary["members"] if m is not member],
             **{k: v for k, v in summary.items() if k not in ("effect", "members")}}
            for member in summary["members"]]
    return out


def unmovable(res: dict, library: tuple) -> list:
    """The significant residuals (z > ``settings.NOISE_LEVEL``, not ``settings.DERIVED``) that no effect of
    ``library`` moves, largest z first: the loop reports them unexplained before its rounds, without using one
    (no effect added later can close them)."""
    moved = {name for e in library for name in e.moves}
    return sorted((r for r in res.values() if r.z > settings.NOISE_LEVEL and r.name not in settings.DERIVED
                   and r.name not in moved), key=lambda r: -r.z)


def prepare(rec: Recording, axis_map: str | None = None, distance_m: float | None = None) -> tuple[
        Recording, FrameCheck, NavReference]:
    """Step 0 of the module docstring: the recording checked (:func:`nav.checks.check_recording`), in the body
    frame (:func:`gaitsim.loop.frame.require_body_frame`, after ``axis_map``), and its reference kind (a
    simulated recording without a reference is scored against its true track).

    Raises
    ------
    RecordingError
        naming what is wrong with the recording (NaN, timestamps, units, frame) or with ``distance_m``.
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the non-fatal findings are kept in the report's counts
        check_recording(rec, rec.gravity, name=str(rec.meta.get("source", "imu.csv")))
    mapped, frame = require_body_frame(rec, axis_map)
    if mapped.reference is None and mapped.truth is not None:  # a simulated recording: its truth is the reference
        mapped = dataclasses.replace(mapped, reference=as_measured(mapped).reference)
    return mapped, frame, nav_reference(mapped, distance_m)


class Workers:
    """Where the loop's independent simulations run: in this process (one worker) or on a local pool of worker
    processes (:func:`gaitsim.experiments.runner.process_pool`). A task is a module-level function whose first
    argument is a twin simulator: this process's, or the worker process's own (a walk a worker has simulated is
    reused by its later tasks). A task's result follows from its arguments alone (seeded simulations), so it does
    not depend on where it ran or on the number of workers.
    """

    def __init__(self, pool: concurrent.futures.Executor | None = None):
        self.pool = pool
        self.simulate = tw.TwinSimulator()

    @classmethod
    @contextlib.contextmanager
    def started(cls, workers: int):
        """``workers`` (>= 1) workers for the duration of the ``with`` block; one runs in this process."""
        if workers < 1:
            raise ValueError(f"workers = {workers}: must be >= 1")
        if workers == 1:
            yield cls()
            return
        from ..experiments.runner import process_pool
        with process_pool(workers) as pool:
            yield cls(pool)

    def map(self, task, *arguments):
        """The results of ``task(simulator, *args)`` for each tuple of ``arguments``, in order (an iterator: each
        result as soon as it and those before it are done)."""
        if self.pool is None:
            return (task(self.simulate, *args) for args in zip(*arguments))
        return self.pool.map(_in_worker, [task] * len(arguments[0]), *arguments)


_WORKER_SIMULATOR: tw.TwinSimulator | None = None  # a pool worker's own simulator (:class:`Workers`)


def _in_worker(task, *args):
    global _WORKER_SIMULATOR
    if _WORKER_SIMULATOR is None:
        _WORKER_SIMULATOR = tw.TwinSimulator()
    return task(_WORKER_SIMULATOR, *args)


def run_loop(rec: Recording, max_effects: int = settings.MAX_EFFECTS, log=lambda message: None,
             axis_map: str | None = None, distance_m: float | None = None, workers: int = 1) -> LoopResult:
    """The whole loop on one recording (module docstring). ``log`` receives progress lines; ``axis_map`` is the
    ``--axes`` map and ``distance_m`` the ``--distance`` of the command line. ``workers`` processes run the
    independent simulations (the comparison noise's seeds, a round's candidate effects; :class:`Workers`): the
    result does not depend on their number.

    Raises
    ------
    RecordingError
        for a recording the loop cannot use (:func:`prepare`; too few regular strides).
    """
    with Workers.started(workers) as pool:
        return _run_loop(rec, max_effects, Progress(log), axis_map, distance_m, pool)


def _run_loop(rec: Recording, max_effects: int, progress: Progress, axis_map: str | None, distance_m: float | None,
              workers: Workers) -> LoopResult:
    rec, frame, ref = prepare(rec, axis_map, distance_m)
    simulate = workers.simulate
    measured = measure(rec, ref)
    progress.note(f"navigated the recording ({ref.kind} reference): {measured.nav}")
    base_twin = tw.fit_twin(rec, measured.signature, measured.solution, simulate)
    progress.note("fitted the twin")
    noise = comparison_noise(workers, base_twin, measured, progress)
    before = simulate_side(simulate, base_twin, measured, True)
    current_twin, current_side = base_twin, before
    current = compare(measured, before, noise)
    first = dict(current)
    attributions, acted_names, used = [], set(), set()
    fitted = {}  # effect name -> its fit to the current twin (an effect's fit depends on the twin, not on the
    # residual acted on: fitted once per twin)
    joint_cache = {}  # the joint fit's probes and refined sets on the current twin
    ctx = fx.context(rec, base_twin.scenario, measured.signature, before.signature)
    for acted in unmovable(current, fx.LIBRARY):
        acted_names.add(acted.name)
        attributions += _records(acted, None, False, [])
        progress.note(f"{acted.name} (z = {acted.z:.1f}): moved by no effect of the library, unexplained")
    round_number = 0
    while len(used) < max_effects:
        round_number += 1
        ranked = sorted((r for r in current.values() if r.name not in acted_names
                         and r.name not in settings.DERIVED + settings.REFITTED and r.z > settings.NOISE_LEVEL),
                        key=lambda r: (r.name.startswith("nav_"), -r.z))
        if not ranked:
            break
        acted = ranked[0]
        acted_names.add(acted.name)
        ctx = fx.context(rec, current_twin.scenario, measured.signature, current_side.signature)
        candidates = [e for e in fx.LIBRARY if acted.name in e.moves and e.name not in used and fx.applicable(e, ctx)]
        progress.stage(f"round {round_number}, {acted.name} (z = {acted.z:.1f})", len(candidates))
        new = [e for e in candidates if e.name not in fitted]
        for _ in range(len(candidates) - len(new)):
            progress.step("effects fitted (on this twin in an earlier round)")
        n = len(new)
        for fit in workers.map(fit_effect, new, [current_twin] * n, [measured] * n, [current] * n, [ctx] * n,
                               [noise] * n):
            fitted[fit.effect.name] = fit
            progress.step(f"effects fitted ({fit.effect.name})")
        fits = [judged(fitted[e.name], current, acted.name) for e in candidates]
        ranked_fits = sorted(fits, key=lambda f: (f.acceptable, -f.total_after), reverse=True)
        best = ranked_fits[0] if ranked_fits else None
        accepted = best is not None and best.acceptable
        linear = [e for e in fx.LIBRARY if e.linear and e.name not in used and fx.applicable(e, ctx)]
        size = min(settings.JOINT_SIZE, max_effects - len(used))
        if any(acted.name in e.moves for e in linear) and size >= 2:
            progress.note(f"round {round_number}, {acted.name}: {len(linear)} linear sensor effects fitted together")
            joints = [judged(j, current, acted.name) for j in fit_joint(
                workers, linear, current_twin, measured, current, ctx, noise, size, current_side.signature,
                acted.name, joint_cache)]
            fits += joints
            if any(j.acceptable for j in joints):  # each member beyond the first pays one residual at the noise level
                best = min([j for j in joints if j.acceptable] + ([best] if accepted else []),
                           key=lambda f: f.total_after + (len(f.named()) - 1) * settings.NOISE_LEVEL ** 2)
                accepted = True
        progress.note(f"round {round_number}, {acted.name}: " + (
            ", ".join(f"{e.name} = {m:.4g} {e.unit}" for e, m, _ in best.named())
            + f", explains {best.fraction:.0%}" if accepted else "unexplained"))
        if not accepted:
            attributions += _records(acted, best, accepted, fits)
            continue
        if isinstance(best, JointFit):  # each member in the context of the twin with the ones before it, as the
            # held-out transfer adds them (gaitsim.loop.transfer.with_effects)
            current_twin, applied = add_effects(current_twin, [(e, m) for e, m, _ in best.named()], measured,
                                                simulate, current_side.signature)
        else:  # a single fit's own changes: a refined fit's context (Effect.refine) is not the round's
            current_twin, applied = tw.with_effect(current_twin, best.changes, measured.signature, simulate), \
                (best.changes,)
        attributions += _records(acted, best, accepted, fits, applied)
        used.update(e.name for e, _, _ in best.named())
        fitted, joint_cache = {}, {}
        current_side = simulate_side(simulate, current_twin, measured, True)
        current = compare(measured, current_side, noise)
    return LoopResult(measured, base_twin, current_twin, before, current_side, first, current, attributions,
                      noise, ctx, frame)
