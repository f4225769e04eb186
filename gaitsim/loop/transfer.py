"""Held-out prediction: do the effects fitted on one recording predict another recording of the same dataset?

For every ordered pair (source, target) of recordings of one dataset (same sensor model and subject), the
target's default twin (its own gait, path, mount and sensor noise fit, no effect added) is compared with the
same twin given the source's accepted effects at the source's fitted magnitudes. What each effect derives from
the recording it is applied to stays the target's: the mount's roll and pitch, the ringing frequency and the
direction of a stance rotation (a left and a right foot rotate mirrored), so only the magnitudes travel.

Both twins are scored against the target recording with the target's comparison noise
(:func:`gaitsim.loop.attribution.comparison_noise`):

- ``q_signature``: sum of z^2 over the signature residuals (:func:`gaitsim.loop.residuals.signature_misfit`), the
  misfit the loop minimises;
- ``nav_discrepancy``: ``|twin - recording|`` of each navigation metric the target's reference allows.

The transferred twin predicts better when its ``q_signature`` is lower. Each source effect is also added alone
to the target's default twin: an effect that does not lower ``q_signature`` there does not transfer and is
marked so.

The stance kinematics are cross-validated on their own (:func:`kinematics_table`, also across datasets): the
``stance_kinematics`` factor is fitted to each source's default twin by the loop's own fit (whether or not the
loop named it there) and applied to the target's default twin. Old defaults = the simulator's stance rates
(factor 1, the target's default twin); new = the rates times the source's factor. Both are scored on the
target's Fig. 5 residuals (``q_fig5``, :func:`fig5_prediction_error`: sum over :data:`gaitsim.loop.fig5.NUMBERS`
of the squared error in units of the recording's own uncertainty) and ``q_signature``;
the factor fitted on the target itself is given for comparison, not used.
"""

from __future__ import annotations

import math

from nav.recording import RecordingError

from . import attribution as att
from . import effects as fx
from . import fig5, residuals
from . import twin as tw


def nav_discrepancy(res: dict) -> dict:
    """Navigation metric -> |twin - recording| (the metric's unit)."""
    return {name: abs(r.value) for name, r in res.items() if name.startswith("nav_")}


def accepted_effects(result: att.LoopResult) -> list[tuple[str, float]]:
    """(effect name, fitted magnitude) of every effect the loop added to ``result``'s twin, in order."""
    return [(a["effect"], a["magnitude"]) for a in result.attributions if a["effect"] != "unexplained"]


def score(target: att.LoopResult, twin: tw.Twin, simulate: tw.TwinSimulator) -> dict:
    """``q_signature`` and ``nav_discrepancy`` of ``twin`` against the target recording."""
    side = att.simulate_side(simulate, twin, target.measured, True)
    res = att.compare(target.measured, side, target.noise)
    return {"q_signature": residuals.signature_misfit(res), "nav_discrepancy": nav_discrepancy(res),
            **fig5_prediction_error(target, res)}


def fig5_prediction_error(target: att.LoopResult, res: dict) -> dict:
    """``q_fig5``: sum over the Fig. 5 residuals ``res`` of (recording - twin)^2 over the recording's own
    uncertainty squared (its bootstrap standard error and the comparison floor, not the twin's spread: a twin
    whose sweep scatters, e.g. a filter that loses its stances, must not predict better by it), and
    ``fig5``: each residual with that uncertainty (name -> dict)."""
    out = {}
    for name in fig5.NUMBERS:
        if name in res:
            own = math.hypot(target.measured.signature.scalars[name].se, target.noise.get(name, 0.0))
            out[name] = {**res[name].as_dict(), "recording_uncertainty": own, "prediction_z": abs(res[name].value) / own}
    return {"q_fig5": float(sum(v["prediction_z"] ** 2 for v in out.values())), "fig5": out}


def transferred_score(target: att.LoopResult, effects: list[tuple[str, float]], simulate: tw.TwinSimulator) -> dict:
    """:func:`score` of the target's default twin with ``effects`` added (:func:`with_effects`); a twin whose
    simulation shows no regular strides on the way (an effect moved onto a recording it does not fit, e.g. a
    low-pass that smooths the strides away) scores an infinite misfit, with the reason."""
    try:
        return score(target, with_effects(target, effects, simulate), simulate)
    except (ValueError, RecordingError) as exc:
        return {"q_signature": math.inf, "nav_discrepancy": {}, "failed": str(exc)}


def with_effects(target: att.LoopResult, effects: list[tuple[str, float]],
                 simulate: tw.TwinSimulator) -> tw.Twin:
    """The target's default twin with ``effects`` added in order, each in the context of the twin so far and as
    the loop adds it (:func:`gaitsim.loop.twin.with_effect`)."""
    return att.add_effects(target.twin_before, [(fx.BY_NAME[name], magnitude) for name, magnitude in effects],
                           target.measured, simulate)[0]


def predict(source_label: str, source: att.LoopResult, target_label: str, target: att.LoopResult,
            log=lambda message: None) -> dict:
    """The held-out row of (source, target) (module docstring)."""
    simulate = tw.TwinSimulator()
    effects = accepted_effects(source)
    default = score(target, target.twin_before, simulate)
    row = {"source": source_label, "target": target_label, "effects": [name for name, _ in effects],
           "default": default}
    if not effects:
        row.update(transferred=default, better=False, per_effect={})
        return row
    row["transferred"] = transferred_score(target, effects, simulate)
    row["better"] = row["transferred"]["q_signature"] < default["q_signature"]
    row["per_effect"] = {}
    for name, magnitude in effects:
        alone = transferred_score(target, [(name, magnitude)], simulate)
        row["per_effect"][name] = {"magnitude": magnitude, "unit": fx.BY_NAME[name].unit,
                                   "q_signature": alone["q_signature"],
                                   "transfers": alone["q_signature"] < default["q_signature"]}
        log(f"held-out {source_label} -> {target_label}: {name} alone q {alone['q_signature']:.1f} "
            f"(default {default['q_signature']:.1f})")
    return row


def prediction_table(results: dict, log=lambda message: None) -> list[dict]:
    """The held-out rows of every ordered pair of ``results`` (label -> LoopResult) of one dataset."""
    return [predict(a, results[a], b, results[b], log) for a in results for b in results if a != b]


def markdown_rows(dataset: str, rows: list[dict]) -> list[str]:
    """Lines of the held-out table (one per pair) for the results README."""
    out = []
    for r in rows:
        nav_d, nav_t = r["default"]["nav_discrepancy"], r["transferred"]["nav_discrepancy"]
        nav = ", ".join(f"{k}: {nav_d[k]:.4g} -> {nav_t.get(k, math.nan):.4g}" for k in nav_d) or "-"
        effects = ", ".join(f"{name}{'' if e['transfers'] else ' (does not transfer)'}"
                            for name, e in r["per_effect"].items()) or "none named"
        out.append(f"| {dataset} | {r['source']} -> {r['target']} | {effects} | "
                   f"{r['default']['q_signature']:.1f} -> {r['transferred']['q_signature']:.1f} | "
                   f"{'yes' if r['better'] else 'no'} | {nav} |")
    return out


KINEMATICS = "stance_kinematics"
KINEMATICS_NOTE = ("The stance_kinematics factor (1 = the simulator's stance rates, the old defaults) fitted to each "
                   "source recording's default twin, applied to the target's default twin (new defaults) and scored "
                   "on the target's Fig. 5 residuals (q_fig5 = sum of (recording - twin)^2 over the recording's own "
                   "uncertainty squared; lower predicts better).")


def kinematics_factor(result: att.LoopResult, simulate: tw.TwinSimulator) -> dict | None:
    """The ``stance_kinematics`` factor fitted to ``result``'s default twin (:func:`gaitsim.loop.attribution.fit_effect`
    against its residuals before any effect, with its comparison noise), whether it lies on its search bound, and
    whether the loop named the effect there; None where the effect cannot be tried (no Fig. 5 residuals)."""
    effect = fx.BY_NAME[KINEMATICS]
    ctx = fx.context(result.measured.recording, result.twin_before.scenario, result.measured.signature,
                     result.before.signature)
    if not fx.applicable(effect, ctx):
        return None
    fit = att.fit_effect(simulate, effect, result.twin_before, result.measured, result.residuals_before, ctx,
                         result.noise)
    return {"factor": fit.magnitude, "at_search_bound": fit.at_bound,
            "named_by_the_loop": KINEMATICS in dict(accepted_effects(result))}


def kinematics_table(results: dict, pairs=None, log=lambda message: None) -> list[dict]:
    """The stance-kinematics cross-validation (module docstring) of every ordered pair of ``results`` (label ->
    LoopResult), or of the (source, target) label ``pairs`` given; pairs whose source or target has no Fig. 5
    residuals are left out."""
    simulate = tw.TwinSimulator()
    pairs = [(a, b) for a in results for b in results if a != b] if pairs is None else pairs
    factors = {label: kinematics_factor(results[label], simulate) for label in {x for pair in pairs for x in pair}}
    pairs = [(a, b) for a, b in pairs if factors[a] is not None and factors[b] is not None]
    old_scores = {b: score(results[b], results[b].twin_before, simulate) for b in {b for _, b in pairs}}
    rows = []
    for source, target in pairs:
        factor, old = factors[source]["factor"], old_scores[target]
        new = transferred_score(results[target], [(KINEMATICS, factor)], simulate)
        rows.append({"source": source, "target": target, "source_factor": factors[source],
                     "target_own_factor": factors[target], "old_defaults": old, "new_defaults": new,
                     "better": new["q_fig5"] < old["q_fig5"]})
        log(f"stance kinematics {source} -> {target}: factor {factor:.3g}, q_fig5 {old['q_fig5']:.1f} -> "
            f"{new['q_fig5']:.1f}")
    return rows


def kinematics_markdown_rows(rows: list[dict]) -> list[str]:
    """Lines of the stance-kinematics cross-validation table (one per pair) for the results README."""
    out = []
    for r in rows:
        source, own = r["source_factor"], r["target_own_factor"]
        errors = ", ".join(f"{name}: {r['old_defaults']['fig5'][name]['value']:.3g} -> "
                           f"{r['new_defaults']['fig5'].get(name, {}).get('value', math.nan):.3g}"
                           for name in fig5.NUMBERS if name in r["old_defaults"]["fig5"])
        out.append(f"| {r['source']} -> {r['target']} | {source['factor']:.3g}"
                   f"{' (on its bound)' if source['at_search_bound'] else ''} | {own['factor']:.3g} | "
                   f"{r['old_defaults']['q_fig5']:.1f} -> {r['new_defaults']['q_fig5']:.1f} | "
                   f"{'yes' if r['better'] else 'no'} | {errors} |")
    return out


KINEMATICS_HEADER = ["| effects of -> applied to | factor fitted on the source | target's own factor | q_fig5 old -> "
                     "new defaults | better | Fig. 5 residual (recording - twin) old -> new defaults |",
                     "|---|---|---|---|---|---|"]
