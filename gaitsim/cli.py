"""Command line: ``gaitsim generate | nav | run | reproduce | loop | stance | import | fixtures | score``. A thin layer
over the Python API."""

from __future__ import annotations

import argparse
import os
import sys
from importlib import import_module

# gaitsim draws nothing with MuJoCo: without this its import loads an OpenGL backend (glfw, ~0.1 s); a value the
# user set is kept
os.environ.setdefault("MUJOCO_GL", "disable")

from nav import storage  # noqa: E402 (after MUJOCO_GL)

# subcommand -> the module defining it with add_parser(subparsers); a command imports only its own module (and
# so only the libraries it needs: no numba, scipy.signal or matplotlib for ``generate``)
SUBCOMMANDS = {"nav": "nav.command", "reproduce": "gaitsim.experiments.command",
               "run": "gaitsim.experiments.command", "loop": "gaitsim.loop.command",
               "stance": "gaitsim.stance.command", "import": "gaitsim.measured.import_command",
               "fixtures": "gaitsim.fixtures.command", "score": "gaitsim.fixtures.command"}


def _generate(args) -> int:
    from .ranges import check_value
    from .scenario import load_scenario
    from .simulate import generate, summary

    scenario = load_scenario(args.scenario)
    if args.seed is not None:
        check_value("scenario", "seed", args.seed, "gaitsim generate --seed")
    if args.runs is not None:
        check_value("scenario", "runs", args.runs, "gaitsim generate --runs")
    recs = generate(scenario, args.out, seed=args.seed, runs=args.runs, overwrite=args.force, form=args.format,
                    parquet=args.parquet, progress=not args.no_progress)
    print(summary(recs[0]))
    if len(recs) > 1:
        print(f"  ... {len(recs)} runs written to {args.out}/run-000 .. run-{len(recs) - 1:03d}")
    else:
        print(f"  written to {args.out}")
    return 0


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The command-line parser: with ``command`` (a subcommand name) only that subcommand's module is imported
    and its parser added (with ``generate``); otherwise every subcommand's, for the overall help."""
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
    if command != "generate":
        modules = [SUBCOMMANDS[command]] if command in SUBCOMMANDS else dict.fromkeys(SUBCOMMANDS.values())
        for name in modules:
            import_module(name).add_parser(sub)
    return parser


def _command(argv: list[str]) -> str | None:
    """The subcommand named in ``argv`` (its first word not starting with ``-``), or None."""
    return next((word for word in argv if not word.startswith("-")), None)


EXIT_INPUT = 2  # bad input: scenario, recording, options or output path (the message says which)
EXIT_RUNS_FAILED = 3  # some Monte Carlo runs failed; the others are stored for the next call
EXIT_INTERNAL = 4  # a bug: an exception no input check anticipated (traceback with GAITSIM_DEBUG=1)


def _runs_failed(exc: Exception) -> bool:
    """True for the runner's RunsFailedError, looked up only if the runner was imported (a command that runs no
    experiments does not import it: it costs ~0.07 s)."""
    runner = sys.modules.get("gaitsim.experiments.runner")
    return runner is not None and isinstance(exc, runner.RunsFailedError)


def main(argv: list[str] | None = None) -> int:
    """Run one subcommand; every failure ends in one message on stderr and a non-zero exit code, never a
    traceback (set the environment variable GAITSIM_DEBUG=1 to see the traceback of an internal error)."""
    argv = sys.argv[1:] if argv is None else argv
    args = build_parser(_command(argv)).parse_args(argv)
    try:
        return args.func(args)
    except (ValueError, OSError, ImportError) as exc:  # ScenarioError and RecordingError are ValueErrors; a
        # missing optional dependency (pyarrow, pandas) names its extra
        print(f"gaitsim {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_INPUT
    except MemoryError:
        print(f"gaitsim {args.command}: error: out of memory; use a shorter walk, a lower rate or fewer runs",
              file=sys.stderr)
        return EXIT_INPUT
    except KeyboardInterrupt:
        print(f"gaitsim {args.command}: interrupted; nothing was written to the output", file=sys.stderr)
        return 130
    except Exception as exc:  # an internal error: still one line, and a non-zero exit code
        if _runs_failed(exc):
            print(f"gaitsim {args.command}: error: {exc}", file=sys.stderr)
            return EXIT_RUNS_FAILED
        if os.environ.get("GAITSIM_DEBUG"):
            raise
        print(f"gaitsim {args.command}: internal error (a bug; please report it with GAITSIM_DEBUG=1 output): "
              f"{type(exc).__name__}: {exc}", file=sys.stderr)
        return EXIT_INTERNAL


if __name__ == "__main__":
    sys.exit(main())
