"""Entry point of the ``slipcycle`` command.

Each sub-command lives in its own module of this package with two functions,
``add_parser(subparsers)`` and ``execute(args) -> int``; :data:`COMMANDS` lists them.
Invalid input ends with one line ``error: <key>: <problem>`` on stderr and exit code 2; a
solver that cannot proceed on a valid model (:class:`~slipcycle.errors.SolverError`) with
``error: solver: <problem>`` and exit code 3. No result files are left in either case.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from slipcycle import __version__

COMMANDS = ["run", "demo", "map", "reduce", "limits", "shakedown", "basins", "sweep"]

EXIT_BAD_INPUT = 2
EXIT_SOLVER = 3


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="slipcycle",
        description="Frictional interfaces under periodic loading.",
    )
    parser.add_argument("--version", action="version", version=f"slipcycle {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in COMMANDS:
        importlib.import_module(f"slipcycle.cli.cmd_{name}").add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    from slipcycle.errors import SolverError
    from slipcycle.io import CaseError

    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.execute(args) or 0)
    except CaseError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except SolverError as exc:
        print(f"error: solver: {exc}", file=sys.stderr)
        return EXIT_SOLVER
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
