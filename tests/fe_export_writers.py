"""Writers of stiffness exports in the layouts of the FE codes, for the import tests.

Each writer takes a dense symmetric K (n×n, N/m), the (node, dof) label of each row (dof 1,
2, 3 = global x, y, z) and optional nodal load vectors, and writes the file the way the
code does (see the module docstrings of ``slipcycle.io.fe_formats``). They are written
independently of the readers: fixed-width Fortran fields by hand, one stored triangle.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import scipy.io as sio
import scipy.sparse as sp

ANSYS_LABELS = {1: "UX", 2: "UY", 3: "UZ", 4: "ROTX", 5: "ROTY", 6: "ROTZ"}


def fortran_e(v: float, width: int = 20, digits: int = 13) -> str:
    """Fortran ``E{width}.{digits}``: 0.ddddE+xx, right-justified."""
    if v == 0:
        body = "0." + "0" * digits + "E+00"
    else:
        s = f"{abs(v):.{digits - 1}e}"                  # d.ddd...e±xx
        mant, exp = s.split("e")
        body = f"{'-' if v < 0 else ''}0.{mant.replace('.', '')}E{int(exp) + 1:+03d}"
    return body.rjust(width)


def _lower(K):
    n = K.shape[0]
    for i in range(n):
        for j in range(i + 1):
            if K[i, j] != 0:
                yield i, j, K[i, j]


# -- Abaqus ---------------------------------------------------------------------------------
def abaqus_matrix_input(path: Path, K, labels, load=None) -> Path:
    """``*MATRIX OUTPUT, STIFFNESS, FORMAT=MATRIX INPUT``: ``jobname_STIF<k>.mtx`` lines
    ``node,dof, node,dof, value`` (lower triangle) and ``jobname_LOAD<k>.mtx``."""
    lines = [f"{labels[i][0]},{labels[i][1]}, {labels[j][0]},{labels[j][1]}, {v:.16E}"
             for i, j, v in _lower(K)]
    path.write_text("\n".join(lines) + "\n")
    if load is not None:
        lp = path.with_name(path.name.replace("_STIF", "_LOAD"))
        lp.write_text("".join(f"{labels[i][0]},{labels[i][1]}, {v:.16E}\n"
                              for i, v in enumerate(load) if v != 0))
    return path


def abaqus_coordinate(path: Path, K) -> Path:
    """``FORMAT=COORDINATE``: ``row, column, value`` with 1-based equation numbers."""
    path.write_text("".join(f"{i + 1}, {j + 1}, {v:.16E}\n" for i, j, v in _lower(K)))
    return path


def abaqus_user_element(path: Path, K, labels) -> Path:
    """Abaqus ``*SUBSTRUCTURE/ELEMENT MATRIX OUTPUT, OUTPUT FILE=USER DEFINED``: every
    node with the same dofs; the lower triangle row by row, 4 values per line."""
    nodes = list(dict.fromkeys(int(a) for a, _ in labels))
    dofs = [int(d) for a, d in labels if a == nodes[0]]
    out = ["**", "** SUBSTRUCTURE MATRIX OUTPUT", f"*USER ELEMENT, NODES= {len(nodes)}, LINEAR",
           "** ELEMENT NODES", "** " + ", ".join(map(str, nodes)), ", ".join(map(str, dofs)),
           "*MATRIX,TYPE=STIFFNESS"]
    n = K.shape[0]
    for i in range(n):
        row = [repr(float(K[i, j])) for j in range(i + 1)]
        for k in range(0, len(row), 4):
            out.append(" , ".join(row[k:k + 4]) + (" ," if k + 4 < len(row) else ""))
    path.write_text("\n".join(out) + "\n")
    return path


# -- CalculiX -------------------------------------------------------------------------------
def calculix_user_element(path: Path, K, labels) -> Path:
    """CalculiX ``*SUBSTRUCTURE MATRIX OUTPUT`` (USER DEFINED), as its Fortran writes it:
    one "node" per retained dof, the dof of each position, then for each column j the
    entries i = 1..j in E20.13, four per line."""
    n = K.shape[0]
    out = ["**", "** GENERATION OF SUBSTRUCTURE", f"*USER ELEMENT,NODES= {n:10d},LINEAR",
           "** ELEMENT NODES"]
    nodes = [int(a) for a, _ in labels]
    for k in range(0, n, 10):
        out.append("**" + "".join(f"{m:10d}," for m in nodes[k:k + 10]))
    out.append(f"{int(labels[0][1]):10d}")
    out += [f"{i + 1:10d},{int(labels[i][1]):10d}" for i in range(1, n)]
    out.append("*MATRIX,TYPE=STIFFNESS")
    for j in range(n):
        col = [fortran_e(K[i, j]) + "," for i in range(j + 1)]
        out += ["".join(col[k:k + 4]) for k in range(0, len(col), 4)]
    path.write_text("\n".join(out) + "\n")
    return path


def calculix_matrix_storage(path: Path, K, labels) -> Path:
    """``*FREQUENCY, SOLVER=MATRIXSTORAGE``: ``jobname.sti`` (row column value, column by
    column) and ``jobname.dof`` (node.dof per row)."""
    n = K.shape[0]
    lines = [f"{i + 1:10d}{j + 1:10d} {K[i, j]:23.16e}" for j in range(n) for i in range(j + 1)
             if K[i, j] != 0]
    path.write_text("\n".join(lines) + "\n")
    path.with_suffix(".dof").write_text("".join(f"{a}.{d}\n" for a, d in labels))
    return path


# -- Harwell-Boeing (ANSYS HBMAT) -----------------------------------------------------------
def _cards(values, per_line, fmt):
    return ["".join(fmt(v) for v in values[k:k + per_line])
            for k in range(0, len(values), per_line)]


def harwell_boeing(path: Path, K, labels=None, rhs=None) -> Path:
    """RSA (lower triangle by columns), (10I8) pointers and indices, (4E20.12) values and
    right-hand side; ``Fname.mapping`` when labels are given."""
    n = K.shape[0]
    L = sp.csc_matrix(np.tril(K))
    L.sort_indices()
    ptr = _cards(list(L.indptr + 1), 10, lambda v: f"{v:8d}")
    ind = _cards(list(L.indices + 1), 10, lambda v: f"{v:8d}")
    val = _cards(list(L.data), 4, lambda v: fortran_e(v, 20, 12))
    rhsc = _cards(list(rhs), 4, lambda v: fortran_e(v, 20, 12)) if rhs is not None else []
    tot = len(ptr) + len(ind) + len(val) + len(rhsc)
    head = [f"{'slipcycle test stiffness':72s}{'KSTIFF':8s}",
            f"{tot:14d}{len(ptr):14d}{len(ind):14d}{len(val):14d}{len(rhsc):14d}",
            f"{'RSA':3s}{'':11s}{n:14d}{n:14d}{L.nnz:14d}{0:14d}",
            f"{'(10I8)':16s}{'(10I8)':16s}{'(4E20.12)':20s}{'(4E20.12)':20s}"]
    if rhs is not None:
        head.append(f"{'F':3s}{'':11s}{1:14d}{0:14d}")
    path.write_text("\n".join(head + ptr + ind + val + rhsc) + "\n")
    if labels is not None:
        path.with_suffix(".mapping").write_text(
            "Matrix Eqn   Node   DOF\n"
            + "".join(f"{k + 1:10d}{a:10d}{ANSYS_LABELS[d]:>8s}\n"
                      for k, (a, d) in enumerate(labels)))
    return path


# -- MATLAB ---------------------------------------------------------------------------------
def matlab_v5(path: Path, K, labels=None, load=None, name="K") -> Path:
    data = {name: sp.csc_matrix(K)}
    if labels is not None:
        data["dof_labels"] = np.asarray(labels, float)
    if load is not None:
        data["Fv"] = np.asarray(load, float)[:, None]
    sio.savemat(path, data)
    return path


def matlab_v73(path: Path, K, labels=None, load=None, name="K") -> Path:
    """MATLAB 7.3: HDF5 with a 512-byte MATLAB header, column-major (transposed)
    arrays, sparse matrices as (data, ir, jc) groups."""
    import h5py

    with h5py.File(path, "w", userblock_size=512) as f:
        Ks = sp.csc_matrix(K)
        g = f.create_group(name)
        g.attrs["MATLAB_class"] = np.bytes_("double")
        g.attrs["MATLAB_sparse"] = np.uint64(K.shape[0])
        g.create_dataset("data", data=Ks.data)
        g.create_dataset("ir", data=Ks.indices.astype(np.uint64))
        g.create_dataset("jc", data=Ks.indptr.astype(np.uint64))
        if labels is not None:
            d = f.create_dataset("dof_labels", data=np.asarray(labels, float).T)
            d.attrs["MATLAB_class"] = np.bytes_("double")
        if load is not None:
            d = f.create_dataset("Fv", data=np.asarray(load, float)[None, :])
            d.attrs["MATLAB_class"] = np.bytes_("double")
    header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created by: slipcycle tests HDF5 " \
             b"schema 1.00 ."
    with open(path, "r+b") as fh:
        fh.write(header.ljust(116, b" ") + b"\x00" * 8 + b"\x00\x02IM")
    return path


# -- Nastran DMIG ---------------------------------------------------------------------------
def _large(*fields):
    return "".join(f"{str(x):>16s}" for x in fields)


def _dmig_value(v):
    return f"{v: .9E}".replace("E", "D")


def nastran_dmig_punch(path: Path, K, labels, load=None, coords=None, name="KAAX") -> Path:
    """``PARAM,EXTOUT,DMIGPCH`` punch: large-field DMIG* cards (IFO 6, upper triangle by
    columns, double precision), the load matrix PAX (IFO 9), optional GRIDs."""
    n = K.shape[0]
    out = ["$ DMIG punch written for the slipcycle import tests",
           f"DMIG*   {name:<16s}{_large(0, 6, 2)}", f"*       {_large(0, '', '', '')}"]
    for j in range(n):
        out.append(f"DMIG*   {name:<16s}{_large(labels[j][0], labels[j][1], '')}")
        for i in range(j + 1):
            if K[i, j] != 0:
                out.append(f"*       {_large(labels[i][0], labels[i][1])}"
                           f"{_dmig_value(K[i, j]):>16s}")
    if load is not None:
        out += [f"DMIG*   {'PAX':<16s}{_large(0, 9, 2)}", f"*       {_large(0, '', '', 1)}",
                f"DMIG*   {'PAX':<16s}{_large(1, 0, '')}"]
        out += [f"*       {_large(labels[i][0], labels[i][1])}{_dmig_value(v):>16s}"
                for i, v in enumerate(load) if v != 0]
    for nid, xyz in (coords or {}).items():
        out.append(f"GRID    {nid:8d}{0:8d}" + "".join(f"{x:8.4f}" for x in xyz))
    path.write_text("\n".join(out) + "\n")
    return path


def nastran_dmig_bulk(path: Path, K, labels, name="KAAX") -> Path:
    """Small-field DMIG cards in a bulk data deck (lower triangle by columns)."""
    n = K.shape[0]
    out = ["SOL 101", "CEND", "BEGIN BULK", f"DMIG    {name:<8s}{0:8d}{6:8d}{2:8d}{0:8d}"]
    for j in range(n):
        entries = [(labels[i][0], labels[i][1], K[i, j]) for i in range(j, n) if K[i, j] != 0]
        first = f"DMIG    {name:<8s}{labels[j][0]:8d}{labels[j][1]:8d}{'':8s}"
        cells = []
        for g, c, v in entries:
            cells += [f"{g:8d}", f"{c:8d}", _short(v), ""]
        # 4 fields on the first card after GJ CJ blank, then 8 per continuation
        line, rest = first + "".join(cells[:4]), cells[4:]
        out.append(line)
        for k in range(0, len(rest), 8):
            out.append("        " + "".join(f"{x:>8s}" for x in rest[k:k + 8]))
    out.append("ENDDATA")
    path.write_text("\n".join(out) + "\n")
    return path


def _short(v: float) -> str:
    """A real in 8 characters (Nastran small field): exact for integer values."""
    if float(v).is_integer() and len(f"{int(v)}.") <= 8:
        return f"{int(v)}."
    for d in range(7, 0, -1):
        s = f"{v:.{d}E}".replace("E+0", "+").replace("E-0", "-").replace("E+", "+") \
            .replace("E-", "-")
        if len(s) <= 8:
            return s
    raise ValueError(v)


def matrix_market(path: Path, K, labels=None) -> Path:
    sio.mmwrite(str(path), sp.coo_matrix(K), symmetry="symmetric")
    if labels is not None:
        roles = {1: "x", 2: "y", 3: "z"}
        path.with_suffix(".csv").write_text(
            "node,dof,role\n" + "".join(f"{a},{d},{roles.get(d, 'retained')}\n"
                                        for a, d in labels))
    return path


def isclose_digits(a, b):
    return math.isclose(a, b, rel_tol=1e-12)
