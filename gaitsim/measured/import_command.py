"""``gaitsim import FILE.csv --out DIR``: a logger's CSV file turned into a recording folder.

Columns are named by the file's header; units and the axis map are stated (see
:mod:`gaitsim.measured.importer` for what is converted and checked). Example, x-io's NGIMU logger
(``../shared/data/xio-ngimu/short_walk.csv``: Time (s), Gyroscope X/Y/Z (deg/s), Accelerometer X/Y/Z (g))::

    gaitsim import short_walk.csv --out walk --time "Time (s)" \\
        --acc "Accelerometer X (g),Accelerometer Y (g),Accelerometer Z (g)" --acc-unit g \\
        --gyr "Gyroscope X (deg/s),Gyroscope Y (deg/s),Gyroscope Z (deg/s)" --gyr-unit deg/s \\
        --drop-repeated --loop-closure
"""

from __future__ import annotations

import argparse

from nav import storage
from nav.constants import DEFAULT_GRAVITY

from .axes import IDENTITY
from .importer import ImportSpec, import_csv, write_import


def _three(text: str, option: str) -> tuple[str, str, str]:
    names = tuple(n.strip() for n in text.split(","))
    if len(names) != 3:
        raise ValueError(f"{option} {text!r}: {len(names)} column names; expected three (x, y, z), comma-separated")
    return names


def add_parser(subparsers) -> None:
    """Register the ``import`` subcommand on an argparse subparsers object."""
    p = subparsers.add_parser("import", help="turn a logger's CSV file into a recording folder",
                              description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("file", help="CSV file with a header row (plain or .gz)")
    p.add_argument("--out", required=True, help="output recording folder")
    p.add_argument("--force", action="store_true", help="replace an existing output folder")
    p.add_argument("--time", default=None, help="time column name (default t, or none with --rate-hz)")
    p.add_argument("--rate-hz", type=float, default=None, help="sample rate when the file has no time column")
    p.add_argument("--acc", default="acc_x,acc_y,acc_z", help="three specific-force column names, file x,y,z")
    p.add_argument("--gyr", default="gyr_x,gyr_y,gyr_z", help="three angular-rate column names, file x,y,z")
    p.add_argument("--time-unit", default="s", help="s (default), ms, us, ns")
    p.add_argument("--acc-unit", default="m/s^2", help="m/s^2 (default), g, mg, ...")
    p.add_argument("--gyr-unit", default="rad/s", help="rad/s (default), deg/s, ...")
    p.add_argument("--axes", default=IDENTITY,
                   help="axis map, file axes that become the body x (toes), y (left), z (up), e.g. y,-x,z "
                        "(default x,y,z)")
    p.add_argument("--drop-repeated", action="store_true",
                   help="drop (and count) rows whose time does not increase, instead of refusing the file")
    p.add_argument("--loop-closure", action="store_true", help="the walk ends where it started (scored as such)")
    p.add_argument("--delimiter", default=",", help="column separator (default ,)")
    p.add_argument("--skip-rows", type=int, default=0, help="lines before the header row (default 0)")
    p.add_argument("--gravity", type=float, default=DEFAULT_GRAVITY, help="local gravity, m/s^2 (default 9.81)")
    p.add_argument("--no-frame-check", action="store_true",
                   help="import even if the frame checks fail (they are reported as warnings)")
    storage.add_arguments(p)
    p.set_defaults(func=run)


def spec_from_args(args) -> ImportSpec:
    """The ImportSpec of parsed arguments."""
    if args.time is not None and args.rate_hz is not None:
        raise ValueError(f"--time {args.time!r} and --rate-hz {args.rate_hz}: give one of them (the time column, or "
                         "the sample rate of a file without one)")
    return ImportSpec(
        time_column=None if args.rate_hz is not None else (args.time or "t"),
        acc_columns=_three(args.acc, "--acc"), gyr_columns=_three(args.gyr, "--gyr"), time_unit=args.time_unit,
        acc_unit=args.acc_unit, gyr_unit=args.gyr_unit, axes=args.axes, rate_hz=args.rate_hz,
        drop_repeated=args.drop_repeated, loop_closure=args.loop_closure, delimiter=args.delimiter,
        skip_rows=args.skip_rows, gravity=args.gravity, frame_check=not args.no_frame_check,
    )


def run(args) -> int:
    """Execute ``gaitsim import``; returns the exit code."""
    rec, report = import_csv(args.file, spec_from_args(args))
    write_import(rec, report, args.out, overwrite=args.force, form=args.format, parquet=args.parquet)
    print(report.markdown())
    print(f"written to {args.out}")
    return 0
