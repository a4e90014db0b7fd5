"""Roles of the rows of an exported stiffness, node frames, and the reduction to A, B, C.

Every row of an exported K has a *role*: a local contact direction of its node
(``t1``, ``t2``, ``n``), a global translation (``x``, ``y``, ``z``, rotated into the node's
frame), or ``retained`` (a degree of freedom that is not a contact direction: an interior
node, a rotation, a node of the loading; it is condensed out). A :class:`DofMap` holds the
node and the role of each row; it comes from

- the file's own labels: ``(node, dof)`` with dof 1, 2, 3 the global x, y, z translations
  and 4–6 rotations (Abaqus, CalculiX, ANSYS ``.mapping``, Nastran component numbers), every
  labelled node a contact node unless listed as retained (:func:`labelled_map`);
- a standard ordering of an unlabelled K (:func:`standard_map`): ``"tangential_first"``
  ([t1 of every node, t2 of every node (3-D), n of every node]), ``"interleaved"``
  ([t1, t2, n] node by node) or ``"xyz"`` ([x, y, z] node by node, in the global frame);
- a table, one row ``(node, dof, role)`` per matrix row (:func:`table_map`), read from a
  CSV file or given as a list.

Conventions (those of slipcycle's discrete model, J. R. Barber, J. Phys.: Conf. Ser. 382
(2012) 012002, §3, and of its 2-D finite-element reduction): K maps the displacements of
the contact nodes — tangential slip v and normal separation w, w > 0 opening the gap — to
the reactions that the opposing body exerts on them, q along the tangents and p along the
inward normal (p > 0 compressive):

    q = q^w + A v + Bᵀ w,      p = p^w + B v + C w.

A node frame is given by its *outward* unit normal n (out of the body, into the contact).
The separation direction is e = −n: w = e·u and p = e·f, so that C = eᵀ K e. The
tangents follow one documented rule unless given (``frames["t1"]``):

- 2-D (one tangent): t1 = (e_y, −e_x, 0), the rule of slipcycle's plane-strain models
  (:mod:`slipcycle.fe.contact`; a body on a flat below it, n = (0, −1), has t1 = +x);
- 3-D (two tangents): t1 is the global x-axis projected onto the tangent plane
  (the y-axis when |e·x| > 0.9), normalised; t2 = e × t1, so (t1, t2, e) is right-handed
  (a body on a flat below it, n = (0, 0, −1), has t1 = +x, t2 = +y).

Retained rows are condensed out by static condensation (Guyan 1965; one factorisation of
the retained block K_rr, Cholesky when dense, sparse LU when sparse):

    S = K_cc − K_cr K_rr⁻¹ K_rc,      r^w = K_cr K_rr⁻¹ f_r − f_c,

where f are the nodal forces of a load case stored with K and r^w the reactions at the
contact rows held fixed (the p^w, q^w of the case, after rotation).

References
----------
Guyan, R. J. (1965). Reduction of stiffness and mass matrices. AIAA Journal 3(2), 380.
Barber, J. R. (2012). Frictional systems under periodic loads — history-dependence,
non-uniqueness and energy dissipation. J. Phys.: Conf. Ser. 382, 012002.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.sparse.linalg import norm as sparse_norm

from slipcycle.condensation import SingularModelError, schur_complement
from slipcycle.io.fe_formats.common import StiffnessError, file_error

__all__ = ["DofMap", "ROLES", "ORDERINGS", "standard_map", "labelled_map", "table_map",
           "read_dof_table", "node_frames", "reduce_to_contact", "check_symmetric"]

ROLES = ("t1", "t2", "n", "x", "y", "z", "retained")
ORDERINGS = ("tangential_first", "interleaved", "xyz")
_AXIS = {"x": 0, "y": 1, "z": 2}
_LOCAL = ("t1", "t2", "n")
_GLOBAL = ("x", "y", "z")


def _node_list(node) -> str:
    """The nodes of a map in a few words: "its nodes: 1, 2, 22" or "its 40 nodes: 1, 2,
    3, ..., 40" (for the message of a node that is not among them)."""
    u = np.unique(np.asarray(node))
    if u.size <= 6:
        return "its nodes: " + ", ".join(map(str, u))
    return f"its {u.size} nodes: {', '.join(map(str, u[:3]))}, ..., {u[-1]}"


@dataclass(frozen=True)
class DofMap:
    """Node and role of every row of an exported K.

    Attributes
    ----------
    node : numpy.ndarray of int, shape (n,)
        Node label of each row.
    role : tuple of str, length n
        One of :data:`ROLES` per row.
    """

    node: np.ndarray
    role: tuple

    def __post_init__(self):
        if len(self.node) != len(self.role):
            raise ValueError("node and role must have one entry per row")
        bad = sorted({r for r in self.role if r not in ROLES})
        if bad:
            raise StiffnessError("dof_map", f"unknown role {bad[0]!r}; roles are "
                                 + ", ".join(ROLES))

    def with_retained(self, nodes, where: str) -> DofMap:
        """Every row of the listed nodes marked ``retained`` (condensed out)."""
        nodes = np.atleast_1d(np.asarray(nodes, np.int64))
        missing = sorted(set(nodes.tolist()) - set(self.node.tolist()))
        if missing:
            raise StiffnessError("retained", f"node {missing[0]} is not a node of {where}"
                                 f" ({_node_list(self.node)})")
        mask = np.isin(self.node, nodes)
        return DofMap(self.node, tuple("retained" if m else r
                                       for m, r in zip(mask, self.role, strict=True)))

    def with_contact_nodes(self, nodes, where: str) -> DofMap:
        """Every row of every node not listed marked ``retained``."""
        nodes = np.atleast_1d(np.asarray(nodes, np.int64))
        missing = sorted(set(nodes.tolist()) - set(self.node.tolist()))
        if missing:
            raise StiffnessError("contact_nodes", f"node {missing[0]} is not a node of {where}"
                                 f" ({_node_list(self.node)})")
        return self.with_retained(np.setdiff1d(np.unique(self.node), nodes), where)


def standard_map(n_dofs: int, ordering: str, tangential_dims: int, where: str) -> DofMap:
    """The map of an unlabelled K in one of :data:`ORDERINGS` (nodes labelled 0..N−1)."""
    if ordering not in ORDERINGS:
        raise StiffnessError("dof_map", f"must be one of {', '.join(ORDERINGS)} or a table "
                             f"of (node, dof, role) rows, got {ordering!r}")
    d = tangential_dims + 1
    if n_dofs % d:
        raise file_error(where, f"K has {n_dofs} dofs, not a multiple of the {d} dofs per "
                         f"node of a {'3-D' if d == 3 else '2-D'} contact "
                         f"(tangential_dims = {tangential_dims})")
    n = n_dofs // d
    roles = (_GLOBAL if ordering == "xyz" else _LOCAL)[:d] if d == 3 else (
        ("x", "y") if ordering == "xyz" else ("t1", "n"))
    if ordering == "tangential_first":
        node = np.tile(np.arange(n), d)
        role = tuple(r for r in roles for _ in range(n))
    else:
        node = np.repeat(np.arange(n), d)
        role = tuple(roles) * n
    return DofMap(node, role)


def labelled_map(labels: np.ndarray) -> DofMap:
    """Roles from FE labels (node, dof): 1, 2, 3 → x, y, z; any other dof → retained."""
    labels = np.asarray(labels, np.int64)
    words = {1: "x", 2: "y", 3: "z"}
    return DofMap(labels[:, 0], tuple(words.get(int(d), "retained") for d in labels[:, 1]))


def read_dof_table(source, where: str = "dof_map") -> list[tuple]:
    """Rows ``(node, dof, role)`` from a CSV file or a list of rows.

    A CSV file has columns ``node, dof, role`` (a header line naming them is optional;
    ``#`` starts a comment). A list row is ``[node, dof, role]`` or ``[node, role]``.
    """
    if isinstance(source, (str, Path)):
        path = Path(source)
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise StiffnessError(where, f"cannot read dof table {path.name}: "
                                 f"{getattr(exc, 'strerror', None) or exc}") from None
        rows = [r for r in csv.reader(line for line in text.splitlines()
                                      if line.strip() and not line.lstrip().startswith("#"))]
        if rows and rows[0] and rows[0][0].strip().lower() == "node":
            rows = rows[1:]
    else:
        rows = list(source)
    out = []
    for i, row in enumerate(rows):
        cells = [c.strip() if isinstance(c, str) else c for c in row]
        if len(cells) == 2:
            cells = [cells[0], 0, cells[1]]
        if len(cells) != 3:
            raise StiffnessError(where, f"row {i + 1}: expected (node, dof, role), got {row!r}")
        try:
            node, dof = int(cells[0]), int(cells[1])
        except (TypeError, ValueError):
            raise StiffnessError(where, f"row {i + 1}: node and dof must be integers, "
                                 f"got {row!r}") from None
        role = str(cells[2]).strip().lower()
        if role not in ROLES:
            raise StiffnessError(where, f"row {i + 1}: unknown role {cells[2]!r}; roles are "
                                 + ", ".join(ROLES))
        out.append((node, dof, role))
    if not out:
        raise StiffnessError(where, "the dof table is empty")
    return out


def table_map(table: list[tuple], n_dofs: int, labels: np.ndarray | None,
              where: str) -> DofMap:
    """The map from a dof table; matched by (node, dof) label when the file has labels,
    row by row otherwise. Labelled rows the table does not list keep their default role."""
    if labels is None:
        if len(table) != n_dofs:
            nodes = {r[0] for r in table}
            per = len(table) / max(len(nodes), 1)
            detail = (f"{len(nodes)} nodes × {int(per)} dofs = {len(table)}"
                      if per == int(per) else f"{len(table)} dofs")
            raise file_error(where, f"K has {n_dofs} dofs but the map lists {detail}")
        return DofMap(np.array([r[0] for r in table], np.int64), tuple(r[2] for r in table))
    base = labelled_map(labels)
    index = {(int(a), int(b)): i for i, (a, b) in enumerate(labels)}
    role = list(base.role)
    for node, dof, r in table:
        if (node, dof) not in index:
            raise StiffnessError("dof_map", f"node {node} dof {dof} is not a row of {where}")
        role[index[(node, dof)]] = r
    return DofMap(base.node, tuple(role))


def _unit(v, what: str) -> np.ndarray:
    v = np.asarray(v, float)
    if v.shape[-1] == 2:
        v = np.concatenate([v, np.zeros(v.shape[:-1] + (1,))], axis=-1)
    if v.shape[-1] != 3 or not np.all(np.isfinite(v)):
        raise StiffnessError(what, "must be finite vectors of 2 or 3 components")
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    if np.any(norm == 0):
        raise StiffnessError(what, "must not be a zero vector")
    return v / norm


def node_frames(frames, n_nodes: int, tangential_dims: int) -> tuple[np.ndarray, np.ndarray]:
    """Outward normals (N, 3) and tangents (N, t, 3) of the contact nodes.

    Parameters
    ----------
    frames : dict
        ``normal``: outward unit normal, (3,) (or (2,)) for every node or (N, 3) per node
        (nodes in increasing label order); optional ``t1``: first tangent, (3,) or (N, 3),
        orthogonal to the normal. Without ``t1`` the rule of the module docstring applies.
    n_nodes : int
    tangential_dims : int
        1 (2-D: normals must lie in the x–y plane) or 2.

    Returns
    -------
    normals : numpy.ndarray, shape (N, 3)
    tangents : numpy.ndarray, shape (N, t, 3)
    """
    if not isinstance(frames, dict) or "normal" not in frames:
        raise StiffnessError("frames", "must be a table with 'normal' (the outward unit "
                             "normal, e.g. {normal = [0, 0, -1]}) and optionally 't1'")
    unknown = sorted(set(frames) - {"normal", "t1"})
    if unknown:
        raise StiffnessError(f"frames.{unknown[0]}", "unknown key (frames take normal, t1)")
    nrm = _unit(frames["normal"], "frames.normal")
    nrm = np.broadcast_to(nrm, (n_nodes, 3)).copy() if nrm.ndim == 1 or len(nrm) == 1 else nrm
    if nrm.shape != (n_nodes, 3):
        raise StiffnessError("frames.normal", f"must be one vector or one per contact node "
                             f"({n_nodes}), got {len(nrm)}")
    e = -nrm                                        # separation direction (inward)
    if "t1" in frames:
        t1 = _unit(frames["t1"], "frames.t1")
        t1 = np.broadcast_to(t1, (n_nodes, 3)).copy() if t1.ndim == 1 or len(t1) == 1 else t1
        if t1.shape != (n_nodes, 3):
            raise StiffnessError("frames.t1", f"must be one vector or one per contact node "
                                 f"({n_nodes})")
        if np.max(np.abs(np.sum(t1 * e, axis=1))) > 1e-6:
            raise StiffnessError("frames.t1", "must be orthogonal to the normal")
    elif tangential_dims == 1:
        if np.max(np.abs(nrm[:, 2])) > 1e-9:
            raise StiffnessError("frames.normal", "a 2-D contact needs normals in the x–y "
                                 "plane (z component 0)")
        t1 = np.stack([e[:, 1], -e[:, 0], np.zeros(n_nodes)], axis=1)
    else:
        a = np.where(np.abs(e[:, :1]) > 0.9, [[0.0, 1.0, 0.0]], [[1.0, 0.0, 0.0]])
        t1 = a - np.sum(a * e, axis=1, keepdims=True) * e
        t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    if tangential_dims == 1:
        if np.max(np.abs(t1[:, 2])) > 1e-9:
            raise StiffnessError("frames.t1", "a 2-D contact needs tangents in the x–y plane")
        return nrm, t1[:, None, :]
    t2 = np.cross(e, t1)
    return nrm, np.stack([t1, t2], axis=1)


def check_symmetric(K, where: str, rtol: float = 1e-6):
    """K symmetric within ``rtol`` (relative Frobenius norm) and finite; its symmetric part."""
    if sp.issparse(K):
        K = sp.csr_matrix(K, dtype=float)
        data = K.data
        scale = sparse_norm(K)
        asym = sparse_norm(K - K.T) / scale if scale > 0 else 0.0
    else:
        K = np.asarray(K, float)
        data = K
        scale = np.linalg.norm(K)
        asym = np.linalg.norm(K - K.T) / scale if scale > 0 else 0.0
    if not np.all(np.isfinite(data)):
        raise file_error(where, "K must contain only finite numbers (found nan or inf)")
    if asym > rtol:
        raise file_error(where, f"K is not symmetric: relative asymmetry {asym:.2e} > {rtol:g}")
    return 0.5 * (K + K.T)


def _condense(K, c: np.ndarray, r: np.ndarray, loads: dict, where: str):
    """Schur complement onto rows ``c`` and the held-contact reactions of ``loads``.

    The one condensation engine of slipcycle (:func:`slipcycle.condensation.
    schur_complement`, also used by the FE reduction), with the retained rows ``r`` first.
    """
    order = np.concatenate([r, c])
    Kq = sp.csr_matrix(K)[order][:, order]
    names = list(loads)
    F = np.column_stack([np.asarray(loads[n], float)[order] for n in names]) if names \
        else None
    try:
        S, R = schur_complement(Kq, r.size, F)
        _check_schur(Kq, r.size, S, where)
    except SingularModelError:
        raise file_error(where, "the retained (condensed) block of K is singular or not "
                         "positive definite: the body is not supported with the contact "
                         "nodes held") from None
    return S, {n: R[:, k] for k, n in enumerate(names)}


#: largest accepted residual of the condensation's equilibrium, relative to ‖K_bb z‖ + ‖S z‖
SCHUR_RTOL = 1e-8


def _check_schur(Kq, ni: int, S: np.ndarray, where: str) -> None:
    """Check that S is the Schur complement K_bb − K_bi K_ii⁻¹ K_ib of ``Kq`` (retained
    dofs first), independently of how it was computed: for two random contact motions z,
    the retained dofs x = −K_ii⁻¹ K_ib z (a separate sparse LU) must leave the contact
    reactions K_bb z + K_bi x = S z. A failed factorisation path (a lost pivot, an
    ill-conditioned retained block) gives a plausible symmetric S that fails this.
    """
    from slipcycle.condensation import factorize

    if ni == 0:
        return
    nb = Kq.shape[0] - ni
    Z = np.random.default_rng(0).standard_normal((nb, 2))
    K_ib = Kq[:ni, ni:]
    X = -factorize(Kq[:ni, :ni]).solve(np.asfortranarray(np.asarray(K_ib @ Z)))
    direct = np.asarray(Kq[ni:, ni:] @ Z)
    got = direct + np.asarray(Kq[ni:, :ni] @ X)
    res = np.linalg.norm(got - S @ Z) / (np.linalg.norm(direct) + np.linalg.norm(S @ Z))
    if not res <= SCHUR_RTOL:
        raise file_error(where, f"the condensation of K is not its Schur complement "
                         f"(equilibrium residual {res:.1e} > {SCHUR_RTOL:g}): K is too "
                         "ill-conditioned for its retained rows to be condensed out")


def _constrained(K, Lc: np.ndarray, loads: dict, where: str):
    """Static stiffness of the physical dofs u_c = L_c q of a reduced-order model.

    Minimising ½ qᵀ K q − fᵀ q subject to L_c q = u_c gives the reactions
    r = S u_c + r^w with S = (L_c K⁻¹ L_cᵀ)⁻¹ (the inverse of the flexibility of the
    contact dofs) and r^w = −S L_c K⁻¹ f; for a selection L_c = [I 0] this is the Schur
    complement and r^w = K_cr K_rr⁻¹ f_r − f_c of :func:`_condense`.
    """
    Kd = K.toarray() if sp.issparse(K) else np.asarray(K)
    try:
        fac = sla.cho_factor(Kd)
    except np.linalg.LinAlgError:
        raise file_error(where, "K is not positive definite: a model with rigid-body modes "
                         "cannot be reduced to its contact dofs through L") from None
    X = sla.cho_solve(fac, Lc.T)                     # K⁻¹ L_cᵀ
    G = Lc @ X                                       # flexibility of the contact dofs
    try:
        gfac = sla.cho_factor(0.5 * (G + G.T))
    except np.linalg.LinAlgError:
        raise file_error(where, "the contact rows of L are linearly dependent (their "
                         "flexibility L K⁻¹ Lᵀ is singular)") from None
    S = sla.cho_solve(gfac, np.eye(G.shape[0]))
    out = {name: -sla.cho_solve(gfac, X.T @ np.asarray(f, float))
           for name, f in loads.items()}
    return 0.5 * (S + S.T), out


def reduce_to_contact(K, dmap: DofMap, *, tangential_dims: int | None, frames=None,
                      loads: dict | None = None, condense_retained: bool = True,
                      where: str = "K", transform: np.ndarray | None = None) -> dict:
    """A, B, C of the contact nodes from an exported K and the roles of its rows.

    Parameters
    ----------
    K : numpy.ndarray or scipy.sparse matrix, shape (n, n)
        Stiffness, N/m, symmetric.
    dmap : DofMap
        Node and role of each row.
    tangential_dims : int or None
        1 (2-D) or 2 (3-D); None takes it from the roles (a node with t2 or z is 3-D).
    frames : dict, optional
        Node frames (:func:`node_frames`); needed when rows are global x, y, z.
    loads : dict of str to numpy.ndarray (n,), optional
        Nodal forces of load cases, N.
    condense_retained : bool
        Condense ``retained`` rows out (otherwise refuse them).
    where : str
        The file, for messages.
    transform : numpy.ndarray, shape (m, n), optional
        L of a reduced-order model, physical dofs u = L q of its coordinates q: the map
        then describes the m rows of L (``retained`` rows are ignored) and the contact rows
        are reduced by :func:`_constrained`.

    Returns
    -------
    dict
        ``A`` (tN, tN), ``B`` (N, tN), ``C`` (N, N) in N/m; ``nodes`` (N,); ``t``;
        ``normals`` (N, 3) and ``tangents`` (N, t, 3) or None; ``loads`` name →
        {"q": (tN,), "p": (N,)} in N.
    """
    n = K.shape[0]
    if K.ndim != 2 or K.shape[1] != n or n == 0:
        raise file_error(where, f"K must be a non-empty square matrix, got shape {K.shape}")
    if transform is not None:
        if transform.ndim != 2 or transform.shape[1] != n:
            raise file_error(where, f"L must have {n} columns (one per row of K), got shape "
                             f"{transform.shape}")
        n = transform.shape[0]                      # the map describes the rows of L
    if len(dmap.node) != n:
        nodes = np.unique(dmap.node)
        per = len(dmap.node) / max(len(nodes), 1)
        detail = (f"{len(nodes)} nodes × {int(per)} dofs = {len(dmap.node)}"
                  if per == int(per) else f"{len(dmap.node)} dofs")
        what = "L has" if transform is not None else "K has"
        raise file_error(where, f"{what} {n} dofs but the map lists {detail}")
    K = check_symmetric(K, where)
    role = np.array(dmap.role)
    retained = role == "retained"
    contact_nodes = np.unique(dmap.node[~retained])
    if contact_nodes.size == 0:
        raise file_error(where, "no contact degree of freedom: every row is retained")
    if retained.any() and not condense_retained:
        raise file_error(where, f"K has {int(retained.sum())} retained dofs (not contact "
                         "directions); allow their static condensation (condense_retained)")
    # roles of each contact node, counted per (node, role) at once
    c = np.nonzero(~retained)[0]
    r = np.nonzero(retained)[0]
    words_c, code = np.unique(role[c], return_inverse=True)
    code = np.array([ROLES.index(w) for w in words_c], np.int64)[code.ravel()]
    contact_nodes, inv = np.unique(dmap.node[c], return_inverse=True)
    counts = np.zeros((contact_nodes.size, 6), np.int64)
    np.add.at(counts, (inv, code), 1)
    have = counts > 0
    words = np.array(ROLES[:6])
    dup = np.nonzero(counts.max(axis=1) > 1)[0]
    if dup.size:
        j = dup[0]
        raise file_error(where, f"node {contact_nodes[j]} has two rows with role "
                         f"{words[np.argmax(counts[j])]!r}")
    is_local, is_global = have[:, :3].any(axis=1), have[:, 3:].any(axis=1)
    mixed = np.nonzero(is_local & is_global)[0]
    if mixed.size:
        j = mixed[0]
        raise file_error(where, f"node {contact_nodes[j]} mixes local "
                         f"({', '.join(words[:3][have[j, :3]])}) and global "
                         f"({', '.join(words[3:][have[j, 3:]])}) directions")
    # the valid sets: t1, n | t1, t2, n | x, y | x, y, z → t = 1, 2, 1, 2
    valid = {(1, 0, 1, 0, 0, 0): 1, (1, 1, 1, 0, 0, 0): 2, (0, 0, 0, 1, 1, 0): 1,
             (0, 0, 0, 1, 1, 1): 2}
    t_node = np.array([valid.get(tuple(p), 0) for p in have.astype(int).tolist()], np.int64)
    bad = np.nonzero(t_node == 0)[0]
    if bad.size:
        j = bad[0]
        kind = "translations" if is_global[j] else "directions"
        need = ("x, y (2-D) or x, y, z (3-D)" if is_global[j]
                else "t1, n (2-D) or t1, t2, n (3-D)")
        raise file_error(where, f"node {contact_nodes[j]} has {kind} "
                         f"{', '.join(words[have[j]])}; a contact node needs {need}")
    if np.any(t_node != t_node[0]):
        j2 = int(np.nonzero(t_node != t_node[0])[0][0])
        raise file_error(where, f"node {contact_nodes[0]} has {t_node[0] + 1} dofs but node "
                         f"{contact_nodes[j2]} has {t_node[j2] + 1}: all contact nodes must "
                         "be 2-D or all 3-D")
    t = int(t_node[0])
    if tangential_dims is not None and tangential_dims != t:
        glob = bool(is_global[0])
        what = ("x, y, z" if glob else "t1, t2, n") if t == 2 else ("x, y" if glob else "t1, n")
        raise file_error(where, f"the contact nodes have {t + 1} dofs each ({what}: a "
                         f"{'3-D' if t == 2 else '2-D'} model) but a "
                         f"{'3-D' if tangential_dims == 2 else '2-D'} model needs "
                         f"{tangential_dims + 1}; the matrix is not reinterpreted")
    N = contact_nodes.size
    normals = tangents = None
    if frames is not None:
        normals, tangents = node_frames(frames, N, t)
    elif is_global.any():
        raise file_error(where, "the contact rows are global x, y, z displacements: give the "
                         "outward normal of the contact nodes (frames = {'normal': [...]}; in "
                         "a case file stiffness.normal = [...]) to rotate them into (t1, n)")
    loads = loads or {}
    if transform is not None:
        S, rw = _constrained(K, np.asarray(transform, float)[c], loads, where)
    elif r.size:
        S, rw = _condense(K, c, r, loads, where)
    else:
        S = K.toarray() if sp.issparse(K) else np.array(K)
        S = S[np.ix_(c, c)]
        rw = {name: -np.asarray(f, float)[c] for name, f in loads.items()}
    # T maps local contact dofs [tangential node-major (tN), normal (N)] to the rows c:
    # u_c = T x_local (T orthonormal per node)
    T = np.zeros((c.size, (t + 1) * N))
    i = np.arange(c.size)
    for k in range(2):                              # t1, t2
        m = code == k
        T[i[m], inv[m] * t + k] = 1.0
    m = code == 2
    T[i[m], t * N + inv[m]] = 1.0
    for a in range(3):                              # x, y, z: rotated (frames given)
        m = code == 3 + a
        if not m.any():
            continue
        for k in range(t):
            T[i[m], inv[m] * t + k] = tangents[inv[m], k, a]
        T[i[m], t * N + inv[m]] = -normals[inv[m], a]
    Kl = T.T @ S @ T
    Kl = 0.5 * (Kl + Kl.T)
    try:
        np.linalg.cholesky(Kl)
    except np.linalg.LinAlgError:
        lam = np.linalg.eigvalsh(Kl)
        raise file_error(where, f"the reduced K is not positive definite: smallest eigenvalue "
                         f"{lam[0]:.3e} (largest {lam[-1]:.3e}); is the body supported "
                         "against rigid motion?") from None
    tN = t * N
    out_loads = {}
    for name, v in rw.items():
        vl = T.T @ v
        out_loads[name] = {"q": vl[:tN], "p": vl[tN:]}
    return {"A": Kl[:tN, :tN], "B": Kl[tN:, :tN], "C": Kl[tN:, tN:], "t": t,
            "nodes": contact_nodes.astype(np.int64), "normals": normals, "tangents": tangents,
            "loads": out_loads}
