"""Write one loop result: ``attribution.json``, ``report.md``, ``twin.toml`` and figures (``*.png``) into a folder.

``attribution.json`` holds, per residual acted on, the effect named (or ``"unexplained"``), the scenario key,
the fitted magnitude and unit, the residual before and after with uncertainties, whether it is at the noise
level after, the fraction explained, the candidates that fit as well (``equivalent``) and every candidate tried;
then the predicted-versus-measured navigation metrics before and after, the Fig. 5 residuals before and after
(or why the recording has none; :func:`gaitsim.loop.fig5.summary`), all residuals before and after, and the fitted twin (its scenario document, which a
user can save as TOML and simulate). ``twin.toml`` is the twin after all accepted effects as a scenario file
(``gaitsim generate twin.toml --out DIR`` simulates it).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from nav.files import jsonable, write_json  # noqa: E402

from ..numbers import shown  # noqa: E402
from . import attribution as att  # noqa: E402
from . import fig5, settings  # noqa: E402
from .residuals import profile_fit  # noqa: E402
from .twin_file import write_twin_toml  # noqa: E402
from .signature import CHANNELS  # noqa: E402


def attribution_document(result: att.LoopResult, label: str) -> dict:
    """The content of ``attribution.json`` (module docstring)."""
    return jsonable({
        "recording": label,
        "noise_level": f"|residual| <= {settings.NOISE_LEVEL} x uncertainty",
        "reference": {"kind": result.measured.reference.kind, "distance_m": result.measured.reference.distance_m,
                      "what_is_compared": result.measured.reference.describe()},
        "sensor_frame": {"axes": result.measured.recording.meta.get("axes", "x,y,z"),
                         "numbers": result.frame.numbers if result.frame is not None else None},
        "explained_threshold": settings.EXPLAINED_FRACTION,
        "attributions": result.attributions,
        "navigation": result.navigation_summary(),
        "fig5": fig5.summary(result.residuals_before, result.residuals_after, result.measured.reference.kind),
        "comparison_noise": result.noise,
        "residuals_before": {k: r.as_dict() for k, r in result.residuals_before.items()},
        "residuals_after": {k: r.as_dict() for k, r in result.residuals_after.items()},
        "effect_context": result.context,
        "profile_fit_before": profile_fit(result.measured.signature, result.before.signature),
        "profile_fit_after": profile_fit(result.measured.signature, result.after.signature),
        "twin_before": {"scenario": result.twin_before.document(), "fit_notes": result.twin_before.notes},
        "twin_after": {"scenario": result.twin_after.document()},
    })


def _figures(result: att.LoopResult, folder: Path) -> list[str]:
    names = []
    phase = np.linspace(0, 100, len(result.measured.signature.profiles[CHANNELS[0]].mean), endpoint=False)
    fig, axes = plt.subplots(2, 3, figsize=(13, 6.5), sharex=True)
    for ax, c in zip(axes.ravel(), CHANNELS):
        for side, label, style in ((result.measured, "recording", "k-"), (result.before, "twin before", "C0--"),
                                   (result.after, "twin after", "C3-")):
            p = side.signature.profiles[c]
            ax.plot(phase, p.mean, style, lw=1.2, label=label)
            if side is result.measured:
                ax.fill_between(phase, p.mean - 2 * p.se, p.mean + 2 * p.se, color="0.8")
        ax.set_title(c + (" (m/s^2)" if c.startswith("acc") else " (deg/s)"))
        ax.set_xlabel("gait phase from stance onset (%)")
    axes[0, 0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(folder / "profiles.png", dpi=90)
    plt.close(fig)
    names.append("profiles.png")

    fig, ax = plt.subplots(figsize=(7, 4))
    for side, label, style in ((result.measured, "recording", "k-"), (result.before, "twin before", "C0--"),
                               (result.after, "twin after", "C3-")):
        f, p = side.signature.spectrum
        ax.semilogy(f[1:], np.maximum(p[1:], 1e-12), style, lw=1, label=label)
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("share of |a| power per bin")
    ax.legend()
    fig.tight_layout()
    fig.savefig(folder / "spectrum.png", dpi=90)
    plt.close(fig)
    names.append("spectrum.png")

    keys = sorted(result.residuals_before, key=lambda k: -np.nan_to_num(result.residuals_before[k].z))
    z_before = [np.nan_to_num(result.residuals_before[k].z) for k in keys]
    z_after = [np.nan_to_num(result.residuals_after[k].z) if k in result.residuals_after else 0.0 for k in keys]
    fig, ax = plt.subplots(figsize=(8, 0.28 * len(keys) + 1.2))
    y = np.arange(len(keys))
    ax.barh(y + 0.2, z_before, 0.4, label="before", color="C0")
    ax.barh(y - 0.2, z_after, 0.4, label="after", color="C3")
    ax.axvline(settings.NOISE_LEVEL, color="k", ls=":", lw=1)
    ax.set_yticks(y, keys, fontsize=8)
    ax.set_xscale("symlog", linthresh=1)
    ax.invert_yaxis()
    ax.set_xlabel("|residual| / uncertainty")
    ax.legend()
    fig.tight_layout()
    fig.savefig(folder / "residuals.png", dpi=90)
    plt.close(fig)
    names.append("residuals.png")
    return names


def markdown(result: att.LoopResult, label: str, figures: list[str]) -> str:
    """The human report of one loop result."""
    kind = result.twin_before.notes.get("gait_kind", {})
    gait = (f"a {kind['kind'].replace('-', ', ')} strike" if kind.get("kind", "walk") != "walk" else "a walk") + (
        f" ({kind['speed_mps']:.2f} m/s; a run from {kind['walk_run_speed_mps']:g} m/s)" if kind else "")
    lines = [f"# Sim-to-real loop: {label}", "",
             f"Twin: {gait}; {result.twin_before.notes.get('path', '')}; track from the "
             f"{result.twin_before.notes.get('track', '')}. Residual = recording - twin; z = |residual| / "
             f"uncertainty; at the noise level when z <= {settings.NOISE_LEVEL}. An effect is named when it "
             f"explains at least {settings.EXPLAINED_FRACTION:.0%} of the residual acted on and lowers the total misfit.", "",
             "## Attribution", "",
             "| residual | z before | effect | magnitude | before | after | uncertainty after | explained |",
             "|---|---|---|---|---|---|---|---|"]
    for a in result.attributions:
        mag = f"{shown(a['magnitude'])} {a['magnitude_unit']}" if a["magnitude"] is not None else "-"
        best = a.get("best_candidate") or {}
        effect = a["effect"] if a["effect"] != "unexplained" else (
            f"unexplained (best: {best.get('effect', '-')}, {best.get('fraction_explained', 0):.0%})")
        if a.get("joint_with"):
            effect += f" (fitted together with {', '.join(a['joint_with'])})"
        if a.get("equivalent"):
            alternatives = ", ".join(f"{e['effect']} {shown(e['magnitude'])} {e['unit']}" for e in a["equivalent"])
            effect += f" (as good: {alternatives})"
        lines.append(f"| {a['residual']} ({a['unit']}) | {shown(a['z_before'], '.3g')} | {effect} | {mag} | "
                     f"{shown(a['residual_before'])} | {shown(a['residual_after'])} | {shown(a['uncertainty_after'])} | "
                     f"{a['fraction_explained']:.0%} |")
    if not result.attributions:
        lines.append("| (no residual above the noise level) | | | | | | | |")
    lines += ["", "## Navigation: predicted (twin) versus measured", "",
              f"Reference: {result.measured.reference.describe()}.", "",
              "| metric | measured | twin before | twin after | discrepancy before | discrepancy after |",
              "|---|---|---|---|---|---|"]
    for key, v in result.navigation_summary().items():
        lines.append(f"| {key} ({v['unit']}) | {shown(v['measured'])} | {shown(v['twin_before'])} | "
                     f"{shown(v['twin_after'])} | {shown(v['discrepancy_before'])} | {shown(v['discrepancy_after'])} |")
    lines += ["", "## Fig. 5: length underestimate and in-window velocity over the zero-velocity thresholds", ""]
    figure5 = fig5.summary(result.residuals_before, result.residuals_after, result.measured.reference.kind)
    if "absent_because" in figure5:
        lines.append(f"Absent: {figure5['absent_because']}.")
    else:
        lines += ["Recording against its reference, twin against its true track at the IMU site, both swept by "
                  "`gaitsim.stance.sweep` (level = mean over the thresholds, slope = largest minus smallest).", "",
                  "| residual | unit | recording | twin before | z before | twin after | z after |",
                  "|---|---|---|---|---|---|---|"]
        for key, v in figure5["residuals"].items():
            lines.append(f"| {key} | {v['unit']} | {shown(v['recording'])} | {shown(v['twin_before'])} | "
                         f"{shown(v['z_before'], '.3g')} | {shown(v['twin_after'])} | {shown(v['z_after'], '.3g')} |")
    lines += ["", f"## Phase profiles: twin within {settings.PROFILE_SPREAD_FACTOR:g}x the recording's "
              "stride-to-stride spread?", "", "| channel | share of phases within | largest ratio | phases beyond (% of "
              "stride) |", "|---|---|---|---|"]
    for channel, fit in profile_fit(result.measured.signature, result.after.signature).items():
        runs = ", ".join(f"{a:.0f}-{b:.0f}" for a, b in fit["phases_beyond_pct"]) or "none"
        lines.append(f"| {channel} | {fit['within_share']:.0%} | {fit['largest_ratio']:.3g} | {runs} |")
    lines += ["", "## All residuals", "", "| residual | unit | recording | twin before | residual before | z before "
              "| twin after | residual after | z after |", "|---|---|---|---|---|---|---|---|---|"]
    for key in sorted(result.residuals_before, key=lambda k: -np.nan_to_num(result.residuals_before[k].z)):
        b = result.residuals_before[key]
        a = result.residuals_after.get(key)
        lines.append(f"| {key} | {b.unit} | {shown(b.measured)} | {shown(b.twin)} | {shown(b.value)} | {shown(b.z, '.3g')} | "
                     f"{shown(a.twin) if a else '-'} | {shown(a.value) if a else '-'} | {shown(a.z, '.3g') if a else '-'} |")
    lines += ["", "## Figures", ""] + [f"![{name}]({name})" for name in figures] + [""]
    return "\n".join(lines)


def write_result(result: att.LoopResult, folder: Path, label: str) -> dict:
    """Write attribution.json, report.md and the figures into ``folder`` (which must exist); returns the
    attribution document."""
    doc = attribution_document(result, label)
    write_json(folder / "attribution.json", doc)
    figures = _figures(result, folder)
    (folder / "report.md").write_text(markdown(result, label, figures))
    write_twin_toml(result.twin_after.scenario, folder / "twin.toml",
                    f"Digital twin of {label} fitted by `gaitsim loop`, with the effects it named:\n"
                    + "\n".join(f"  {a['effect']} = {a['magnitude']:.4g} {a['magnitude_unit']} ({a['scenario_key']})"
                                 for a in result.attributions if a["effect"] != "unexplained")
                    + "\nSimulate it with `gaitsim generate twin.toml --out DIR`.")
    return doc
