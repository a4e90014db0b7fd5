"""Geometry of element faces: outward normals, tributary areas, consistent pressure loads.

A face (``tri3``, ``tri6``, ``quad4``, ``quad8``) is x(ξ, η) = Σ_a N_a(ξ, η) x_a with the
shape functions of its element (the 8-node face of C3D20 and C3D15 is the serendipity
quadrilateral); a = x_ξ × x_η dξ dη is its area element, oriented out of the element that
owns it (away from that element's centroid). With Gauss quadrature (2 × 2 on 4-node
quadrilaterals, 3 × 3 on 8-node ones; the 3-point rule of degree 2 on triangles:
Zienkiewicz, Taylor & Zhu, *The Finite Element Method*, 7th ed., §6.5, Tables 6.3–6.4):

- the consistent nodal forces of a uniform pressure p (positive pushing into the body)
  are f_a = −p ∫ N_a n dA;
- the tributary area of a node is ∫ N_a dA on linear faces (a third of a flat triangle, a
  quarter of a rectangle to each corner); on a 6-node triangle, whose corner integrals are
  zero, each of the four sub-triangles cut by the mid-points gives a third of its area to
  its vertices: A/12 to a corner, A/4 to a mid-point (the rule of
  :func:`slipcycle.fe.meshfile3d.node_areas` for P2 surfaces). An 8-node quadrilateral,
  whose corner integrals are negative, is cut the same way by its mid-points into four
  corner triangles (an eighth of a parallelogram each, a third of it to each vertex) and
  the quadrilateral of the mid-points (half, a quarter of it to each): A/24 to a corner,
  5A/24 to a mid-point. The areas of a surface sum to its area;
- a node's outward normal is the normalised sum of ∫ N_a n dA over its faces (for a 6-node
  triangle and an 8-node quadrilateral the sub-triangle weights above), i.e. the
  area-weighted mean normal.
"""

from __future__ import annotations

import numpy as np

from slipcycle.fe_import.mesh import FaceSet

__all__ = ["surface_nodes", "node_normals", "node_areas", "pressure_forces", "face_areas"]

_TRI_PTS = np.array([[1 / 6, 1 / 6], [2 / 3, 1 / 6], [1 / 6, 2 / 3]])
_TRI_W = np.full(3, 1 / 6)
_G = 1 / np.sqrt(3.0)
_QUAD_PTS = np.array([[-_G, -_G], [_G, -_G], [_G, _G], [-_G, _G]])
_QUAD_W = np.ones(4)
_QUAD_XI = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], float)
_G3 = np.sqrt(0.6)
_QUAD8_PTS = np.array([[a, b] for b in (-_G3, 0.0, _G3) for a in (-_G3, 0.0, _G3)])
_QUAD8_W = np.array([a * b for b in (5, 8, 5) for a in (5, 8, 5)]) / 81.0
#: (ξ, η) of the nodes of an 8-node face: corners, then the mid-points of 1-2, 2-3, 3-4, 4-1
_QUAD8_XI = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1], [0, -1], [1, 0], [0, 1],
                      [-1, 0]], float)
#: share of the face's area of each node of a quadratic face (module docstring)
_SHARE = {"tri6": np.array([1 / 12] * 3 + [1 / 4] * 3),
          "quad8": np.array([1 / 24] * 4 + [5 / 24] * 4)}


def _shape(kind: str):
    """(weights (q,), N (q, m), dN/dξ (q, m), dN/dη (q, m)) at the Gauss points."""
    if kind == "quad8":
        return (_QUAD8_W, *_serendipity(_QUAD8_PTS[:, :1], _QUAD8_PTS[:, 1:]))
    if kind == "quad4":
        xi, eta = _QUAD_PTS[:, :1], _QUAD_PTS[:, 1:]
        a, b = _QUAD_XI[:, 0], _QUAD_XI[:, 1]
        N = 0.25 * (1 + a * xi) * (1 + b * eta)
        return _QUAD_W, N, 0.25 * a * (1 + b * eta), 0.25 * b * (1 + a * xi)
    r, s = _TRI_PTS[:, 0], _TRI_PTS[:, 1]
    L1 = 1 - r - s
    if kind == "tri3":
        one = np.ones_like(r)
        return (_TRI_W, np.column_stack([L1, r, s]),
                np.column_stack([-one, one, 0 * one]), np.column_stack([-one, 0 * one, one]))
    N = np.column_stack([L1 * (2 * L1 - 1), r * (2 * r - 1), s * (2 * s - 1),
                         4 * L1 * r, 4 * r * s, 4 * s * L1])
    dr = np.column_stack([1 - 4 * L1, 4 * r - 1, 0 * r, 4 * (L1 - r), 4 * s, -4 * s])
    ds = np.column_stack([1 - 4 * L1, 0 * r, 4 * s - 1, -4 * r, 4 * r, 4 * (L1 - s)])
    return _TRI_W, N, dr, ds


def _serendipity(xi: np.ndarray, eta: np.ndarray):
    """N, dN/dξ, dN/dη (q, 8) of the 8-node serendipity quadrilateral at (ξ, η) (q, 1)
    (Zienkiewicz, Taylor & Zhu, §6.4)."""
    a, b = _QUAD8_XI[:, 0], _QUAD8_XI[:, 1]
    corner, mid_x, mid_y = np.arange(8) < 4, a == 0, b == 0
    N = np.where(corner, 0.25 * (1 + a * xi) * (1 + b * eta) * (a * xi + b * eta - 1),
                 np.where(mid_x, 0.5 * (1 - xi ** 2) * (1 + b * eta),
                          0.5 * (1 + a * xi) * (1 - eta ** 2)))
    dxi = np.where(corner, 0.25 * a * (1 + b * eta) * (2 * a * xi + b * eta),
                   np.where(mid_x, -xi * (1 + b * eta), 0.5 * a * (1 - eta ** 2)))
    deta = np.where(corner, 0.25 * b * (1 + a * xi) * (a * xi + 2 * b * eta),
                    np.where(mid_y, -eta * (1 + a * xi), 0.5 * b * (1 - xi ** 2)))
    return N, dxi, deta


def _area_vectors(points: np.ndarray, fs: FaceSet) -> tuple[np.ndarray, np.ndarray]:
    """N (q, m) and the outward area vectors w_q x_ξ × x_η (k, q, 3) of the faces."""
    w, N, dxi, deta = _shape(fs.kind)
    X = points[fs.nodes]                                     # (k, m, 3)
    a = np.cross(np.einsum("qm,kmd->kqd", dxi, X), np.einsum("qm,kmd->kqd", deta, X))
    a *= w[None, :, None]
    centre = X.mean(axis=1)
    sign = np.sign(np.einsum("kd,kd->k", a.sum(axis=1), centre - fs.inside))
    return N, a * np.where(sign == 0, 1.0, sign)[:, None, None]


def face_areas(points: np.ndarray, fs: FaceSet) -> np.ndarray:
    """Area (k,), m², of each face of ``fs`` (Gauss quadrature of |x_ξ × x_η|)."""
    return np.linalg.norm(_area_vectors(points, fs)[1], axis=2).sum(axis=1)


def surface_nodes(facesets: list[FaceSet]) -> np.ndarray:
    """Sorted node indices on the faces."""
    if not facesets:
        return np.zeros(0, np.int64)
    return np.unique(np.concatenate([fs.nodes.ravel() for fs in facesets]))


def _weights(points: np.ndarray, fs: FaceSet) -> np.ndarray:
    """Area vector of each face node (k, m, 3): ∫ N_a n dA, or the sub-triangle rule."""
    N, a = _area_vectors(points, fs)
    if fs.kind not in _SHARE:
        return np.einsum("qm,kqd->kmd", N, a)
    whole = a.sum(axis=1)                                    # (k, 3): A n of each face
    return _SHARE[fs.kind][None, :, None] * whole[:, None, :]


def node_normals(points: np.ndarray, facesets: list[FaceSet], nodes: np.ndarray
                 ) -> np.ndarray:
    """Outward unit normals (len(nodes), 3) of the surface at ``nodes`` (module docstring)."""
    acc = np.zeros((points.shape[0], 3))
    for fs in facesets:
        np.add.at(acc, fs.nodes.ravel(), _weights(points, fs).reshape(-1, 3))
    v = acc[nodes]
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def node_areas(points: np.ndarray, facesets: list[FaceSet], nodes: np.ndarray) -> np.ndarray:
    """Tributary areas (len(nodes),), m², of ``nodes`` on the faces (module docstring)."""
    acc = np.zeros(points.shape[0])
    for fs in facesets:
        np.add.at(acc, fs.nodes.ravel(),
                  np.linalg.norm(_weights(points, fs), axis=2).ravel()
                  if fs.kind in _SHARE else
                  np.einsum("qm,kq->km", *_n_and_da(points, fs)).ravel())
    return acc[nodes]


def _n_and_da(points: np.ndarray, fs: FaceSet):
    N, a = _area_vectors(points, fs)
    return N, np.linalg.norm(a, axis=2)


def pressure_forces(points: np.ndarray, facesets: list[FaceSet], pressure: float
                    ) -> np.ndarray:
    """Consistent nodal forces (n_nodes, 3), N, of a uniform pressure (Pa, > 0 into the
    body) on the faces: f_a = −p ∫ N_a n dA."""
    f = np.zeros((points.shape[0], 3))
    for fs in facesets:
        N, a = _area_vectors(points, fs)
        np.add.at(f, fs.nodes.ravel(), -pressure * np.einsum("qm,kqd->kmd", N, a)
                  .reshape(-1, 3))
    return f
