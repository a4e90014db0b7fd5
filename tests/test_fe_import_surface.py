"""Face geometry of slipcycle.fe_import.surface against closed forms, on faces of any
planar shape and orientation (hypothesis: affine images of the reference faces)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from slipcycle.fe_import.mesh import FaceSet
from slipcycle.fe_import.surface import node_areas, node_normals, pressure_forces

_REF = {"tri3": [[0, 0], [1, 0], [0, 1]],
        "tri6": [[0, 0], [1, 0], [0, 1], [0.5, 0], [0.5, 0.5], [0, 0.5]],
        "quad4": [[0, 0], [1, 0], [1, 1], [0, 1]]}

coord = st.floats(-2.0, 2.0, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(kind=st.sampled_from(sorted(_REF)), m=st.lists(coord, min_size=9, max_size=9),
       shift=st.lists(coord, min_size=3, max_size=3), p=st.floats(-1e9, 1e9))
def test_face_area_normal_and_pressure_resultant(kind, m, shift, p):
    M = np.array(m).reshape(3, 3)
    ref = np.array(_REF[kind], float)
    X = np.column_stack([ref, np.zeros(len(ref))]) @ M.T + shift   # planar, any shape
    n = np.cross(M[:, 0], M[:, 1])
    jac = np.linalg.norm(n)
    if jac < 1e-3 or np.linalg.cond(np.column_stack([M[:, 0], M[:, 1], n])) > 1e6:
        return                                          # a degenerate face: no area
    n = n / jac
    area = jac * (0.5 if kind != "quad4" else 1.0)      # the reference area times |J|
    inside = X.mean(axis=0) - n                         # the element lies behind −n ...
    fs = FaceSet(kind, np.arange(len(X))[None, :], inside[None, :])
    nodes = np.arange(len(X))
    a = node_areas(X, [fs], nodes)
    assert np.all(a > 0) and abs(a.sum() - area) <= 1e-12 * area
    np.testing.assert_allclose(node_normals(X, [fs], nodes), np.tile(n, (len(X), 1)),
                               atol=1e-9)                # ... so n is outward
    f = pressure_forces(X, [fs], p)
    np.testing.assert_allclose(f.sum(axis=0), -p * area * n, atol=1e-9 * abs(p) * area
                               + 1e-300)
    if kind == "tri6":                                  # consistent loads: 0 at corners
        np.testing.assert_allclose(f[:3], 0.0, atol=1e-9 * abs(p) * area + 1e-300)
        np.testing.assert_allclose(a[:3], area / 12, rtol=1e-12)
    if kind == "tri3":
        np.testing.assert_allclose(a, area / 3, rtol=1e-12)


def test_a_face_seen_from_the_other_side_flips_its_normal():
    X = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    up = FaceSet("quad4", np.arange(4)[None, :], np.array([[0.5, 0.5, -1.0]]))
    down = FaceSet("quad4", np.arange(4)[None, :], np.array([[0.5, 0.5, 1.0]]))
    assert np.allclose(node_normals(X, [up], np.arange(4)), [0, 0, 1])
    assert np.allclose(node_normals(X, [down], np.arange(4)), [0, 0, -1])
    np.testing.assert_allclose(node_areas(X, [up], np.arange(4)), 0.25, rtol=1e-14)
