"""``slipcycle demo --out DIR``: run shipped example cases and write a report.

The report (``DIR/report.md``) lists each case, its key numbers and its figures; every
case's own results (summary.json, result.nc, figures/) sit in ``DIR/<case>/``. The whole
report is written in a staging folder beside ``DIR`` and moved into place at the end, so an
interrupted demo leaves no partial report. An existing ``DIR`` is replaced only when it is
empty or an earlier demo report; one holding other files is refused (they would be lost).
"""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path
from typing import Any

from slipcycle.cli.common import StageBar, progress_enabled


def add_parser(sub) -> None:
    p = sub.add_parser("demo", help="run shipped example cases and write a report",
                       description=__doc__)
    p.add_argument("--out", type=Path, default=Path("demo-report"), help="report directory")
    p.set_defaults(execute=execute)


def execute(args: argparse.Namespace) -> int:
    import os
    import shutil
    import tempfile

    from slipcycle.io.results import check_output_dir, remove_stale_partials

    out = Path(args.out)
    check_output_dir(out)
    _check_replaceable(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_partials(out)
    stage = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-{os.getpid()}-",
                                  dir=out.parent))
    # mkdtemp makes the folder 0700; the report it becomes gets the user's umask
    umask = os.umask(0)
    os.umask(umask)
    stage.chmod(0o777 & ~umask)
    try:
        # read at call time: tests may narrow the module's DEMO_CASES
        from slipcycle.demo import write_report

        cases = globals().get("DEMO_CASES") or __getattr__("DEMO_CASES")
        with StageBar(progress_enabled(args), "demo", total=len(cases) + 1) as bar:
            report = write_report(stage, cases, progress=bar.update)
        if out.exists():
            old = out.with_name(f".{out.name}.partial-{os.getpid()}-old")
            out.rename(old)
            stage.rename(out)
            shutil.rmtree(old, ignore_errors=True)
        else:
            stage.rename(out)
    finally:
        shutil.rmtree(stage, ignore_errors=True)
    if not args.quiet:
        print(f"report written to {out / report.name}")
    return 0


#: the first line of a demo report (``slipcycle.demo.write_report``)
_REPORT_HEAD = "# slipcycle demo report"


def _check_replaceable(out: Path) -> None:
    """The demo replaces ``out`` whole: refuse a directory that holds anything but an
    earlier demo report (a user's files there would be deleted)."""
    from slipcycle.io import CaseError

    if not out.is_dir() or not any(out.iterdir()):
        return
    report = out / "report.md"
    try:
        head = report.read_text(encoding="utf-8").split("\n", 1)[0]
    except (OSError, UnicodeDecodeError):
        head = ""
    if not head.startswith(_REPORT_HEAD):
        raise CaseError("--out", f"{out} holds files that are no demo report (the demo "
                        "replaces its --out directory whole); choose a new or empty "
                        "directory")


def __getattr__(name: str) -> Any:
    """``DEMO_CASES`` (of :mod:`slipcycle.demo`), loaded on first use so that the command
    line starts without the solvers."""
    if name == "DEMO_CASES":
        return importlib.import_module("slipcycle.demo").DEMO_CASES
    raise AttributeError(name)
