"""The mesh of an exported body: node labels and coordinates, solid elements, named sets.

Two sources:

- an Abaqus / CalculiX input deck (``.inp``), scanned for ``*NODE``, ``*ELEMENT``,
  ``*NSET``, ``*ELSET``, ``*SURFACE`` and ``*INCLUDE`` (every other keyword is skipped but
  ``*BOUNDARY``, whose non-zero prescribed displacements are refused: the export holds a
  fixed dof at zero).
  meshio 5.3 reads the nodes and elements of a deck but drops the node labels (which the
  stiffness export uses), the element labels and ``*SURFACE`` (which names the contact as
  element faces ``ELSET, S1``), and a second ``*NODE`` block replaces the first; so the deck
  is scanned here, for these few keywords only;
- any other mesh file meshio reads (Gmsh ``.msh``, ``.vtu``, ...): node ``k`` (0-based in
  the file) has the label ``k + 1``; point sets are node sets, and a cell set or a Gmsh
  physical group of triangles or quadrilaterals is a surface.

Element node orders are those of Abaqus/CalculiX (``C3D4``, ``C3D10``, ``C3D8``,
``C3D8I``, ``C3D8R``, ``C3D20``, ``C3D20R``, ``C3D6``, ``C3D15``), which are those of
VTK/meshio for the same elements (corners first, then the mid-side nodes edge by edge);
their faces are numbered S1…S6 as in the CalculiX CrunchiX User's Manual (§6.2, element
types). A face of a quadratic element lists its corners, then its mid-side nodes
(between corners 1–2, 2–3, ...).
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
                 "C3D8I": "hexahedron", "C3D8R": "hexahedron", "C3D20": "hexahedron20",
                 "C3D20R": "hexahedron20", "C3D6": "wedge", "C3D15": "wedge15"}

#: faces S1, S2, ... of each kind: local node positions (0-based), corners first
FACES = {
    "tetra": ((0, 1, 2), (0, 3, 1), (1, 3, 2), (2, 3, 0)),
    "tetra10": ((0, 1, 2, 4, 5, 6), (0, 3, 1, 7, 8, 4), (1, 3, 2, 8, 9, 5),
                (2, 3, 0, 9, 7, 6)),
    "hexahedron": ((0, 1, 2, 3), (4, 7, 6, 5), (0, 4, 5, 1), (1, 5, 6, 2), (2, 6, 7, 3),
                   (3, 7, 4, 0)),
    "wedge": ((0, 1, 2), (3, 5, 4), (0, 3, 4, 1), (1, 4, 5, 2), (2, 5, 3, 0)),
    # mid-side nodes 8..19 on the edges 0-1, 1-2, 2-3, 3-0, 4-5, 5-6, 6-7, 7-4, 0-4, 1-5,
    # 2-6, 3-7 (CalculiX manual, C3D20)
    "hexahedron20": ((0, 1, 2, 3, 8, 9, 10, 11), (4, 7, 6, 5, 15, 14, 13, 12),
                     (0, 4, 5, 1, 16, 12, 17, 8), (1, 5, 6, 2, 17, 13, 18, 9),
                     (2, 6, 7, 3, 18, 14, 19, 10), (3, 7, 4, 0, 19, 15, 16, 11)),
    # mid-side nodes 6..14 on the edges 0-1, 1-2, 2-0, 3-4, 4-5, 5-3, 0-3, 1-4, 2-5 (C3D15)
    "wedge15": ((0, 1, 2, 6, 7, 8), (3, 5, 4, 11, 10, 9), (0, 3, 4, 1, 12, 9, 13, 6),
                (1, 4, 5, 2, 13, 10, 14, 7), (2, 5, 3, 0, 14, 11, 12, 8)),
}
_NODES_PER = {"tetra": 4, "tetra10": 10, "hexahedron": 8, "wedge": 6, "hexahedron20": 20,
              "wedge15": 15}


def face_kind(n_nodes: int) -> str:
    """``tri3``, ``tri6``, ``quad4`` or ``quad8`` of a face with ``n_nodes`` nodes."""
    return {3: "tri3", 6: "tri6", 4: "quad4", 8: "quad8"}[n_nodes]


def _face_corners(n_nodes: int) -> int:
    """The corners of a face of ``n_nodes`` nodes (listed first): 3 or 4."""
    return 3 if n_nodes in (3, 6) else 4


@dataclass(frozen=True)
class FaceSet:
    """Element faces of one kind.

    Attributes
    ----------
    kind : str
        ``tri3``, ``tri6``, ``quad4`` or ``quad8``.
    nodes : numpy.ndarray of int, shape (k, m)
        Mesh node indices of each face, corners first, in the order of the face's
        parametrisation.
    inside : numpy.ndarray, shape (k, 3)
        A point inside the element that owns the face (its centroid), m, which tells the
        outward side.
    owners : numpy.ndarray of int, shape (k,), or None
        The label of the element of each face (a deck's surface), for messages.
    side : int
        The face number (1 for S1, ...) of a deck's surface; 0 where unknown.
    """

    kind: str
    nodes: np.ndarray
    inside: np.ndarray
    owners: np.ndarray | None = None
    side: int = 0

    def corners(self) -> np.ndarray:
        """(k, 3 or 4) node indices of each face's corners, sorted along each row: the
        same face of two elements gives the same row."""
        return np.sort(self.nodes[:, :_face_corners(self.nodes.shape[1])], axis=1)

    def name(self, row: int, labels: np.ndarray) -> str:
        """``element 12, S2`` (a deck's face) or ``the face of nodes 3, 4, 9`` (node
        ``labels`` of the mesh)."""
        if self.owners is not None:
            return f"element {int(self.owners[row])}, S{self.side}"
        return f"the face of nodes {', '.join(str(labels[i]) for i in self.nodes[row])}"


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
    incompatible : int
        The number of elements with internal nodes of their own (``C3D8I``: CalculiX adds
        3 nodes to each, with rows in its stiffness export).
    """

    labels: np.ndarray
    points: np.ndarray
    cells: dict
    node_sets: dict = field(default_factory=dict)
    surfaces: dict = field(default_factory=dict)
    path: Path = Path()
    incompatible: int = 0

    def index_of(self) -> dict:
        """Node label → node index."""
        return {int(label): i for i, label in enumerate(self.labels)}

    def boundary_corners(self) -> set:
        """The sorted corner labels of every face on the body's surface (one element's)."""
        out = set()
        for fs in self.boundary_faces():
            out.update(map(tuple, fs.corners()))
        return out

    def boundary_faces(self) -> list[FaceSet]:
        """The faces that belong to one element only (the surface of the body)."""
        out = []
        keys, owners = [], []
        for kind, conn in self.cells.items():
            for f, local in enumerate(FACES[kind]):
                corners = np.sort(conn[:, list(local[:_face_corners(len(local))])], axis=1)
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
    return {"tetra": 4, "tetra10": 4, "hexahedron": 8, "wedge": 6, "hexahedron20": 8,
            "wedge15": 6}[kind]


# -- deck -------------------------------------------------------------------------------------

_PARAM = re.compile(r"\s*([A-Za-z_]+)\s*(?:=\s*([^,]*))?")


def _keyword(line: str) -> tuple[str, dict]:
    parts = line[1:].split(",")
    params = {}
    for p in parts[1:]:
        m = _PARAM.match(p)
        if m and m.group(1):
            # NAME="SBOTTOM": Abaqus allows a quoted value; the name is what is inside
            params[m.group(1).upper()] = (m.group(2) or "").strip().strip("\"'")
    return parts[0].strip().upper(), params


def _include(path: Path, root: Path, inc: str, where: str, key: str) -> Path:
    """The file of ``*INCLUDE, INPUT=inc`` met in ``path``: ccx opens a relative name from
    the directory it runs in (the main deck's, ``root``), so that comes first; then the
    including file's folder (a deck written for a code that resolves it there)."""
    if Path(inc).is_absolute():
        candidates = [Path(inc)]
    else:
        candidates = [root / inc, path.parent / inc]
    for target in candidates:
        if target.is_file():
            return target
    raise CaseError(key, f"{where}: *INCLUDE file {inc!r} not found")


def _deck_lines(path: Path, key: str, depth: int = 0, root: Path | None = None):
    """(file name, line number, text) of a deck and its ``*INCLUDE`` files, comments out."""
    root = path.parent if root is None else root
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
            target = _include(path, root, inc, f"{path.name}, line {no}", key)
            yield from _deck_lines(target, key, depth + 1, root)
            continue
        yield path.name, no, s


def _numbers(tokens, where: str, key: str, kind=int) -> list:
    try:
        return [kind(t) for t in tokens if t]
    except ValueError:
        raise CaseError(key, f"{where}: expected numbers, got {', '.join(tokens)!r}") from None


def _rotation(axis_a, axis_b, degrees: float, where: str, key: str) -> np.ndarray:
    """The matrix of a right-handed rotation by ``degrees`` about the axis a → b."""
    n = np.asarray(axis_b, float) - np.asarray(axis_a, float)
    if not np.linalg.norm(n) > 0.0:
        raise CaseError(key, f"{where}: the rotation axis has two equal points a = b")
    n = n / np.linalg.norm(n)
    t = np.radians(degrees)
    cross = np.array([[0.0, -n[2], n[1]], [n[2], 0.0, -n[0]], [-n[1], n[0], 0.0]])
    return np.cos(t) * np.eye(3) + np.sin(t) * cross + (1 - np.cos(t)) * np.outer(n, n)


class _Deck:
    """The state of a deck scan (labels, elements, sets, surfaces by label)."""

    def __init__(self, key: str):
        self.key = key
        self.nodes: dict[int, list] = {}
        self.node_where: dict[int, str] = {}
        self.elements: dict[int, tuple[str, list]] = {}
        self.nsets: dict[str, list] = {}
        self.elsets: dict[str, list] = {}
        self.surfaces: dict[str, dict] = {}
        self.pending: list = []            # element being continued over lines
        self.part: str | None = None       # the *PART being read (Abaqus assemblies)
        self.part_nodes: dict[str, list] = {}
        self.instance: dict = {}           # the *INSTANCE being read: part, data lines
        self.placed: set = set()

    def members(self, table: dict, tokens, generate: bool, where: str) -> list:
        if generate:
            a = _numbers(tokens, where, self.key)
            if len(a) not in (2, 3):
                raise CaseError(self.key, f"{where}: GENERATE needs first, last[, step]")
            step = a[2] if len(a) == 3 else 1
            if step < 1 or a[1] < a[0]:
                raise CaseError(self.key, f"{where}: GENERATE {', '.join(map(str, a))} "
                                "names no label (it needs first <= last and a step >= 1)")
            return list(range(a[0], a[1] + 1, step))
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

    def keyword(self, mode: str, params: dict, where: str) -> None:
        """Start a keyword block: check the element type, open sets, parts, instances."""
        if mode == "ELEMENT":
            word = params.get("TYPE", "").upper()
            if word not in ELEMENT_KINDS:
                raise CaseError(self.key, f"{where}: element type {word or '(none)'} is not "
                                "a solid element slipcycle reads (" +
                                ", ".join(ELEMENT_KINDS) + ")")
        elif mode in ("NSET", "ELSET"):
            # an *NSET with no data lines is a set, an empty one (refused where used)
            (self.nsets if mode == "NSET" else self.elsets).setdefault(
                params.get(mode, "").upper(), [])
        elif mode == "PART":
            self.part = params.get("NAME", "").upper()
            self.part_nodes.setdefault(self.part, [])
        elif mode == "END PART":
            self.part = None
        elif mode == "INSTANCE":
            self.instance = {"part": params.get("PART", "").upper(), "lines": [],
                             "where": where}
        elif mode == "END INSTANCE":
            self.place()

    def node(self, vals: list, where: str, params: dict) -> None:
        if len(vals) < 3 or vals[0] != int(vals[0]):
            raise CaseError(self.key, f"{where}: a node line is label, x, y[, z]")
        label, xyz = int(vals[0]), (vals[1:4] + [0.0])[:3]
        if not np.all(np.isfinite(xyz)):
            raise CaseError(self.key, f"{where}: node {label} has a coordinate that is not "
                            f"a finite number ({', '.join(map(str, xyz))})")
        if label in self.nodes and self.nodes[label] != xyz:
            raise CaseError(self.key, f"{where}: node {label} is defined a second time at "
                            f"another place (first: {self.node_where[label]}): which one "
                            "is meant is ambiguous")
        self.nodes[label], self.node_where[label] = xyz, where
        if self.part is not None:
            self.part_nodes[self.part].append(label)
        if "NSET" in params:
            self.nsets.setdefault(params["NSET"].upper(), []).append(label)

    def element(self, tokens, where: str, params: dict) -> None:
        word = params["TYPE"].upper()
        self.pending += _numbers(tokens, where, self.key)
        need = _NODES_PER[ELEMENT_KINDS[word]] + 1
        if len(self.pending) < need:
            return
        label = self.pending[0]
        if len(self.pending) > need:
            raise CaseError(self.key, f"{where}: element {label} has "
                            f"{len(self.pending) - 1} nodes; {word} has {need - 1}")
        if label in self.elements:
            raise CaseError(self.key, f"{where}: element {label} is defined a second time "
                            "(element labels must be unique)")
        self.elements[label] = (word, self.pending[1:])
        if "ELSET" in params:
            self.elsets.setdefault(params["ELSET"].upper(), []).append(label)
        self.pending = []

    def surface(self, tokens, where: str, params: dict, s: str) -> None:
        sname = params.get("NAME", "").upper()
        if params.get("TYPE", "ELEMENT").upper() == "NODE":
            self.nsets.setdefault(sname, []).extend(
                self.members(self.nsets, tokens[:1], False, where))
            return
        face = tokens[1].upper() if len(tokens) > 1 else ""
        if not re.fullmatch(r"S[1-6]", face):
            raise CaseError(self.key, f"{where}: a surface line is 'element or elset, "
                            f"S1..S6', got {s!r}")
        els = self.members(self.elsets, tokens[:1], False, where)
        # a surface is a set of faces: a face named twice (in one block or in two blocks
        # of one name) is one face, or its area would count twice
        faces = self.surfaces.setdefault(sname, {})
        faces.update(dict.fromkeys((e, int(face[1]) - 1) for e in els))

    def place(self) -> None:
        """Move the nodes of the instanced part: Abaqus translates them by the first data
        line, then rotates them about the axis a → b of the second (a, b, angle in
        degrees; keyword reference, *INSTANCE)."""
        inst, self.instance = self.instance, {}
        lines, where = inst.get("lines", []), inst.get("where", "")
        if not lines:
            return
        part = inst["part"]
        if part in self.placed:
            raise CaseError(self.key, f"{where}: a second *INSTANCE of part {part}: "
                            "slipcycle reads one instance of each part")
        self.placed.add(part)
        if len(lines[0]) != 3 or (len(lines) > 1 and len(lines[1]) != 7) or len(lines) > 2:
            raise CaseError(self.key, f"{where}: *INSTANCE data are a translation "
                            "(x, y, z) and a rotation (a, b, angle in degrees)")
        rot = (_rotation(lines[1][:3], lines[1][3:6], lines[1][6], where, self.key)
               if len(lines) > 1 else None)
        for label in self.part_nodes.get(part, []):
            x = np.asarray(self.nodes[label], float) + lines[0]
            if rot is not None:
                x = np.asarray(lines[1][:3]) + rot @ (x - np.asarray(lines[1][:3]))
            self.nodes[label] = x.tolist()

    def data(self, mode: str, params: dict, s: str, where: str) -> None:
        """One data line of the block ``mode``."""
        tokens = [t.strip() for t in s.split(",")]
        if mode == "NODE":
            self.node(_numbers(tokens, where, self.key, float), where, params)
        elif mode == "ELEMENT":
            self.element(tokens, where, params)
        elif mode in ("NSET", "ELSET"):
            table = self.nsets if mode == "NSET" else self.elsets
            table.setdefault(params.get(mode, "").upper(), []).extend(
                self.members(table, tokens, "GENERATE" in params, where))
        elif mode == "SURFACE":
            self.surface(tokens, where, params, s)
        elif mode == "INSTANCE" and self.instance:
            self.instance["lines"].append(_numbers(tokens, where, self.key, float))
        elif mode == "BOUNDARY":
            self.boundary(tokens, where)

    def boundary(self, tokens, where: str) -> None:
        """Refuse a ``*BOUNDARY`` line that prescribes a non-zero displacement (node or
        set, first dof, last dof, value): the stiffness export leaves a fixed dof out,
        and slipcycle can only hold such a dof at zero, not at the deck's value."""
        if len(tokens) < 4 or not tokens[3]:
            return
        try:
            value = float(tokens[3].replace("D", "E").replace("d", "e"))
        except ValueError:
            return
        if value != 0.0:
            raise CaseError(self.key, f"{where}: *BOUNDARY prescribes {value:g} on dofs "
                            f"{tokens[1]}-{tokens[2] or tokens[1]} of {tokens[0]}; a fixed "
                            "dof has no row in the stiffness export and would be held at 0: "
                            "leave it free in the deck and move it with a [[fe_import.load]] "
                            "displacement")


def read_deck(path: Path, key: str, scale: float = 1.0) -> ImportedMesh:
    """Scan an Abaqus/CalculiX deck (module docstring); errors name ``key`` and the line."""
    d = _Deck(key)
    mode, params = None, {}
    for name, no, s in _deck_lines(path, key):
        where = f"{name}, line {no}"
        if s.startswith("*"):
            mode, params = _keyword(s)
            d.keyword(mode, params, where)
        else:
            d.data(mode, params, s, where)
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
    nsets = {n: np.unique(np.array([idx(lab, f"*NSET {n}") for lab in v], np.int64))
             for n, v in d.nsets.items()}
    surfaces = {name: _deck_surface(name, faces, where_el, points, cells, path, key)
                for name, faces in d.surfaces.items()}
    incompatible = sum(word == "C3D8I" for word, _ in d.elements.values())
    return ImportedMesh(labels, points, cells, nsets, surfaces, path, incompatible)


def _deck_surface(name, faces, where_el, points, cells, path, key) -> list:
    """The :class:`FaceSet` list of the surface ``name`` ((element label, face) pairs)."""
    groups: dict = {}
    for e, f in faces:
        if e not in where_el:
            raise CaseError(key, f"{path.name}: *SURFACE {name} names element {e}, "
                            "which has no *ELEMENT line")
        kind, row = where_el[e]
        if f >= len(FACES[kind]):
            raise CaseError(key, f"{path.name}: *SURFACE {name}: element {e} has no "
                            f"face S{f + 1}")
        groups.setdefault((kind, f), []).append((row, e))
    return [_faceset(points, cells[kind], [r for r, _ in rows], FACES[kind][f], kind,
                     np.array([e for _, e in rows], np.int64), f + 1)
            for (kind, f), rows in groups.items()]


def _faceset(points, conn, rows, local, kind, owners=None, side=0) -> FaceSet:
    c = conn[np.asarray(rows)]
    return FaceSet(face_kind(len(local)), c[:, list(local)],
                   points[c[:, :_corner_count(kind)]].mean(axis=1), owners, side)


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
        raise CaseError(key, f"{path.name} has no solid elements (" +
                        ", ".join(_NODES_PER) + ")")
    cells = {k: np.vstack(v) for k, v in cells.items()}
    points = np.asarray(m.points, float)
    if points.shape[1] != 3:
        raise CaseError(key, f"{path.name} has {points.shape[1]}-D points; need x, y, z")
    bad = np.flatnonzero(~np.isfinite(points).all(axis=1))
    if bad.size:
        raise CaseError(key, f"{path.name}: node {bad[0] + 1} (point {bad[0]} of the "
                        f"file) has a coordinate that is not a finite number "
                        f"({', '.join(map(str, points[bad[0]]))})")
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
        ncorner = _face_corners(fs.nodes.shape[1])
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
        # a cell listed twice is one face (a surface is a set of faces)
        surfaces[name] = [FaceSet(fs.kind, fs.nodes[np.unique(rows)],
                                  fs.inside[np.unique(rows)])
                          for fs, rows in groups.values()]
    return ImportedMesh(mesh.labels, mesh.points, mesh.cells, mesh.node_sets, surfaces,
                        mesh.path)
