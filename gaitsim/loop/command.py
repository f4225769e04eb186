"""``gaitsim loop DATASET --out DIR``: the sim-to-real loop on a measured dataset or any recording folder.

DATASET is a shared dataset name (``gaitmap-healthy``, ``ucr-fgo``, ``xio-ngimu``; each recording of it gets
its own sub-folder), ``blind`` (the blind-test table of :mod:`gaitsim.loop.blind`), ``all`` (the three datasets
and ``blind``, one sub-folder each: ``gaitsim loop all --out results/loop`` regenerates the committed results),
or a recording folder (or a folder of ``run-NNN`` recordings) with whatever reference it has: a
``reference.csv`` track, start and end only (a loop closure), a walked distance (``--distance M``), or none
(signatures only). ``--axes y,-x,z`` maps the sensor axes into the body frame first (body x = sensor y, ...);
a recording whose frame is not x toes, y left, z up is refused with the map to use.

Every recording's folder gets ``report.md``, ``attribution.json``, ``twin.toml`` (the fitted twin, which
``gaitsim generate`` runs) and figures; DIR gets a ``README.md`` summary. A dataset of several recordings also
gets the held-out prediction (:mod:`gaitsim.loop.transfer`): ``held_out.json`` and a table in the summary;
recordings with a position track get the stance-kinematics cross-validation, within a dataset and from
gaitmap-healthy onto ucr-fgo (:data:`CROSS_DATASET`): ``held_out_kinematics.json`` and a table. A
recording the loop cannot use is a failure: its folder holds a ``report.md`` saying why, the summary lists it,
the other recordings go on, and the command exits 1. Written atomically: nothing appears at DIR when every recording failed.
"""

from __future__ import annotations

import time
import warnings
from pathlib import Path

from nav.files import atomic_output_dir, write_json
from nav.recording import RecordingError, list_runs, read_recording

from ..experiments.runner import process_pool
from ..measured import load_dataset
from ..measured.axes import parse_axis_map
from ..numbers import shown
from . import attribution, blind, report, settings, transfer

DATASETS = ("gaitmap-healthy", "ucr-fgo", "xio-ngimu")
# (source dataset, target dataset): the stance kinematics fitted on the first are also scored on the second
CROSS_DATASET = (("gaitmap-healthy", "ucr-fgo"),)
CHOICES = DATASETS + ("blind", "all")


def add_parser(subparsers) -> None:
    """Register the ``loop`` subcommand on an argparse subparsers object."""
    p = subparsers.add_parser("loop", help="close the loop between a recording and its simulated twin",
                              description=__doc__)
    p.add_argument("dataset", help=f"one of {', '.join(CHOICES)}, or a recording folder")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--max-effects", type=int, default=settings.MAX_EFFECTS,
                   help="largest number of effects added to a recording's twin; every significant residual is "
                        f"acted on until then, 0 reports the residuals alone (default {settings.MAX_EFFECTS})")
    p.add_argument("--data", default=None, help="folder holding the shared datasets (default: $GAITSIM_DATA or "
                                                "../shared/data)")
    p.add_argument("--axes", default=None, help="sensor axes as body x,y,z, e.g. 'y,-x,z' (default: as recorded)")
    p.add_argument("--distance", type=float, default=None, metavar="M",
                   help="walked distance (m) of a recording folder, compared with the navigated length")
    p.add_argument("--force", action="store_true", help="replace an existing output folder")
    p.add_argument("--jobs", type=int, default=1,
                   help="processes: the datasets of 'all' run side by side in this many, one dataset or recording "
                        "folder runs each recording's independent simulations on this many (default 1; results "
                        "do not depend on it)")
    p.set_defaults(func=run)


def _recordings(dataset: str, data_root) -> list[tuple[str, object]]:
    """(label, reader) per recording of ``dataset``; a reader returns the Recording (a folder's recordings are
    read one by one, so that one unreadable run fails alone)."""
    if dataset in DATASETS:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the loaders' data-quality warnings are in each recording's meta
            recs = load_dataset(dataset, data_root)
        return [(str(r.meta.get("recording", i)), lambda r=r: r) for i, r in enumerate(recs)]
    runs = list_runs(Path(dataset))
    return [(p.name if len(runs) > 1 else "recording", lambda p=p: read_recording(p)) for p in runs]


def _summary_line(label: str, doc: dict) -> str:
    effects = ", ".join(f"{a['residual']} -> {a['effect']}" + (f" {a['magnitude']:.4g} {a['magnitude_unit']}"
                                                                if a["magnitude"] is not None else "")
                        for a in doc["attributions"]) or "no residual above the noise level"
    if not doc["navigation"]:
        return f"| {label} | {effects} | no reference: signatures only | |"
    nav = doc["navigation"].get("nav_length_ratio") or doc["navigation"].get("nav_final_error") or {}
    name = "length ratio" if "nav_length_ratio" in doc["navigation"] else "final error (m)"
    return (f"| {label} | {effects} | {name}: {shown(nav.get('measured'))} | "
            f"{shown(nav.get('discrepancy_before'))} -> {shown(nav.get('discrepancy_after'))} |")


def _failure_report(title: str, exc: Exception) -> str:
    kind = "input error" if isinstance(exc, ValueError) else f"internal error ({type(exc).__name__})"
    return f"# Sim-to-real loop: {title}\n\nThe loop could not run ({kind}): {exc}\n"


def _run_recordings(dataset: str, folder: Path, args, workers: int) -> tuple[list[str], list[str], dict]:
    """Run the loop on every recording of ``dataset`` (each on ``workers`` processes); returns the summary lines,
    the failures and the results (label -> LoopResult) of the recordings that succeeded."""
    lines, failures, results = [], [], {}
    try:
        recordings = _recordings(dataset, args.data)
    except (ValueError, OSError) as exc:
        return [f"| {dataset} | could not be read: {exc} | | |"], [f"{dataset}: {exc}"], results
    for label, read in recordings:
        started = time.time()
        sub = folder / label
        sub.mkdir(parents=True)
        try:
            result = attribution.run_loop(read(), max_effects=args.max_effects, axis_map=args.axes,
                                          distance_m=args.distance, workers=workers,
                                          log=lambda m, lab=label: print(f"  [{dataset}/{lab}] {m}", flush=True))
            doc = report.write_result(result, sub, f"{dataset} / {label}")
        except Exception as exc:  # noqa: BLE001 -- any failure of one recording is reported, the others go on
            (sub / "report.md").write_text(_failure_report(f"{dataset} / {label}", exc))
            lines.append(f"| [{label}]({label}/report.md) | FAILED: {exc} | | |")
            failures.append(f"{dataset} / {label}: {exc}")
            print(f"{dataset} {label}: FAILED: {exc}", flush=True)
            continue
        results[label] = result
        lines.append(_summary_line(f"[{label}]({label}/report.md)", doc))
        print(f"{dataset} {label}: done in {time.time() - started:.1f} s", flush=True)
    return lines, failures, results


def _run_held_out(dataset: str, folder: Path, results: dict) -> list[str]:
    """The held-out prediction rows (:mod:`gaitsim.loop.transfer`) of ``dataset`` into ``folder``/held_out.json;
    returns the README table lines."""
    rows = transfer.prediction_table(results, log=lambda m: print(f"  [{dataset}] {m}", flush=True))
    write_json(folder / "held_out.json", rows)
    return transfer.markdown_rows(dataset, rows)


FOUND_AS = {"named": "yes", "unexplained": "yes", "equivalent": "as good as the effect named", None: "no"}


def _run_blind(folder: Path) -> list[str]:
    """The blind table (:mod:`gaitsim.loop.blind`) of every simulated sensor, run and measured recording into
    ``folder``/blind.md and blind.json."""
    rows, summary = [], []
    for source in blind.SENSORS + tuple(blind.RUNS) + blind.MEASURED:
        untouched = blind.run(source, None)
        print(f"blind {source} untouched: {blind.named_effects(untouched)}", flush=True)
        inside, outside = [], []  # the library cases' rows, the case outside the library's found_as
        for case in blind.cases(source):
            result = blind.run(source, case)
            row = {"sensor": source, "untouched_named": blind.named_effects(untouched),
                   **blind.verdict(case, result, untouched, blind.untouched_estimates(case, result, untouched))}
            rows.append(row)
            if case.named == ("unexplained",):
                outside.append(row["found_as"])
            else:
                inside.append(row)
            print(f"blind {source} {case.name}: found = {row['found_as']} {row['named_beyond_untouched']}", flush=True)
        found_as = [r["found_as"] for r in inside]
        summary.append(f"{source}: {found_as.count('named')} of {len(inside)} library effects named within "
                       f"{settings.BLIND_MAGNITUDE_TOLERANCE:.0%} ("
                       f"{sum(r['found_subtracting_named'] for r in inside)} subtracting only what the untouched "
                       "recording named)" +
                       (f", {found_as.count('equivalent')} more fit as well as the effect named"
                        if "equivalent" in found_as else "") +
                       (f"; outside effect unexplained: {outside[0] is not None}" if outside else ""))
    write_json(folder / "blind.json", rows)
    lines = ["# Blind tests", "", blind.__doc__.strip(), ""] + [f"- {line}" for line in summary] + [
        "", "| recording | case | injected | expected | named beyond the untouched recording (the change of the "
        "loop's estimate) | found |",
        "|---|---|---|---|---|---|"]
    for r in rows:
        named = ", ".join(f"{k} {shown(v)}" for k, v in r["named_beyond_untouched"].items()) or "-"
        if r["equivalent_beyond_untouched"]:
            named += " (as good: " + ", ".join(
                f"{k} {shown(v)}" for k, v in r["equivalent_beyond_untouched"].items()) + ")"
        if r["untouched_estimated"]:
            named += " (less the untouched run's estimate, not named there: " + ", ".join(
                f"{k} {shown(v)}" for k, v in r["untouched_estimated"].items()) + ")"
        if r["unexplained_beyond_untouched"]:
            named += f"; unexplained: {', '.join(r['unexplained_beyond_untouched'])}"
        lines.append(f"| {r['sensor']} | {r['case']} | {shown(r['injected'])} {r['unit']} | {r['expected_effect']} "
                     f"{shown(r['expected_magnitude'])} | {named} | {FOUND_AS[r['found_as']]} |")
    untouched_named = {r["sensor"]: r["untouched_named"] for r in rows}
    lines += ["", "Named on the untouched recordings (subtracted): " + "; ".join(
        f"{s}: {named}" for s, named in untouched_named.items())]
    (folder / "blind.md").write_text("\n".join(lines) + "\n")
    return [f"| [blind tests](blind.md) | {'; '.join(summary)} | | |"]


def _run_target(target: str, folder: Path, args, workers: int = 1) -> tuple[list[str], list[str], list[str], dict]:
    """One target of the command (a dataset, ``blind`` or a recording folder) into ``folder``, each recording's
    loop on ``workers`` processes: its summary lines, failures, held-out table lines and loop results (label ->
    :class:`gaitsim.loop.attribution.LoopResult`)."""
    folder.mkdir(parents=True, exist_ok=True)
    if target == "blind":
        return _run_blind(folder), [], [], {}
    found, failed, results = _run_recordings(target, folder, args, workers)
    return found, failed, (_run_held_out(target, folder, results) if len(results) > 1 else []), results


def kinematics_pairs(results: dict) -> list[tuple[str, str]]:
    """(source, target) labels ``dataset/recording`` of the stance-kinematics cross-validation
    (:func:`gaitsim.loop.transfer.kinematics_table`): every ordered pair within a dataset, and every recording of
    the first dataset of a :data:`CROSS_DATASET` pair onto every recording of the second."""
    def dataset(label: str) -> str:
        return label.rsplit("/", 1)[0]

    return [(a, b) for a in results for b in results if a != b and (
        dataset(a) == dataset(b) or (dataset(a), dataset(b)) in CROSS_DATASET)]


def _run_kinematics(folder: Path, results: dict) -> list[str]:
    """The stance-kinematics cross-validation into ``folder``/held_out_kinematics.json and its README lines
    (nothing when no pair has the Fig. 5 residuals)."""
    rows = transfer.kinematics_table(results, kinematics_pairs(results),
                                     log=lambda m: print(f"  {m}", flush=True))
    if not rows:
        return []
    write_json(folder / "held_out_kinematics.json", rows)
    return ["", "## Held-out stance kinematics", "", transfer.KINEMATICS_NOTE, ""] + transfer.KINEMATICS_HEADER + \
        transfer.kinematics_markdown_rows(rows)


def run(args) -> int:
    """Run the loop as the command line asked; returns the exit code (1 when any recording failed)."""
    if args.max_effects < 0:
        raise ValueError(f"--max-effects {args.max_effects}: must be >= 0")
    if args.jobs < 1:
        raise ValueError(f"--jobs {args.jobs}: must be >= 1")
    if args.axes is not None:
        parse_axis_map(args.axes)  # a malformed map is refused before anything runs
    if args.distance is not None and args.dataset in CHOICES:
        raise ValueError(f"--distance applies to a recording folder, not to {args.dataset!r} (its recordings carry "
                         "their own references)")
    if args.dataset not in CHOICES and not Path(args.dataset).is_dir():
        raise RecordingError(f"loop: {args.dataset!r} is neither a dataset ({', '.join(CHOICES)}) nor a recording "
                             "folder")
    targets = list(DATASETS) + ["blind"] if args.dataset == "all" else [args.dataset]
    failures, recordings, held_out, results = [], 0, [], {}
    with atomic_output_dir(args.out, overwrite=args.force) as tmp:
        lines = ["# Sim-to-real loop results", "", f"Regenerate with `gaitsim loop {args.dataset} --out DIR`.", "",
                 "| recording | residual -> effect (fitted) | navigation metric (measured) | "
                 "predicted-vs-measured discrepancy before -> after |", "|---|---|---|---|"]
        folders = [tmp / target if len(targets) > 1 else tmp for target in targets]
        if args.jobs > 1 and len(targets) > 1:
            with process_pool(min(args.jobs, len(targets))) as pool:
                outcomes = list(pool.map(_run_target, targets, folders, [args] * len(targets)))
        else:
            outcomes = [_run_target(target, folder, args, args.jobs) for target, folder in zip(targets, folders)]
        for target, (found, failed, held, loops) in zip(targets, outcomes):
            prefix = f"{target}/" if len(targets) > 1 else ""
            results.update({f"{target}/{label}": result for label, result in loops.items()})
            recordings += len(found)
            failures += failed
            held_out += held
            lines += [line.replace("](", f"]({prefix}", 1) for line in found]
        if held_out:
            lines += ["", "## Held-out prediction", "", transfer.__doc__.strip(), "",
                      "| dataset | effects of -> applied to | effects (alone: lowers the target's misfit?) | "
                      "q_signature default -> transferred | better | navigation discrepancy default -> "
                      "transferred |", "|---|---|---|---|---|---|"] + held_out
        lines += _run_kinematics(tmp, results)
        if failures:
            lines += ["", f"**{len(failures)} recording(s) failed:**", ""] + [f"- {f}" for f in failures]
        (tmp / "README.md").write_text("\n".join(lines) + "\n")
        if failures and len(failures) == recordings:
            raise LoopFailed(failures)
    print(f"written to {args.out}" + (f"; {len(failures)} recording(s) FAILED:" if failures else ""))
    for f in failures:
        print(f"  {f}")
    return 1 if failures else 0


class LoopFailed(ValueError):
    """Every recording failed: nothing is written (the message lists why)."""

    def __init__(self, failures: list[str]):
        super().__init__("every recording failed (nothing written): " + "; ".join(failures))
