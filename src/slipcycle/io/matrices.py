"""Reading reduced stiffness matrices from files (``.npz`` or Matrix Market ``.mtx``).

An ``.npz`` file holds arrays named ``A``, ``B``, ``C`` (N×N) and optionally ``p_w``,
``q_w`` (reactions of basic load cases, (n_cases, N)), ``coords`` (N, 2) and ``dof_order``.
A ``.mtx`` file holds the full reduced K (2N×2N); its degree-of-freedom ordering is
``"tangential_first"`` ([v1..vN, w1..wN], the default) or ``"interleaved"``
([v1, w1, v2, w2, ...]).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["read_stiffness", "split_stiffness", "DOF_ORDERS"]

DOF_ORDERS = ("tangential_first", "interleaved")


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


def read_stiffness(path: str | Path, dof_order: str | None = None) -> dict:
    """Read A, B, C (and any load vectors, coordinates) from ``.npz`` or ``.mtx``.

    Returns
    -------
    dict
        ``A``, ``B``, ``C`` as dense (N, N) float arrays, plus whatever optional arrays the
        file holds (``p_w``, ``q_w``, ``coords``, ...).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".npz":
        with np.load(path, allow_pickle=False) as data:
            out = {k: np.asarray(data[k]) for k in data.files}
        if "K" in out and "A" not in out:
            order = dof_order or str(out.get("dof_order", "tangential_first"))
            out.update(split_stiffness(out.pop("K"), order))
        missing = [k for k in ("A", "B", "C") if k not in out]
        if missing:
            raise ValueError(f"{path.name} lacks array(s) {', '.join(missing)}")
        return out
    if suffix == ".mtx":
        from scipy.io import mmread

        K = mmread(str(path))
        K = K.toarray() if hasattr(K, "toarray") else np.asarray(K)
        return split_stiffness(K, dof_order or "tangential_first")
    raise ValueError(f"unsupported stiffness file type {suffix!r} (use .npz or .mtx)")
