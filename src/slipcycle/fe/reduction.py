"""From an assembled finite-element problem to A, B, C and p^w, q^w.

The global displacement vector is written as u = T z + u₀ with z = [y; d]:

- y: every degree of freedom that is neither prescribed, tied to a rigid platen, nor a
  body-1 contact DOF, followed by the platen's translations;
- d = [v₁…v_N, (w₁−g₁)…(w_N−g_N)]: the relative displacements of the contact pairs
  (:mod:`slipcycle.fe.contact`); a body-1 contact node moves as u¹ = u² + t v + n (w − g)
  (u² = 0 for a rigid flat).

With K' = Tᵀ K T and f' = Tᵀ (f − K u₀), equilibrium with the contact reactions r
conjugate to d reads K' z = f' + [0; r]. Condensing y out (:func:`schur_complement`)
gives r = K_red d + r_f; the initial gap enters through d, so

    [q; p] = K_red [v; w] + [q^w; p^w],     [q^w; p^w] = r_f − K_red [0; g],

K_red = [[A, Bᵀ], [B, C]]. Each basic load case contributes one column of p^w, q^w per
unit of its load; the initial-gap case (``gap``) contributes −[Bᵀ g; C g] once.
"""

from __future__ import annotations

import json
import os
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from slipcycle.condensation import schur_complement
from slipcycle.fe.assembly import BodyDofs
from slipcycle.fe.contact import ContactSet
from slipcycle.figure_task import figure_task
from slipcycle.materials import dundurs_beta
from slipcycle.result import _Contract, _fmt, _html_table

__all__ = ["LoadCase", "Problem", "ReducedModel", "reduce_problem", "transformation"]


@dataclass
class LoadCase:
    """One basic load case, applied with unit magnitude.

    Attributes
    ----------
    name : str
        e.g. ``"normal"``, ``"tangential"``, ``"gap"``.
    unit : str
        What "one unit" of the case is: ``"N"`` (force), ``"m"`` (displacement) or
        ``"1"`` (the initial gap, used as it is).
    description : str
    f : numpy.ndarray, shape (n,), optional
        Nodal forces, N.
    u_fixed : numpy.ndarray, shape (n_fixed,), optional
        Values of the prescribed DOFs (``Problem.fixed``), m.
    f_master : numpy.ndarray, shape (n_master,), optional
        Forces on the platen translations, N.
    gap : bool
        The initial-gap case.
    """

    name: str
    unit: str
    description: str = ""
    f: np.ndarray | None = None
    u_fixed: np.ndarray | None = None
    f_master: np.ndarray | None = None
    gap: bool = False


@dataclass
class Problem:
    """An assembled model ready for reduction.

    Attributes
    ----------
    K : scipy.sparse matrix, shape (n, n)
        Block-diagonal stiffness of all bodies, N/m.
    dofs : list of BodyDofs
    contact : ContactSet
    fixed : numpy.ndarray of int
        Global DOFs with prescribed displacement (zero unless a load case sets them).
    ties : list of (numpy.ndarray of int, str)
        Groups of global DOFs moving as one master translation (rigid platen), with the
        master's name (e.g. ``"platen_x"``).
    cases : list of LoadCase
    info : dict
        Geometry description for the output metadata.
    """

    K: sp.csr_matrix
    dofs: list[BodyDofs]
    contact: ContactSet
    fixed: np.ndarray
    ties: list = field(default_factory=list)
    cases: list[LoadCase] = field(default_factory=list)
    info: dict = field(default_factory=dict)

    @property
    def ndofs(self) -> int:
        return self.K.shape[0]


#: unit of every numeric entry of :meth:`ReducedModel.summary`
REDUCED_UNITS = {"n_contact_nodes": "1", "n_dofs": "1", "coupling_B_over_A": "1",
                 "dundurs_beta": "1", "thickness": "m"}


def _beta(info: dict) -> float | None:
    """Dundurs β of the model's bodies from its metadata (None if not known)."""
    g = info.get("geometry")
    if g in ("block_on_rigid", "mesh") and "E" in info:
        return float(dundurs_beta(info["E"], info["nu"]))
    pair = {"two_blocks": ("upper", "lower"), "cylinder_on_block": ("cylinder", "block")}
    if g in pair:
        b1, b2 = (info[k] for k in pair[g])
        return float(dundurs_beta(b1["E"], b1["nu"], b2["E"], b2["nu"]))
    return None


@dataclass(repr=False)
class ReducedModel(_Contract):
    """Reduced stiffness of the contact nodes and the load vectors.

    Offers the analysis contract: :meth:`summary` (with ``units``), :meth:`to_dataset`,
    :meth:`figures`, a one-line ``repr`` and an HTML table; :meth:`save` writes the
    ``.npz`` of ``slipcycle reduce``.

    Attributes
    ----------
    A, B, C : numpy.ndarray, shape (N, N)
        Blocks of K = [[A, Bᵀ], [B, C]], N/m; A tangential, C normal, B normal force per
        unit slip.
    q_w, p_w : numpy.ndarray, shape (n_cases, N)
        Reactions with every node held at v = w = 0, per unit of each load case (N per
        N, N per m, or N for the gap case); p compressive positive.
    load_cases, load_units : list of str
    coords : numpy.ndarray, shape (N, 2)
        Body-1 contact node coordinates, m.
    gap : numpy.ndarray, shape (N,)
        Initial gaps, m.
    normal, tangent : numpy.ndarray, shape (2,)
    info : dict
        Model size, element, timings, geometry.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    q_w: np.ndarray
    p_w: np.ndarray
    load_cases: list[str]
    load_units: list[str]
    coords: np.ndarray
    gap: np.ndarray
    normal: np.ndarray
    tangent: np.ndarray
    info: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        return self.A.shape[0]

    @property
    def K(self) -> np.ndarray:
        """Full reduced stiffness, DOFs ordered [v₁…v_N, w₁…w_N], shape (2N, 2N)."""
        return np.block([[self.A, self.B.T], [self.B, self.C]])

    def case(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """(q^w, p^w) of the load case ``name``, each shape (N,)."""
        i = self.load_cases.index(name)
        return self.q_w[i], self.p_w[i]

    def combine(self, **factors: float) -> tuple[np.ndarray, np.ndarray]:
        """Σ factor × (q^w, p^w) over the named cases (the gap case enters with 1 unless given)."""
        q = np.zeros(self.n)
        p = np.zeros(self.n)
        for i, name in enumerate(self.load_cases):
            a = factors.get(name, 1.0 if name == "gap" else 0.0)
            q += a * self.q_w[i]
            p += a * self.p_w[i]
        return q, p

    # -- the analysis contract ---------------------------------------------------------------
    def summary(self) -> dict:
        """Size and coupling of the reduced model, with ``units``.

        Returns
        -------
        dict
            ``model`` (``"fe"``), ``analysis`` (``"reduction"``), ``geometry``,
            ``n_contact_nodes`` N, ``n_dofs``, ``element``, ``load_cases`` and
            ``load_units``, ``coupling_B_over_A`` ‖B‖_F/‖A‖_F [1] (Barber 2012),
            ``dundurs_beta`` β [1] of the bodies (Dundurs 1969; None when unknown),
            ``units``. No critical friction coefficient is computed by the reduction.
        """
        out = {"model": "fe", "analysis": "reduction",
               "geometry": self.info.get("geometry"),
               "n_contact_nodes": int(self.n),
               "n_dofs": self.info.get("n_dofs"),
               "element": self.info.get("element"),
               "load_cases": list(self.load_cases), "load_units": list(self.load_units),
               "coupling_B_over_A": float(np.linalg.norm(self.B) / np.linalg.norm(self.A)),
               "dundurs_beta": _beta(self.info)}
        out["units"] = {k: u for k, u in REDUCED_UNITS.items() if k in out}
        return out

    def _build_dataset(self):
        """A, B, C (``node`` × ``node_j``) [N/m], q^w, p^w (``load_case`` × ``node``) [N
        per unit of the case], node coordinates x, y and gaps [m]: the arrays of the
        ``.npz`` with units."""
        import xarray as xr

        dims2, dimsw = ("node", "node_j"), ("load_case", "node")
        ds = xr.Dataset(
            {"A": (dims2, self.A, {"units": "N/m", "long_name": "tangential stiffness"}),
             "B": (dims2, self.B, {"units": "N/m",
                                   "long_name": "normal force per unit slip"}),
             "C": (dims2, self.C, {"units": "N/m", "long_name": "normal stiffness"}),
             "q_w": (dimsw, self.q_w, {"units": "N per unit of the load case",
                                       "long_name": "tangential reaction, nodes held"}),
             "p_w": (dimsw, self.p_w, {"units": "N per unit of the load case",
                                       "long_name": "normal reaction, nodes held"}),
             "gap": ("node", self.gap, {"units": "m", "long_name": "initial gap"})},
            coords={"node": ("node", np.arange(self.n)),
                    "node_j": ("node_j", np.arange(self.n)),
                    "load_case": ("load_case", np.array(self.load_cases, dtype=str)),
                    "load_unit": ("load_case", np.array(self.load_units, dtype=str)),
                    "x": ("node", self.coords[:, 0], {"units": "m"}),
                    "y": ("node", self.coords[:, 1], {"units": "m"})})
        ds.attrs.update(normal=np.asarray(self.normal, float),
                        tangent=np.asarray(self.tangent, float),
                        dof_order="tangential_first")
        return ds

    def figures(self, dataset=None) -> dict:
        """``coupling``: |A|, |B|, |C| as images over the contact nodes
        (:func:`slipcycle.plot.fe.coupling`)."""
        return {"coupling": figure_task("slipcycle.plot.fe:coupling", self.A, self.B, self.C)}

    def __repr__(self) -> str:
        s = self.summary()
        return (f"<ReducedModel fe reduction: geometry={s['geometry']}, "
                f"n_contact_nodes={s['n_contact_nodes']}, load_cases={s['load_cases']}, "
                f"coupling_B_over_A={_fmt(s['coupling_B_over_A'])}, "
                f"dundurs_beta={_fmt(s['dundurs_beta'])}>")

    def _repr_html_(self) -> str:
        s = self.summary()
        return _html_table("ReducedModel (fe reduction)",
                           [(k, s[k], s["units"].get(k, "")) for k in
                            ("geometry", "n_contact_nodes", "n_dofs", "load_cases",
                             "coupling_B_over_A", "dundurs_beta")])

    def arrays(self) -> dict:
        return {
            "A": self.A, "B": self.B, "C": self.C, "q_w": self.q_w, "p_w": self.p_w,
            "load_cases": np.array(self.load_cases, dtype=str),
            "load_units": np.array(self.load_units, dtype=str),
            "coords": self.coords, "gap": self.gap, "normal": self.normal,
            "tangent": self.tangent, "dof_order": np.array("tangential_first"),
        }

    def save(self, path: str | Path, metadata: dict | None = None, *,
             atomic: bool = True) -> Path:
        """Write an ``.npz`` atomically (temporary name, then ``os.replace``).

        ``metadata`` (e.g. :func:`slipcycle.io.results.provenance`) and :attr:`info` are
        stored as a JSON string in the array ``metadata``. ``atomic=False`` writes ``path``
        directly (a caller staging several files together does the renaming).
        """
        path = Path(path)
        meta = dict(metadata or {})
        meta["model_info"] = self.info
        arrays = self.arrays()
        arrays["metadata"] = np.array(json.dumps(meta, default=_json_default))
        if not atomic:
            with open(path, "wb") as fh:
                np.savez_compressed(fh, **arrays)
            return path
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".partial.npz",
                                   dir=path.parent)
        os.close(fd)
        try:
            with open(tmp, "wb") as fh:
                np.savez_compressed(fh, **arrays)
            os.chmod(tmp, 0o644)
            os.replace(tmp, path)
        finally:
            if os.path.exists(tmp):
                os.remove(tmp)
        return path


def _json_default(obj):
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    return str(obj)


def transformation(problem: Problem) -> tuple[sp.csr_matrix, int, np.ndarray, list[str]]:
    """Build T with u = T z + u₀ (see module docstring).

    Returns
    -------
    T : scipy.sparse.csr_matrix, shape (n, n_y + 2N)
    n_y : int
        Number of interior variables (own DOFs, then platen masters).
    source : numpy.ndarray of int, shape (n,)
        For each DOF, the DOF whose prescribed value it copies into u₀ (itself if fixed,
        its partner if it is a body-1 contact DOF whose partner is fixed), else −1.
    masters : list of str
        Names of the platen translations (their variables follow the own DOFs).
    """
    n = problem.ndofs
    cs = problem.contact
    N = cs.n
    status = np.zeros(n, dtype=np.int8)  # 0 own, 1 fixed, 2 tied, 3 body-1 contact
    fixed = np.asarray(problem.fixed, dtype=np.int64)
    status[fixed] = 1
    master_of = np.full(n, -1)
    masters = []
    for k, (group, name) in enumerate(problem.ties):
        status[np.asarray(group)] = 2
        master_of[np.asarray(group)] = k
        masters.append(name)
    b1: BodyDofs = problem.dofs[cs.body1]
    c1x, c1y = b1.ux[cs.nodes1], b1.uy[cs.nodes1]
    if np.any(status[c1x] != 0) or np.any(status[c1y] != 0):
        raise ValueError("a contact node is also supported or tied to a platen")
    status[c1x] = 3
    status[c1y] = 3
    own = np.nonzero(status == 0)[0]
    col = np.full(n, -1)
    col[own] = np.arange(len(own))
    n_y = len(own) + len(masters)
    rows, cols, vals = [own], [col[own]], [np.ones(len(own))]
    tied = np.nonzero(status == 2)[0]
    rows.append(tied)
    cols.append(len(own) + master_of[tied])
    vals.append(np.ones(len(tied)))
    source = np.full(n, -1)
    source[fixed] = fixed
    t, nrm = cs.tangent, cs.normal
    jv = n_y + np.arange(N)
    jw = n_y + N + np.arange(N)
    for comp, c1 in ((0, c1x), (1, c1y)):
        rows += [c1, c1]
        cols += [jv, jw]
        vals += [np.full(N, t[comp]), np.full(N, nrm[comp])]
        if cs.body2 is not None:
            b2 = problem.dofs[cs.body2]
            c2 = (b2.ux if comp == 0 else b2.uy)[cs.nodes2]
            st = status[c2]
            m_own = st == 0
            rows.append(c1[m_own])
            cols.append(col[c2[m_own]])
            vals.append(np.ones(m_own.sum()))
            m_tied = st == 2
            rows.append(c1[m_tied])
            cols.append(len(own) + master_of[c2[m_tied]])
            vals.append(np.ones(m_tied.sum()))
            m_fix = st == 1
            source[c1[m_fix]] = c2[m_fix]
            if np.any(st == 3):
                raise ValueError("a contact node of body 2 is also a contact node of body 1")
    T = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(n, n_y + 2 * N))
    return T, n_y, source, masters


def reduce_problem(problem: Problem, block: int = 128) -> ReducedModel:
    """Condense ``problem`` to its contact pairs (see module docstring).

    With u = T z + u₀, z = [y; v; w − g], the transformed stiffness K' = Tᵀ K T is
    condensed onto the contact variables, K_red = K'_dd − K'_dy K'_yy⁻¹ K'_yd (one sparse
    factorisation, :func:`slipcycle.condensation.schur_complement`), so that
    [q; p] = K_red [v; w] + [q^w; p^w] with K_red = [[A, Bᵀ], [B, C]].

    Parameters
    ----------
    problem : Problem
        The assembled model: stiffness (N/m), DOF bookkeeping, the N contact pairs,
        prescribed DOFs, platen ties and the basic load cases.
    block : int
        Right-hand sides solved at once should the condensation fall back to block solves
        with the interior factors (memory against speed; the result does not depend on it).

    Returns
    -------
    ReducedModel
        ``A``, ``B``, ``C`` (N, N) (N/m; A tangential, C normal, B normal force per unit
        slip); ``q_w``, ``p_w`` (n_cases, N), one row per case of ``problem.cases`` in
        order: the reactions with every pair held at v = w = 0 per unit of the case (N/N,
        N/m, N/Pa; the ``gap`` row, −[Bᵀ g; C g], in N), p compressive positive;
        ``load_cases`` and ``load_units``; ``coords`` (N, 2) and ``gap`` (N,) (m);
        ``normal``, ``tangent`` (2,); ``info`` (``problem.info`` with ``n_dofs``,
        ``n_interior``, ``n_contact_nodes``, ``formulations``, ``transform_seconds``,
        ``condense_seconds``).

    Raises
    ------
    slipcycle.condensation.SingularModelError
        The stiffness with every contact node held is singular: a body or part of one
        is not supported against rigid motion.
    ValueError
        A contact node that is also supported or tied to a platen, or a body-2 contact
        node that is also a body-1 contact node.

    References
    ----------
    Guyan, R. J. (1965). Reduction of stiffness and mass matrices. AIAA J. 3(2), 380.
    Barber, J. R. (2012). Frictional systems under periodic loads — history-dependence,
    non-uniqueness and energy dissipation. J. Phys.: Conf. Ser. 382, 012002 (the reduced
    stiffness A, B, C of the contact nodes).
    """
    t0 = time.perf_counter()
    cs = problem.contact
    N = cs.n
    T, n_y, source, masters = transformation(problem)
    K = problem.K
    Kp = (T.T @ K @ T).tocsr()
    fixed = np.asarray(problem.fixed, dtype=np.int64)
    cases = [c for c in problem.cases if not c.gap]
    F = np.zeros((Kp.shape[0], len(cases)))
    for k, case in enumerate(cases):
        f = np.zeros(problem.ndofs) if case.f is None else np.asarray(case.f, float).copy()
        if case.u_fixed is not None:
            u_fixed = np.zeros(problem.ndofs)
            u_fixed[fixed] = case.u_fixed
            u0 = np.zeros(problem.ndofs)
            has = source >= 0
            u0[has] = u_fixed[source[has]]
            f -= K @ u0
        F[:, k] = T.T @ f
        if case.f_master is not None:
            F[n_y - len(masters):n_y, k] += case.f_master
    t1 = time.perf_counter()
    S, r = schur_complement(Kp, n_y, F, block=block)
    t2 = time.perf_counter()
    rows_q, rows_p, names, units = [], [], [], []
    r_by_name = {c.name: r[:, k] for k, c in enumerate(cases)}
    for case in problem.cases:
        if case.gap:
            rc = -S[:, N:] @ cs.gap
        else:
            rc = r_by_name[case.name]
        rows_q.append(rc[:N])
        rows_p.append(rc[N:])
        names.append(case.name)
        units.append(case.unit)
    info = dict(problem.info)
    info.update({
        "n_dofs": int(problem.ndofs),
        "n_interior": int(n_y),
        "n_contact_nodes": int(N),
        "formulations": {d.body.name: d.body.info.get("formulation", "")
                         for d in problem.dofs},
        "transform_seconds": t1 - t0,
        "condense_seconds": t2 - t1,
    })
    return ReducedModel(
        A=S[:N, :N].copy(), B=S[N:, :N].copy(), C=S[N:, N:].copy(),
        q_w=np.array(rows_q).reshape(len(names), N), p_w=np.array(rows_p).reshape(len(names), N),
        load_cases=names, load_units=units, coords=cs.coords, gap=cs.gap,
        normal=cs.normal, tangent=cs.tangent, info=info,
    )
