"""``gaitsim nav RECORDING --out DIR [options]``: navigate a recording with the shared filter and score it.

RECORDING is a recording folder or a folder of ``run-NNN`` recordings (navigated together as a batch when they
have equal length). Writes ``solution.csv`` and ``score.json`` (per run in ``DIR/run-NNN/`` plus
``DIR/summary.json`` for several runs), atomically: nothing appears at DIR if anything fails.
"""

from __future__ import annotations

import math
from pathlib import Path

from tqdm import tqdm

from . import metrics
from .adaptive_detector import AdaptiveThreshold
from .calm_anchor import CalmAnchor
from .calibration import TERM_GROUPS
from .checks import ALLOWABLE
from .constants import DEFAULT_SIGMA_A, DEFAULT_SIGMA_G, DEFAULT_THRESHOLD, DEFAULT_WINDOW
from .detectors import DETECTORS
from .ekf import STATE_SIZES, FilterConfig
from .files import atomic_output_dir, write_json
from .pipeline import METHODS, NavOptions, navigate, score_solution
from .recording import TIME_UNITS, list_runs, read_recording
from .solution import write_solution_into

_DEFAULT_FILTER = FilterConfig()
_DEFAULT_ADAPTIVE = AdaptiveThreshold()
_DEFAULT_ANCHOR = CalmAnchor()
ANCHOR_FLAGS = (  # (flag, CalmAnchor field, unit, meaning)
    ("--anchor-span", "half_span_s", "s", "a stride's calmest window is the calmest within +- this"),
    ("--anchor-widen", "widen", "dimensionless", "windows within this factor of the calmest one's statistic are taken"),
    ("--anchor-cap", "cap", "dimensionless", "a calmest window at or above this factor of --threshold is motion"),
    ("--anchor-calm", "calm_s", "s", "the statistic is averaged over this centred duration first"))
_DEFAULT_DETECTOR = NavOptions().detector


def add_parser(subparsers) -> None:
    """Register the ``nav`` subcommand on an argparse subparsers object."""
    p = subparsers.add_parser("nav", help="navigate a recording with the ZUPT-aided EKF and score it",
                              description=__doc__)
    p.add_argument("recording", help="recording folder (imu.csv, ...) or a folder of run-NNN recordings")
    p.add_argument("--out", required=True, help="output folder for solution.csv and score.json")
    p.add_argument("--force", action="store_true", help="replace an existing output folder")
    p.add_argument("--detector", choices=DETECTORS, default=_DEFAULT_DETECTOR,
                   help=f"zero-velocity detector (default {_DEFAULT_DETECTOR}: SHOE plus each stride's calmest "
                        "stretch where the fixed threshold finds none)")
    p.add_argument("--threshold", type=float, default=DEFAULT_THRESHOLD, help="detector threshold (default 3e4)")
    p.add_argument("--sigma-a", type=float, default=DEFAULT_SIGMA_A,
                   help="detector accelerometer sigma, m/s^2 (default 0.01)")
    p.add_argument("--sigma-g-dps", type=float, default=math.degrees(DEFAULT_SIGMA_G),
                   help="detector gyro sigma, deg/s (default 0.1; converted to rad/s)")
    p.add_argument("--window", type=int, default=DEFAULT_WINDOW, help="detector window, samples (default 3)")
    for flag, field, unit, text in ANCHOR_FLAGS:
        p.add_argument(flag, type=float, default=getattr(_DEFAULT_ANCHOR, field),
                       help=f"anchored detector: {text}, {unit} (default {getattr(_DEFAULT_ANCHOR, field):g})")
    p.add_argument("--adaptive-ratio", type=float, default=_DEFAULT_ADAPTIVE.ratio,
                   help="adaptive detector: threshold = max(--threshold, ratio x the span's peak gyro energy in "
                        f"sigma_g^2), dimensionless (default {_DEFAULT_ADAPTIVE.ratio:g}; 0: fixed threshold)")
    p.add_argument("--adaptive-span", type=float, default=_DEFAULT_ADAPTIVE.span_s,
                   help=f"adaptive detector: centred span the peak is taken over, s (default {_DEFAULT_ADAPTIVE.span_s:g})")
    p.add_argument("--adaptive-window", type=float, default=_DEFAULT_ADAPTIVE.window_s,
                   help=f"adaptive detector: window duration, s (default {_DEFAULT_ADAPTIVE.window_s:g}; replaces --window)")
    p.add_argument("--states", type=int, choices=STATE_SIZES, default=_DEFAULT_FILTER.states,
                   help="EKF size: 9 (pos, vel, att), 15 (+biases), 24 (+gyro g-sensitivity)")
    p.add_argument("--zupt-sigma", type=float, default=_DEFAULT_FILTER.zupt_sigma,
                   help="ZUPT noise std, m/s (default 0.01)")
    p.add_argument("--zaru", action="store_true", help="also apply a zero angular-rate update (needs --states >= 15)")
    p.add_argument("--level-sigma", type=float, default=_DEFAULT_FILTER.level_sigma,
                   help="height constraint std at ZUPTs, m (default 0: no level-walking constraint)")
    p.add_argument("--method", choices=METHODS, default="auto", help="mechanisation (default auto)")
    p.add_argument("--heading-deg", type=float, default=None,
                   help="initial heading, deg counter-clockwise from east (default: from truth/reference, else 0)")
    p.add_argument("--gravity", type=float, default=None, help="gravity, m/s^2 (default: meta.json, else 9.81)")
    p.add_argument("--calibration", default=None, help="calibration file applied before mechanisation (step 1)")
    p.add_argument("--calibration-terms", default=",".join(TERM_GROUPS),
                   help="comma-separated terms of the calibration to apply (default all)")
    p.add_argument("--stance-velocity", default=None,
                   help="stance velocity model JSON (step 2; default zero velocity)")
    p.add_argument("--rts", action="store_true", help="RTS-smooth the solution")
    p.add_argument("--no-progress", action="store_true", help="no progress bars over a folder of runs")
    p.add_argument("--time-unit", choices=TIME_UNITS, default="s",
                   help="unit of the recording's time columns (default s; the input check refuses a sample rate "
                        "outside 20 Hz..5 kHz and says when the time looks like ms or us)")
    p.add_argument("--allow", action="append", choices=ALLOWABLE, default=[],
                   help="turn the refusal of one input check into a warning (repeatable): rate (sample rate "
                        "outside 20 Hz..5 kHz), units (accelerometer in g, gyro above any walking rate), closure "
                        "(gyro against accelerometer over the strides)")
    p.set_defaults(func=run)


def _anchor(args) -> CalmAnchor:
    """The anchored detector's settings from the ``ANCHOR_FLAGS`` arguments."""
    return CalmAnchor(**{field: getattr(args, flag[2:].replace("-", "_")) for flag, field, _, _ in ANCHOR_FLAGS})


def options_from_args(args) -> NavOptions:
    """NavOptions from parsed arguments (units converted once here)."""
    cfg = FilterConfig(states=args.states, zupt_sigma=args.zupt_sigma, zaru=args.zaru, level_sigma=args.level_sigma)
    terms = tuple(x.strip() for x in args.calibration_terms.split(",") if x.strip())
    return NavOptions(
        detector=args.detector, threshold=args.threshold, sigma_a=args.sigma_a, sigma_g=math.radians(args.sigma_g_dps),
        window=args.window, anchor=_anchor(args),
        adaptive=AdaptiveThreshold(args.adaptive_ratio, args.adaptive_span, args.adaptive_window),
        filter=cfg, method=args.method, calibration=args.calibration, calibration_terms=terms,
        stance_velocity=args.stance_velocity, rts=args.rts,
        heading=None if args.heading_deg is None else math.radians(args.heading_deg), gravity=args.gravity,
        allow=tuple(args.allow),
    )


def _print_score(label: str, score: dict) -> None:
    keys = ("along_track_error_m", "perpendicular_error_m", "final_error_m", "length_ratio", "heading_drift_deg_per_s")
    parts = [f"{k}={score[k]:.4g}" for k in keys if isinstance(score.get(k), float)]
    print(f"{label}: scored against {score['scored_against']}; " + (", ".join(parts) or
          f"estimated start-to-end {score['estimated_start_to_end_m']:.4g} m"))


def run(args) -> int:
    """Execute ``gaitsim nav``; returns the exit code."""
    options = options_from_args(args)
    folders = list_runs(args.recording)
    quiet = args.no_progress or len(folders) == 1
    recs = [read_recording(f, time_unit=args.time_unit)
            for f in tqdm(folders, desc="read runs", unit="run", disable=quiet)]
    solutions = navigate(recs, options)  # one compiled batch call when the runs share their length
    scores = [score_solution(r, s) for r, s in tqdm(zip(recs, solutions), total=len(recs), desc="score runs",
                                                     unit="run", disable=quiet)]
    with atomic_output_dir(args.out, overwrite=args.force) as tmp:
        if len(recs) == 1:
            write_solution_into(tmp, solutions[0], scores[0])
        else:
            for folder, sol, score in zip(folders, solutions, scores):
                (tmp / folder.name).mkdir()
                write_solution_into(tmp / folder.name, sol, score)
            flat = [{k: v for k, v in s.items() if not isinstance(v, (dict, list))} for s in scores]
            write_json(tmp / "summary.json", metrics.summarise_runs(flat))
    for folder, score in zip(folders, scores):
        _print_score(Path(folder).name, score)
    print(f"written to {args.out}")
    return 0
