"""Reading reduced stiffness matrices from files (``.npz`` or Matrix Market ``.mtx``).

An ``.npz`` file holds arrays named ``A``, ``B``, ``C`` (N×N) and optionally ``p_w``,
``q_w`` (reactions of basic load cases, (n_cases, N)), ``coords`` (N, 2) and ``dof_order``.
A ``.mtx`` file holds the full reduced K (2N×2N); its degree-of-freedom ordering is
``"tangential_first"`` ([v1..vN, w1..wN], the default) or ``"interleaved"``
([v1, w1, v2, w2, ...]). The ordering can be stated in the file (``.npz``: a string
array ``dof_order``; ``.mtx``: a comment line ``% dof_order: interleaved``) or passed by
the caller; when both are given they must agree.

:func:`check_stiffness` applies the import checks: A, B, C square N×N,
finite, K = [[A, Bᵀ], [B, C]] symmetric (relative asymmetry ≤ ``rtol``; the symmetric
part is used) and positive definite (Cholesky), load arrays (n_cases, N). Sign
conventions: v tangential slip, w normal separation, p compressive positive,
q = q^w + A v + Bᵀ w, p = p^w + B v + C w.
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np

from slipcycle.errors import InputError

__all__ = ["read_stiffness", "stiffness_nodes", "split_stiffness", "check_stiffness",
           "mtx_dof_order", "StiffnessError", "DOF_ORDERS"]

DOF_ORDERS = ("tangential_first", "interleaved")


class StiffnessError(InputError):
    """A reduced stiffness file is inconsistent; ``key`` names the offending array."""


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
        if "K" in out and "A" not in out:
            stated = str(out["dof_order"]) if "dof_order" in out else None
            order = _resolve_order(stated, dof_order, path.name)
            out.update(_split_checked(out.pop("K"), order, check, rtol))
        missing = [k for k in ("A", "B", "C") if k not in out]
        if missing:
            raise ValueError(f"{path.name} lacks array(s) {', '.join(missing)}")
    elif suffix == ".mtx":
        from scipy.io import mmread

        order = _resolve_order(mtx_dof_order(path), dof_order, path.name)
        K = mmread(str(path))
        K = K.toarray() if hasattr(K, "toarray") else np.asarray(K)
        out = _split_checked(K, order, check, rtol)
    else:
        raise ValueError(f"unsupported stiffness file type {suffix!r} (use .npz or .mtx)")
    if check:
        return check_stiffness(out, rtol)
    return out
