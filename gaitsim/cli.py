"""Command line: ``gaitsim generate | nav | run | reproduce | loop | import | fixtures | score``. A thin layer over the Python API."""

from __future__ import annotations

import argparse
import sys

from nav import command as nav_command
from nav import storage

from .errors import ScenarioError
from .experiments import command as experiments_command
from .fixtures import command as fixtures_command
from .loop import command as loop_command
from .measured import import_command
from .scenario import load_scenario
from .simulate import generate, summary

# subcommands living in their own modules; each exposes add_parser(subparsers)
SUBCOMMANDS = (nav_command, experiments_command, loop_command, import_command, fixtures_command)


def _generate(args) -> int:
    scenario = load_scenario(args.scenario)
    recs = generate(scenario, args.out, seed=args.seed, runs=args.runs, overwrite=args.force, form=args.format,
                    parquet=args.parquet, progress=not args.no_progress)
    print(summary(recs[0]))
    if len(recs) > 1:
        print(f"  ... {len(recs)} runs written to {args.out}/run-000 .. run-{len(recs) - 1:03d}")
    else:
        print(f"  written to {args.out}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="gaitsim", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    gen = sub.add_parser("generate", help="simulate a scenario and write recording folders")
    gen.add_argument("scenario", help="scenario TOML file")
    gen.add_argument("--out", required=True, help="output folder (run-NNN subfolders when --runs > 1)")
    gen.add_argument("--seed", type=int, default=None, help="base seed (default: the scenario's)")
    gen.add_argument("--runs", type=int, default=None, help="number of runs (default: the scenario's)")
    gen.add_argument("--force", action="store_true", help="replace an existing output folder")
    storage.add_arguments(gen)
    gen.add_argument("--no-progress", action="store_true", help="no progress bar over the runs")
    gen.set_defaults(func=_generate)
    for module in SUBCOMMANDS:
        module.add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except (ScenarioError, FileExistsError, FileNotFoundError, ValueError, ImportError) as exc:
        print(f"gaitsim {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
