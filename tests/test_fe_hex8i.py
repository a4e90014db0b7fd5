"""Hexahedra with incompatible modes (slipcycle.fe.hex8i).

The element must have exactly the six rigid-body modes; pass the patch test on the
distorted MacNeal–Harder (1985) solid patch (Taylor, Beresford & Wilson's modification);
represent pure bending exactly on rectangular elements with one element through the
height (the 3-D Saint-Venant solution, Timoshenko & Goodier 1970 §102), where linear
tetrahedra lock; converge at second order for a sinusoidal load; agree with scikit-fem's
trilinear hexahedron when the incompatible modes are not excited; and reject inverted
elements and invalid materials.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse.linalg as spla
from skfem import Basis, ElementHex1, ElementTetP1, ElementVector, MeshHex

from slipcycle.errors import InputError
from slipcycle.fe.assembly import stiffness
from slipcycle.fe.hex8i import hex8i_element_matrices, hex8i_stiffness

E, NU = 210e9, 0.3
# the prismatic beam of the bending tests: length x, width y, height z (m)
L, B, H = 0.1, 0.01, 0.004
I_Y = B * H**3 / 12

# natural coordinates of our vertices (bottom face counter-clockwise, then the top)
XI = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
               [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)


def box_mesh(nx, ny, nz, lx, ly, lz, origin=(0.0, 0.0, 0.0)):
    """Structured mesh of a box in our vertex order: points (3, n), hexes (8, m)."""
    axes = [o + np.linspace(0.0, s, k + 1) for o, s, k in zip(origin, (lx, ly, lz),
                                                            (nx, ny, nz), strict=True)]
    Z, Y, X = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    points = np.array([X.ravel(), Y.ravel(), Z.ravel()])

    def node(i, j, k):
        return i + (nx + 1) * (j + (ny + 1) * k)

    i, j, k = (a.ravel() for a in np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz),
                                              indexing="ij"))
    hexes = np.array([node(i + dx, j + dy, k + dz)
                      for dx, dy, dz in ((XI + 1) / 2).astype(int)])
    return points, hexes


def node_major(n):
    """dof[i, node] = 3 node + i, the numbering of hex8i_stiffness."""
    return 3 * np.arange(n) + np.arange(3)[:, None]


def solve(K, f, fixed, values):
    """Solve K u = f with u[fixed] = values."""
    u = np.zeros(K.shape[0])
    u[fixed] = values
    free = np.setdiff1d(np.arange(K.shape[0]), fixed)
    K = K.tocsr()
    rhs = f[free] - K[free][:, fixed] @ values
    u[free] = spla.spsolve(K[free][:, free].tocsc(), rhs)
    return u


def rigid_modes(points):
    """The six rigid-body displacement fields (6, 3 n), node-major."""
    x = points - points.mean(axis=1, keepdims=True)
    modes = []
    for i in range(3):
        t = np.zeros_like(x)
        t[i] = 1.0
        modes.append(t)
    for w in np.eye(3):
        modes.append(np.cross(w, x.T).T)
    return np.array([m.T.ravel() for m in modes])


def test_single_distorted_element_has_exactly_the_six_rigid_body_modes():
    rng = np.random.default_rng(1)
    X = (XI + 1) / 2 * [0.006, 0.004, 0.002] + rng.uniform(-4e-4, 4e-4, (8, 3)) * [1, 1, 0.5]
    Ke = hex8i_element_matrices(X[None], E, NU)[0]
    assert Ke.shape == (24, 24)
    assert np.array_equal(Ke, Ke.T)
    w = np.linalg.eigvalsh(Ke)
    rel = w / w[-1]
    assert np.all(np.abs(rel[:6]) < 1e-12)  # six zero eigenvalues ...
    assert rel[6] > 1e-3  # ... and no seventh (no spurious zero-energy mode)
    assert rel.min() > -1e-12  # positive semi-definite
    R = rigid_modes(X.T)
    assert np.abs(Ke @ R.T).max() < 1e-12 * np.abs(Ke).max() * np.abs(R).max()


# MacNeal & Harder (1985), Fig. 2: unit cube, inner nodes in the order of the outer corners
MH_INNER = np.array([[0.249, 0.342, 0.192], [0.826, 0.288, 0.288], [0.850, 0.649, 0.263],
                     [0.273, 0.750, 0.230], [0.320, 0.186, 0.643], [0.677, 0.305, 0.683],
                     [0.788, 0.693, 0.644], [0.165, 0.745, 0.702]])
# faces of a hexahedron, counter-clockwise seen from outside
FACES = ((0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7))


def macneal_harder_patch():
    """Seven distorted hexahedra filling the unit cube; nodes 0-7 outer, 8-15 inner."""
    points = np.concatenate([(XI + 1) / 2, MH_INNER]).T
    outer, inner = np.arange(8), np.arange(8, 16)
    hexes = [inner]
    for f in FACES:  # outer face as the bottom, seen counter-clockwise from the inside
        q = [f[0], f[3], f[2], f[1]]
        hexes.append(np.concatenate([outer[q], inner[q]]))
    return points, np.array(hexes).T


def test_patch_test_on_the_distorted_macneal_harder_patch():
    points, hexes = macneal_harder_patch()
    K = hex8i_stiffness(points, hexes, E, NU)
    rng = np.random.default_rng(2)
    a = rng.normal(size=3) * 1e-3
    G = rng.normal(size=(3, 3)) * 1e-3  # general: stretch, shear and rotation
    u_lin = (a[:, None] + G @ points).T.ravel()
    dof = node_major(16)
    outer, inner = dof[:, :8].T.ravel(), dof[:, 8:].T.ravel()
    u = solve(K, np.zeros(48), outer, u_lin[outer])
    assert np.abs(u[inner] - u_lin[inner]).max() < 1e-10 * np.abs(u_lin).max()
    # reactions = consistent nodal forces of the constant stress σ = D ε on the cube's
    # faces: each face is one flat unit square, 1/4 of σ n to each of its corners
    eps = 0.5 * (G + G.T)
    lam, mu = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    sigma = lam * np.trace(eps) * np.eye(3) + 2 * mu * eps
    r = (K @ u_lin).reshape(16, 3)
    corner_normals = 2 * points[:, :8].T - 1  # Σ of the outward normals at each corner
    assert np.allclose(r[:8], corner_normals @ sigma / 4, rtol=0,
                       atol=1e-10 * np.abs(sigma).max())
    assert np.abs(r[8:]).max() < 1e-10 * np.abs(sigma).max()


def pure_bending(points, dof, K, M=1.0):
    """Beam x ∈ [0, L], |y| ≤ B/2, |z| ≤ H/2 (one element through width and height) under
    the end moment M about y. Returns the computed and exact displacements (3, n).

    The end x = L carries the consistent nodal forces of σ_xx = M z / I; the end x = 0 has
    u_x = 0 at every node (exact there, with the exact reactions) and three more dofs set
    to the exact values (against rigid motion only), so the anticlastic/Poisson
    deformation is free.
    """
    x, y, z = points
    R = E * I_Y / M  # radius of curvature
    exact = np.array([x * z / R, -NU * y * z / R, -(x**2 + NU * (z**2 - y**2)) / (2 * R)])
    f = np.zeros(K.shape[0])
    end = np.flatnonzero(np.isclose(x, L))
    # ∫ N_a σ_xx dA over the B × H face: ±(M/I)(B/2)(H²/12) at its four corners
    f[dof[0, end]] = M / I_Y * (B / 2) * H**2 / 12 * np.sign(z[end])
    root = np.flatnonzero(np.isclose(x, 0.0))
    corner = root[np.isclose(y[root], -B / 2)]
    lo, hi = corner[np.argmin(z[corner])], corner[np.argmax(z[corner])]
    fixed = np.concatenate([dof[0, root], [dof[1, lo], dof[1, hi], dof[2, lo]]])
    nodes = np.concatenate([root, [lo, hi, lo]])
    values = exact[[0] * root.size + [1, 1, 2], nodes]
    u = solve(K, f, fixed, values)
    return u[dof], exact


def test_pure_bending_is_exact_with_one_element_through_the_height_where_tets_lock():
    points, hexes = box_mesh(10, 1, 1, L, B, H, origin=(0.0, -B / 2, -H / 2))
    K = hex8i_stiffness(points, hexes, E, NU)
    u, exact = pure_bending(points, node_major(points.shape[1]), K)
    # the exact field, Poisson terms included: u_x = x z/R, u_y = −ν y z/R,
    # u_z = −(x² + ν (z² − y²))/(2R); deflection of the axis −M x²/(2 E I)
    assert np.abs(u - exact).max() < 1e-8 * np.abs(exact).max()

    # linear tetrahedra (6 per brick) on the same nodes: far too stiff
    tets = MeshHex.init_tensor(np.linspace(0, L, 11), np.linspace(-B / 2, B / 2, 2),
                               np.linspace(-H / 2, H / 2, 2)).to_meshtet()
    basis = Basis(tets, ElementVector(ElementTetP1()))
    Kt = stiffness(basis, E, NU, 1.0, "displacement")
    ut, exact_t = pure_bending(tets.p, basis.nodal_dofs, Kt)
    tip = np.isclose(tets.p[0], L)
    ratio = ut[2, tip].mean() / exact_t[2, tip].mean()  # tip deflection / exact
    assert ratio < 0.5  # measured 0.106: an error of 89 %


def sinusoidal_midspan_deflection(nx, ny, nz, q0=1000.0):
    """Beam (L × B × H) under the top pressure (q0/B) sin(πx/L), N/m², downwards,
    supported at both ends as in the separable elasticity solution (u_y = u_z = 0 on the
    whole end faces, u_x free; u_x = 0 at one mid-span node against rigid motion).
    Returns the mean deflection of the mid-span section, m."""
    points, hexes = box_mesh(nx, ny, nz, L, B, H, origin=(0.0, -B / 2, -H / 2))
    K = hex8i_stiffness(points, hexes, E, NU)
    dof = node_major(points.shape[1])
    x = points[0]
    # consistent nodal loads ∫ N_a p dA on each top face (6-point Gauss along x: the
    # sine is not a polynomial; exact in y)
    f = np.zeros(K.shape[0])
    gx, gw = np.polynomial.legendre.leggauss(6)
    hx, hy = L / nx, B / ny
    for top in hexes[4:, np.isclose(points[2, hexes[4]], H / 2)].T:
        x0 = x[top].min()
        xq = x0 + hx * (gx + 1) / 2
        p = q0 / B * np.sin(np.pi * xq / L) * gw * hx / 2 * hy / 2
        for v in top:
            shape = 1 - np.abs(xq - x[v]) / hx  # the linear shape function along x
            f[dof[2, v]] -= np.sum(p * shape)
    ends = np.flatnonzero(np.isclose(x, 0) | np.isclose(x, L))
    mid = np.flatnonzero(np.isclose(x, L / 2))
    fixed = np.concatenate([dof[1, ends], dof[2, ends], [dof[0, mid[0]]]])
    u = solve(K, f, fixed, np.zeros(fixed.size))
    return -u[dof[2, mid]].mean()


@pytest.mark.parametrize("meshes", [
    pytest.param([(8, 2, 2), (16, 4, 4), (32, 8, 8)], id="refined-in-all-directions"),
    pytest.param([(8, 1, 1), (16, 1, 1), (32, 1, 1)], id="one-element-through-the-height"),
])
def test_second_order_convergence_under_a_sinusoidal_load(meshes):
    """Simply supported beam under a sine load (not a polynomial: no mesh is exact).
    Observed order from three meshes h, h/2, h/4 (Richardson):
    p = log2((w1 − w2)/(w2 − w3)); measured 2.02 (all directions refined) and 1.99 (in
    plane only, one element through the height: the thin-plate use)."""
    q0 = 1000.0
    w = np.array([sinusoidal_midspan_deflection(*m, q0=q0) for m in meshes])
    assert np.all(np.diff(w) > 0)  # monotone, from below (too stiff)
    order = np.log2((w[1] - w[0]) / (w[2] - w[1]))
    assert 1.5 < order < 2.5
    # converges to the beam solution: Timoshenko, with the shear correction 5/6
    G = E / (2 * (1 + NU))
    w_beam = q0 * L**4 / (np.pi**4 * E * I_Y) + q0 * L**2 / (np.pi**2 * 5 / 6 * G * B * H)
    w_extrapolated = w[2] + (w[2] - w[1]) / (2**order - 1)
    assert abs(w_extrapolated / w_beam - 1) < 5e-3
    assert abs(w[2] / w_beam - 1) < 1e-2


def test_equals_the_trilinear_hexahedron_of_skfem_under_linear_fields():
    """A linear field does no work on the incompatible modes (Taylor's modification), so
    K u is that of the fully integrated trilinear hexahedron, on distorted elements too."""
    mesh = MeshHex.init_tensor(np.linspace(0, 0.02, 3), np.linspace(0, 0.01, 3),
                               np.linspace(0, 0.004, 3))
    # our vertex order from skfem's: bit code of each vertex's position in its element
    lo = mesh.p[:, mesh.t].min(axis=1)
    span = mesh.p[:, mesh.t].max(axis=1) - lo
    bits = np.rint((mesh.p[:, mesh.t] - lo[:, None]) / span[:, None]).astype(int)
    code = bits[0] + 2 * bits[1] + 4 * bits[2]  # (8, m)
    ours = [0, 1, 3, 2, 4, 5, 7, 6]  # codes of (ξ, η, ζ) = (−1,−1,−1), (1,−1,−1), …
    hexes = np.array([mesh.t[np.argmax(code == c, axis=0), np.arange(mesh.t.shape[1])]
                      for c in ours])
    p = mesh.p.copy()
    centre = np.flatnonzero(np.all(np.isclose(p, [[0.01], [0.005], [0.002]]), axis=0))
    p[:, centre] += [[0.002], [-0.0015], [0.0005]]  # all eight elements distorted
    mesh = MeshHex(p, mesh.t)
    basis = Basis(mesh, ElementVector(ElementHex1()))
    Ks = stiffness(basis, E, NU, 1.0, "displacement")
    K = hex8i_stiffness(p, hexes, E, NU)
    dof = node_major(p.shape[1])
    for k in range(12):  # every constant and linear field
        c = np.zeros(12)
        c[k] = 1e-3
        field = c[:3, None] + c[3:].reshape(3, 3) @ p
        u, us = np.zeros(K.shape[0]), np.zeros(Ks.shape[0])
        u[dof] = field
        us[basis.nodal_dofs] = field
        r, rs = (K @ u)[dof], (Ks @ us)[basis.nodal_dofs]
        scale = abs(Ks).max() * np.abs(field).max()  # round-off of K u
        assert np.abs(r - rs).max() < 1e-10 * scale
    # ... whereas bending (u_x = x z, u_z = −x²/2 at the nodes) excites them: the
    # trilinear element adds spurious shear energy (energy ratio measured 0.71)
    u[:], us[:] = 0.0, 0.0
    u[dof[0]] = us[basis.nodal_dofs[0]] = p[0] * p[2]
    u[dof[2]] = us[basis.nodal_dofs[2]] = -p[0] ** 2 / 2
    assert u @ (K @ u) < 0.8 * (us @ (Ks @ us))


def test_inverted_elements_and_invalid_materials_are_rejected():
    points, hexes = box_mesh(3, 1, 1, 0.03, 0.01, 0.004)
    inverted = hexes.copy()
    inverted[:, 1] = hexes[[4, 5, 6, 7, 0, 1, 2, 3], 1]  # top and bottom swapped
    with pytest.raises(InputError, match=r"1 element\(s\).*first: element 1") as info:
        hex8i_stiffness(points, inverted, E, NU)
    assert info.value.key == "hexes"
    twisted = hexes.copy()
    twisted[:, 2] = hexes[[1, 0, 2, 3, 4, 5, 6, 7], 2]  # two vertices exchanged
    with pytest.raises(InputError) as info:
        hex8i_stiffness(points, twisted, E, NU)
    assert info.value.key == "hexes"
    for bad in (hexes[:4], hexes.astype(float), hexes + points.shape[1], hexes - 100):
        with pytest.raises(InputError) as info:
            hex8i_stiffness(points, bad, E, NU)
        assert info.value.key == "hexes"
    for nu in (0.5, -0.1, np.nan, [0.3, 0.3]):
        with pytest.raises(InputError) as info:
            hex8i_stiffness(points, hexes, E, nu)
        assert info.value.key == "nu"
    for e in (0.0, -1.0, np.inf, np.ones(2)):
        with pytest.raises(InputError) as info:
            hex8i_stiffness(points, hexes, e, NU)
        assert info.value.key == "E"
    with pytest.raises(InputError) as info:
        hex8i_element_matrices(points.T[inverted.T], E, NU)
    assert info.value.key == "X"


def test_per_element_materials_equal_separate_calls_summed():
    points, hexes = box_mesh(2, 1, 1, 0.02, 0.01, 0.004)
    points[2, np.isclose(points[0], 0.01)] += 0.0005  # shared face not flat-normal: distorted
    E2, nu2 = 70e9, 0.33
    K = hex8i_stiffness(points, hexes, [E, E2], np.array([NU, nu2]))
    K_sum = (hex8i_stiffness(points, hexes[:, :1], E, NU)
             + hex8i_stiffness(points, hexes[:, 1:], E2, nu2))
    assert K.shape == (3 * points.shape[1],) * 2
    assert abs(K - K_sum).max() < 1e-12 * abs(K).max()
    assert abs(K - hex8i_stiffness(points, hexes, E, NU)).max() > 0.1 * abs(K).max()
    # chunking changes nothing, and the result is exactly symmetric
    K1 = hex8i_stiffness(points, hexes, [E, E2], [NU, nu2], chunk=1)
    assert abs(K - K1).max() < 1e-12 * abs(K).max()
    assert abs(K - K.T).max() == 0.0
