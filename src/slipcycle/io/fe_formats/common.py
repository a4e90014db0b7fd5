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

__all__ = ["StiffnessError", "RawMatrix", "from_triplets", "file_error"]


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
    """

    K: object | None
    labels: np.ndarray | None = None
    coordinates: dict = field(default_factory=dict)
    loads: dict = field(default_factory=dict)
    stated: dict = field(default_factory=dict)
    extra: dict = field(default_factory=dict)
    format: str = ""
    transform: np.ndarray | None = None


def from_triplets(rows, cols, vals, n: int, where: str | Path) -> sp.csr_matrix:
    """Sparse K from (row, col, value) triplets (0-based); one stored triangle is mirrored.

    FE codes write a symmetric K as one triangle (Abaqus ``*MATRIX OUTPUT``, CalculiX,
    Harwell–Boeing ``RSA``, Nastran DMIG ``IFO=6``), in their own equation order. When no
    off-diagonal entry has its transpose in the file, the transposes are filled in by
    symmetry; otherwise the matrix is taken as written (and checked for symmetry later).
    Duplicates add up (assembly).
    """
    rows = np.asarray(rows, np.int64)
    cols = np.asarray(cols, np.int64)
    vals = np.asarray(vals, float)
    if rows.size and (rows.min() < 0 or cols.min() < 0 or rows.max() >= n or cols.max() >= n):
        raise file_error(where, f"an entry lies outside the {n}×{n} matrix")
    off = rows != cols
    # one triangle stored (in the file's own equation order, which need not be the order
    # of the labels): no off-diagonal entry has its transpose in the file
    directed = rows[off] * n + cols[off]
    mirrored = cols[off] * n + rows[off]
    if directed.size and not np.isin(mirrored, directed).any():
        rows, cols, vals = (np.concatenate([rows, cols[off]]),
                            np.concatenate([cols, rows[off]]),
                            np.concatenate([vals, vals[off]]))
    return sp.csr_matrix((vals, (rows, cols)), shape=(n, n))
