"""Reading FE exports (``slipcycle.io.matrices.read_reduced_stiffness``): a CalculiX
``SOLVER=MATRIXSTORAGE`` full model (``.sti`` + ``.dof``; 30 000 dofs, 0.36 M stored
entries) condensed onto 200 contact nodes (3-D), and an Abaqus/CalculiX substructure
(``*USER ELEMENT`` layout, 600 dofs dense, 0.18 M values). Median of 3 reads.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from slipcycle.io.matrices import read_reduced_stiffness


def _chain(n_nodes: int, seed: int = 0) -> sp.csr_matrix:
    """SPD (diagonally dominant) banded K of a chain of 3-dof nodes."""
    n = 3 * n_nodes
    rng = np.random.default_rng(seed)
    parts = [sp.diags(rng.uniform(-1, 1, n - off), -off, shape=(n, n)) for off in range(1, 12)]
    L = sum(parts)
    return (L + L.T + 30 * sp.identity(n)).tocsr()


def _write_sti(d: Path, n_nodes: int) -> Path:
    K = sp.triu(_chain(n_nodes)).tocoo()
    order = np.lexsort((K.row, K.col))              # column by column
    rows, cols, vals = K.row[order] + 1, K.col[order] + 1, K.data[order]
    with open(d / "job.sti", "w") as fh:
        fh.writelines(f"{i:10d}{j:10d} {v:23.16e}\n" for i, j, v in zip(rows, cols, vals,
                                                                       strict=True))
    (d / "job.dof").write_text("".join(f"{a}.{k}\n" for a in range(1, n_nodes + 1)
                                       for k in (1, 2, 3)))
    return d / "job.sti"


def _write_user_element(d: Path, n_nodes: int) -> Path:
    K = _chain(n_nodes).toarray()
    n = K.shape[0]
    out = ["**", f"*USER ELEMENT, NODES= {n_nodes}, LINEAR", "** ELEMENT NODES",
           "** " + ", ".join(str(a) for a in range(1, n_nodes + 1)), "1, 2, 3",
           "*MATRIX,TYPE=STIFFNESS"]
    for i in range(n):
        row = [f"{v:.16e}" for v in K[i, :i + 1]]
        out += [" , ".join(row[k:k + 4]) for k in range(0, len(row), 4)]
    (d / "sub.mtx").write_text("\n".join(out) + "\n")
    return d / "sub.mtx"


def _median_read(path: Path, **kw) -> float:
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        read_reduced_stiffness(path, frames={"normal": [0, 0, -1]}, **kw)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def benchmarks() -> list[dict]:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        sti = _write_sti(d, 10_000)
        t = _median_read(sti, contact_nodes=list(range(1, 201)))
        rows.append({"name": "calculix .sti 30k dofs -> 200 contact nodes (3-D)", "value": t,
                     "unit": "s", "target": "<= 15", "ok": t <= 15})
        ue = _write_user_element(d, 200)
        t = _median_read(ue, contact_nodes=list(range(1, 101)))
        rows.append({"name": "substructure *USER ELEMENT 600 dofs dense -> 100 nodes",
                     "value": t, "unit": "s", "target": "<= 5", "ok": t <= 5})
    return rows
