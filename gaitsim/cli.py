"""Command line: ``gaitsim generate | nav | run | reproduce | loop``. A thin layer over the Python API."""

from __future__ import annotations

import argparse
import importlib
import sys

from nav import command as nav_command

from .errors import ScenarioError

# subcommands living in their own modules; each exposes add_parser(subparsers) and run(args) -> int
PLUGGED = ("gaitsim.experiments.command", "gaitsim.loop.command")


def _generate(args) -> int:
    from .generate import generate, summary
    from .scenario import load_scenario

    scenario = load_scenario(args.scenario)
    recs = generate(scenario, args.out, seed=args.seed, runs=args.runs, overwrite=args.force)
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
    gen.set_defaults(func=_generate)
    nav_command.add_parser(sub)
    for name in PLUGGED:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name is not None and name.startswith(exc.name):
                continue  # that part of the project is not installed in this version
            raise
        module.add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except (ScenarioError, FileExistsError, FileNotFoundError, ValueError) as exc:
        print(f"gaitsim {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
