"""Bodies from mesh files (any format meshio reads: Gmsh ``.msh``, ``.vtu``, ``.xdmf``, ...).

The file must hold triangles (``triangle`` or ``triangle6``; only the corner nodes are
used, scikit-fem adds its own mid-points for P2) and line cells that carry the named
boundaries. A boundary is named either by a cell set (``mesh.cell_sets``) or by a Gmsh
physical group (``field_data`` name → tag, matched against ``cell_data["gmsh:physical"]``);
an integer tag given as a string ("7") is matched against the physical tag directly.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from skfem import MeshTri

from slipcycle.fe.geometry import Body
from slipcycle.io.case import CaseError

__all__ = ["read_mesh_body", "read_meshio", "is_solid_mesh", "check_planar", "cells_of_tag",
           "known_tags"]


def cells_of_tag(m, tag: str, kind: str = "line", corners: int = 2) -> np.ndarray | None:
    """(corners, k) corner vertices of the cells of type ``kind*`` named ``tag`` (a cell
    set, a Gmsh physical name, or a physical number as a string), or None if none."""
    found = []
    sets = getattr(m, "cell_sets", None) or {}
    if tag in sets:
        for block, idx in zip(m.cells, sets[tag], strict=False):
            if block.type.startswith(kind) and idx is not None and len(idx):
                found.append(block.data[np.asarray(idx, int), :corners])
        if found:
            return np.vstack(found).T
    phys = m.cell_data.get("gmsh:physical")
    if phys is not None:
        number = None
        if tag in (m.field_data or {}):
            number = int(m.field_data[tag][0])
        elif tag.isdigit():
            number = int(tag)
        if number is not None:
            for block, data in zip(m.cells, phys, strict=False):
                if block.type.startswith(kind):
                    sel = np.asarray(data) == number
                    if np.any(sel):
                        found.append(block.data[sel, :corners])
            if found:
                return np.vstack(found).T
    return None


def known_tags(m, dim: int = 1) -> list[str]:
    """Cell-set names and Gmsh physical names of dimension ``dim`` in ``m``."""
    names = set((getattr(m, "cell_sets", None) or {}).keys())
    names |= {k for k, v in (m.field_data or {}).items() if len(v) > 1 and int(v[1]) == dim}
    return sorted(names)


def read_meshio(path: str | Path, key: str):
    """``meshio.read(path)``; any failure is a :class:`CaseError` naming ``key``.

    meshio prints (a blank line on stdout with the Gmsh reader, its "Error: ..." lines on
    stderr) and, for a file none of its readers takes, calls ``sys.exit(1)``: both are
    kept off the command's output, and what it said goes into the one-line message.
    """
    import contextlib
    import io

    import meshio

    said = io.StringIO()
    try:
        with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said):
            return meshio.read(str(path))
    except SystemExit:
        text = " ".join(said.getvalue().replace("Error:", "").split())[:200]
        raise CaseError(key, f"cannot read mesh file {path}: "
                        f"{text or 'no reader of meshio takes it'}") from None
    except Exception as exc:  # meshio raises many types
        text = " ".join(str(exc).split())[:200]
        if isinstance(exc, IndexError | EOFError | StopIteration) or "unexpected end" in \
                text.lower():
            # meshio's parsers run off the end of a cut file ("list index out of range")
            text = f"the file ends early (truncated?): {type(exc).__name__}: {text}"
        raise CaseError(key, f"cannot read mesh file {path}: {text}") from None


def used_cells(m, types: tuple[str, ...], corners: int, what: str, path, key: str
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The corner vertices of the cells of ``types`` in ``m``, numbered among the nodes they
    use: (cells (k, corners) renumbered, used node numbers of the file, file number →
    new number or −1). A file without such cells is a :class:`CaseError` naming ``key``."""
    found = [b.data[:, :corners] for b in m.cells if b.type in types]
    if not found:
        raise CaseError(key, f"mesh file {path} holds no {what} "
                        f"(cell types: {', '.join(b.type for b in m.cells)})")
    t = np.vstack(found)
    used = np.unique(t)
    renumber = np.full(len(m.points), -1)
    renumber[used] = np.arange(len(used))
    return renumber[t], used, renumber


def is_solid_mesh(m) -> bool:
    """Whether the meshio mesh ``m`` holds tetrahedra (a 3-D body)."""
    return any(b.type in ("tetra", "tetra10") for b in m.cells)


def check_planar(m, path, key: str = "fe.mesh.file") -> None:
    """Refuse a mesh without tetrahedra whose nodes do not lie in one plane z = const.

    Such a file (e.g. the triangulated skin of a solid) is neither a plane body (read by
    :func:`read_mesh_body` in the x–y plane) nor a 3-D body (which needs volume elements).

    Parameters
    ----------
    m : meshio.Mesh
    path : str or pathlib.Path
        The file, for the message.
    key : str
        Case-file key the error names.

    Raises
    ------
    CaseError
        ``key``: z varies by more than 1e-12 of the extent in x–y (at least 1e-12).
    """
    pts = np.asarray(m.points, float)
    if pts.ndim != 2 or pts.shape[1] < 3 or not len(pts):
        return
    dz = float(np.ptp(pts[:, 2]))
    if dz > 1e-12 * max(float(np.ptp(pts[:, :2])), 1.0):
        kinds = ", ".join(sorted({b.type for b in m.cells})) or "none"
        raise CaseError(key, f"mesh file {path} has no 3-D (volume) elements (tetra, "
                             f"tetra10; cells: {kinds}) but its nodes are not in a plane "
                             f"(z varies by {dz:.3g}): a 3-D body needs tetrahedra, a plane "
                             "body a mesh in z = const")


def read_mesh_body(path: str | Path, tags: dict[str, str], E: float, nu: float,
                   name: str = "body", key: str = "fe.mesh.file",
                   scale: float = 1.0, data=None) -> Body:
    """Read a triangle mesh and name its boundaries.

    Triangles (``triangle`` or ``triangle6``; only the corner nodes are kept) make a
    linear scikit-fem mesh in the x–y plane; each line cell of a tag must be an edge of
    the triangles, and becomes a facet of the named boundary (module docstring for how
    tags are matched).

    Parameters
    ----------
    path : str or pathlib.Path
        Mesh file in any format meshio reads (Gmsh ``.msh``, ``.vtu``, ``.xdmf``, ...);
        planar (z constant).
    tags : dict of str to str
        Boundary name used by slipcycle (e.g. ``"contact"``, a clamped or loaded
        boundary) → tag in the file: a cell-set name, a Gmsh physical name, or a physical
        number as a string.
    E : float
        Young's modulus (Pa).
    nu : float
        Poisson's ratio (plane strain), 0 ≤ ν < 0.5.
    name : str
        Name of the body in messages and metadata.
    key : str
        Case-file key the errors name (a tag error names ``<table of key>.<boundary>``).
    scale : float
        Factor applied to the coordinates to give metres (e.g. 1e-3 for a file in mm).
    data : meshio.Mesh, optional
        The file already read (:func:`read_meshio`); read from ``path`` if None.

    Returns
    -------
    Body
        ``name``, the mesh (coordinates in m, ``mesh.boundaries`` the named facet arrays,
        one per key of ``tags``), ``E``, ``nu`` and ``info = {"file": str(path)}``.

    Raises
    ------
    CaseError
        Unreadable file, no triangles, a mesh that is not planar, a tag that names no
        line cells, or a line that is not an edge of the triangles.
    """
    m = read_meshio(path, key) if data is None else data
    t, used, renumber = used_cells(m, ("triangle", "triangle6"), 3, "triangles", path, key)
    check_planar(m, path, key)
    p = np.asarray(m.points, float)[used, :2].T * scale
    mesh = MeshTri(p, t.T)
    facet_of = {}
    f = mesh.facets
    for k in range(f.shape[1]):
        a, b = int(f[0, k]), int(f[1, k])
        facet_of[(min(a, b), max(a, b))] = k
    boundaries = {}
    for our, theirs in tags.items():
        lines = cells_of_tag(m, str(theirs))
        if lines is None:
            raise CaseError(key.rsplit(".", 1)[0] + f".{our}",
                            f"boundary tag {theirs!r} not found in {Path(path).name} "
                            f"(line tags present: {', '.join(known_tags(m)) or 'none'})")
        lines = renumber[lines]
        idx = []
        for a, b in lines.T:
            k = facet_of.get((min(a, b), max(a, b)))
            if k is None:
                raise CaseError(key.rsplit(".", 1)[0] + f".{our}",
                                f"a line of tag {theirs!r} is not an edge of the triangles")
            idx.append(k)
        boundaries[our] = np.unique(np.asarray(idx, dtype=np.int64))
    mesh = mesh.with_boundaries(boundaries)
    return Body(name, mesh, E, nu, info={"file": str(path)})
