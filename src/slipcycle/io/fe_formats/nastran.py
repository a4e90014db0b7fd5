"""Nastran DMIG matrices (punch ``.pch`` of ``PARAM,EXTOUT,DMIGPCH`` or bulk data), read
with pyNastran.

A DMIG entry (MSC/NX Nastran Quick Reference Guide, "DMIG") has a header card
``DMIG NAME 0 IFO TIN TOUT POLAR NCOL`` (IFO 6: symmetric, one triangle given; 1: square)
and column cards ``DMIG NAME GJ CJ`` followed by ``Gi Ci Ai`` triples, in small or large
(``DMIG*``) field format; G is a grid (or scalar point) id and C its component, 1–3 the
translations along the grid's displacement coordinate system, 4–6 rotations, 0 a scalar
point (e.g. a modal coordinate of a Craig–Bampton reduction: retained). The stiffness
matrix is the DMIG named by ``keys["matrix"]`` (default ``KAAX``, the stiffness written
with ``DMIGNAME = AX``, or the only DMIG in the file); ``keys["loads"]`` (default ``PAX``
when present) names the load matrix, one column per load case. GRID cards in the same file
give the node coordinates; a contact grid with a displacement coordinate system CD ≠ 0 is
refused (its components are not the global x, y, z).
"""

from __future__ import annotations

import contextlib
import importlib
import io
import logging
from pathlib import Path

import numpy as np

from slipcycle.io.fe_formats.common import (
    RawMatrix,
    StiffnessError,
    check_last_node,
    file_error,
    from_triplets,
)

__all__ = ["read"]


def _bdf_class():
    """pyNastran's BDF reader, imported on first use (its import takes about a second)."""
    try:
        return importlib.import_module("pyNastran.bdf.bdf").BDF
    except ImportError:
        return None


def _triplets(dmig):
    """(row label, column label, value) of a DMIG, from pyNastran's dense matrix."""
    M, rows, cols = dmig.get_matrix(is_sparse=False, apply_symmetry=True)
    M = np.asarray(M)
    if np.iscomplexobj(M):
        if np.any(M.imag != 0):
            raise ValueError("complex")
        M = M.real
    r, c = np.nonzero(M)
    rl = [tuple(int(x) for x in rows[i]) for i in range(len(rows))]
    cl = [tuple(int(x) for x in cols[j]) for j in range(len(cols))]
    return rl, cl, r, c, M[r, c]


def _assemble(dmig, name: str, path: Path):
    """:func:`_triplets`, with pyNastran's failures on malformed cards as one line."""
    try:
        return _triplets(dmig)
    except ValueError as exc:
        if str(exc) == "complex":
            raise file_error(path, f"DMIG {name} is complex; a stiffness is real") from None
        raise file_error(path, f"cannot assemble DMIG {name}: {exc}") from None
    except Exception as exc:  # noqa: BLE001 - pyNastran fails in many ways on bad cards
        raise file_error(path, f"cannot assemble DMIG {name} (no columns, or malformed "
                         f"cards): {type(exc).__name__}") from None


def read(path: Path, keys: dict | None = None) -> RawMatrix:
    """K (and load columns) of the DMIG matrices of ``path`` (see module docstring)."""
    path = Path(path)
    keys = dict(keys or {})
    unknown = sorted(set(keys) - {"matrix", "loads"})
    if unknown:
        raise StiffnessError(f"keys.{unknown[0]}", "unknown key; a DMIG file takes 'matrix' "
                             "and 'loads' (matrix names)")
    BDF = _bdf_class()
    if BDF is None:
        raise file_error(path, "reading Nastran DMIG needs pyNastran (pip install pyNastran)")
    text = path.read_text(encoding="latin-1", errors="replace")
    punch = "BEGIN BULK" not in text.upper()
    log = logging.getLogger("slipcycle.nastran")
    log.setLevel(logging.ERROR)
    model = BDF(debug=None, log=log)
    try:
        # pyNastran prints the fields of a card it cannot parse: keep the terminal to the
        # one line said below
        with contextlib.redirect_stdout(io.StringIO()):
            model.read_bdf(str(path), punch=punch, xref=False, validate=False)
    except Exception as exc:  # noqa: BLE001 - pyNastran raises many kinds; say it in one line
        msg = str(exc).strip().splitlines()
        raise file_error(path, "cannot read the Nastran DMIG cards, a card is cut short "
                         "or malformed (file truncated?): "
                         f"{type(exc).__name__}: {msg[0] if msg else ''}") from None
    if not model.dmig:
        raise file_error(path, "holds no DMIG matrix")
    name = keys.get("matrix")
    if name is None:
        name = "KAAX" if "KAAX" in model.dmig else (next(iter(model.dmig))
                                                    if len(model.dmig) == 1 else None)
        if name is None:
            raise file_error(path, f"holds several DMIG matrices ({', '.join(model.dmig)}); "
                             "name the stiffness with keys = {matrix = \"...\"}")
    if name not in model.dmig:
        raise file_error(path, f"holds no DMIG {name!r} (matrices: {', '.join(model.dmig)})")
    rl, cl, r, c, v = _assemble(model.dmig[name], name, path)
    labels = sorted(set(rl) | set(cl))
    index = {lab: k for k, lab in enumerate(labels)}
    rows = [index[rl[i]] for i in r]
    cols = [index[cl[j]] for j in c]
    dmig = model.dmig[name]
    gcj = np.asarray(getattr(dmig, "GCj", []), np.int64).reshape(-1, 2)
    if gcj.size:
        check_last_node(np.array(labels, np.int64), int(gcj[-1, 0]), path)
    # IFO 1 (square) stores every entry: a lone triangle there is half a matrix
    ifo = getattr(dmig, "matrix_form", None)
    K = from_triplets(rows, cols, v, len(labels), path,
                      storage="full" if ifo == 1 else "either", declared=f"IFO = {ifo}")
    loads = {}
    lname = keys.get("loads", "PAX" if "PAX" in model.dmig else None)
    if lname is not None:
        if lname not in model.dmig:
            raise file_error(path, f"holds no DMIG {lname!r} for the loads")
        lrl, lcl, lr, lc, lv = _assemble(model.dmig[lname], lname, path)
        for j, col in enumerate(lcl):
            f = np.zeros(len(labels))
            for i, val in zip(lr[lc == j], lv[lc == j], strict=True):
                if lrl[i] not in index:
                    raise file_error(path, f"DMIG {lname} loads grid {lrl[i][0]} component "
                                     f"{lrl[i][1]}, not a row of {name}")
                f[index[lrl[i]]] += val
            loads[f"{lname}_{col[0]}"] = f
    coords, frames_cd = {}, {}
    for nid, grid in model.nodes.items():
        if getattr(grid, "cp", 0) == 0:
            coords[int(nid)] = np.asarray(grid.xyz, float)
        frames_cd[int(nid)] = int(getattr(grid, "cd", 0) or 0)
    local = sorted(g for g, comp in labels if comp in (1, 2, 3) and frames_cd.get(g, 0) != 0)
    if local:
        raise file_error(path, f"GRID {local[0]} has displacement coordinate system CD = "
                         f"{frames_cd[local[0]]}: its components are not the global x, y, z; "
                         "export with CD = 0 or give a dof map")
    return RawMatrix(K, labels=np.array(labels, np.int64), coordinates=coords, loads=loads,
                     format="nastran-dmig")
