"""Writing an imported joint: a runnable ``discrete3d`` case, its stiffness file, a report.

``slipcycle reduce MODEL.toml --out DIR`` with ``model = "fe_import"`` writes, all or
nothing (:func:`slipcycle.io.results.write_together`):

- ``DIR/stiffness.npz``: A, B, C (N/m), the load cases (reactions with the contact held,
  N), node coordinates (m) and frames, and the provenance (the model file's text);
- ``DIR/case.toml``: the ``discrete3d`` case (docs/discrete3d.md) naming it, with the
  tributary ``area`` of each node (m²) and one ``[[loading.load_case]]`` per load case with
  the time function of ``[fe_import.discrete]``;
- ``DIR/report.txt``: what was read and checked (JSON).
"""

from __future__ import annotations

import json
from pathlib import Path

from slipcycle.fe.files import _savez, _stiffness_arrays
from slipcycle.fe.model import discrete3d_case_text
from slipcycle.fe_import.joint import ImportedJoint, import_joint
from slipcycle.fe_import.model import MODEL, ImportModel, read_import_model
from slipcycle.io.case import CaseError, read_text_file
from slipcycle.io.metadata import provenance
from slipcycle.io.results import write_together

__all__ = ["write_import", "reduce_import", "is_import_model", "OUTPUT_FILES"]

#: the files written into the output directory
OUTPUT_FILES = ("case.toml", "stiffness.npz", "report.txt")


def is_import_model(path: str | Path) -> bool:
    """Whether the TOML file ``path`` says ``model = "fe_import"`` (read as text).

    Parameters
    ----------
    path : str or Path
        A case or model file.

    Returns
    -------
    bool
        True for an ``fe_import`` model file; False for any other file, also an
        unreadable or malformed one (its reader reports that).
    """
    import tomllib

    try:
        return tomllib.loads(read_text_file(path)).get("model") == MODEL
    except (CaseError, tomllib.TOMLDecodeError):
        return False


def write_import(model: ImportModel, joint: ImportedJoint, out: str | Path) -> list[Path]:
    """Write ``case.toml``, ``stiffness.npz`` and ``report.txt`` into ``out`` (module doc).

    Parameters
    ----------
    model : ImportModel
        The model file read (its ``discrete`` table and provenance).
    joint : ImportedJoint
        Its reduction (:func:`import_joint`).
    out : str or Path
        The folder to write into (created; all three files or none are written).

    Returns
    -------
    list of Path
        The files written.
    """
    out = Path(out)
    if (out.exists() and not out.is_dir()) or out.suffix.lower() == ".npz":
        raise CaseError("--out", f"{out} is a file; an fe_import model writes a directory "
                        f"({', '.join(OUTPUT_FILES)})")
    meta = provenance(model.text, model.path)
    data = _stiffness_arrays(joint.reduced, meta)
    text = discrete3d_case_text(model.discrete, joint.reduced, "stiffness.npz", joint.area,
                                key=f"{MODEL}.discrete")
    _check_runnable(text, data)
    report = json.dumps(joint.report, indent=2, default=str) + "\n"
    paths = [out / name for name in OUTPUT_FILES]
    write_together([
        (paths[0], lambda tmp: tmp.write_text(text, encoding="utf-8")),
        (paths[1], lambda tmp: _savez(tmp, data)),
        (paths[2], lambda tmp: tmp.write_text(report, encoding="utf-8")),
    ])
    return paths


#: the key of ``[fe_import.discrete]`` behind a key of the ``discrete3d`` case it writes
_WRITTEN_KEYS = {"discrete3d.friction": "friction", "loading.lam": "lam",
                 "run.cycles": "cycles", "run.steps_per_cycle": "steps_per_cycle"}


def _check_runnable(text: str, data: dict) -> None:
    """Refuse, before anything is written, a ``discrete3d`` case that ``slipcycle run``
    would refuse: the case text and its stiffness are read by the ``discrete3d`` reader
    itself (in a temporary folder), and its error is said of the model file's
    ``[fe_import.discrete]`` key (a tensile mean load, 1e30 cycles, f = 1e300 were
    written, and refused only by the run)."""
    import tempfile

    from slipcycle.discrete3d.case import read_discrete3d_case
    from slipcycle.io.case import read_case

    with tempfile.TemporaryDirectory(prefix="slipcycle-reduce-") as tmp:
        case = Path(tmp) / "case.toml"
        _savez(Path(tmp) / "stiffness.npz", data)
        case.write_text(text, encoding="utf-8")
        try:
            read_discrete3d_case(read_case(case))
        except CaseError as exc:
            key = _WRITTEN_KEYS.get(exc.key, "mean" if exc.key.startswith("loading")
                                    else None)
            where = f"{MODEL}.discrete" + (f".{key}" if key else "")
            raise CaseError(where, f"the discrete3d case it writes would be refused: "
                            f"{exc.key}: {exc.problem}") from None


def reduce_import(path: str | Path, out: str | Path) -> dict:
    """Read the model file ``path``, reduce it and write the case into the directory
    ``out``: :func:`read_import_model`, :func:`import_joint`, :func:`write_import`.

    Parameters
    ----------
    path : str or Path
        The ``fe_import`` model file.
    out : str or Path
        The folder of the written ``discrete3d`` case.

    Returns
    -------
    dict
        The report, with ``written`` (the files).

    Raises
    ------
    CaseError
        One line naming the key at fault; nothing is written.
    """
    model = read_import_model(path)
    if Path(out).suffix.lower() == ".npz":                 # said before the work is done
        raise CaseError("--out", f"{out} is a file; an fe_import model writes a directory "
                        f"({', '.join(OUTPUT_FILES)})")
    joint = import_joint(model)
    written = write_import(model, joint, out)
    return {**joint.report, "written": [str(p) for p in written]}
