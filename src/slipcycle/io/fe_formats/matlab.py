"""MATLAB ``.mat`` files: v4/v5/v7 (:func:`scipy.io.loadmat`) and v7.3 (HDF5, via h5py).

Reduced-order models kept in MATLAB (e.g. the Hurty/Craig–Bampton ROMs of the
tmdsimpy examples, with variables ``K``, ``M``, ``R``, ``Fv``) hold the stiffness as a
matrix variable. The variables are named by ``keys``:

- ``K`` (default ``"K"``): the stiffness (dense or sparse), rows in the order the dof map
  describes;
- ``A``, ``B``, ``C``: the blocks themselves, when the file holds them instead of K;
- ``dof_labels``: an (n, 2) integer array of (node, dof) per row (dof 1–3 = x, y, z);
- ``loads``: nodal force vectors, (n,) or (n, m) (one column per load case), N;
- ``L``: for a reduced-order model whose coordinates q are not all physical (modal
  coordinates of a Hurty/Craig–Bampton reduction), the physical dofs u = L q (m × n);
  ``dof_labels`` and the dof map then describe the m rows of L, and the contact rows are
  reduced by u_c = L_c q (see :func:`slipcycle.io.fe_formats.dofmap.reduce_to_contact`).
  Not read unless named (tmdsimpy's ROMs: ``keys = {L = "L"}``).

A v7.3 file is HDF5 with MATLAB's column-major layout: arrays are transposed on reading
and a sparse matrix is the group (``data``, ``ir``, ``jc``) of its compressed columns
(MATLAB, "MAT-File Versions"; MAT-file Level 5 format).
"""

from __future__ import annotations

import importlib
from pathlib import Path

import numpy as np
import scipy.io as sio
import scipy.sparse as sp

from slipcycle.io.fe_formats.common import RawMatrix, StiffnessError, file_error

__all__ = ["read", "KEY_NAMES"]

KEY_NAMES = ("K", "A", "B", "C", "dof_labels", "loads", "L")


def _is_v73(path: Path) -> bool:
    with open(path, "rb") as fh:
        head = fh.read(520)
    return b"MATLAB 7.3" in head[:128] or head[512:520] == b"\x89HDF\r\n\x1a\n" \
        or head.startswith(b"\x89HDF")


def _h5py():
    """h5py, imported on first use (optional, and slow to import), or None."""
    try:
        return importlib.import_module("h5py")
    except ImportError:
        return None


def _load_v73(path: Path) -> dict:
    h5py = _h5py()
    if h5py is None:
        raise file_error(path, "is a MATLAB v7.3 (HDF5) file and h5py is not installed: "
                         "install h5py, or save the file with save(..., '-v7')")
    out = {}
    try:
        with h5py.File(path, "r") as f:
            for name, obj in f.items():
                if name.startswith("#"):
                    continue
                if isinstance(obj, h5py.Group) and "MATLAB_sparse" in obj.attrs:
                    nrow = int(obj.attrs["MATLAB_sparse"])
                    jc = np.asarray(obj["jc"], np.int64)
                    data = (np.asarray(obj["data"], float) if "data" in obj
                            else np.zeros(jc[-1]))
                    ir = np.asarray(obj["ir"], np.int64) if "ir" in obj else np.zeros(0, int)
                    out[name] = sp.csc_matrix((data, ir, jc), shape=(nrow, jc.size - 1))
                elif isinstance(obj, h5py.Dataset) and obj.dtype.kind in "fiu":
                    out[name] = np.asarray(obj, float).T
    except OSError as exc:
        raise file_error(path, f"cannot read the MATLAB v7.3 (HDF5) file: {exc}") from None
    return out


def _load(path: Path) -> dict:
    if _is_v73(path):
        return _load_v73(path)
    try:
        data = sio.loadmat(str(path), squeeze_me=False, struct_as_record=True)
    except NotImplementedError:                     # scipy: "use HDF reader" (v7.3)
        return _load_v73(path)
    except (ValueError, TypeError, OSError, EOFError, IndexError, KeyError) as exc:
        raise file_error(path, f"not a readable MATLAB .mat file: {exc}") from None
    return {k: v for k, v in data.items() if not k.startswith("__")}


def _numeric(data: dict, name: str, path: Path):
    v = data[name]
    if sp.issparse(v):
        if np.iscomplexobj(v.data):
            raise file_error(path, f"variable {name!r} is complex; a stiffness is real")
        return sp.csr_matrix(v, dtype=float)
    v = np.asarray(v)
    if v.dtype.kind == "c":
        raise file_error(path, f"variable {name!r} is complex; a stiffness is real")
    if v.dtype.kind not in "fiub":
        raise file_error(path, f"variable {name!r} is not a numeric array (MATLAB class "
                         f"{v.dtype})")
    return v.astype(float)


def read(path: Path, keys: dict | None = None) -> RawMatrix:
    """K (or A, B, C), labels and loads from a ``.mat`` file (see module docstring)."""
    path = Path(path)
    keys = dict(keys or {})
    unknown = sorted(set(keys) - set(KEY_NAMES))
    if unknown:
        raise StiffnessError(f"keys.{unknown[0]}", "unknown key; the variables named are "
                             + ", ".join(KEY_NAMES))
    data = _load(path)
    names = {k: keys.get(k, k) for k in KEY_NAMES}
    listing = ", ".join(sorted(data)) or "none"
    if names["K"] in data:
        K = _numeric(data, names["K"], path)
        if K.ndim != 2 or K.shape[0] != K.shape[1]:
            raise file_error(path, f"variable {names['K']!r} is {K.shape}, not a square "
                             "matrix")
        n = K.shape[0]
        transform = None
        if "L" in keys:
            if names["L"] not in data:
                raise file_error(path, f"holds no variable {names['L']!r} (variables: "
                                 f"{listing})")
            transform = _numeric(data, names["L"], path)
            transform = transform.toarray() if hasattr(transform, "toarray") else transform
            if transform.ndim != 2 or transform.shape[1] != n:
                raise file_error(path, f"variable {names['L']!r} must have {n} columns (one "
                                 f"per coordinate of K), got shape {transform.shape}")
        m = n if transform is None else transform.shape[0]
        labels = None
        if names["dof_labels"] in data:
            labels = np.asarray(_numeric(data, names["dof_labels"], path))
            if labels.shape == (2, m) and m != 2:
                labels = labels.T
            if labels.shape != (m, 2) or np.any(labels != np.round(labels)):
                raise file_error(path, f"variable {names['dof_labels']!r} must be an "
                                 f"({m}, 2) integer array of (node, dof) per row"
                                 + (" of L" if transform is not None else ""))
            labels = labels.astype(np.int64)
        loads = {}
        if names["loads"] in data:
            F = _numeric(data, names["loads"], path)
            F = F.toarray() if sp.issparse(F) else np.asarray(F)
            F = F.reshape(n, -1) if F.size == n else F
            if F.ndim == 2 and F.shape[0] != n and F.shape[1] == n:
                F = F.T
            if F.ndim != 2 or F.shape[0] != n:
                raise file_error(path, f"variable {names['loads']!r} must have {n} rows "
                                 f"(one per row of K), got shape {F.shape}")
            base = names["loads"]
            loads = {(base if F.shape[1] == 1 else f"{base}{k + 1}"): F[:, k]
                     for k in range(F.shape[1])}
        return RawMatrix(K, labels=labels, loads=loads, format="matlab", transform=transform)
    if all(names[k] in data for k in ("A", "B", "C")):
        extra = {k: np.asarray(_numeric(data, names[k], path).toarray()
                               if sp.issparse(data[names[k]])
                               else _numeric(data, names[k], path)) for k in ("A", "B", "C")}
        return RawMatrix(None, extra=extra, format="matlab")
    raise file_error(path, f"holds no variable {names['K']!r} (variables: {listing}); name "
                     "the stiffness with keys = {K = \"...\"}")
