"""Three-dimensional FE reduction of a body on a rigid flat (slipcycle.fe.solid3d).

The reduced stiffness of the contact nodes, in their (t1, t2, n) frames, must be
symmetric positive definite; a rigid translation of the whole body (top face and contact
nodes together) must produce no reaction; and the normal contact of a parabolic gap (the
Hertz geometry of a sphere of radius R on a flat) must reach the Hertz contact radius
a = (3 P R / 4 E*)^{1/3} (Johnson 1985, §4.2) to within the node spacing.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import cholesky, solve_triangular
from scipy.optimize import nnls

from slipcycle.errors import InputError
from slipcycle.fe.solid3d import Block3D, block_on_rigid_3d

E, NU, R = 200e9, 0.3, 0.05


@pytest.fixture(scope="module")
def small():
    return block_on_rigid_3d(Block3D(width_x=0.02, width_y=0.02, height=0.01, E=E, nu=NU,
                                     contact_x=0.006, contact_y=0.006, elements=2,
                                     element="P2", radius=R))


def test_reduced_stiffness_is_spd_with_two_tangential_directions(small):
    N = small.C.shape[0]
    assert small.tangential_dims == 2
    assert small.A.shape == (2 * N, 2 * N) and small.B.shape == (N, 2 * N)
    K = np.block([[small.A, small.B.T], [small.B, small.C]])
    assert np.allclose(K, K.T, rtol=0, atol=1e-10 * np.abs(K).max())
    assert np.linalg.eigvalsh(K).min() > 0


def test_rigid_translation_of_the_whole_body_gives_no_reaction(small):
    """Top face and contact nodes moved together: q = q^w + A v + Bᵀ w = 0, p = 0."""
    N = small.C.shape[0]
    scale = np.abs(small.C).max()
    ones = np.ones(N)
    # normal: top 1 m towards the flat, every contact node too (w = −1)
    q = small.loads["normal"]["q"] - small.B.T @ ones
    p = small.loads["normal"]["p"] - small.C @ ones
    assert np.abs(q).max() <= 1e-8 * scale and np.abs(p).max() <= 1e-8 * scale
    for name, comp in (("tangential", 0), ("tangential2", 1)):
        v = np.zeros(2 * N)
        v[comp::2] = 1.0
        q = small.loads[name]["q"] + small.A @ v
        p = small.loads[name]["p"] + small.B @ v
        assert np.abs(q).max() <= 1e-8 * scale and np.abs(p).max() <= 1e-8 * scale


def test_gap_case_is_minus_the_stiffness_times_the_gap(small):
    g = (small.coordinates[:, 0] ** 2 + small.coordinates[:, 1] ** 2) / (2 * R)
    assert np.allclose(small.loads["gap"]["p"], -small.C @ g)
    assert np.allclose(small.loads["gap"]["q"], -small.B.T @ g)


def _normal_contact(red, delta):
    """Signorini problem p = p^w + C w ≥ 0, w ≥ 0, p·w = 0 as min ½wᵀCw + p^wᵀw, w ≥ 0."""
    pw = delta * red.loads["normal"]["p"] + red.loads["gap"]["p"]
    L = cholesky(red.C, lower=True)
    w, _ = nnls(L.T, -solve_triangular(L, pw, lower=True), maxiter=100 * pw.size)
    return w, pw + red.C @ w


@pytest.mark.slow
def test_hertz_contact_radius_within_the_node_spacing():
    red = block_on_rigid_3d(Block3D(width_x=0.04, width_y=0.04, height=0.02, E=E, nu=NU,
                                    contact_x=0.008, contact_y=0.008, elements=4,
                                    radius=R))
    spacing = 0.008 / 4 / 2  # P2: vertices and mid-points
    Estar = E / (1 - NU**2)
    for delta in (6e-5, 1e-4):
        w, p = _normal_contact(red, delta)
        assert p.min() >= -1e-9 * p.max()
        P = p.sum()
        a_hertz = (3 * P * R / (4 * Estar)) ** (1 / 3)
        x, y = red.coordinates[:, 0], red.coordinates[:, 1]
        axis = np.abs(y) < 1e-12
        closed = w <= 1e-12 * np.abs(w).max()
        a_in = np.abs(x[axis & closed]).max()
        a_out = np.abs(x[axis & ~closed]).min()
        assert a_in <= a_hertz + spacing and a_out >= a_hertz - spacing


def test_block_refuses_bad_input_with_the_key():
    with pytest.raises(InputError) as err:
        Block3D(width_x=0.02, width_y=0.02, height=0.01, E=E, nu=0.5, contact_x=0.006,
                contact_y=0.006)
    assert err.value.key == "nu"
    with pytest.raises(InputError) as err:
        Block3D(width_x=0.02, width_y=0.02, height=0.01, E=E, nu=NU, contact_x=0.03,
                contact_y=0.006)
    assert err.value.key == "contact_x"


def test_nested_dissection_condensation_equals_minimum_degree(monkeypatch):
    """The METIS-ordered one-factorisation Schur complement and load reactions agree with
    the minimum-degree path (two factorisations) to round-off."""
    import slipcycle.condensation as cond

    pytest.importorskip("pymetis")
    block = Block3D(width_x=0.02, width_y=0.02, height=0.01, E=E, nu=NU, contact_x=0.006,
                    contact_y=0.006, elements=4, element="P1", radius=R)
    nd = block_on_rigid_3d(block)
    monkeypatch.setattr(cond, "nested_dissection", lambda K: None)
    mmd = block_on_rigid_3d(block)
    for name in ("A", "B", "C"):
        M1, M2 = getattr(nd, name), getattr(mmd, name)
        assert np.allclose(M1, M2, rtol=0, atol=1e-10 * np.abs(M2).max())
    for case in ("normal", "tangential", "tangential2", "gap"):
        for k in ("q", "p"):
            ref = mmd.loads[case][k]
            assert np.allclose(nd.loads[case][k], ref, rtol=0,
                               atol=1e-10 * np.abs(mmd.C).max())


@pytest.mark.parametrize("formulation", ["displacement", "mixed"])
def test_p1_stiffness_with_one_quadrature_point_equals_the_default_rule(formulation):
    """P1 strains are constant per tetrahedron: the one-point rule of the 3-D reduction
    integrates the stiffness exactly, i.e. as scikit-fem's default four-point rule does."""
    from skfem import Basis, ElementTetP1, ElementVector

    from slipcycle.fe.assembly import stiffness
    from slipcycle.fe.contact3d import _stiffness
    from slipcycle.fe.solid3d import block_mesh_3d

    mesh = block_mesh_3d(Block3D(width_x=0.02, width_y=0.02, height=0.01, E=E, nu=NU,
                                 contact_x=0.006, contact_y=0.006, elements=3,
                                 element="P1"))
    elem = ElementVector(ElementTetP1())
    if formulation == "displacement":                            # two materials, two halves
        materials = [(E, NU), (2 * E, 0.2)]
        body = (mesh.p[0, mesh.t].mean(axis=0) > 0).astype(int)
    else:
        materials, body = [(E, 0.45)], np.zeros(mesh.t.shape[1], int)
    K, _ = _stiffness(mesh, elem, materials, body, "P1", formulation)
    ref = sum(stiffness(Basis(mesh, elem, elements=np.flatnonzero(body == k)), Ek, nuk,
                        1.0, formulation)
              for k, (Ek, nuk) in enumerate(materials))
    assert Basis(mesh, elem).X.shape[1] == 4                     # the default rule
    assert abs(K - ref).max() <= 1e-14 * abs(ref).max()
