"""The model file of an imported joint (``model = "fe_import"``), read and checked.

.. code-block:: toml

    model = "fe_import"
    [fe_import]
    tolerance = 1e-9            # m: two bodies' contact nodes match within this distance
    [[fe_import.body]]          # one body (on a rigid counter-surface) or two
    stiffness = "block.sti"     # the export (format from the file, or format = "...")
    mesh = "block.inp"          # the deck, or any mesh meshio reads
    units = "m"                 # the deck's units: "m" (m, N, Pa) or "mm" (mm, N, MPa)
    contact = "SBOTTOM"         # a surface (element faces) or a node set on the surface
    clamped = []                # node sets (or surfaces) held at u = 0 in every case
    [[fe_import.load]]          # one load case each, named
    name = "normal"
    nodes = "TOP"               # a node set of body 1 (body = 2 for the second body) ...
    displacement = [0, 0, -1e-6]   # m, prescribed motion (held at 0 in the other cases)
    # or: force = [fx, fy, fz]  N on each node of the set
    # or: surface = "STOP", pressure = 1e6   Pa, into the body
    [fe_import.discrete]        # the discrete3d case written: as [fe.discrete]
    friction = 0.5
    [fe_import.discrete.amplitude]
    normal = 1.0

Every mistake is a :class:`~slipcycle.io.CaseError` naming the key.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from slipcycle.fe.model import read_discrete_table
from slipcycle.io.case import CaseError, Section, read_case
from slipcycle.io.fe_formats import FORMATS

__all__ = ["BodySpec", "LoadSpec", "ImportModel", "read_import_model", "MODEL", "UNITS"]

MODEL = "fe_import"

#: consistent unit systems of a deck → (metres per length unit, N/m per stiffness unit):
#: "mm" is mm, N, MPa (t/mm³), so that K is in N/mm
UNITS = {"m": (1.0, 1.0), "mm": (1e-3, 1e3)}


@dataclass(frozen=True)
class BodySpec:
    """One body: its export, its mesh and its named sets (keys for the messages).

    Attributes
    ----------
    stiffness : Path
        The stiffness export (a format of :mod:`slipcycle.io.fe_formats`).
    mesh : Path
        The mesh: the deck (``.inp``) or any file meshio reads.
    contact : str
        Name of the contact surface (a surface or node set of the mesh).
    clamped : tuple of str
        Node sets held at zero displacement.
    units : str
        ``"m"`` (m, N, Pa) or ``"mm"`` (mm, N, MPa: K in N/mm), see :data:`UNITS`.
    format : str or None
        The export's format word; None: recognised from the file.
    key : str
        The model-file table of this body, named in error messages.
    """

    stiffness: Path
    mesh: Path
    contact: str
    clamped: tuple = ()
    units: str = "m"
    format: str | None = None
    key: str = "fe_import.body[0]"


@dataclass(frozen=True)
class LoadSpec:
    """One load case: ``kind`` ``displacement`` (m) or ``force`` (N per node) of the node
    set ``target``, or ``pressure`` (Pa) on the surface ``target``, of body ``body`` (0 or
    1).

    Attributes
    ----------
    name : str
        Name of the load case in the written case (a plain word other than ``gap``).
    kind : str
        ``"displacement"``, ``"force"`` or ``"pressure"``.
    target : str
        The node set (displacement, force) or surface (pressure) loaded.
    value : numpy.ndarray, shape (3,) or ()
        Displacement (m) or force per node (N) along x, y, z; or the pressure (Pa).
    body : int
        Index of the loaded body (0 or 1).
    key : str
        The model-file table of this load, named in error messages.
    """

    name: str
    kind: str
    target: str
    value: np.ndarray
    body: int = 0
    key: str = "fe_import.load[0]"


@dataclass(frozen=True, eq=False)
class ImportModel:
    """A checked model file: bodies, loads, matching tolerance (m), the ``discrete`` table.

    Attributes
    ----------
    bodies : tuple of BodySpec
        One or two bodies.
    loads : tuple of LoadSpec
        The load cases.
    tolerance : float
        Distance (m) within which the contact nodes of two bodies are matched in pairs.
    discrete : dict
        The ``[fe_import.discrete]`` table, copied into the written ``discrete3d`` case.
    text : str
        The model file's text (for the provenance of the written files).
    path : Path or None
        The model file.
    """

    bodies: tuple
    loads: tuple
    tolerance: float
    discrete: dict
    text: str = ""
    path: Path | None = None


def _names(sec: Section, key: str) -> tuple:
    raw = sec.raw(key, [])
    if isinstance(raw, str):
        raw = [raw]
    if not isinstance(raw, list) or not all(isinstance(s, str) and s for s in raw):
        raise sec.error(key, f"must be a list of set names, got {raw!r}")
    return tuple(raw)


def _body(b: Section) -> BodySpec:
    for name in ("stiffness", "mesh"):
        if b.has(name) and isinstance(b.raw(name), str) and not b.raw(name).strip():
            # an empty name would resolve to the model file's folder ("is a directory")
            raise b.error(name, "is empty: name the file")
    fmt = b.string("format", None, choices=FORMATS) if b.has("format") else None
    spec = BodySpec(stiffness=b.path("stiffness"), mesh=b.path("mesh"),
                    contact=b.string("contact"), clamped=_names(b, "clamped"),
                    units=b.string("units", "m", choices=tuple(UNITS)), format=fmt,
                    key=b.prefix)
    b.finish()
    return spec


def _load(sec: Section, n_bodies: int) -> LoadSpec:
    name = sec.string("name")
    if not name.isidentifier() or name == "gap":
        raise sec.error("name", f"must be a plain word (letters, digits, _) other than "
                        f"'gap', got {name!r}")
    body = sec.int("body", 1, ge=1, le=n_bodies) - 1
    kinds = [k for k in ("displacement", "force", "pressure") if sec.has(k)]
    if len(kinds) != 1:
        raise sec.error("displacement", "give exactly one of displacement, force (with "
                        "nodes) or pressure (with surface)")
    kind = kinds[0]
    if kind == "pressure":
        value = np.array(sec.float("pressure"))
        target = sec.string("surface")
    else:
        value = sec.array(kind, shape=(3,))
        target = sec.string("nodes")
    if not np.any(value):
        raise sec.error(kind, "is zero: a load case must load the body")
    sec.finish()
    return LoadSpec(name, kind, target, value, body, sec.prefix)


def read_import_model(path: str | Path) -> ImportModel:
    """Read and check an ``fe_import`` model file (module docstring).

    Parameters
    ----------
    path : str or Path
        The TOML model file (``model = "fe_import"``).

    Returns
    -------
    ImportModel
        The bodies, loads, tolerance and ``discrete`` table, every file name resolved
        against the model file's folder.

    Raises
    ------
    CaseError
        A missing or unknown key, a missing file, a wrong shape, two loads of one name.
    """
    case = read_case(path, models=[MODEL])
    sec = case.section(MODEL)
    bodies = sec.tables("body")
    if len(bodies) not in (1, 2):
        raise sec.error("body", f"give one body (on a rigid counter-surface) or two, got "
                        f"{len(bodies)}")
    specs = tuple(_body(b) for b in bodies)
    loads = tuple(_load(s, len(specs)) for s in sec.tables("load", []))
    seen = set()
    for ld in loads:
        if ld.name in seen:
            raise CaseError(f"{ld.key}.name", f"a second load case named {ld.name!r}")
        seen.add(ld.name)
    tolerance = sec.float("tolerance", 1e-9, gt=0.0)
    discrete = read_discrete_table(sec)
    if discrete is None:
        raise sec.error("discrete", "required table is missing (friction and the time "
                        "functions of the load cases of the case written)")
    sec.finish()
    case.finish()
    return ImportModel(specs, loads, tolerance, discrete, case.text, case.path)
