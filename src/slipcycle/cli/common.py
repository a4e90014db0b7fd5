"""Options and helpers shared by the commands.

Every command takes the output options of :func:`conventions_parent`: ``-q/--quiet``
(results files only, nothing printed but errors), ``-v/--verbose`` (diagnostics; twice for
debugging detail), ``--no-progress`` and ``--progress`` (progress bars go to stderr, by
default only when stderr is a terminal). Diagnostics use :mod:`logging` (logger
``slipcycle``) and go to stderr; the results headline goes to stdout.

This module imports only the standard library: it is loaded for ``slipcycle --help``.
"""

from __future__ import annotations

import argparse
import logging
import re
import sys
import threading
import time
from pathlib import Path

EXIT_BAD_INPUT = 2
EXIT_SOLVER = 3
EXIT_INTERNAL = 4

log = logging.getLogger("slipcycle")


# -- output conventions (every command) ----------------------------------------------------

_ROLE = re.compile(r":(?:func|class|meth|mod|data|attr|obj|exc|ref|doc):`(~?)([^`<]*?)"
                   r"(?:\s*<[^>]*>)?`")
_LITERAL = re.compile(r"``([^`]+)``")


def plain(text: str) -> str:
    """``text`` without reST markup, for ``--help``: roles become their target (its last
    component for ``~``: ``:func:`~a.b.f``` -> ``f``), double-backtick literals their
    content."""
    def role(m: re.Match) -> str:
        name = m.group(2).strip()
        return name.rsplit(".", 1)[-1] if m.group(1) else name

    return _LITERAL.sub(r"\1", _ROLE.sub(role, text))


def conventions_parent() -> argparse.ArgumentParser:
    """A parent parser with ``--quiet``, ``--verbose``, ``--no-progress``, ``--progress``."""
    p = argparse.ArgumentParser(add_help=False)
    g = p.add_argument_group("output")
    g.add_argument("-q", "--quiet", action="store_true",
                   help="print nothing but errors (results are still written)")
    g.add_argument("-v", "--verbose", action="count", default=0,
                   help="print diagnostics on stderr (twice: debugging detail)")
    bar = g.add_mutually_exclusive_group()
    bar.add_argument("--no-progress", action="store_true", help="no progress bar")
    bar.add_argument("--progress", action="store_true",
                     help="show progress bars even when stderr is not a terminal")
    return p


_LEADING = (("-q", "--quiet", "lead_quiet"), ("-v", "--verbose", "lead_verbose"),
            (None, "--no-progress", "lead_no_progress"), (None, "--progress", "lead_progress"))


def add_leading_conventions(parser: argparse.ArgumentParser) -> None:
    """The output options of :func:`conventions_parent` before the command name as well
    (``slipcycle -q run ...``); :func:`merge_leading_conventions` merges them."""
    g = parser.add_argument_group("output (before or after COMMAND)")
    for short, long, dest in _LEADING:
        names = [n for n in (short, long) if n]
        if dest == "lead_verbose":
            g.add_argument(*names, dest=dest, action="count", default=0,
                           help="print diagnostics on stderr (twice: debugging detail)")
        else:
            g.add_argument(*names, dest=dest, action="store_true",
                           help={"lead_quiet": "print nothing but errors",
                                 "lead_no_progress": "no progress bar",
                                 "lead_progress": "progress bars even off a terminal"}[dest])


def merge_leading_conventions(parser: argparse.ArgumentParser,
                              args: argparse.Namespace) -> argparse.Namespace:
    """Merge the output options given before the command into those given after it (a
    sub-parser's defaults would otherwise hide them); ``--progress`` with
    ``--no-progress`` is refused wherever each was given."""
    lead = {dest: getattr(args, dest, False) for _, _, dest in _LEADING}
    for _, _, dest in _LEADING:
        if hasattr(args, dest):
            delattr(args, dest)
    args.quiet = bool(getattr(args, "quiet", False) or lead["lead_quiet"])
    args.verbose = int(getattr(args, "verbose", 0) or 0) + int(lead["lead_verbose"] or 0)
    args.no_progress = bool(getattr(args, "no_progress", False) or lead["lead_no_progress"])
    args.progress = bool(getattr(args, "progress", False) or lead["lead_progress"])
    if args.progress and args.no_progress:
        parser.error("argument --progress: not allowed with argument --no-progress")
    return args


def named_files(case: str | Path) -> list[tuple[str, Path]]:
    """``(key, path)`` of every existing file a TOML case or model file names.

    Every string value of the file (tables, arrays of tables, lists) that names an
    existing regular file, relative to the case file's directory, counts: the readers
    resolve file keys that way. A file that is not readable TOML names nothing here (its
    reader reports it).
    """
    import os
    import tomllib

    case = Path(case)
    try:
        if case.suffix.lower() != ".toml" or not case.is_file():
            return []
        data = tomllib.loads(case.read_text(encoding="utf-8-sig"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return []
    found: list[tuple[str, Path]] = []

    def walk(value, key: str) -> None:
        if isinstance(value, dict):
            for k, v in value.items():
                walk(v, f"{key}.{k}" if key else str(k))
        elif isinstance(value, list):
            for i, v in enumerate(value[:10_000]):
                walk(v, f"{key}[{i}]")
        elif isinstance(value, str) and value and "\0" not in value and len(value) < 4096:
            path = Path(value) if os.path.isabs(value) else case.parent / value
            try:
                if path.is_file():
                    found.append((key, path))
            except (OSError, ValueError):           # a name too long to be a path
                pass

    walk(data, "")
    return found


class _StderrHandler(logging.StreamHandler):
    """A handler writing to the current ``sys.stderr`` (which tests and callers may swap)."""

    def __init__(self):
        super().__init__(sys.stderr)

    @property
    def stream(self):  # type: ignore[override]
        return sys.stderr

    @stream.setter
    def stream(self, value):  # the base class assigns it; the current stderr wins
        pass


def configure_logging(args: argparse.Namespace) -> int:
    """Set the level of the ``slipcycle`` logger from ``--quiet``/``--verbose``.

    Warnings by default, errors only with ``--quiet``, INFO with ``-v``, DEBUG with
    ``-vv``; messages go to stderr as ``slipcycle: <message>``. Returns the level.
    """
    if getattr(args, "quiet", False):
        level = logging.ERROR
    else:
        level = {0: logging.WARNING, 1: logging.INFO}.get(getattr(args, "verbose", 0),
                                                          logging.DEBUG)
    for h in list(log.handlers):
        if isinstance(h, _StderrHandler):
            log.removeHandler(h)
    handler = _StderrHandler()
    handler.setFormatter(logging.Formatter("slipcycle: %(message)s"))
    log.addHandler(handler)
    log.setLevel(level)
    log.propagate = False
    return level


def progress_enabled(args: argparse.Namespace) -> bool:
    """Whether to draw progress bars: ``--progress`` forces them; ``--no-progress`` and
    ``--quiet`` turn them off; otherwise only when stderr is a terminal."""
    if getattr(args, "no_progress", False) or getattr(args, "quiet", False):
        return False
    if getattr(args, "progress", False):
        return True
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


class StageBar:
    """A progress bar (tqdm, stderr) for a command made of a few long stages.

    ``update(done, total)`` is the progress callback of :func:`slipcycle.run` (a solver
    that reports its progress moves the bar); ``stage(name)`` names the current stage. The
    elapsed time keeps ticking while a stage that reports nothing runs. Does nothing when
    disabled.
    """

    def __init__(self, enabled: bool, desc: str, total: float = 1.0):
        self._bar = None
        self._stop = threading.Event()
        if not enabled:
            return
        from tqdm import tqdm

        self._bar = tqdm(total=total, desc=desc, file=sys.stderr, leave=False,
                         bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed}")
        self._ticker = threading.Thread(target=self._tick, daemon=True)
        self._ticker.start()

    def _tick(self) -> None:
        while not self._stop.wait(0.5):
            if self._bar is not None:
                self._bar.refresh()

    def update(self, done: float, total: float | None = None) -> None:
        """Set the fraction done (``done`` of ``total``)."""
        if self._bar is None:
            return
        if total:
            self._bar.total = total
        self._bar.n = done
        self._bar.refresh()

    def stage(self, name: str) -> None:
        """Show the name of the current stage."""
        if self._bar is not None:
            self._bar.set_description_str(name, refresh=True)

    def close(self) -> None:
        self._stop.set()
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class Timer:
    """Seconds since creation (for ``--verbose`` diagnostics)."""

    def __init__(self):
        self.t0 = time.perf_counter()

    def __str__(self) -> str:
        return f"{time.perf_counter() - self.t0:.2f} s"


# -- options of the sweep-based commands (sweep, basins, shakedown) -----------------------

def count_option(text: str) -> int:
    """argparse ``type`` of a count option: an integer, also written as an integral float
    (``1e6``), so that a huge value is judged by its memory rather than its spelling."""
    try:
        return int(text)
    except ValueError:
        pass
    try:
        val = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer, got {text!r}") from None
    if not val.is_integer():
        raise argparse.ArgumentTypeError(f"must be an integer, got {text!r}")
    return int(val)


class Workers(argparse.Action):
    """``--workers N``: a whole number >= 1, refused in one line otherwise."""

    def __call__(self, parser, namespace, values, option_string=None):
        try:
            n = int(values)
        except ValueError:
            n = 0
        if n < 1:
            # parser.exit, not parser.error: one line, no usage text
            parser.exit(2, f"error: --workers: must be a whole number >= 1, got "
                           f"{values!r}\n")
        setattr(namespace, self.dest, n)


def add_common(p) -> None:
    """Options shared by the sweep-based commands (sweep, basins, shakedown)."""
    p.add_argument("--workers", action=Workers, default=None, metavar="N",
                   help="local worker processes (default: all cores; 1 = this process)")
    p.add_argument("--scheduler", default=None,
                   help="address of an existing Dask scheduler, e.g. tcp://10.0.0.1:8786")
    p.add_argument("--resume", action="store_true",
                   help="complete an interrupted run from its Zarr store")
    p.add_argument("--stop-after", type=int, default=None, help=argparse.SUPPRESS)


def print_result(args: argparse.Namespace, summary: dict, keys=None) -> None:
    """Print the results headline (JSON of ``summary``, or of its ``keys``) and where the
    results went, unless ``--quiet``."""
    import json

    from slipcycle.io.results import to_jsonable

    if getattr(args, "quiet", False):
        return
    shown = summary if keys is None else {k: summary[k] for k in keys if k in summary}
    print(json.dumps(to_jsonable(shown), indent=2, default=str))
    out = getattr(args, "out", None)
    if out is not None:
        print(f"results written to {out}/")


def _number(value) -> str:
    return f"{value:.6g}" if isinstance(value, float) else str(value)


def run_headline(summary: dict, out, resolution: float = 0.0) -> list[str]:
    """The short summary of a run: its steady-state class, cycles, dissipation per cycle
    with its unit, and where the files are (no per-node lists).

    A dissipation within ``resolution`` [J] of zero (round-off of the run, e.g. -3e-18 J
    for a shakedown) is shown as 0; ``result.nc`` keeps the raw value."""
    import numbers

    state = summary.get("steady_state_class") or summary.get("steady_state")
    words = [str(summary.get("model", "result"))]
    if state:
        words.append(str(state))
    cycles = summary.get("cycles_run")
    head = ": ".join(words[:1] + [", ".join(words[1:])]) if len(words) > 1 else words[0]
    if isinstance(cycles, numbers.Integral):
        head += f" after {cycles} cycles"
    if summary.get("converged") is False:
        head += f" (not converged; residual {_number(summary.get('residual'))})"
    lines = [head]
    d = summary.get("dissipation_per_cycle")
    unit = summary.get("units", {}).get("dissipation_per_cycle", "")
    if isinstance(d, numbers.Real) and not isinstance(d, bool):
        d = 0.0 if abs(d) <= resolution else float(d)
        lines.append(f"dissipation per cycle D = {_number(d)} {unit}".rstrip())
    elif d is None and "dissipation_per_cycle" in summary:
        lines.append("dissipation per cycle D: none (see summary.json)")
    if out is not None:
        lines.append(f"results in {out}/: summary.json (every number), result.nc, figures/")
    return lines


def dissipation_resolution(result) -> float:
    """The round-off of the dissipation per cycle [J] of a coupled discrete run: the
    energies summed into D are of order F·x (force times displacement scale) per node,
    each known to a few ulps, so |D| <= 64 ε F x N is not resolved (0 for models that do
    not state their scales)."""
    sol = getattr(result, "solution", None)
    force, disp = getattr(sol, "force_scale", 0.0), getattr(sol, "disp_scale", 0.0)
    nodes = getattr(getattr(sol, "dissipation_per_node", None), "size", 0)
    try:
        return 64 * 2.220446049250313e-16 * float(force) * float(disp) * max(int(nodes), 1)
    except (TypeError, ValueError):
        return 0.0


def print_run_summary(args: argparse.Namespace, summary: dict,
                      resolution: float = 0.0) -> None:
    """Print the short summary of a run (:func:`run_headline`) unless ``--quiet``; with
    ``--verbose`` the whole summary as JSON after it."""
    import json

    from slipcycle.io.results import to_jsonable

    if getattr(args, "quiet", False):
        return
    print("\n".join(run_headline(summary, getattr(args, "out", None), resolution)))
    if getattr(args, "verbose", 0):
        print(json.dumps(to_jsonable(summary), indent=2, default=str))


def finish_study(status, args: argparse.Namespace, case, keys: tuple[str, ...], *,
                 what: str = "stopped", unit: str = "cells", write: bool = True) -> int:
    """End a resumable command: report progress if it stopped early; otherwise write its
    outputs (unless the study wrote them itself), print the ``keys`` of its summary as JSON
    and where the results went. Returns the exit code (0)."""
    from slipcycle.io import write_outputs

    if not status.complete:
        if not args.quiet:
            print(f"{what} with {status.cells_done} of {status.cells_total} {unit} done; "
                  "complete it with --resume", flush=True)
        return 0
    if write:
        write_outputs(args.out, status.outputs, case.text, case.path)
    print_result(args, status.outputs.summary, keys)
    return 0


def refuse_sweep_options(args: argparse.Namespace, study: str, takes: str) -> None:
    """Refuse ``--workers``, ``--scheduler`` and ``--resume`` for a study that runs its
    simulations in this process without a sweep store (``study``, e.g. "a discrete3d
    shakedown study"); ``takes`` names the cases that accept them."""
    from slipcycle.io import CaseError

    for option, given in (("--workers", args.workers is not None),
                          ("--scheduler", args.scheduler is not None),
                          ("--resume", bool(args.resume))):
        if given:
            raise CaseError(option, f"{study} runs its simulations one after another in "
                                    "this process, without a sweep store to share or "
                                    f"resume; --workers, --scheduler and --resume are for "
                                    f"{takes}")


def study_options(args: argparse.Namespace) -> dict:
    """The keyword arguments of the library's resumable studies from the common options."""
    return {"workers": args.workers, "scheduler": args.scheduler, "resume": args.resume,
            "progress": progress_enabled(args), "stop_after": args.stop_after}
