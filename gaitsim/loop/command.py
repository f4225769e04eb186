"""``gaitsim loop DATASET --out DIR``: the sim-to-real loop on a measured dataset or any recording folder.

DATASET is a shared dataset name (``gaitmap-healthy``, ``ucr-fgo``, ``xio-ngimu``; each recording of it gets
its own sub-folder), ``blind`` (the blind-test table of :mod:`gaitsim.loop.blind`), ``all`` (the three datasets
and ``blind``, one sub-folder each: ``gaitsim loop all --out results/loop`` regenerates the committed results),
or a recording folder (or a folder of ``run-NNN`` recordings). Every recording's folder gets ``report.md``,
``attribution.json`` and figures; DIR gets a ``README.md`` summary. Written atomically: nothing appears at DIR
if anything fails.
"""

from __future__ import annotations

import time
import warnings
from pathlib import Path

from nav.files import atomic_output_dir, write_json
from nav.recording import RecordingError, list_runs, read_recording

from ..measured import load_dataset
from ..numbers import shown
from . import attribution, blind, report, settings

DATASETS = ("gaitmap-healthy", "ucr-fgo", "xio-ngimu")
CHOICES = DATASETS + ("blind", "all")


def add_parser(subparsers) -> None:
    """Register the ``loop`` subcommand on an argparse subparsers object."""
    p = subparsers.add_parser("loop", help="close the loop between a recording and its simulated twin",
                              description=__doc__)
    p.add_argument("dataset", help=f"one of {', '.join(CHOICES)}, or a recording folder")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--rounds", type=int, default=settings.MAX_ROUNDS,
                   help=f"largest number of residuals acted on per recording (default {settings.MAX_ROUNDS})")
    p.add_argument("--data", default=None, help="folder holding the shared datasets (default: $GAITSIM_DATA or "
                                                "../shared/data)")
    p.add_argument("--force", action="store_true", help="replace an existing output folder")
    p.set_defaults(func=run)


def _recordings(dataset: str, data_root) -> list[tuple[str, object]]:
    if dataset in DATASETS:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the loaders' data-quality warnings are in each recording's meta
            recs = load_dataset(dataset, data_root)
        return [(str(r.meta.get("recording", i)), r) for i, r in enumerate(recs)]
    folder = Path(dataset)
    if not folder.is_dir():
        raise RecordingError(f"loop: {dataset!r} is neither a dataset ({', '.join(CHOICES)}) nor a recording folder")
    runs = list_runs(folder)
    return [(p.name if len(runs) > 1 else "recording", read_recording(p)) for p in runs]


def _summary_line(label: str, doc: dict) -> str:
    effects = ", ".join(f"{a['residual']} -> {a['effect']}" + (f" {a['magnitude']:.4g} {a['magnitude_unit']}"
                                                                if a["magnitude"] is not None else "")
                        for a in doc["attributions"]) or "no residual above the noise level"
    nav = doc["navigation"].get("nav_length_ratio") or doc["navigation"].get("nav_final_error") or {}
    name = "length ratio" if "nav_length_ratio" in doc["navigation"] else "final error (m)"
    return (f"| {label} | {effects} | {name}: {shown(nav.get('measured'))} | "
            f"{shown(nav.get('discrepancy_before'))} -> {shown(nav.get('discrepancy_after'))} |")


def _run_recordings(dataset: str, folder: Path, rounds: int, data_root) -> list[str]:
    lines = []
    for label, rec in _recordings(dataset, data_root):
        started = time.time()
        sub = folder / label
        sub.mkdir(parents=True)
        try:
            result = attribution.run_loop(rec, max_rounds=rounds, log=lambda m, lab=label: print(f"  [{lab}] {m}"))
        except (ValueError, RecordingError) as exc:  # one unusable recording must not stop the others
            (sub / "report.md").write_text(f"# Sim-to-real loop: {dataset} / {label}\n\nThe loop could not run: {exc}\n")
            lines.append(f"| [{label}]({label}/report.md) | loop failed: {exc} | | |")
            print(f"{dataset} {label}: FAILED: {exc}")
            continue
        doc = report.write_result(result, sub, f"{dataset} / {label}")
        lines.append(_summary_line(f"[{label}]({label}/report.md)", doc))
        print(f"{dataset} {label}: done in {time.time() - started:.1f} s")
    return lines


def _run_blind(folder: Path) -> list[str]:
    rows = []
    for case in blind.CASES:
        result = blind.run_case(case)
        rows += blind.table_rows(case, result)
        print(f"blind {case.name}: {[a['effect'] for a in result.attributions]}")
    write_json(folder / "blind.json", rows)
    lines = ["# Blind tests", "", blind.__doc__.strip(), "",
             "| case | true effect | true magnitude | found | fitted | residual | before | after (uncertainty) | "
             "nav final-error discrepancy before -> after (m) |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['case']} | {r['true_effect']} | {shown(r['true_magnitude'])} {r['unit']} | "
                     f"{r['found_effect']} | {shown(r['fitted_magnitude'])} | {r['residual']} | "
                     f"{shown(r['residual_before'])} | {shown(r['residual_after'])} ({shown(r['uncertainty_after'])}) | "
                     f"{shown(r['nav_final_error_discrepancy_before_m'])} -> "
                     f"{shown(r['nav_final_error_discrepancy_after_m'])} |")
    (folder / "blind.md").write_text("\n".join(lines) + "\n")
    return [f"| [blind tests](blind.md) | {len(blind.CASES)} cases | | |"]


def run(args) -> int:
    """Run the loop as the command line asked; returns the exit code."""
    if args.rounds < 1:
        raise ValueError(f"--rounds {args.rounds}: must be >= 1")
    targets = list(DATASETS) + ["blind"] if args.dataset == "all" else [args.dataset]
    with atomic_output_dir(args.out, overwrite=args.force) as tmp:
        lines = ["# Sim-to-real loop results", "", f"Regenerate with `gaitsim loop {args.dataset} --out DIR`.", "",
                 "| recording | residual -> effect (fitted) | navigation metric (measured) | "
                 "predicted-vs-measured discrepancy before -> after |", "|---|---|---|---|"]
        for target in targets:
            folder = tmp / target if len(targets) > 1 else tmp
            folder.mkdir(parents=True, exist_ok=True)
            prefix = f"{target}/" if len(targets) > 1 else ""
            found = _run_blind(folder) if target == "blind" else _run_recordings(target, folder, args.rounds, args.data)
            lines += [line.replace("](", f"]({prefix}", 1) for line in found]
        (tmp / "README.md").write_text("\n".join(lines) + "\n")
    print(f"written to {args.out}")
    return 0
