"""Contact nodes: identification, pairing and the relative displacements v, w.

Sign conventions
--------------------------
Body 1 is the body whose contact nodes are listed; body 2 is the opposing body, or a
rigid flat that does not move. ``normal`` n is the unit vector pointing from body 2 into
body 1 (out of body 2's surface), ``tangent`` t = (n_y, −n_x) (so n = (0, 1) gives
t = (1, 0)). At pair j, with u¹, u² the nodal displacements of the two nodes,

    v_j = t · (u¹_j − u²_j)                 tangential slip of body 1 relative to body 2
    w_j = g_j + n · (u¹_j − u²_j)           normal separation (gap), w_j ≥ 0 in contact

where g_j is the initial gap of the undeformed geometry. The reactions q_j, p_j are the
forces that body 2 (or the flat) exerts on body 1 at node j, along t and n: p_j > 0 is
compression, and body 2 receives −(q_j t + p_j n).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from slipcycle.fe.assembly import BodyDofs
from slipcycle.io.case import CaseError

__all__ = ["ContactSet", "tangent_of", "contact_on_flat", "contact_pairs"]


def tangent_of(normal) -> np.ndarray:
    """Unit tangent t = (n_y, −n_x) of a unit normal n."""
    n = np.asarray(normal, float)
    return np.array([n[1], -n[0]])


@dataclass
class ContactSet:
    """The N contact node pairs of a model.

    Attributes
    ----------
    body1 : int
        Index of body 1 in the model's body list.
    nodes1 : numpy.ndarray of int, shape (N,)
        Local node indices in body 1, ordered by increasing position along ``tangent``.
    body2 : int or None
        Index of body 2, or None for a rigid flat.
    nodes2 : numpy.ndarray of int, shape (N,) or None
        Matching local node indices in body 2.
    normal, tangent : numpy.ndarray, shape (2,)
        Unit vectors n (from body 2 into body 1) and t.
    gap : numpy.ndarray, shape (N,)
        Initial gap g_j ≥ 0, m.
    coords : numpy.ndarray, shape (N, 2)
        Coordinates of the body-1 nodes, m.
    """

    body1: int
    nodes1: np.ndarray
    body2: int | None
    nodes2: np.ndarray | None
    normal: np.ndarray
    tangent: np.ndarray
    gap: np.ndarray
    coords: np.ndarray

    @property
    def n(self) -> int:
        return len(self.nodes1)


def _order_along(xy: np.ndarray, nodes: np.ndarray, tangent: np.ndarray) -> np.ndarray:
    s = tangent @ xy[:, nodes]
    return nodes[np.argsort(s, kind="stable")]


def contact_on_flat(dofs: list[BodyDofs], body: int, tag: str, normal=(0.0, 1.0),
                    gap: np.ndarray | None = None, key: str = "contact") -> ContactSet:
    """Contact nodes of ``body`` on the boundary ``tag`` against a rigid flat.

    The flat is perpendicular to ``normal``. Unless ``gap`` is given, it passes through
    the contact node lowest along ``normal``, so g_j = n·(x_j − x_lowest) ≥ 0.
    """
    bd = dofs[body]
    nodes = bd.boundary_nodes(tag)
    if len(nodes) == 0:
        known = ", ".join(sorted(bd.body.mesh.boundaries or {}))
        raise CaseError(key, f"no nodes on the boundary tagged {tag!r} of body "
                        f"{bd.body.name!r} (tags: {known})")
    n = np.asarray(normal, float)
    n = n / np.linalg.norm(n)
    t = tangent_of(n)
    nodes = _order_along(bd.xy, nodes, t)
    coords = bd.xy[:, nodes].T.copy()
    if gap is None:
        h = coords @ n
        gap = h - h.min()
    return ContactSet(body, nodes, None, None, n, t, np.asarray(gap, float), coords)


def contact_pairs(dofs: list[BodyDofs], body1: int, tag1: str, body2: int, tag2: str,
                  normal=(0.0, 1.0), gap: np.ndarray | None = None, tol: float | None = None,
                  key: str = "contact") -> ContactSet:
    """Pair each contact node of body 1 with the node of body 2 at the same tangential position.

    Nodes are matched by their coordinate along t (the interface may have an initial
    gap along n, e.g. a curved profile); every body-1 node needs a partner within ``tol``
    (default 1e-6 of the smallest node spacing). Unless given, the initial gap is
    g_j = n·(x¹_j − x²_j).
    """
    b1, b2 = dofs[body1], dofs[body2]
    n = np.asarray(normal, float)
    n = n / np.linalg.norm(n)
    t = tangent_of(n)
    nodes1 = _order_along(b1.xy, b1.boundary_nodes(tag1), t)
    cand2 = b2.boundary_nodes(tag2)
    if len(nodes1) == 0:
        raise CaseError(key, f"no nodes on the boundary tagged {tag1!r} of body {b1.body.name!r}")
    if len(cand2) == 0:
        raise CaseError(key, f"no nodes on the boundary tagged {tag2!r} of body {b2.body.name!r}")
    s1 = t @ b1.xy[:, nodes1]
    s2 = t @ b2.xy[:, cand2]
    order = np.argsort(s2)
    s2s = s2[order]
    spacing = np.min(np.diff(s1)) if len(s1) > 1 else 1.0
    tol = 1e-6 * spacing if tol is None else tol
    idx = np.clip(np.searchsorted(s2s, s1), 1, len(s2s) - 1) if len(s2s) > 1 else \
        np.zeros(len(s1), int)
    if len(s2s) > 1:
        left = np.abs(s2s[idx - 1] - s1) < np.abs(s2s[idx] - s1)
        idx = np.where(left, idx - 1, idx)
    miss = np.abs(s2s[idx] - s1) > tol
    if np.any(miss):
        j = int(np.argmax(miss))
        raise CaseError(key, f"contact node at {b1.xy[:, nodes1[j]].round(12).tolist()} of body "
                        f"{b1.body.name!r} has no partner node of body {b2.body.name!r} within "
                        f"{tol:.3g} m along the interface (meshes must match node to node)")
    nodes2 = cand2[order[idx]]
    if len(np.unique(nodes2)) != len(nodes2):
        raise CaseError(key, "two contact nodes of body 1 share one partner node of body 2")
    coords = b1.xy[:, nodes1].T.copy()
    if gap is None:
        gap = (b1.xy[:, nodes1] - b2.xy[:, nodes2]).T @ n
    return ContactSet(body1, nodes1, body2, nodes2, n, t, np.asarray(gap, float), coords)
