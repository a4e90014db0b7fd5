"""What every reader of a finite-element matrix export shares.

A reader returns a :class:`RawMatrix`: the stiffness K as it is stored in the file (rows
in the file's own order), the label of each row where the file has one (node and
degree-of-freedom number, as Abaqus, CalculiX, ANSYS ``.mapping`` and Nastran DMIG give
them), node coordinates and load vectors where the file holds them. Turning this into the
contact blocks A, B, C (roles of the rows, rotation into the node frames, condensation of
retained rows) is :mod:`slipcycle.io.fe_formats.dofmap`'s job, the same for every format.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from slipcycle.errors import InputError

__all__ = ["StiffnessError", "RawMatrix", "check_diagonal", "check_last_node", "from_triplets",
           "file_error"]


class StiffnessError(InputError):
    """A reduced stiffness file is inconsistent; ``key`` names the offending array or file."""


def file_error(path: str | Path, problem: str) -> StiffnessError:
    """The one-line error naming ``path`` (its name only, the key of the message)."""
    return StiffnessError(Path(path).name, problem)


@dataclass
class RawMatrix:
    """A stiffness matrix as stored in an export, before roles and frames are applied.

    Attributes
    ----------
    K : numpy.ndarray or scipy.sparse matrix, shape (n, n)
        The stiffness, N/m, rows and columns in the file's order.
    labels : numpy.ndarray of int, shape (n, 2), or None
        ``(node, dof)`` of each row; ``dof`` 1, 2, 3 are the global x, y, z
        translations, 4–6 rotations (Abaqus, CalculiX, ANSYS, Nastran numbering).
    coordinates : dict of int to numpy.ndarray (3,)
        Node label → coordinates, m, where the file gives them.
    loads : dict of str to numpy.ndarray (n,)
        Nodal force vectors of load cases stored with K, N, rows as K.
    stated : dict
        Settings the file states about itself (``dof_order``, ``tangential_dims``).
    extra : dict
        Arrays already split by the file (``A``, ``B``, ``C``, ``p_w``, ``q_w``, ...).
    transform : numpy.ndarray, shape (m, n), or None
        L of a reduced-order model (physical dofs u = L q); ``labels`` then label the m
        rows of L.
    format : str
        The format word (``"abaqus"``, ...).
    missing_labels : str or None
        The file that labels the rows and is absent (CalculiX ``jobname.dof``, ANSYS
        ``Fname.mapping``): rows cannot then be matched to nodes without a dof map.
    """

    K: object | None
    labels: np.ndarray | None = None
    coordinates: dict = field(default_factory=dict)
    loads: dict = field(default_factory=dict)
    stated: dict = field(default_factory=dict)
    extra: dict = field(default_factory=dict)
    format: str = ""
    transform: np.ndarray | None = None
    missing_labels: str | None = None


def from_triplets(rows, cols, vals, n: int, where: str | Path,
                  storage: str = "either", declared: str = "") -> sp.csr_matrix:
    """Sparse K from (row, col, value) triplets (0-based); one stored triangle is mirrored.

    FE codes write a symmetric K as one triangle (Abaqus ``*MATRIX OUTPUT``, CalculiX,
    Harwell–Boeing ``RSA``, Nastran DMIG ``IFO=6``), in their own equation order. When no
    off-diagonal entry has its transpose in the file, the transposes are filled in by
    symmetry; otherwise the matrix is taken as written (and checked for symmetry later).
    Duplicates add up (assembly).

    ``storage`` is what the file declares: ``"triangle"`` (a symmetric storage) or
    ``"either"`` mirror a lone triangle; ``"full"`` (Harwell–Boeing ``RUA``, DMIG
    ``IFO=1``: every entry stored) refuses a file that holds one triangle only, since its
    other half would be read as zeros by the code that wrote it. ``declared`` names the
    declaration in the file's words for that message (``"RUA"``, ``"IFO = 1"``).
    """
    rows = np.asarray(rows, np.int64)
    cols = np.asarray(cols, np.int64)
    vals = np.asarray(vals, float)
    if rows.size and (rows.min() < 0 or cols.min() < 0 or rows.max() >= n or cols.max() >= n):
        raise file_error(where, f"an entry lies outside the {n}×{n} matrix")
    off = (rows != cols) & (vals != 0)
    # one triangle stored (in the file's own equation order, which need not be the order
    # of the labels): no off-diagonal entry has its transpose in the file
    directed = rows[off] * n + cols[off]
    mirrored = cols[off] * n + rows[off]
    if directed.size and not np.isin(mirrored, directed).any():
        if storage == "full":
            raise file_error(where, f"is declared {declared or 'unsymmetric'} (every entry "
                             f"stored) but holds one triangle only ({directed.size} "
                             "off-diagonal entries, none with its transpose); a full "
                             "matrix was cut to a triangle: export it as symmetric or "
                             "with both triangles")
        rows, cols, vals = (np.concatenate([rows, cols[off]]),
                            np.concatenate([cols, rows[off]]),
                            np.concatenate([vals, vals[off]]))
    return sp.csr_matrix((vals, (rows, cols)), shape=(n, n))


def check_diagonal(K, labels, where: str | Path) -> None:
    """Refuse a stiffness with a row that has no (positive) diagonal entry.

    Every dof a stiffness matrix lists carries stiffness of its own (K_ii > 0 for a
    positive definite or semi-definite K with that dof loaded). An export cut short (the
    last rows or columns of its triangle missing, a truncated file) leaves rows that appear
    only as off-diagonal entries of others: their diagonal is zero.
    """
    d = K.diagonal() if hasattr(K, "diagonal") else np.diagonal(K)

    def name(i):
        return (f"node {labels[i][0]} dof {labels[i][1]}" if labels is not None
                else f"row {i + 1}")

    neg = np.flatnonzero(d < 0)
    if neg.size:
        raise file_error(where, f"K is not positive definite: the diagonal entry of "
                         f"{name(int(neg[0]))} is {d[neg[0]]:.3e} < 0")
    bad = np.flatnonzero(d == 0)                    # NaN is refused later, as non-finite
    if bad.size:
        more = f" (and {bad.size - 1} more)" if bad.size > 1 else ""
        raise file_error(where, f"K has no diagonal entry for {name(int(bad[0]))}{more}; "
                         "every dof of a stiffness has one (file truncated or incomplete?)")


def check_last_node(labels, last: int, where: str | Path) -> None:
    """Refuse an export whose last node (in file order) lacks translations the others have.

    Abaqus ``*MATRIX OUTPUT`` (boundary conditions are not applied to generated
    matrices) and a Nastran a-set DMIG list every translation of every node, one triangle
    row by row (column by column): a file cut at the end of a row (column) looks complete
    but leaves its last node with fewer dofs than the others.

    Parameters
    ----------
    labels : array of int, shape (n, 2)
        ``(node, dof)`` of every row.
    last : int
        The node of the file's last entry.
    """
    lab = np.asarray(labels, np.int64)
    trans = lab[(lab[:, 1] >= 1) & (lab[:, 1] <= 3)]
    mine = set(trans[trans[:, 0] == last, 1].tolist())
    others = set(trans[trans[:, 0] != last, 1].tolist())
    if mine and others - mine:
        raise file_error(where, f"its last node {last} has dof(s) "
                         f"{', '.join(map(str, sorted(mine)))} only, the other nodes "
                         f"{', '.join(map(str, sorted(others)))} (file truncated?)")
