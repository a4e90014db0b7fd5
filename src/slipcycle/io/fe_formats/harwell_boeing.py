"""Harwell–Boeing sparse matrices, as written by ANSYS ``HBMAT`` (with its mapping file).

Layout (Duff, Grimes & Lewis, "Users' Guide for the Harwell-Boeing Sparse Matrix
Collection", RAL-92-086, 1992): a four- or five-line header

1. title (A72), key (A8);
2. TOTCRD, PTRCRD, INDCRD, VALCRD, RHSCRD (5I14): lines of each section;
3. MXTYPE (A3: R real, S symmetric / U unsymmetric, A assembled), NROW, NCOL, NNZERO,
   NELTVL (14X, 4I14);
4. PTRFMT, INDFMT (A16), VALFMT, RHSFMT (A20): Fortran formats of the sections;
5. (when RHSCRD > 0) RHSTYP (A3, F = full), NRHS, NRHSIX;

then the column pointers (NCOL+1), row indices (NNZERO), values (NNZERO), all 1-based and
column by column, and the right-hand sides (NRHS × NROW). A symmetric matrix (``RSA``)
stores its lower triangle. Fields are fixed-width: each line is cut at the width of its
section's format (``(10I8)`` → 8 characters), so numbers that fill their field are read
right.

ANSYS ``HBMAT, Fname, Ext, --, ASCII, STIFF, YES, YES`` (Mechanical APDL Command
Reference, HBMAT) writes the stiffness and the load vector (the right-hand side) and, with
Mapping = YES, ``Fname.mapping``: a header line, then one line per matrix equation,
``equation node dof`` with the dof as a label (UX, UY, UZ, ROTX, ROTY, ROTZ, or another
label, which is treated as a retained dof). Without the mapping file a dof map is needed.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from slipcycle.io.fe_formats.common import RawMatrix, file_error, from_triplets
from slipcycle.io.sniff import looks_like_harwell_boeing

__all__ = ["read", "DOF_LABELS"]

#: ANSYS dof labels → slipcycle's dof numbers (1-3 translations, 4-6 rotations)
DOF_LABELS = {"UX": 1, "UY": 2, "UZ": 3, "ROTX": 4, "ROTY": 5, "ROTZ": 6}
_FMT = re.compile(r"(\d*)\s*([IEDFG])\s*(\d+)", re.IGNORECASE)


def _width(fmt: str, where, what: str) -> int:
    m = _FMT.findall(fmt)
    if not m:
        raise file_error(where, f"cannot read the {what} format {fmt.strip()!r}")
    return int(m[-1][2])


def _section(lines: list[str], start: int, n_lines: int, width: int, count: int,
             conv, where, what: str) -> np.ndarray:
    out = []
    for ln in lines[start:start + n_lines]:
        ln = ln.rstrip("\r\n")
        for k in range(0, len(ln), width):
            tok = ln[k:k + width].strip()
            if tok:
                try:
                    out.append(conv(tok))
                except ValueError:
                    raise file_error(where, f"{what}: {tok!r} is not a number") from None
    if len(out) < count:
        raise file_error(where, f"{what}: expected {count} numbers, found {len(out)} "
                         "(file truncated?)")
    return np.array(out[:count])


def _real(tok: str) -> float:
    tok = tok.replace("D", "E").replace("d", "e")
    # Fortran may drop the E of a 3-digit exponent: 1.0-100
    if "E" not in tok.upper() and re.search(r"\d[+-]\d+$", tok):
        tok = re.sub(r"(\d)([+-]\d+)$", r"\1E\2", tok)
    return float(tok)


def read(path: Path) -> RawMatrix:
    """K (and the right-hand sides as load cases) of a Harwell–Boeing file, with labels
    from ANSYS's ``.mapping`` file when one lies beside it."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise file_error(path, f"cannot read: {exc.strerror or exc}") from None
    if b"\x00" in raw:
        raise file_error(path, "is a binary file; write the Harwell-Boeing matrix as ASCII "
                         "(HBMAT, ..., ASCII)")
    lines = raw.decode("latin-1").splitlines()
    if not looks_like_harwell_boeing("\n".join(lines[:4])):
        raise file_error(path, "not a Harwell-Boeing file (its 4-line header is missing)")
    try:
        totcrd, ptrcrd, indcrd, valcrd, *rest = (int(t) for t in lines[1].split())
        rhscrd = rest[0] if rest else 0
        mxtype = lines[2][:3].upper()
        nrow, ncol, nnz = (int(t) for t in lines[2][3:].split()[:3])
    except ValueError:
        raise file_error(path, "cannot read the Harwell-Boeing header") from None
    if mxtype[0] != "R" or mxtype[2] != "A" or mxtype[1] not in "SU":
        raise file_error(path, f"matrix type {mxtype!r}: only real assembled matrices "
                         "(RSA, RUA) are stiffness matrices")
    if nrow != ncol:
        raise file_error(path, f"K is {nrow}×{ncol}, not square")
    fl = lines[3]
    ptrfmt, indfmt, valfmt, rhsfmt = fl[0:16], fl[16:32], fl[32:52], fl[52:72]
    pos = 4
    nrhs, rhstyp = 0, ""
    if rhscrd > 0:
        rhstyp = lines[4][:3].upper()
        try:
            nrhs = int(lines[4][3:].split()[0])
        except (ValueError, IndexError):
            raise file_error(path, "cannot read the right-hand-side header line") from None
        pos = 5
    ptr = _section(lines, pos, ptrcrd, _width(ptrfmt, path, "pointer"), ncol + 1, int, path,
                   "column pointers")
    pos += ptrcrd
    ind = _section(lines, pos, indcrd, _width(indfmt, path, "index"), nnz, int, path,
                   "row indices")
    pos += indcrd
    val = _section(lines, pos, valcrd, _width(valfmt, path, "value"), nnz, _real, path,
                   "values")
    pos += valcrd
    if ptr[0] != 1 or ptr[-1] != nnz + 1 or np.any(np.diff(ptr) < 0):
        raise file_error(path, "inconsistent column pointers")
    if ind.min() < 1 or ind.max() > nrow:
        raise file_error(path, "a row index lies outside the matrix")
    cols = np.repeat(np.arange(ncol), np.diff(ptr))
    # RSA: the lower triangle, mirrored; RUA stores every entry
    K = from_triplets(ind - 1, cols, val, nrow, path,
                      storage="triangle" if mxtype[1] == "S" else "full", declared=mxtype)
    loads = {}
    if nrhs and rhstyp.startswith("F"):
        rhs = _section(lines, pos, rhscrd, _width(rhsfmt, path, "right-hand side"),
                       nrhs * nrow, _real, path, "right-hand sides").reshape(nrhs, nrow)
        loads = {("RHS" if nrhs == 1 else f"RHS{k + 1}"): rhs[k] for k in range(nrhs)}
    labels = _mapping(path, nrow)
    return RawMatrix(K, labels=labels, loads=loads, format="harwell-boeing",
                     missing_labels=None if labels is not None else f"{path.stem}.mapping")


def _mapping(path: Path, n: int):
    """(node, dof) of each equation from ANSYS's ``Fname.mapping``, or None."""
    cands = [path.with_suffix(".mapping"), path.with_suffix(".MAPPING")]
    mp = next((c for c in cands if c.is_file()), None)
    if mp is None:
        return None
    labels, other = {}, {}
    for i, ln in enumerate(mp.read_text(encoding="latin-1").splitlines()):
        tok = ln.split()
        if len(tok) < 3 or not tok[0].isdigit():
            continue                                # header line
        try:
            eq, node = int(tok[0]), int(tok[1])
        except ValueError:
            raise file_error(mp, f"line {i + 1}: expected 'equation node dof'") from None
        word = tok[2].upper()
        # any other label (TEMP, PRES, ...) is a distinct non-translational dof (7, 8, ...)
        dof = DOF_LABELS.get(word) or other.setdefault(word, 7 + len(other))
        labels[eq] = (node, dof)
    if sorted(labels) != list(range(1, n + 1)):
        raise file_error(path, f"K has {n} equations but {mp.name} maps {len(labels)}")
    return np.array([labels[k] for k in range(1, n + 1)], np.int64)
