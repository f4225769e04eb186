"""Figures, summary and README of ``gaitsim stance`` (:mod:`gaitsim.stance.command`)."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

CURVES = (("underestimate_pct", "length underestimate (%)", 1.0),
          ("in_window_velocity_mps", "in-window site velocity (mm/s)", 1000.0),
          ("window_s", "detected window (s)", 1.0))
PROFILE_PANELS = (("rate_dps", "|angular rate| (deg/s)", 1.0), ("sagittal_rate_dps", "sagittal rate (deg/s)", 1.0),
                  ("forward_velocity_mps", "forward velocity (mm/s)", 1000.0),
                  ("vertical_velocity_mps", "vertical velocity (mm/s)", 1000.0))


def figures(result: dict, folder: Path, title: str) -> None:
    """``fig5.png`` (real and twin against the threshold, real with its bootstrap standard deviation) and
    ``profiles.png`` (foot-flat profiles, real and twin) of one recording's study."""
    fig, axes = plt.subplots(1, 3, figsize=(14, 4))
    for ax, (name, label, scale) in zip(axes, CURVES):
        for side, style in (("real", "o-"), ("twin", "s--")):
            curve = result[side][name]
            ax.errorbar(result[side]["thresholds"], np.asarray(curve["value"]) * scale,
                        yerr=np.asarray(curve["sd"]) * scale, fmt=style, capsize=3, label=side)
        ax.set_xticks(result["real"]["thresholds"], [f"{t:.0e}" for t in result["real"]["thresholds"]])
        ax.set_xlabel("SHOE threshold")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    real = result["real"]["underestimate_track_pseudo_pct"]
    axes[0].plot(result["real"]["thresholds"], real["value"], "o:", color="grey",
                 label="real, true in-window velocity as pseudo-measurement")
    axes[0].legend(fontsize=8)
    fig.suptitle(f"{title}: Fig. 5 on the measured foot and its twin")
    fig.tight_layout()
    fig.savefig(folder / "fig5.png", dpi=90)
    plt.close(fig)

    fig, axes = plt.subplots(1, 4, figsize=(16, 3.8))
    for ax, (name, label, scale) in zip(axes, PROFILE_PANELS):
        for side, style in (("real", "-"), ("twin", "--")):
            prof = result["profiles"][side]
            ax.plot(prof["phase"], np.asarray(prof["median"][name]) * scale, style, label=side)
        ax.axvspan(0.0, 1.0, color="0.92", zorder=0)
        ax.set_xlabel("foot-flat phase (0 forefoot contact, 1 heel off)")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].set_yscale("log")
    axes[0].legend(fontsize=8)
    fig.suptitle(f"{title}: foot-flat profiles (median over strides)")
    fig.tight_layout()
    fig.savefig(folder / "profiles.png", dpi=90)
    plt.close(fig)


def summary(results: dict) -> dict:
    """Per recording: the comparison and how many bounds hold."""
    out = {}
    for key, result in results.items():
        comparison = result["comparison"]
        held = {name: sum(row["within"] for row in comparison[name])
                for name in ("underestimate_pct", "in_window_velocity_mps", "window_s")}
        out[key] = {"comparison": comparison, "thresholds_within": held,
                    "slope_within": comparison["slope"]["within"], "strides": result["real"]["strides"]}
    return out


def _fmt(x: float, digits: int = 2) -> str:
    return "-" if x is None or not math.isfinite(x) else f"{x:.{digits}f}"


def _curve_table(results: dict, name: str, scale: float, unit: str, digits: int) -> list[str]:
    thresholds = next(iter(results.values()))["real"]["thresholds"]
    lines = ["| recording | " + " | ".join(f"{t:.0e}" for t in thresholds) + " |",
             "|---|" + "---|" * len(thresholds)]
    for key, result in results.items():
        cells = []
        for row in result["comparison"][name]:
            mark = "" if row["within"] else " **x**"
            star = "*" if row["bound_is_real_sd"] else ""
            cells.append(f"{_fmt(row['real'] * scale, digits)} ± {_fmt(row['real_sd'] * scale, digits)} / "
                         f"{_fmt(row['twin'] * scale, digits)} (bound {_fmt(row['bound'] * scale, digits)}{star}){mark}")
        lines.append(f"| {key} | " + " | ".join(cells) + " |")
    return [f"**{name}** ({unit}): real ± bootstrap sd / twin (bound; * = the real curve's sd is the bound; "
            "**x** = outside)", "", *lines, ""]


def _path_table(results: dict) -> list[str]:
    """The twin's underestimate along its path to the real one: exact increments of an ideal sensor, its point
    samples integrated (RK4), and a sensor of the recording's class (the compared twin), next to the real."""
    thresholds = next(iter(results.values()))["real"]["thresholds"]
    lines = ["", "**the twin's path**: length underestimate (%) of one twin truth navigated from the ideal sensor's "
             "exact increments / the ideal sensor's point samples (RK4) / the sensor of the recording's class "
             "(RK4, the compared twin) || the real recording", "",
             "| recording | " + " | ".join(f"{t:.0e}" for t in thresholds) + " |", "|---|" + "---|" * len(thresholds)]
    for key, result in results.items():
        columns = zip(*(result[name]["underestimate_pct"]["value"] for name in ("twin_exact", "twin_sampled", "twin",
                                                                                 "real")))
        lines.append(f"| {key} | " + " | ".join(f"{_fmt(e)} / {_fmt(p)} / {_fmt(s)} &#124;&#124; {_fmt(r)}"
                                                 for e, p, s, r in columns) + " |")
    return lines


def readme(results: dict, fitted: dict | None, args) -> str:
    """The README of the results folder: what was run and the tables."""
    datasets = " ".join(args.datasets)
    lines = ["# Real feet in stance: Fig. 5 on measured recordings and their twins", "",
             f"Regenerate with `gaitsim stance {datasets} --out DIR{' --fit' if fitted else ''}` "
             f"(bootstrap {args.bootstrap}).", "",
             "Filter: SHOE, sigma_a 0.01 m/s^2, sigma_g 0.07 deg/s, window 3 samples, 9 states. Like with like: "
             "the real recording and its twin (default stance model, the recording's gait, rate and IMU site, "
             "a sensor of the recording's class) are both integrated from point samples (RK4). Length "
             "underestimate = 1 - sum of estimated over sum of reference distances between consecutive "
             "detected-stance middles.", ""]
    lines += _curve_table(results, "underestimate_pct", 1.0, "%", 2)
    lines += _curve_table(results, "in_window_velocity_mps", 1000.0, "mm/s", 1)
    lines += _curve_table(results, "window_s", 1.0, "s", 3)
    lines += ["**slope** of the underestimate (5e4 minus 1e4, percentage points): real ± sd / twin (bound)", "",
              "| recording | real | twin | bound | same sign | within |", "|---|---|---|---|---|---|"]
    for key, result in results.items():
        s = result["comparison"]["slope"]
        lines.append(f"| {key} | {_fmt(s['real'])} ± {_fmt(s['real_sd'])} | {_fmt(s['twin'])} | "
                     f"{_fmt(s['bound'])}{'*' if s['bound_is_real_sd'] else ''} | {s['same_sign']} | {s['within']} |")
    lines += ["", "**stance-velocity share** of the real underestimate (percentage points): the real recording "
              "navigated again with its reference's own velocity as the stance pseudo-measurement removes the "
              "share the foot's in-window motion causes; the rest is not the foot's.", "",
              "| recording | " + " | ".join(f"{t:.0e}" for t in next(iter(results.values()))["real"]["thresholds"])
              + " |", "|---|" + "---|" * 5]
    for key, result in results.items():
        total, share = result["real"]["underestimate_pct"], result["real"]["stance_velocity_share_pct"]
        twin_share = result["twin"]["stance_velocity_share_pct"]
        cells = [f"{_fmt(t)} = {_fmt(s)} ± {_fmt(sd)} + {_fmt(t - s)} (twin share {_fmt(ts)})"
                 for t, s, sd, ts in zip(total["value"], share["value"], share["sd"], twin_share["value"])]
        lines.append(f"| {key} | " + " | ".join(cells) + " |")
    lines += _path_table(results)
    lines += ["", "Per recording: `<dataset>/<recording>/fig5.png`, `profiles.png`, `fig5.json` (gait, twin "
              "scenario, both sweeps with bootstrap, profiles, comparison).", ""]
    if fitted:
        joint = fitted["joint"]
        lines += ["## Fit of the stance model (fit.json)", "",
                  "| parameter | fitted (all recordings) | " + " | ".join(fitted["folds"]) + " |",
                  "|---|---|" + "---|" * len(fitted["folds"])]
        for key, value in joint["values"].items():
            lines.append(f"| {key} | {value:.4g} | " + " | ".join(f"{f['values'][key]:.4g}"
                                                                   for f in fitted["folds"].values()) + " |")
        lines += ["", "Profile rms residual (in tolerances, module gaitsim.stance.fit) of each model on each "
                  "recording; held-out recordings are the ones a fold was not fitted to:", "",
                  "| recording | joint | " + " | ".join(fitted["folds"]) + " |",
                  "|---|---|" + "---|" * len(fitted["folds"])]
        for name, value in joint["rms_residual_fit"].items():
            cells = []
            for fold in fitted["folds"].values():
                mark = "" if name in fold["train"] else " (held out)"
                cells.append(f"{fold['rms'][name]:.2f}{mark}")
            lines.append(f"| {name} | {value:.2f} | " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines)
