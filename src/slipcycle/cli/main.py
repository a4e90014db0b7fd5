"""Entry point of the ``slipcycle`` command.

Each sub-command lives in its own module of this package with two functions,
``add_parser(subparsers)`` and ``execute(args) -> int``; :data:`COMMANDS` lists them.
Invalid input ends with one line ``error: <key>: <problem>`` on stderr and exit code 2; a
solver that cannot proceed on a valid model (:class:`~slipcycle.errors.SolverError`) with
``error: solver: <problem>`` and exit code 3. No result files are left in either case.

Start-up is kept short: this module and the command modules import only the standard
library at load time, so ``slipcycle --help``, ``--version`` and argument errors answer
without NumPy; each command imports its model when it runs. Every command takes
``--quiet``, ``--verbose`` and ``--no-progress``/``--progress`` (:mod:`slipcycle.cli.common`):
results go to stdout, diagnostics to stderr through :mod:`logging`, progress bars to stderr
when it is a terminal.
"""

from __future__ import annotations

import argparse
import gc
import importlib
import sys

from slipcycle._version import __version__
from slipcycle.cli.common import (
    EXIT_BAD_INPUT,
    EXIT_INTERNAL,
    EXIT_SOLVER,
    add_leading_conventions,
    configure_logging,
    conventions_parent,
    merge_leading_conventions,
    plain,
)

__all__ = ["COMMANDS", "EXIT_BAD_INPUT", "EXIT_SOLVER", "EXIT_INTERNAL", "build_parser",
           "main"]

COMMANDS = ["run", "demo", "examples", "map", "reduce", "limits", "shakedown", "basins",
            "sweep", "roughness"]

#: optional dependencies -> the extra that installs them (``pip install 'slipcycle[X]'``)
EXTRAS = {
    "zarr": "sweep", "dask": "sweep", "distributed": "sweep",
    "skfem": "fe", "meshio": "fe",
}

#: optional packages a command needs before it creates anything (its results store)
_REQUIRES = {"sweep": ("zarr",), "shakedown": ("zarr",), "basins": ("zarr",)}

#: the argument of each command that names a file (not a directory) it writes
_FILE_OUTPUTS = {"reduce": ("out", "case")}

#: the arguments that name a file a command reads (``case`` unless it is an output)
_INPUTS = ("case", "model", "protocols")

#: thresholds of the cyclic garbage collector while a command runs. A command imports
#: NumPy, xarray, Numba and matplotlib (about 10^6 objects): at Python's default (700, 10,
#: 10) the collector runs some 400 times, 0.2 s of a 1.5 s ``slipcycle run``; young
#: garbage is still collected every 20 000 allocations.
_GC_THRESHOLDS = (20_000, 20, 20)


def _path(text: str):
    """argparse ``type`` of a path argument: an empty one is refused (``Path("")`` would
    be the current directory)."""
    from pathlib import Path

    if not text.strip():
        raise argparse.ArgumentTypeError("must not be empty; name a file or directory")
    return Path(text)


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (``error: <option>: <problem>``), exit code 2; path
    arguments (``type=Path``) are refused when empty."""

    def add_argument(self, *args, **kwargs):
        from pathlib import Path

        if kwargs.get("type") is Path:
            kwargs["type"] = _path
        return super().add_argument(*args, **kwargs)

    def error(self, message: str):  # noqa: D401 - argparse's hook
        self.exit(EXIT_BAD_INPUT, f"error: {self.prog}: {_one_line(message)} "
                  f"(see '{self.prog} --help')\n")

    def format_help(self) -> str:
        # descriptions are the command modules' docstrings: show them without reST markup
        return plain(super().format_help())


class _Commands:
    """The sub-parsers action, giving every command the shared output options."""

    def __init__(self, sub, parent: argparse.ArgumentParser):
        self._sub, self._parent = sub, parent

    def add_parser(self, name: str, **kwargs):
        kwargs["parents"] = [*kwargs.get("parents", ()), self._parent]
        return self._sub.add_parser(name, **kwargs)


def build_parser() -> argparse.ArgumentParser:
    """The ``slipcycle`` argument parser (imports the command modules, nothing heavier)."""
    parser = _Parser(
        prog="slipcycle",
        description="Frictional interfaces under periodic loading: coupled discrete "
                    "frictional systems, half-space microslip, rods, finite-element "
                    "reduction, sweeps. 'slipcycle COMMAND --help' describes a command; "
                    "'slipcycle examples' lists the shipped example cases.",
    )
    parser.add_argument("--version", action="version", version=f"slipcycle {__version__}")
    add_leading_conventions(parser)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    commands = _Commands(sub, conventions_parent())
    for name in COMMANDS:
        importlib.import_module(f"slipcycle.cli.cmd_{name}").add_parser(commands)
    return parser


def _outputs(args: argparse.Namespace) -> list[tuple[str, object, str]]:
    """``(option, path, kind)`` of every output of the command (kind "file" or "dir")."""
    files = _FILE_OUTPUTS.get(args.command, ())
    found = []
    for name in ("out", "case"):
        value = getattr(args, name, None)
        if value is None or (name == "case" and name not in files):
            continue
        kind = "file" if name in files else "dir"
        if args.command == "reduce" and name == "out" and value.suffix.lower() != ".npz":
            kind = "dir"                    # a model file's case, stiffness and report
        found.append((f"--{name}", value, kind))
    return found


def _inputs(args: argparse.Namespace) -> list[tuple[str, object]]:
    """``(key, path)`` of every file the command reads: its file arguments and the files
    they name (:func:`slipcycle.cli.common.named_files`)."""
    from slipcycle.cli.common import named_files
    from slipcycle.io.case import MAX_CASE_BYTES
    from slipcycle.io.files import check_input_file

    outputs = _FILE_OUTPUTS.get(args.command, ())
    found = []
    for name in _INPUTS:
        value = getattr(args, name, None)
        if value is None or name in outputs:
            continue
        key = str(value) if name in ("case", "model") else f"--{name}"
        toml = value.suffix.lower() == ".toml"
        check_input_file(value, key, MAX_CASE_BYTES if toml else None, empty_ok=toml,
                         what="case file" if name == "case" else "file")
        found.append((key, value))
        found += named_files(value)
    return found


def _check_outputs(args: argparse.Namespace) -> None:
    """Refuse, before any work, output paths that cannot be written or that would write
    over an input (one line naming the option and the path)."""
    from slipcycle.io.files import check_no_overwrite
    from slipcycle.io.results import check_output_dir, check_output_file

    outputs = _outputs(args)
    check_no_overwrite(_inputs(args), outputs)
    for _, value, kind in outputs:
        (check_output_file if kind == "file" else check_output_dir)(value)


def _check_extras(args: argparse.Namespace) -> None:
    """Name the missing extra before a command creates anything."""
    import importlib.util

    needed = list(_REQUIRES.get(args.command, ()))
    if getattr(args, "scheduler", None):
        needed.append("distributed")
    for name in needed:
        if importlib.util.find_spec(name) is None:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def _execute(args: argparse.Namespace) -> int:
    """Run the command; xarray is kept from importing dask unless a Dask scheduler is used
    (:func:`slipcycle.io.results.dask_not_imported`)."""
    if not getattr(args, "writes_results", True):
        return int(args.execute(args) or 0)
    _check_extras(args)
    _check_outputs(args)
    if getattr(args, "scheduler", None):
        return int(args.execute(args) or 0)
    from slipcycle.io.results import dask_not_imported

    with dask_not_imported():
        return int(args.execute(args) or 0)


def main(argv: list[str] | None = None) -> int:
    """Run the ``slipcycle`` command; returns the exit code.

    0 success; 2 invalid input, unusable files or a missing optional dependency; 3 a solver
    that cannot proceed on a valid model; 4 an internal error (a bug: please report it, with
    ``SLIPCYCLE_DEBUG=1`` for the traceback); 130 interrupted.

    Without ``argv`` (the ``slipcycle`` script, ``python -m slipcycle.cli.main``) the
    process ends after the command: the objects left are then frozen
    (:func:`gc.freeze`), so that the interpreter's final garbage collection does not walk
    them all (0.3 s with NumPy, xarray, Numba and matplotlib loaded). Called with
    ``argv``, the collector is left as it was.
    """
    thresholds = gc.get_threshold()
    gc.set_threshold(*_GC_THRESHOLDS)
    try:
        return _main(argv)
    finally:
        if argv is None:
            gc.freeze()
        else:
            gc.set_threshold(*thresholds)


def _main(argv: list[str] | None) -> int:
    import os

    parser = build_parser()
    argv = sys.argv[1:] if argv is None else [str(a) for a in argv]
    # figures are files: the non-interactive backend, no GUI toolkit probed
    os.environ.setdefault("MPLBACKEND", "Agg")
    args = merge_leading_conventions(parser, parser.parse_args(argv))
    configure_logging(args)
    if args.command != "examples":
        from slipcycle.io.metadata import set_command_line

        set_command_line(["slipcycle", *argv])

    from slipcycle.errors import InputError, SolverError

    try:
        return _execute(args)
    except InputError as exc:
        print(f"error: {_one_line(exc)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except SolverError as exc:
        print(f"error: solver: {_one_line(exc)}", file=sys.stderr)
        return EXIT_SOLVER
    except KeyboardInterrupt as exc:
        # a command may say how far it got and how to go on (a sweep: --resume)
        text = str(exc)
        print(text if text.startswith("interrupted") else "interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # the reader of stdout went away (``slipcycle examples | head``): not an error
        try:
            sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - until the process exits
        except OSError:
            pass
        return 0
    except ModuleNotFoundError as exc:
        top = (exc.name or "").split(".")[0]
        if top in EXTRAS:
            extra = EXTRAS[top]
            print(f"error: slipcycle {args.command}: needs the optional package {top!r}; "
                  f"install it with: pip install 'slipcycle[{extra}]'", file=sys.stderr)
            return EXIT_BAD_INPUT
        if os.environ.get("SLIPCYCLE_DEBUG"):
            raise
        print(f"error: internal: missing module {exc.name!r} (a broken installation: "
              "reinstall slipcycle)", file=sys.stderr)
        return EXIT_INTERNAL
    except MemoryError:
        print(f"error: slipcycle {args.command}: out of memory; reduce the problem size "
              "(sliders, steps_per_cycle, grid or sweep axes)", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as exc:
        # a file-system problem met during the run (disk full, a path removed meanwhile)
        where = exc.filename or getattr(args, "out", None) or args.command
        print(f"error: {where}: {_one_line(exc.strerror or exc)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except Exception as exc:  # noqa: BLE001 - a traceback is a defect; keep it one line
        if os.environ.get("SLIPCYCLE_DEBUG"):
            raise
        print(f"error: internal: {type(exc).__name__}: {_one_line(exc)} (this is a bug in "
              "slipcycle; rerun with SLIPCYCLE_DEBUG=1 for the traceback and report it)",
              file=sys.stderr)
        return EXIT_INTERNAL


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
