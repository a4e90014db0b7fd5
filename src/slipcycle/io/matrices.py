"""Reduced contact stiffness from files: slipcycle's ``.npz``, Matrix Market and the exports
of FE codes (Abaqus, CalculiX, ANSYS HBMAT / Harwell–Boeing, MATLAB ``.mat``, Nastran DMIG).

:func:`read_reduced_stiffness` reads any of them into a :class:`ReducedStiffness`, for 2-D
(one tangent per node) and 3-D (two tangents) contacts; :func:`read_case_stiffness` does so
for the ``stiffness_file`` key of a case. The layouts are described in
:mod:`slipcycle.io.fe_formats`; roles of the rows, node frames and the condensation of
retained rows in :mod:`slipcycle.io.fe_formats.dofmap`.

Sign conventions (those of :mod:`slipcycle.discrete.model`; J. R. Barber, J. Phys.: Conf.
Ser. 382 (2012) 012002, §3): v is the tangential slip and w the normal separation of a
contact node (w > 0 opens the gap); q, p are the reactions on the body, p compressive
positive; K = [[A, Bᵀ], [B, C]] with

    q = q^w + A v + Bᵀ w,      p = p^w + B v + C w.

A node frame is given by its outward unit normal n (out of the body, into the contact):
w and p act along −n; the tangents t1 (, t2) follow the rule of
:func:`slipcycle.io.fe_formats.dofmap.node_frames` unless given. In 3-D the tangential
block A is node-major: (node 0 t1, node 0 t2, node 1 t1, ...).

The original readers stay: an ``.npz`` file holds arrays ``A``, ``B``, ``C`` (N×N) and
optionally ``p_w``, ``q_w`` (reactions of basic load cases, (n_cases, N)), ``coords``
(N, 2) and ``dof_order``. A ``.mtx`` file holds the full reduced K (2N×2N); its
degree-of-freedom ordering is ``"tangential_first"`` ([v1..vN, w1..wN], the default) or
``"interleaved"`` ([v1, w1, v2, w2, ...]), stated in the file (``.npz``: a string array
``dof_order``; ``.mtx``: a comment line ``% dof_order: interleaved``) or passed by the
caller; when both are given they must agree. :func:`check_stiffness` applies the import
checks: A, B, C square N×N, finite, K symmetric (relative asymmetry ≤ ``rtol``; the
symmetric part is used) and positive definite (Cholesky), load arrays (n_cases, N).
"""

from __future__ import annotations

import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from scipy.io import mminfo

from slipcycle.io.case import CaseError, Section
from slipcycle.io.fe_formats import FORMATS, detect_format, read_raw
from slipcycle.io.fe_formats.common import (
    RawMatrix,
    StiffnessError,
    check_diagonal,
    file_error,
)
from slipcycle.io.fe_formats.dofmap import (
    ORDERINGS,
    DofMap,
    labelled_map,
    node_frames,
    read_dof_table,
    reduce_to_contact,
    standard_map,
    table_map,
)

__all__ = ["read_stiffness", "stiffness_nodes", "split_stiffness", "check_stiffness",
           "mtx_dof_order", "StiffnessError", "DOF_ORDERS", "ReducedStiffness",
           "read_reduced_stiffness", "read_case_stiffness", "FORMATS", "detect_format"]

DOF_ORDERS = ("tangential_first", "interleaved")


def _resolve_order(stated: str | None, given: str | None, where: str) -> str:
    for o in (stated, given):
        if o is not None and o not in DOF_ORDERS:
            raise StiffnessError("dof_order", f"must be one of {', '.join(DOF_ORDERS)}, got {o!r}")
    if stated is not None and given is not None and stated != given:
        raise StiffnessError("dof_order", f"{where} states {stated!r} but {given!r} was requested")
    return stated or given or "tangential_first"


def mtx_dof_order(path: str | Path) -> str | None:
    """The ordering stated in a Matrix Market file's comments (``% dof_order: ...``)."""
    with open(path, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            if not line.startswith("%"):
                break
            text = line.lstrip("%").strip()
            if text.lower().startswith("dof_order"):
                return text.split(":", 1)[-1].split("=", 1)[-1].strip()
    return None


def check_stiffness(data: dict, rtol: float = 1e-6) -> dict:
    """Check A, B, C (and optional load arrays) of a reduced model; return cleaned copies.

    Parameters
    ----------
    data : dict
        ``A``, ``B``, ``C`` (N, N) and optionally ``p_w``, ``q_w`` ((n_cases, N) or
        (N,)), ``coords`` (N, 2).
    rtol : float
        Largest accepted ‖K − Kᵀ‖_F / ‖K‖_F.

    Returns
    -------
    dict
        ``data`` with A, C replaced by their symmetric parts and K symmetrised.

    Raises
    ------
    StiffnessError
        Naming the array and the problem (shape, non-finite, asymmetric, indefinite).
    """
    out = dict(data)
    A = np.asarray(data["A"], float)
    if A.ndim != 2 or A.shape[0] != A.shape[1] or A.shape[0] == 0:
        raise StiffnessError("A", f"must be a non-empty square N×N matrix, got shape {A.shape}")
    n = A.shape[0]
    for name in ("A", "B", "C"):
        M = np.asarray(data[name], float)
        if M.shape != (n, n):
            raise StiffnessError(name, f"wrong shape: expected {n}×{n}, got "
                                 f"{'×'.join(map(str, M.shape))}")
        if not np.all(np.isfinite(M)):
            raise StiffnessError(name, "must contain only finite numbers (found nan or inf)")
    K = np.block([[A, np.asarray(data["B"], float).T],
                  [np.asarray(data["B"], float), np.asarray(data["C"], float)]])
    scale = np.linalg.norm(K)
    asym = np.linalg.norm(K - K.T) / scale if scale > 0 else 0.0
    if asym > rtol:
        i, j = np.unravel_index(np.argmax(np.abs(K - K.T)), K.shape)
        raise StiffnessError("K", f"not symmetric: relative asymmetry {asym:.2e} > {rtol:g} "
                             f"(largest at row {i}, column {j}; K = [[A, Bᵀ], [B, C]])")
    K = 0.5 * (K + K.T)
    try:
        np.linalg.cholesky(K)
    except np.linalg.LinAlgError:
        lam = np.linalg.eigvalsh(K)
        raise StiffnessError("K", f"not positive definite: smallest eigenvalue {lam[0]:.3e} "
                             f"(largest {lam[-1]:.3e}); a reduced stiffness must be SPD — "
                             "is the body supported against rigid motion?") from None
    out["A"], out["B"], out["C"] = K[:n, :n], K[n:, :n], K[n:, n:]
    for name in ("p_w", "q_w"):
        if name in data:
            v = np.asarray(data[name], float)
            if v.ndim == 1:
                v = v[None, :]
            if v.ndim != 2 or v.shape[1] != n:
                raise StiffnessError(name, f"wrong shape: expected (n_cases, {n}), got "
                                     f"{'×'.join(map(str, np.shape(data[name])))}")
            if not np.all(np.isfinite(v)):
                raise StiffnessError(name, "must contain only finite numbers")
            out[name] = v
    if "coords" in data and np.shape(data["coords"]) != (n, 2):
        raise StiffnessError("coords", f"wrong shape: expected ({n}, 2), got "
                             f"{'×'.join(map(str, np.shape(data['coords'])))}")
    return out


def split_stiffness(K: np.ndarray, dof_order: str = "tangential_first") -> dict:
    """Split a reduced K (2N×2N) into A (tangential), B (normal–tangential), C (normal).

    With v the tangential and w the normal degrees of freedom, K = [[A, Bᵀ], [B, C]].
    """
    K = np.asarray(K, float)
    if K.ndim != 2 or K.shape[0] != K.shape[1] or K.shape[0] % 2:
        raise ValueError(f"K must be square with an even size, got shape {K.shape}")
    n = K.shape[0] // 2
    if dof_order == "tangential_first":
        t, w = np.arange(n), np.arange(n, 2 * n)
    elif dof_order == "interleaved":
        t, w = np.arange(0, 2 * n, 2), np.arange(1, 2 * n, 2)
    else:
        raise ValueError(f"dof_order must be one of {DOF_ORDERS}, got {dof_order!r}")
    return {"A": K[np.ix_(t, t)], "B": K[np.ix_(w, t)], "C": K[np.ix_(w, w)]}


def _split_checked(K, order: str, check: bool, rtol: float) -> dict:
    """split_stiffness, refusing a full K whose upper-right block is not Bᵀ."""
    K = np.asarray(K, float)
    if check and K.ndim == 2 and K.shape[0] == K.shape[1] and K.size:
        scale = np.linalg.norm(K)
        asym = np.linalg.norm(K - K.T) / scale if scale > 0 else 0.0
        if not np.isfinite(asym):
            raise StiffnessError("K", "must contain only finite numbers (found nan or inf)")
        if asym > rtol:
            i, j = np.unravel_index(np.argmax(np.abs(K - K.T)), K.shape)
            raise StiffnessError("K", f"not symmetric: relative asymmetry {asym:.2e} > "
                                 f"{rtol:g} (largest at row {i}, column {j})")
    if K.ndim != 2 or K.shape[0] != K.shape[1] or K.shape[0] % 2:
        raise StiffnessError("K", f"must be square with an even size 2N, got shape {K.shape}")
    return split_stiffness(K, order)


def _read_npz(path: Path) -> dict:
    """The arrays of an ``.npz`` file, never unpickling anything.

    A file that is not a zip of ``.npy`` arrays, or holds object (pickled) arrays, is refused
    as "not a valid .npz of A, B, C" rather than with NumPy's advice to allow pickles.
    """
    what = ("not a valid .npz of arrays A, B, C (or K): an .npz file is a zip of numeric "
            ".npy arrays, as written by numpy.savez")
    try:
        data = np.load(path, allow_pickle=False)
    except (ValueError, EOFError, zipfile.BadZipFile):
        raise ValueError(what) from None
    if not isinstance(data, np.lib.npyio.NpzFile):     # a plain .npy renamed to .npz
        raise ValueError(what)
    try:
        with data:
            return {k: np.asarray(data[k]) for k in data.files}
    except (ValueError, OSError, EOFError, zipfile.BadZipFile, KeyError):
        # object arrays (pickles) and damaged members
        raise ValueError(what + " (a member is damaged or is not a numeric array)") from None


def stiffness_nodes(path: str | Path) -> int | None:
    """The number of contact nodes N of a stiffness file, read from its headers only.

    ``.npz``: the shape in the ``.npy`` header of ``A`` (N×N) or ``K`` (2N×2N); ``.mtx``:
    the size line (2N×2N). Nothing else is loaded, so a size check can run before a huge
    file is read. ``None`` when the headers cannot tell (the reader then reports why).
    """
    path = Path(path)
    try:
        _check_file(path)                           # never a device, FIFO or huge file
    except StiffnessError:
        return None                                 # the reader says why
    try:
        if path.suffix.lower() == ".mtx":
            from scipy.io import mminfo

            rows = int(mminfo(str(path))[0])
            return rows // 2
        with zipfile.ZipFile(path) as zf:
            for name, div in (("A.npy", 1), ("K.npy", 2)):
                if name in zf.namelist():
                    with zf.open(name) as fh:
                        version = np.lib.format.read_magic(fh)
                        read = (np.lib.format.read_array_header_1_0 if version == (1, 0)
                                else np.lib.format.read_array_header_2_0)
                        shape = read(fh)[0]
                    return int(shape[0]) // div if shape else None
    except (OSError, ValueError, zipfile.BadZipFile, EOFError, IndexError, TypeError):
        return None
    return None


def read_stiffness(path: str | Path, dof_order: str | None = None, *, check: bool = True,
                   rtol: float = 1e-6) -> dict:
    """Read A, B, C (and any load vectors, coordinates) from ``.npz`` or ``.mtx``.

    Parameters
    ----------
    path : ``.npz`` (arrays A, B, C, or K with ``dof_order``) or ``.mtx`` (full K).
    dof_order : str, optional
        Ordering of a full K when the file does not state it (or to confirm it); not
        used when the file holds A, B, C separately.
    check : bool
        Apply :func:`check_stiffness` (shapes, finite, symmetric, positive definite).

    Returns
    -------
    dict
        ``A``, ``B``, ``C`` as dense (N, N) float arrays, plus whatever optional arrays the
        file holds (``p_w``, ``q_w``, ``coords``, ...).

    Raises
    ------
    ValueError
        (:class:`StiffnessError` for content problems) naming the array and the problem.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".npz":
        out = _read_npz(path)
        for k in ("A", "B", "C", "K", "p_w", "q_w", "coords"):
            if k in out:
                _real(path, k, out[k])
        if "K" in out and "A" not in out:
            stated = str(out["dof_order"]) if "dof_order" in out else None
            order = _resolve_order(stated, dof_order, path.name)
            out.update(_split_checked(out.pop("K"), order, check, rtol))
        missing = [k for k in ("A", "B", "C") if k not in out]
        if missing:
            raise ValueError(f"{path.name} lacks array(s) {', '.join(missing)}")
    elif suffix == ".mtx":
        order = _resolve_order(mtx_dof_order(path), dof_order, path.name)
        K = read_matrix_market(path)
        K = K.toarray() if hasattr(K, "toarray") else np.asarray(K)
        out = _split_checked(K, order, check, rtol)
    else:
        raise ValueError(f"unsupported stiffness file type {suffix!r} (use .npz or .mtx)")
    if check:
        return check_stiffness(out, rtol)
    return out


# -- reduced stiffness of 2-D and 3-D contacts from any supported export ----------------------

def _readonly(a):
    if a is None:
        return None
    a = np.array(a)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class ReducedStiffness:
    """Reduced contact stiffness K = [[A, Bᵀ], [B, C]] of N contact nodes.

    The blocks map the relative displacements of the contact nodes (tangential slip v,
    normal separation w, w > 0 opening) to the reactions on the body (q tangential, p
    normal, compressive positive): q = q^w + A v + Bᵀ w, p = p^w + B v + C w (Barber,
    J. Phys.: Conf. Ser. 382 (2012) 012002, §3; the convention of
    :mod:`slipcycle.discrete.model`). K is checked symmetric (relative asymmetry ≤ 1e-6,
    its symmetric part kept) and positive definite on construction.

    Attributes
    ----------
    A : numpy.ndarray, shape (t N, t N)
        Tangential block, N/m; node-major (node 0 t1, node 0 t2, node 1 t1, ...).
    B : numpy.ndarray, shape (N, t N)
        Normal force per unit slip, N/m.
    C : numpy.ndarray, shape (N, N)
        Normal block, N/m.
    tangential_dims : int
        t: 1 (2-D) or 2 (3-D).
    nodes : numpy.ndarray of int, shape (N,)
        Node labels from the source file (0..N−1 if it has none), increasing.
    coordinates : numpy.ndarray, shape (N, 3), or None
        Node coordinates, m.
    normals : numpy.ndarray, shape (N, 3), or None
        Outward unit normals (out of the body, into the contact); w and p act along −n.
    tangents : numpy.ndarray, shape (N, t, 3), or None
        Unit tangents t1 (, t2) of each node.
    loads : dict of str to dict
        Load cases read with K: name → {"q": (t N,), "p": (N,)}, the reactions with every
        contact node held (q^w, p^w per unit of the case), N.
    source : str
        File and format, for provenance.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    tangential_dims: int = 1
    nodes: np.ndarray | None = None
    coordinates: np.ndarray | None = None
    normals: np.ndarray | None = None
    tangents: np.ndarray | None = None
    loads: dict = field(default_factory=dict)
    source: str = ""

    def __post_init__(self):
        t = self.tangential_dims
        if t not in (1, 2):
            raise StiffnessError("tangential_dims", f"must be 1 (2-D) or 2 (3-D), got {t!r}")
        C = np.asarray(self.C, float)
        if C.ndim != 2 or C.shape[0] != C.shape[1] or C.shape[0] == 0:
            raise StiffnessError("C", f"must be a non-empty square N×N matrix, got shape "
                                 f"{C.shape}")
        n = C.shape[0]
        A = np.asarray(self.A, float)
        B = np.asarray(self.B, float)
        for name, M, shape in (("A", A, (t * n, t * n)), ("B", B, (n, t * n))):
            if M.shape != shape:
                raise StiffnessError(name, f"wrong shape: expected {shape[0]}×{shape[1]} for "
                                     f"{n} nodes with {t} tangential direction(s), got "
                                     f"{'×'.join(map(str, M.shape))}")
        for name, M in (("A", A), ("B", B), ("C", C)):
            if not np.all(np.isfinite(M)):
                raise StiffnessError(name, "must contain only finite numbers (found nan or "
                                     "inf)")
        K = np.block([[A, B.T], [B, C]])
        scale = np.linalg.norm(K)
        asym = np.linalg.norm(K - K.T) / scale if scale > 0 else 0.0
        if asym > 1e-6:
            raise StiffnessError("K", f"not symmetric: relative asymmetry {asym:.2e} > 1e-06 "
                                 "(K = [[A, Bᵀ], [B, C]])")
        K = 0.5 * (K + K.T)
        try:
            np.linalg.cholesky(K)
        except np.linalg.LinAlgError:
            lam = np.linalg.eigvalsh(K)
            raise StiffnessError("K", f"not positive definite: smallest eigenvalue "
                                 f"{lam[0]:.3e} (largest {lam[-1]:.3e}); a reduced stiffness "
                                 "must be SPD — is the body supported against rigid "
                                 "motion?") from None
        tn = t * n
        nodes = np.arange(n) if self.nodes is None else np.asarray(self.nodes)
        if nodes.shape != (n,) or not np.issubdtype(nodes.dtype, np.integer):
            raise StiffnessError("nodes", f"must be {n} integer node labels")
        if np.unique(nodes).size != n:
            raise StiffnessError("nodes", "node labels must be distinct")
        for name, shape in (("coordinates", (n, 3)), ("normals", (n, 3)),
                            ("tangents", (n, t, 3))):
            v = getattr(self, name)
            if v is not None:
                v = np.asarray(v, float)
                if v.shape != shape or not np.all(np.isfinite(v)):
                    raise StiffnessError(name, f"must be finite with shape {shape}, got "
                                         f"{v.shape}")
                if name != "coordinates" and np.max(np.abs(np.linalg.norm(v, axis=-1) - 1)) > 1e-6:
                    raise StiffnessError(name, "must be unit vectors")
                object.__setattr__(self, name, _readonly(v))
        loads = {}
        for name, case in dict(self.loads).items():
            try:
                q = np.asarray(case["q"], float)
                p = np.asarray(case["p"], float)
            except (KeyError, TypeError, ValueError):
                raise StiffnessError(f"loads.{name}", "must be {'q': (tN,), 'p': (N,)}") from None
            if q.shape != (tn,) or p.shape != (n,):
                raise StiffnessError(f"loads.{name}", f"q must have {tn} and p {n} entries, "
                                     f"got {q.size} and {p.size}")
            if not (np.all(np.isfinite(q)) and np.all(np.isfinite(p))):
                raise StiffnessError(f"loads.{name}", "must contain only finite numbers")
            loads[str(name)] = {"q": _readonly(q), "p": _readonly(p)}
        object.__setattr__(self, "A", _readonly(K[:tn, :tn]))
        object.__setattr__(self, "B", _readonly(K[tn:, :tn]))
        object.__setattr__(self, "C", _readonly(K[tn:, tn:]))
        object.__setattr__(self, "nodes", _readonly(nodes.astype(np.int64)))
        object.__setattr__(self, "loads", loads)

    @property
    def n_nodes(self) -> int:
        """N, the number of contact nodes."""
        return self.C.shape[0]

    @property
    def K(self) -> np.ndarray:
        """The full reduced stiffness [[A, Bᵀ], [B, C]], ((t+1)N, (t+1)N), N/m."""
        return np.block([[self.A, self.B.T], [self.B, self.C]])

    def to_arrays(self) -> dict:
        """The arrays of slipcycle's ``.npz`` layout: ``A``, ``B``, ``C`` and, when load
        cases were read, ``p_w`` (n_cases, N), ``q_w`` (n_cases, t N) and ``load_cases``;
        ``coords`` when coordinates are known."""
        out = {"A": self.A, "B": self.B, "C": self.C}
        if self.loads:
            names = list(self.loads)
            out["p_w"] = np.array([self.loads[k]["p"] for k in names])
            out["q_w"] = np.array([self.loads[k]["q"] for k in names])
            out["load_cases"] = np.array(names, dtype=str)
        if self.coordinates is not None:
            out["coords"] = self.coordinates
        return out

    def __repr__(self) -> str:
        dims = "3-D" if self.tangential_dims == 2 else "2-D"
        return (f"<ReducedStiffness {self.n_nodes} nodes, {dims}, "
                f"loads={list(self.loads)}, source={self.source!r}>")


def _real(path: Path, name: str, arr: np.ndarray) -> np.ndarray:
    """``arr`` if it holds real numbers (float or integer dtype); a string, complex or
    boolean array is refused naming the file and the array, instead of being coerced
    (strings parsed as numbers, the imaginary part dropped, booleans read as 0/1)."""
    if arr.dtype.kind not in "fiu":
        raise file_error(path, f"array {name} holds {arr.dtype} values "
                         f"({_KIND_WORDS.get(arr.dtype.kind, 'not numbers')}); it must hold "
                         "real numbers (float or integer)")
    return arr


#: what a non-real dtype kind holds, for the message of :func:`_real`
_KIND_WORDS = {"U": "text", "S": "bytes", "c": "complex numbers", "b": "booleans",
               "O": "objects", "M": "dates", "m": "time spans", "V": "raw records"}


def _raw_npz(path: Path, keys: dict | None) -> RawMatrix:
    """An ``.npz``: blocks A, B, C (with loads, coordinates, frames) or a full K."""
    try:
        data = _read_npz(path)
    except ValueError as exc:
        raise file_error(path, str(exc)) from None
    names = {"A": "A", "B": "B", "C": "C", "K": "K", **(keys or {})}
    stated = {}
    if "dof_order" in data:
        stated["dof_order"] = str(data["dof_order"])
    if "tangential_dims" in data:
        stated["tangential_dims"] = int(data["tangential_dims"])
    if all(names[k] in data for k in ("A", "B", "C")):
        extra = {k: _real(path, names[k], data[names[k]]) for k in ("A", "B", "C")}
        for k in ("p_w", "q_w", "load_cases", "coords", "normal", "tangent"):
            if k in data:
                extra[k] = data[k] if k == "load_cases" else _real(path, k, data[k])
        return RawMatrix(None, stated=stated, extra=extra, format="npz")
    if names["K"] in data:
        labels = data["dof_labels"] if "dof_labels" in data else None
        return RawMatrix(np.asarray(_real(path, names["K"], data[names["K"]]), float),
                         labels=labels, stated=stated, format="npz")
    missing = [names[k] for k in ("A", "B", "C") if names[k] not in data]
    raise file_error(path, f"lacks array(s) {', '.join(missing)} (or a full {names['K']})")


def _check_mm_header(path: Path) -> None:
    """Refuse a Matrix Market file whose header declares no real symmetric-able matrix:
    ``complex`` (NumPy would drop the imaginary part with a warning), ``pattern`` (no
    values), ``skew-symmetric`` or ``hermitian`` (not a stiffness)."""
    try:
        rows, cols, _, _, fld, symm = mminfo(str(path))
    except (ValueError, OSError, IndexError, TypeError) as exc:
        raise file_error(path, f"not a readable Matrix Market file: {exc}") from None
    if fld == "complex":
        raise file_error(path, "is a complex Matrix Market matrix (field 'complex'); a "
                         "stiffness is real")
    if fld == "pattern":
        raise file_error(path, "is a pattern Matrix Market matrix: it holds no values")
    if symm in ("skew-symmetric", "hermitian"):
        raise file_error(path, f"is declared {symm}; a stiffness is symmetric")
    if rows != cols:
        raise file_error(path, f"K is {rows}×{cols}, not square")


def read_matrix_market(path: Path):
    """K of a real Matrix Market file (coordinate or array; general or symmetric), N/m.

    Parsed here rather than by :func:`scipy.io.mmread`, whose compiled reader crashes the
    interpreter (segmentation fault, SciPy 1.17) on a file cut inside a number such as
    ``3.6688E``: a truncated or damaged file is refused in one line instead.

    Returns
    -------
    scipy.sparse.csr_matrix (coordinate) or numpy.ndarray (array), shape (rows, cols)
    """
    _check_mm_header(path)
    rows, cols, entries, layout, _, symm = mminfo(str(path))
    lines = path.read_text(encoding="latin-1").splitlines()
    start = next(i for i, ln in enumerate(lines) if ln.strip() and not ln.startswith("%"))
    tokens = " ".join(lines[start + 1:]).split()
    sym = symm == "symmetric"
    need = (3 * entries if layout == "coordinate"
            else rows * (rows + 1) // 2 if sym else rows * cols)
    if len(tokens) != need:
        raise file_error(path, f"holds {len(tokens)} numbers after its size line where "
                         f"'{lines[start].strip()}' needs {need}"
                         + (" (file truncated?)" if len(tokens) < need else ""))
    try:
        vals = np.array(tokens, float)
    except ValueError:
        bad = next(t for t in tokens if not _is_float(t))
        raise file_error(path, f"{bad!r} is not a number (file truncated or damaged?)") \
            from None
    if layout == "coordinate":
        ijv = vals.reshape(-1, 3)
        i, j = ijv[:, 0] - 1, ijv[:, 1] - 1
        if np.any(i != np.round(i)) or np.any(j != np.round(j)) or i.min(initial=0) < 0 \
                or j.min(initial=0) < 0 or i.max(initial=0) >= rows or j.max(initial=0) >= cols:
            raise file_error(path, "an entry's row or column is not an index of the matrix")
        i, j, v = i.astype(np.int64), j.astype(np.int64), ijv[:, 2]
        if sym:
            off = i != j
            i, j, v = (np.concatenate([i, j[off]]), np.concatenate([j, i[off]]),
                       np.concatenate([v, v[off]]))
        return sp.csr_matrix((v, (i, j)), shape=(rows, cols))
    if not sym:
        return vals.reshape(cols, rows).T.copy()
    K = np.zeros((rows, rows))
    jj, ii = np.triu_indices(rows)                 # column by column, lower triangle
    K[ii, jj] = vals
    K[jj, ii] = vals
    return K


def _is_float(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def _raw_mtx(path: Path) -> RawMatrix:
    """A Matrix Market file: the full K; ``% dof_order:`` / ``% tangential_dims:`` comments."""
    stated = {}
    with open(path, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            if not line.startswith("%"):
                break
            text = line.lstrip("%").strip()
            for word in ("dof_order", "tangential_dims"):
                if text.lower().startswith(word):
                    stated[word] = text.split(":", 1)[-1].split("=", 1)[-1].strip()
    if "tangential_dims" in stated:
        try:
            stated["tangential_dims"] = int(stated["tangential_dims"])
        except ValueError:
            raise file_error(path, "the comment '% tangential_dims:' must be 1 or 2") from None
    K = read_matrix_market(path)
    return RawMatrix(K, stated=stated, format="matrix-market")


def _dof_map(raw: RawMatrix, dof_map, tangential_dims: int | None, where: str) -> DofMap:
    """The roles of the rows of ``raw`` (see :mod:`slipcycle.io.fe_formats.dofmap`)."""
    n = raw.K.shape[0] if raw.transform is None else raw.transform.shape[0]
    if isinstance(dof_map, DofMap):
        return dof_map
    stated_order = raw.stated.get("dof_order")
    stated_t = raw.stated.get("tangential_dims")
    if stated_t is not None and stated_t not in (1, 2):
        raise file_error(where, f"states tangential_dims = {stated_t!r}; must be 1 or 2")
    if stated_t is not None and tangential_dims is not None and stated_t != tangential_dims:
        raise file_error(where, f"states tangential_dims = {stated_t} ("
                         f"{'3-D' if stated_t == 2 else '2-D'}) but a "
                         f"{'3-D' if tangential_dims == 2 else '2-D'} model needs "
                         f"{tangential_dims}; the matrix is not reinterpreted")
    t = tangential_dims or stated_t or 1
    if dof_map is None:
        if raw.labels is not None:
            return labelled_map(raw.labels)
        return standard_map(n, _resolve_order(stated_order, None, where), t, where)
    if isinstance(dof_map, str) and dof_map in ORDERINGS:
        if raw.labels is not None:
            raise StiffnessError("dof_map", f"{where} labels its rows (node, dof); a standard "
                                 "ordering does not apply (give a table or leave it out)")
        if stated_order is not None and stated_order in DOF_ORDERS + ("xyz",) \
                and stated_order != dof_map:
            raise StiffnessError("dof_order", f"{where} states {stated_order!r} but "
                                 f"{dof_map!r} was requested")
        return standard_map(n, dof_map, t, where)
    return table_map(read_dof_table(dof_map), n, raw.labels, where)


def _from_blocks(raw: RawMatrix, tangential_dims: int | None, where: str) -> dict:
    """Fields of a ReducedStiffness from a file that holds A, B, C already."""
    A, B, C = (np.asarray(raw.extra[k], float) for k in ("A", "B", "C"))
    n = C.shape[0] if C.ndim == 2 else 0
    t = A.shape[0] // n if n and A.ndim == 2 and A.shape[0] % n == 0 else 1
    t = raw.stated.get("tangential_dims", t)
    if tangential_dims is not None and t != tangential_dims:
        raise file_error(where, f"A is {A.shape[0]}×{A.shape[0]} for {n} nodes: a "
                         f"{'3-D' if t == 2 else '2-D'} model ({t} tangential direction(s) "
                         f"per node), but a {'3-D' if tangential_dims == 2 else '2-D'} model "
                         "needs " f"{tangential_dims}; the matrix is not reinterpreted")
    loads = {}
    if "p_w" in raw.extra and "q_w" in raw.extra:
        pw = np.atleast_2d(np.asarray(raw.extra["p_w"], float))
        qw = np.atleast_2d(np.asarray(raw.extra["q_w"], float))
        if pw.shape[0] != qw.shape[0]:
            raise file_error(where, f"p_w has {pw.shape[0]} load cases but q_w {qw.shape[0]}")
        names = ([str(s) for s in np.atleast_1d(raw.extra["load_cases"])]
                 if "load_cases" in raw.extra else [f"case{k}" for k in range(pw.shape[0])])
        if len(names) != pw.shape[0]:
            names = [f"case{k}" for k in range(pw.shape[0])]
        loads = {name: {"q": qw[k], "p": pw[k]} for k, name in enumerate(names)}
    coords = None
    if "coords" in raw.extra:
        xy = np.asarray(raw.extra["coords"], float)
        if xy.ndim == 2 and xy.shape[0] == n and xy.shape[1] in (2, 3):
            coords = np.pad(xy, ((0, 0), (0, 3 - xy.shape[1])))
    normals = tangents = None
    if "normal" in raw.extra and "tangent" in raw.extra and t == 2:
        # per-node frames of slipcycle's 3-D reduction, normal stored into the body
        e = np.asarray(raw.extra["normal"], float)
        tg = np.asarray(raw.extra["tangent"], float)
        if e.shape == (n, 3) and tg.shape == (n, 2, 3):
            normals, tangents = -e, tg
    if "normal" in raw.extra and "tangent" in raw.extra and t == 1:
        # slipcycle's FE reduction stores the normal pointing into the body (fe.contact)
        e = np.pad(np.asarray(raw.extra["normal"], float).ravel(), (0, 1))[:3]
        tg = np.pad(np.asarray(raw.extra["tangent"], float).ravel(), (0, 1))[:3]
        if e.shape == (3,) and tg.shape == (3,) and np.isclose(np.linalg.norm(e), 1):
            normals = np.tile(-e, (n, 1))
            tangents = np.tile(tg, (n, 1, 1))
    return {"A": A, "B": B, "C": C, "tangential_dims": t, "coordinates": coords,
            "normals": normals, "tangents": tangents, "loads": loads}


def read_reduced_stiffness(path, *, format: str | None = None,  # noqa: A002 (the API word)
                           tangential_dims: int | None = None, dof_map=None,
                           keys: dict | None = None, frames=None,
                           condense_retained: bool = True,
                           retained=None, contact_nodes=None) -> ReducedStiffness:
    """Read a reduced contact stiffness from an ``.npz``, Matrix Market, Abaqus, CalculiX,
    Harwell–Boeing (ANSYS HBMAT), MATLAB or Nastran DMIG export.

    Parameters
    ----------
    path : str or Path
        The file.
    format : str, optional
        One of :data:`FORMATS`; inferred from the suffix and contents when None.
    tangential_dims : {1, 2}, optional
        1 for a 2-D model, 2 for a 3-D one. A matrix whose nodes carry the other number of
        dofs is refused, never reinterpreted. None: as the file says (1 for an unlabelled
        K that states nothing).
    dof_map : str, path, list of rows or DofMap, optional
        Roles of the rows (:mod:`slipcycle.io.fe_formats.dofmap`): an ordering
        (``"tangential_first"``, ``"interleaved"``, ``"xyz"``), a CSV file or list of
        ``(node, dof, role)`` rows. Default: the file's labels, else its stated ordering,
        else ``"tangential_first"``.
    keys : dict, optional
        Names of the variables holding ``K`` (and ``A``, ``B``, ``C``, ``dof_labels``,
        ``loads``, and ``L``: physical dofs u = L q of a reduced-order model's coordinates
        q, as tmdsimpy's ROMs store it) in a ``.mat`` file, of ``A``, ``B``, ``C``, ``K``
        in an ``.npz``, or ``{"matrix": "KAAX", "loads": "PAX"}`` for DMIG names.
    frames : dict, optional
        Node frames, ``{"normal": [nx, ny, nz]}`` (outward normal; one for every node or
        one per node) and optionally ``"t1"``; needed when the rows are global x, y, z.
    condense_retained : bool
        Condense the rows that are not contact directions out (static condensation);
        False refuses a file that has any.
    retained : sequence of int, optional
        Node labels whose every row is retained (condensed out), e.g. interior nodes of an
        Abaqus substructure.
    contact_nodes : sequence of int, optional
        The contact node labels; every row of every other node is retained (for a full
        model's K, e.g. CalculiX ``.sti``).

    Returns
    -------
    ReducedStiffness

    Raises
    ------
    StiffnessError
        One line naming the file (or key) and the problem: unreadable file, wrong format,
        dof count that does not match the map, a 3-D matrix for a 2-D model (or the
        reverse), K not symmetric, not positive definite after condensation, NaN.
    """
    path = Path(path)
    where = path.name
    _check_file(path)
    fmt = format or detect_format(path)
    if fmt not in FORMATS:
        raise StiffnessError("format", f"must be one of {', '.join(FORMATS)}, got {fmt!r}")
    if tangential_dims not in (None, 1, 2):
        raise StiffnessError("tangential_dims", f"must be 1 or 2, got {tangential_dims!r}")
    if fmt == "npz":
        raw = _raw_npz(path, keys)
    elif fmt == "matrix-market":
        raw = _raw_mtx(path)
    else:
        raw = read_raw(path, fmt, keys)
    source = f"{path} ({fmt})"
    if raw.K is None:
        if dof_map is not None or retained is not None or contact_nodes is not None:
            raise StiffnessError("dof_map", f"{where} holds the blocks A, B, C already; "
                                 "a dof map or retained nodes do not apply")
        fields = _from_blocks(raw, tangential_dims, where)
        if frames is not None:
            fields["normals"], fields["tangents"] = node_frames(
                frames, fields["C"].shape[0], fields["tangential_dims"])
        return _construct(where, **fields, nodes=None, source=source)
    check_diagonal(raw.K, raw.labels if raw.transform is None else None, where)
    _check_labelled(raw, where, dof_map, retained is not None or contact_nodes is not None)
    dmap = _dof_map(raw, dof_map, tangential_dims, where)
    if retained is not None:
        dmap = dmap.with_retained(retained, where)
    if contact_nodes is not None:
        dmap = dmap.with_contact_nodes(contact_nodes, where)
    red = reduce_to_contact(raw.K, dmap, tangential_dims=tangential_dims, frames=frames,
                            loads=raw.loads, condense_retained=condense_retained, where=where,
                            transform=raw.transform)
    coords = None
    if raw.coordinates and all(int(j) in raw.coordinates for j in red["nodes"]):
        coords = np.array([raw.coordinates[int(j)] for j in red["nodes"]], float)
    return _construct(where, A=red["A"], B=red["B"], C=red["C"], tangential_dims=red["t"],
                      nodes=red["nodes"], coordinates=coords, normals=red["normals"],
                      tangents=red["tangents"], loads=red["loads"], source=source)


def _check_file(path: Path) -> None:
    """Refuse, before reading it, a path that is no regular file of a sane size (a device
    such as ``/dev/zero`` or a FIFO would be read forever, a 10 GB file would exhaust the
    memory budget): :func:`slipcycle.io.files.check_input_file`, naming the file."""
    from slipcycle.io.files import check_input_file

    try:
        check_input_file(path, str(path), what="stiffness file")
    except CaseError as exc:                        # named in full: "/dev/zero", not "zero"
        raise StiffnessError(str(path), exc.problem) from None


def _check_labelled(raw: RawMatrix, where: str, dof_map, by_node: bool) -> None:
    """Refuse an export whose labelling file is missing when its rows must be matched to
    nodes (no dof map given, or retained / contact nodes named)."""
    if raw.labels is not None or raw.missing_labels is None:
        return
    table = dof_map is not None and not (isinstance(dof_map, str) and dof_map in ORDERINGS)
    if table or (dof_map is not None and not by_node):
        return
    writer = ("CalculiX writes it beside the .sti" if raw.missing_labels.endswith(".dof")
              else "ANSYS HBMAT writes it with Mapping = YES")
    raise file_error(where, f"{raw.missing_labels} is missing beside it: that file gives "
                     f"the node and dof of each row ({writer}); without it the rows cannot "
                     "be matched to nodes (or give a dof_map table)")


def _construct(where: str, **fields) -> ReducedStiffness:
    """The ReducedStiffness of a file; its checks' errors name the file and the array."""
    try:
        return ReducedStiffness(**fields)
    except StiffnessError as exc:
        raise file_error(where, f"{exc.key}: {exc.problem}") from None


#: option of :func:`read_reduced_stiffness` → key of the ``stiffness`` table of a case
_CASE_KEYS = {"format": "format", "dof_map": "dof_map", "retained": "retained",
              "contact_nodes": "contact_nodes", "frames.normal": "normal", "frames.t1": "t1",
              "frames": "normal", "tangential_dims": "stiffness_file"}


def read_case_stiffness(sec: Section, path: Path, tangential_dims: int) -> ReducedStiffness:
    """The reduced stiffness a case table names: ``stiffness_file`` (``path``) with the
    optional ``dof_order`` and ``stiffness`` table keys (``format``, ``dof_map``, ``keys``,
    ``retained``, ``contact_nodes``, ``normal``, ``t1``, ``condense_retained``).

    Parameters
    ----------
    sec : Section
        The model's table (``[discrete]``).
    path : Path
        The resolved ``stiffness_file``.
    tangential_dims : int
        1 for a 2-D model, 2 for a 3-D one.

    Returns
    -------
    ReducedStiffness

    Raises
    ------
    CaseError
        Under the key at fault: ``<table>.stiffness_file`` for the file and its contents,
        ``<table>.stiffness.<key>`` for an option.
    """
    order = (sec.string("dof_order", choices=DOF_ORDERS + ("xyz",))
             if sec.has("dof_order") else None)
    st = sec.table("stiffness", None)
    opts: dict = {}
    if st is not None:
        if st.has("format"):
            opts["format"] = st.string("format", choices=FORMATS)
        dof_map = st.raw("dof_map", None)
        if isinstance(dof_map, str) and dof_map not in ORDERINGS:
            opts["dof_map"] = st.path("dof_map")
        elif dof_map is not None:
            opts["dof_map"] = dof_map
        keys = st.table("keys", None)
        if keys is not None:
            opts["keys"] = {k: keys.string(k) for k in list(keys.data)}
        for name in ("retained", "contact_nodes"):
            if st.has(name):
                v = st.array(name, shape=(None,))
                if np.any(v != np.round(v)):
                    raise st.error(name, "must be a list of integer node labels")
                opts[name] = v.astype(np.int64)
        frames = {k: st.array(k, shape=(None,)) for k in ("normal", "t1") if st.has(k)}
        if frames:
            if "normal" not in frames:
                raise st.error("normal", "required with t1 (the outward unit normal)")
            opts["frames"] = frames
        opts["condense_retained"] = st.bool("condense_retained", True)
        st.finish()
    if order is not None:
        if "dof_map" in opts:
            raise sec.error("dof_order", "give either dof_order or stiffness.dof_map, not both")
        opts["dof_map"] = order
    try:
        return read_reduced_stiffness(path, tangential_dims=tangential_dims, **opts)
    except StiffnessError as exc:
        sub = _CASE_KEYS.get(exc.key) or ("keys" if exc.key.startswith("keys") else None)
        if sub is None or sub == "stiffness_file" or exc.key in (path.name, str(path)):
            problem = (exc.problem if exc.key in (path.name, str(path))
                       else f"{exc.key}: {exc.problem}")
            raise CaseError(sec.key("stiffness_file"), f"{path.name}: {problem}") from None
        raise CaseError(sec.key(f"stiffness.{sub}"), exc.problem) from None
