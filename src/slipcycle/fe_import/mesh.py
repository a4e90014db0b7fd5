"""The mesh of an exported body: node labels and coordinates, solid elements, named sets.

Two sources:

- an Abaqus / CalculiX input deck (``.inp``), scanned for ``*NODE``, ``*ELEMENT``,
  ``*NSET``, ``*ELSET``, ``*SURFACE`` and ``*INCLUDE`` (every other keyword is skipped).
  meshio 5.3 reads the nodes and elements of a deck but drops the node labels (which the
  stiffness export uses), the element labels and ``*SURFACE`` (which names the contact as
  element faces ``ELSET, S1``), and a second ``*NODE`` block replaces the first; so the deck
  is scanned here, for these few keywords only;
- any other mesh file meshio reads (Gmsh ``.msh``, ``.vtu``, ...): node ``k`` (0-based in
  the file) has the label ``k + 1``; point sets are node sets, and a cell set or a Gmsh
  physical group of triangles or quadrilaterals is a surface.

Element node orders are those of Abaqus/CalculiX (``C3D4``, ``C3D10``, ``C3D8``,
``C3D8I``, ``C3D8R``, ``C3D6``), which are those of VTK/meshio for the same elements; their
faces are numbered S1…S6 as in the CalculiX CrunchiX User's Manual (§6.2, element types).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from slipcycle.io.case import CaseError

__all__ = ["ImportedMesh", "FaceSet", "read_mesh", "read_deck", "FACES", "ELEMENT_KINDS"]

#: solid element word of a deck → kind (meshio's cell type)
ELEMENT_KINDS = {"C3D4": "tetra", "C3D10": "tetra10", "C3D8": "hexahedron",
                 "C3D8I": "hexahedron", "C3D8R": "hexahedron", "C3D6": "wedge"}

#: faces S1, S2, ... of each kind: local node positions (0-based), corners first
FACES = {
    "tetra": ((0, 1, 2), (0, 3, 1), (1, 3, 2), (2, 3, 0)),
    "tetra10": ((0, 1, 2, 4, 5, 6), (0, 3, 1, 7, 8, 4), (1, 3, 2, 8, 9, 5),
                (2, 3, 0, 9, 7, 6)),
    "hexahedron": ((0, 1, 2, 3), (4, 7, 6, 5), (0, 4, 5, 1), (1, 5, 6, 2), (2, 6, 7, 3),
                   (3, 7, 4, 0)),
    "wedge": ((0, 1, 2), (3, 5, 4), (0, 3, 4, 1), (1, 4, 5, 2), (2, 5, 3, 0)),
}
_NODES_PER = {"tetra": 4, "tetra10": 10, "hexahedron": 8, "wedge": 6}
_SURFACE_CELLS = {"triangle": "tri3", "triangle6": "tri6", "quad": "quad4"}


def face_kind(n_nodes: int) -> str:
    """``tri3``, ``tri6`` or ``quad4`` of a face with ``n_nodes`` nodes."""
    return {3: "tri3", 6: "tri6", 4: "quad4"}[n_nodes]


@dataclass(frozen=True)
class FaceSet:
    """Element faces of one kind.

    Attributes
    ----------
    kind : str
        ``tri3``, ``tri6`` or ``quad4``.
    nodes : numpy.ndarray of int, shape (k, m)
        Mesh node indices of each face, corners first, in the order of the face's
        parametrisation.
    inside : numpy.ndarray, shape (k, 3)
        A point inside the element that owns the face (its centroid), m, which tells the
        outward side.
    """

    kind: str
    nodes: np.ndarray
    inside: np.ndarray


@dataclass(frozen=True, eq=False)
class ImportedMesh:
    """A body's mesh.

    Attributes
    ----------
    labels : numpy.ndarray of int, shape (n,)
        Node label of each node (as the stiffness export names them).
    points : numpy.ndarray, shape (n, 3)
        Coordinates, m (the file's times ``scale``).
    cells : dict of str to numpy.ndarray of int
        Element kind → (m, nodes per element) node indices.
    node_sets : dict of str to numpy.ndarray of int
        Name → node indices.
    surfaces : dict of str to list of FaceSet
        Name → its element faces.
    path : Path
    """

    labels: np.ndarray
    points: np.ndarray
    cells: dict
    node_sets: dict = field(default_factory=dict)
    surfaces: dict = field(default_factory=dict)
    path: Path = Path()

    def index_of(self) -> dict:
        """Node label → node index."""
        return {int(label): i for i, label in enumerate(self.labels)}

    def boundary_faces(self) -> list[FaceSet]:
        """The faces that belong to one element only (the surface of the body)."""
        out = []
        keys, owners = [], []
        for kind, conn in self.cells.items():
            for f, local in enumerate(FACES[kind]):
                corners = np.sort(conn[:, list(local[:3 if len(local) in (3, 6) else 4])],
                                  axis=1)
                keys.append(corners if corners.shape[1] == 4 else
                            np.column_stack([corners, np.full(len(corners), -1)]))
                owners.append((kind, f))
        allkeys = np.vstack(keys) if keys else np.zeros((0, 4), np.int64)
        uniq, inv, counts = np.unique(allkeys, axis=0, return_inverse=True,
                                      return_counts=True)
        once = counts[inv.ravel()] == 1
        start = 0
        for (kind, f), k in zip(owners, keys, strict=True):
            sel = once[start:start + len(k)]
            start += len(k)
            if sel.any():
                conn = self.cells[kind][sel]
                out.append(FaceSet(face_kind(len(FACES[kind][f])),
                                   conn[:, list(FACES[kind][f])],
                                   self.points[conn[:, :_corner_count(kind)]].mean(axis=1)))
        return out


def _corner_count(kind: str) -> int:
    return {"tetra": 4, "tetra10": 4, "hexahedron": 8, "wedge": 6}[kind]


# -- deck -------------------------------------------------------------------------------------

_PARAM = re.compile(r"\s*([A-Za-z_]+)\s*(?:=\s*([^,]*))?")


def _keyword(line: str) -> tuple[str, dict]:
    parts = line[1:].split(",")
    params = {}
    for p in parts[1:]:
        m = _PARAM.match(p)
        if m and m.group(1):
            params[m.group(1).upper()] = (m.group(2) or "").strip()
    return parts[0].strip().upper(), params


def _deck_lines(path: Path, key: str, depth: int = 0):
    """(file name, line number, text) of a deck and its ``*INCLUDE`` files, comments out."""
    if depth > 10:
        raise CaseError(key, f"{path.name}: *INCLUDE nested more than 10 deep")
    try:
        text = path.read_bytes()
    except OSError as exc:
        raise CaseError(key, f"cannot read {path}: {exc.strerror or exc}") from None
    if b"\x00" in text[:65536]:
        raise CaseError(key, f"{path.name} is a binary file, not an Abaqus/CalculiX deck")
    for no, line in enumerate(text.decode("latin-1").splitlines(), 1):
        s = line.strip()
        if not s or s.startswith("**"):
            continue
        if s.upper().startswith("*INCLUDE"):
            inc = _keyword(s)[1].get("INPUT", "")
            target = (path.parent / inc) if not Path(inc).is_absolute() else Path(inc)
            if not target.is_file():
                raise CaseError(key, f"{path.name}, line {no}: *INCLUDE file {inc!r} not found")
            yield from _deck_lines(target, key, depth + 1)
            continue
        yield path.name, no, s


def _numbers(tokens, where: str, key: str, kind=int) -> list:
    try:
        return [kind(t) for t in tokens if t]
    except ValueError:
        raise CaseError(key, f"{where}: expected numbers, got {', '.join(tokens)!r}") from None


class _Deck:
    """The state of a deck scan (labels, elements, sets, surfaces by label)."""

    def __init__(self, key: str):
        self.key = key
        self.nodes: dict[int, list] = {}
        self.elements: dict[int, tuple[str, list]] = {}
        self.nsets: dict[str, list] = {}
        self.elsets: dict[str, list] = {}
        self.surfaces: dict[str, list] = {}
        self.pending: list = []            # element being continued over lines

    def members(self, table: dict, tokens, generate: bool, where: str) -> list:
        if generate:
            a = _numbers(tokens, where, self.key)
            if len(a) not in (2, 3):
                raise CaseError(self.key, f"{where}: GENERATE needs first, last[, step]")
            return list(range(a[0], a[1] + 1, a[2] if len(a) == 3 else 1))
        out = []
        for t in tokens:
            if not t:
                continue
            if t.lstrip("-").isdigit():
                out.append(int(t))
            elif t.upper() in table:
                out.extend(table[t.upper()])
            else:
                raise CaseError(self.key, f"{where}: unknown set {t!r}")
        return out


def read_deck(path: Path, key: str, scale: float = 1.0) -> ImportedMesh:
    """Scan an Abaqus/CalculiX deck (module docstring); errors name ``key`` and the line."""
    d = _Deck(key)
    mode, params = None, {}
    for name, no, s in _deck_lines(path, key):
        where = f"{name}, line {no}"
        if s.startswith("*"):
            mode, params = _keyword(s)
            if mode == "ELEMENT":
                word = params.get("TYPE", "").upper()
                if word not in ELEMENT_KINDS:
                    raise CaseError(key, f"{where}: element type {word or '(none)'} is not a "
                                    "solid element slipcycle reads (" +
                                    ", ".join(ELEMENT_KINDS) + ")")
            continue
        tokens = [t.strip() for t in s.split(",")]
        if mode == "NODE":
            vals = _numbers(tokens, where, key, float)
            if len(vals) < 3 or vals[0] != int(vals[0]):
                raise CaseError(key, f"{where}: a node line is label, x, y[, z]")
            d.nodes[int(vals[0])] = (vals[1:4] + [0.0])[:3]
            if "NSET" in params:
                d.nsets.setdefault(params["NSET"].upper(), []).append(int(vals[0]))
        elif mode == "ELEMENT":
            word = params["TYPE"].upper()
            d.pending += _numbers(tokens, where, key)
            need = _NODES_PER[ELEMENT_KINDS[word]] + 1
            if len(d.pending) >= need:
                if len(d.pending) > need:
                    raise CaseError(key, f"{where}: element {d.pending[0]} has "
                                    f"{len(d.pending) - 1} nodes; {word} has {need - 1}")
                d.elements[d.pending[0]] = (word, d.pending[1:])
                if "ELSET" in params:
                    d.elsets.setdefault(params["ELSET"].upper(), []).append(d.pending[0])
                d.pending = []
        elif mode == "NSET":
            d.nsets.setdefault(params.get("NSET", "").upper(), []).extend(
                d.members(d.nsets, tokens, "GENERATE" in params, where))
        elif mode == "ELSET":
            d.elsets.setdefault(params.get("ELSET", "").upper(), []).extend(
                d.members(d.elsets, tokens, "GENERATE" in params, where))
        elif mode == "SURFACE":
            sname = params.get("NAME", "").upper()
            typ = params.get("TYPE", "ELEMENT").upper()
            if typ == "NODE":
                d.nsets.setdefault(sname, []).extend(d.members(d.nsets, tokens[:1], False,
                                                               where))
            else:
                face = tokens[1].upper() if len(tokens) > 1 else ""
                if not re.fullmatch(r"S[1-6]", face):
                    raise CaseError(key, f"{where}: a surface line is 'element or elset, "
                                    f"S1..S6', got {s!r}")
                els = d.members(d.elsets, tokens[:1], False, where)
                d.surfaces.setdefault(sname, []).extend((e, int(face[1]) - 1) for e in els)
    if d.pending:
        raise CaseError(key, f"{path.name}: the last element is incomplete (truncated deck?)")
    return _deck_mesh(d, path, key, scale)


def _deck_mesh(d: _Deck, path: Path, key: str, scale: float) -> ImportedMesh:
    if not d.nodes or not d.elements:
        raise CaseError(key, f"{path.name} has no {'*NODE' if not d.nodes else '*ELEMENT'} "
                        "data: not a deck with a mesh")
    labels = np.array(sorted(d.nodes), np.int64)
    index = {int(lab): i for i, lab in enumerate(labels)}
    points = np.array([d.nodes[int(lab)] for lab in labels], float) * scale

    def idx(lab, what):
        try:
            return index[int(lab)]
        except KeyError:
            raise CaseError(key, f"{path.name}: {what} names node {lab}, which has no "
                            "*NODE line") from None

    cells, where_el = {}, {}
    for e, (word, conn) in sorted(d.elements.items()):
        kind = ELEMENT_KINDS[word]
        lst = cells.setdefault(kind, [])
        where_el[e] = (kind, len(lst))
        lst.append([idx(n, f"element {e}") for n in conn])
    cells = {k: np.array(v, np.int64) for k, v in cells.items()}
    nsets = {n: np.unique([idx(lab, f"*NSET {n}") for lab in v]) for n, v in d.nsets.items()}
    surfaces = {}
    for name, faces in d.surfaces.items():
        groups: dict = {}
        for e, f in faces:
            if e not in where_el:
                raise CaseError(key, f"{path.name}: *SURFACE {name} names element {e}, "
                                "which has no *ELEMENT line")
            kind, row = where_el[e]
            if f >= len(FACES[kind]):
                raise CaseError(key, f"{path.name}: *SURFACE {name}: element {e} has no "
                                f"face S{f + 1}")
            groups.setdefault((kind, f), []).append(row)
        surfaces[name] = [_faceset(points, cells[kind], rows, FACES[kind][f], kind)
                          for (kind, f), rows in groups.items()]
    return ImportedMesh(labels, points, cells, nsets, surfaces, path)


def _faceset(points, conn, rows, local, kind) -> FaceSet:
    c = conn[np.asarray(rows)]
    return FaceSet(face_kind(len(local)), c[:, list(local)],
                   points[c[:, :_corner_count(kind)]].mean(axis=1))


# -- any mesh meshio reads ------------------------------------------------------------------

def read_mesh(path: Path, key: str, scale: float = 1.0) -> ImportedMesh:
    """The mesh of ``path``: a deck (``.inp``) or any file meshio reads (module docstring).

    Parameters
    ----------
    path : Path
        The mesh file.
    key : str
        The model-file key that names it, for error messages.
    scale : float
        Metres per length unit of the file.

    Returns
    -------
    ImportedMesh
        Node labels, coordinates (m), solid cells, node sets and surfaces.

    Raises
    ------
    CaseError
        Naming ``key``: unreadable file, no solid elements, an unknown set.
    """
    path = Path(path)
    if path.suffix.lower() == ".inp":
        return read_deck(path, key, scale)
    from slipcycle.fe.meshfile import read_meshio

    m = read_meshio(path, key)
    cells = {}
    for block in m.cells:
        if block.type in _NODES_PER:
            cells.setdefault(block.type, []).append(np.asarray(block.data, np.int64))
    if not cells:
        raise CaseError(key, f"{path.name} has no solid elements (tetra, tetra10, "
                        "hexahedron, wedge)")
    cells = {k: np.vstack(v) for k, v in cells.items()}
    points = np.asarray(m.points, float)
    if points.shape[1] != 3:
        raise CaseError(key, f"{path.name} has {points.shape[1]}-D points; need x, y, z")
    points = points * scale
    mesh = ImportedMesh(np.arange(1, len(points) + 1), points, cells,
                        {k: np.unique(np.asarray(v, np.int64))
                         for k, v in (m.point_sets or {}).items()}, {}, path)
    return _with_meshio_surfaces(mesh, m)


def _with_meshio_surfaces(mesh: ImportedMesh, m) -> ImportedMesh:
    """Surfaces from named triangle/quad cells, each matched to the face of its element."""
    from slipcycle.fe.meshfile import cells_of_tag, known_tags

    bound = mesh.boundary_faces()
    lookup = {}
    for fs in bound:
        ncorner = 3 if fs.kind in ("tri3", "tri6") else 4
        for row, key in enumerate(map(tuple, np.sort(fs.nodes[:, :ncorner], axis=1))):
            lookup[key] = (fs, row)
    surfaces = {}
    for name in known_tags(m, 2):
        groups: dict = {}
        for cell, corners in (("triangle", 3), ("quad", 4)):
            got = cells_of_tag(m, name, kind=cell, corners=corners)
            if got is None:
                continue
            for key in map(tuple, np.sort(got.T, axis=1)):
                if key in lookup:
                    fs, row = lookup[key]
                    groups.setdefault(id(fs), (fs, []))[1].append(row)
        surfaces[name] = [FaceSet(fs.kind, fs.nodes[rows], fs.inside[rows])
                          for fs, rows in groups.values()]
    return ImportedMesh(mesh.labels, mesh.points, mesh.cells, mesh.node_sets, surfaces,
                        mesh.path)
