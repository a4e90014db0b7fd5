"""A sphere on a flat block, both elastic (slipcycle.fe.sphere3d + slipcycle.discrete3d).

Two bodies of one material (Dundurs β = 0) reduced onto their contact pairs by
:func:`slipcycle.fe.contact3d.reduce_contact_3d` and solved node to node with the 3-D
Coulomb-cone solver, against Hertz (contact radius a = (3PR/4E*)^{1/3}, E* = E/(2(1 − ν²))
for two bodies of one material; Johnson 1985, eq. 4.22), Cattaneo (stick radius
c/a = (1 − Q/fP)^{1/3}; Johnson 1985, eq. 7.46) and Mindlin–Deresiewicz (energy lost per
cycle of a tangential load ±Q*; Johnson 1985, eq. 7.60, in the form verified below),
with a mesh-convergence study and the plane-strain limit of a 3-D slab.

Observed (P1 tetrahedra, h = h_contact; see docs/fe3d.md): the contact radius from the
second moment of the nodal pressures approaches Hertz's with an observed order ≈ 1.35 on
the meshes h = 200, 140, 100 µm (a ≈ 575 µm; errors 5.5 %, 3.0 %, 2.2 %); the stick
radius from the stick area stays within one element size of Cattaneo's but does not
converge monotonically (node-set quantity).
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.sparse.linalg import spsolve
from skfem import Basis, ElementTetP1, ElementVector, MeshTet

from slipcycle.discrete3d.evolution import Evolution3D
from slipcycle.discrete3d.model import FrictionalSystem3D
from slipcycle.fe.assembly import stiffness
from slipcycle.fe.builders import block_on_rigid
from slipcycle.fe.contact3d import Case3D, mesh_nodes, reduce_contact_3d
from slipcycle.fe.geometry import depth_grid, interface_grid
from slipcycle.fe.mesh3d import split_interface
from slipcycle.fe.reduction import reduce_problem
from slipcycle.fe.sphere3d import SphereOnBlock, sphere_on_block

E, NU, R, F = 200e9, 0.3, 0.01, 0.3
E_STAR = E / (2 * (1 - NU**2))           # two bodies of one material
G = E / (2 * (1 + NU))
K_T = 2 * (2 - NU) / G                   # Σ (2 − ν_i)/G_i, tangential compliance factor
DELTA_N = 3e-5                           # approach of the cap top, m
MESHES = (2.0e-4, 1.4e-4, 1.0e-4)        # h_contact, m


def mindlin_loss(Q, P, a):
    """Energy lost per cycle of Q between ±Q* at constant P (J), Mindlin & Deresiewicz.

    W = (9 f² P² K/(10 a)) [1 − (1 − x)^{5/3} − (5x/6)(1 + (1 − x)^{2/3})], x = Q*/fP,
    K = (2 − ν1)/G1 + (2 − ν2)/G2 (Johnson 1985, eq. 7.60 with 1/G* = K; the last
    bracket has 1 + (1 − x)^{2/3}: with 1 − (1 − x)^{2/3} W would not vanish like x³).
    """
    x = Q / (F * P)
    return (9 * F**2 * P**2 * K_T / (10 * a)) * (1 - (1 - x) ** (5 / 3)
                                                - 5 * x / 6 * (1 + (1 - x) ** (2 / 3)))


def test_mindlin_closed_form_is_the_area_of_the_cattaneo_mindlin_loop():
    """The loop of Cattaneo's δ(Q) = (3fPK/16a)[1 − (1 − Q/fP)^{2/3}] with Mindlin's
    unloading δ* − 2δ((Q* − Q)/2), integrated numerically, equals :func:`mindlin_loss`."""
    P, a = 1000.0, 5e-4

    def load(Q):
        return 3 * F * P * K_T / (16 * a) * (1 - (1 - Q / (F * P)) ** (2 / 3))

    for x in (0.05, 0.4, 0.8, 0.99):
        Qs = x * F * P

        def unload(Q, Qs=Qs):
            return load(Qs) - 2 * load((Qs - Q) / 2)

        area = quad(lambda Q, u=unload: u(Q) + u(-Q), -Qs, Qs, epsabs=0, epsrel=1e-12)[0]
        assert area == pytest.approx(mindlin_loss(Qs, P, a), rel=1e-9)


_CACHE: dict = {}


def sphere(h):
    """Reduced sphere-on-block model with h_contact = h (cached for the module)."""
    if h not in _CACHE:
        model = SphereOnBlock(R=R, E=E, nu=NU, contact_radius=7e-4, h_contact=h,
                              h_far=1e-3, radius_body=5e-3, cap_height=5e-3,
                              block_height=5e-3)
        red, area = sphere_on_block(model)
        system = FrictionalSystem3D(red.A, red.B, red.C, F, coordinates=red.coordinates,
                                    normals=red.normals, tangents=red.tangents, area=area,
                                    accept_ill_posed=True)
        _CACHE[h] = (red, area, system)
    return _CACHE[h]


def _case(red, name):
    return np.concatenate([red.loads[name]["q"], red.loads[name]["p"]])


@functools.cache
def normal_contact(h):
    """State after the normal approach: (evolution, load, P, a from the pressure moment,
    r); the evolution is shared: copy its state, never follow it on."""
    red, area, system = sphere(h)
    N = red.C.shape[0]
    base = _case(red, "gap") + DELTA_N * _case(red, "normal")
    evo = Evolution3D(system, np.zeros(3 * N), np.zeros(3 * N), np.abs(base).max())
    evo.follow(np.arange(2.0), np.array([np.zeros(3 * N), base]))
    p = evo.r[2 * N:]
    r = np.hypot(red.coordinates[:, 0], red.coordinates[:, 1])
    P = p.sum()
    # Hertz: Σ p r² / P = (2/5) a² (second moment of p0 √(1 − r²/a²))
    a_moment = np.sqrt(2.5 * np.sum(p * r**2) / P)
    return evo, base, P, a_moment, r


def hertz_radius(P):
    return (3 * P * R / (4 * E_STAR)) ** (1 / 3)


def top_displacement(red, P, a, frac):
    """Cap-top displacement for Q ≈ frac f P: the bodies with the interface stuck (the
    ``tangential`` case) plus the microslip part of Cattaneo's compliance,
    (3fPK/16a)[1 − (1 − Q/fP)^{2/3}] − QK/(8a) (Johnson 1985, eq. 7.42)."""
    k_stuck = -red.loads["tangential"]["q"][::2].sum()   # cap top moved, interface held
    Q = frac * F * P
    slip = 3 * F * P * K_T / (16 * a) * (1 - (1 - frac) ** (2 / 3)) - Q * K_T / (8 * a)
    return Q / k_stuck + slip


@functools.cache
def cattaneo(h, frac=0.5):
    """Monotonic tangential displacement of the cap top (+x) after the normal approach.

    Returns (Q/fP, stick radius from the stick area, stick radius of Cattaneo, the final
    evolution and the normal-contact state)."""
    red, area, system = sphere(h)
    N = red.C.shape[0]
    evo, base, P, a_m, r = normal_contact(h)
    a = hertz_radius(P)
    d = top_displacement(red, P, a, frac)
    evo2 = Evolution3D(system, evo.x.copy(), base, np.abs(base).max())
    evo2.follow(np.arange(2.0), np.array([base, base + d * _case(red, "tangential")]))
    Q = -evo2.r[:2 * N:2].sum()
    c_area = np.sqrt(area[evo2.modes == 0].sum() / np.pi)
    c_cattaneo = a * (1 - Q / (F * P)) ** (1 / 3)
    return Q / (F * P), c_area, c_cattaneo, evo2, evo


@pytest.mark.parametrize("h", [MESHES[-1]])
def test_hertz_contact_radius_of_two_elastic_bodies(h):
    evo, _, P, a_moment, r = normal_contact(h)
    a = hertz_radius(P)
    closed = evo.modes != 2
    assert 0.3 < a / 7e-4 < 0.95                       # inside the candidate zone
    assert r[closed].max() <= a + h and r[~closed].min() >= a - h
    assert abs(a_moment - a) / a < 0.03


def test_cattaneo_stick_radius_within_one_element():
    h = MESHES[-1]
    ratio, c_area, c_cat, _, _ = cattaneo(h)
    assert 0.4 < ratio < 0.6
    assert abs(c_area - c_cat) < h


def test_slip_is_nearly_parallel_to_the_load_cattaneo_mindlin_residual():
    """Cattaneo–Mindlin assume traction and slip along the load (x). With the isotropic
    cone, node to node, at Q ≈ 0.43 fP (h = 100 µm, 47 slipping nodes) the traction
    deviates from x by 24.5° at most (at a node near the stick edge with 6 % of the largest
    slip), 6.3° on average weighted by the slip; the accumulated slip deviates from −q by
    8.9° at most, 3.6° weighted."""
    h = MESHES[-1]
    red = sphere(h)[0]
    N = red.C.shape[0]
    _, _, _, evo2, evo = cattaneo(h)
    slip = evo2.modes == 1
    q = evo2.r[:2 * N].reshape(N, 2)[slip]
    dv = (evo2.x[:2 * N] - evo.x[:2 * N]).reshape(N, 2)[slip]
    s = np.linalg.norm(dv, axis=1)
    traction_angle = np.degrees(np.arctan2(np.abs(q[:, 1]), -q[:, 0]))
    cos = -np.sum(q * dv, axis=1) / (np.linalg.norm(q, axis=1) * s)
    slip_vs_traction = np.degrees(np.arccos(np.clip(cos, -1, 1)))
    assert slip.sum() > 20
    assert traction_angle.max() < 30.0 and np.average(traction_angle, weights=s) < 8.0
    assert slip_vs_traction.max() < 12.0 and np.average(slip_vs_traction, weights=s) < 5.0


@functools.cache
def _loss(h):
    """Cycle the cap top between ±d (16 load steps per cycle) on the mesh h: (W_FE [J],
    W_MD at the measured Q* and P [J], Q*/fP); cached: two tests use h = 140 µm."""
    red, area, system = sphere(h)
    N = red.C.shape[0]
    evo, base, P, _, _ = normal_contact(h)
    a = hertz_radius(P)
    d = top_displacement(red, P, a, 0.6)
    t = _case(red, "tangential")
    evo = Evolution3D(system, evo.x.copy(), base, np.abs(base).max())
    evo.follow(np.arange(2.0), np.array([base, base + d * t]))
    theta = np.linspace(0, 2 * np.pi, 17)
    totals = evo.follow(theta, base + d * np.cos(theta)[:, None] * t[None, :], record=True)
    Q = -totals.samples["r"][:, :2 * N:2].sum(axis=1)
    Qs = 0.5 * (Q.max() - Q.min())
    return totals.dissipation.sum(), mindlin_loss(Qs, P, a), Qs / (F * P)


def test_mindlin_deresiewicz_loss_per_cycle():
    """The dissipation of one full cycle against the closed form at the measured Q* and P
    (h = 140 µm, 16 load steps per cycle: the FE loss is 13 % above Mindlin–Deresiewicz's)."""
    W, W_md, ratio = _loss(MESHES[1])
    assert 0.4 < ratio < 0.8
    assert W == pytest.approx(W_md, rel=0.15)


def test_mindlin_deresiewicz_loss_converges_to_the_closed_form():
    """Once the slip annulus (a − c ≈ 0.2 a ≈ 120 µm at Q*/fP ≈ 0.52) holds more than one
    ring of nodes, the loss error falls under refinement: W_FE / W_MD = 1.131, 1.098,
    1.055 at h = 140, 100, 70 µm, observed order 1.6 over the last step (docs/fe3d.md).
    At h = 200 µm (1.026) the annulus is one element wide and the agreement is chance."""
    hs = (1.4e-4, 1.0e-4, 7.0e-5)
    errors = [W / W_md - 1.0 for W, W_md, _ in map(_loss, hs)]
    assert errors == pytest.approx([0.131, 0.098, 0.055], abs=5e-4)
    assert errors[0] > errors[1] > errors[2] > 0
    order = np.log(errors[1] / errors[2]) / np.log(hs[1] / hs[2])
    assert order == pytest.approx(1.6, abs=0.05)
    W, W_md, _ = _loss(2.0e-4)
    assert W / W_md - 1.0 == pytest.approx(0.026, abs=5e-4)


def test_mesh_convergence_of_the_contact_and_stick_radii():
    """Errors of the moment contact radius fall with h; the observed order is stated."""
    err_a, err_c = [], []
    for h in MESHES:
        _, _, P, a_moment, _ = normal_contact(h)
        a = hertz_radius(P)
        err_a.append(abs(a_moment - a) / a)
        _, c_area, c_cat, _, _ = cattaneo(h)
        err_c.append(abs(c_area - c_cat) / a)
    order_a = np.log(err_a[0] / err_a[-1]) / np.log(MESHES[0] / MESHES[-1])
    assert err_a[0] > err_a[1] > err_a[2]
    assert order_a > 1.0
    assert max(err_c) < MESHES[0] / 5e-4


def test_bonded_interface_of_two_bodies_equals_one_body():
    """Two stacked blocks split at z = 0 and held at v = w = 0 carry the force of the
    unsplit block: top moved 1 m down, bottom held."""
    x = np.linspace(-1, 1, 5)
    mesh = MeshTet.init_tensor(x, x, x)
    eb = (mesh.p[2, mesh.t].mean(axis=0) < 0).astype(int)
    it = split_interface(mesh, eb, 0, 1)
    xyz = mesh_nodes(it.mesh)
    assert np.allclose(xyz[it.pairs[:, 0]], xyz[it.pairs[:, 1]])
    assert np.allclose(it.normals, [0, 0, -1]) and it.area.sum() == pytest.approx(4.0)
    fixed = np.zeros(xyz.shape, bool)
    top, bottom = np.isclose(xyz[:, 2], 1), np.isclose(xyz[:, 2], -1)
    fixed[top | bottom] = True
    u = np.zeros_like(xyz)
    u[top, 2] = -1.0
    red = reduce_contact_3d(it.mesh, materials=[(1.0, 0.3), (1.0, 0.3)], element_body=eb,
                            pairs=it.pairs, normals=it.normals, fixed=fixed,
                            cases=[Case3D("normal", "m", displacement=u)])
    # the unsplit block, solved directly: force on the held bottom face
    basis = Basis(mesh, ElementVector(ElementTetP1()))
    Kf = stiffness(basis, 1.0, 0.3)
    held = np.zeros((mesh.p.shape[1], 3), bool)
    held[np.isclose(mesh.p[2], 1) | np.isclose(mesh.p[2], -1)] = True
    u = np.zeros((mesh.p.shape[1], 3))
    u[np.isclose(mesh.p[2], 1), 2] = -1.0
    u, free = u.ravel(), np.flatnonzero(~held.ravel())   # P1 dofs: 3 × vertex + component
    u[free] = spsolve(Kf[free][:, free].tocsc(), -(Kf @ u)[free])
    reaction = (Kf @ u).reshape(-1, 3)[np.isclose(mesh.p[2], -1)].sum(axis=0)
    # the force on the block's bottom equals the force carried by the interface
    q = red.loads["normal"]["q"].reshape(-1, 2).sum(axis=0)
    assert red.loads["normal"]["p"].sum() == pytest.approx(reaction[2], rel=1e-9)
    assert np.allclose(q, reaction[:2], rtol=0, atol=1e-9 * reaction[2])
    K = np.block([[red.A, red.B.T], [red.B, red.C]])
    assert np.linalg.eigvalsh(K).min() > 0


def _plane_strain_slab(elements, width=1.0, height=0.5, nu=0.3):
    """A one-element-thick P1 slab on a rigid flat, u_y held off the contact; its reduced
    model with v2 = 0 and the two nodes at each x moving together, per unit thickness."""
    x = interface_grid(width, width, elements, 1.0)
    z = depth_grid(height, width / elements, 1.0)
    th = width / elements
    mesh = MeshTet.init_tensor(x, np.array([-th / 2, th / 2]), z)
    xyz = mesh_nodes(mesh)
    contact, top = np.isclose(xyz[:, 2], 0), np.isclose(xyz[:, 2], height)
    fixed = np.zeros(xyz.shape, bool)
    fixed[top] = True
    fixed[~contact, 1] = True                      # plane strain: u_y = 0
    cn = np.flatnonzero(contact)
    cn = cn[np.lexsort((xyz[cn, 1], xyz[cn, 0]))]  # the two nodes at each x adjacent
    cases = []
    for name, move in (("normal", (0, 0, -1.0)), ("tangential", (1.0, 0, 0))):
        u = np.zeros_like(xyz)
        u[top] = move
        cases.append(Case3D(name, "m", displacement=u))
    red = reduce_contact_3d(mesh, materials=[(1.0, nu)], pairs=np.column_stack(
        [cn, -np.ones(cn.size, int)]), normals=(0, 0, -1.0), fixed=fixed, cases=cases)
    N = cn.size // 2
    S = np.zeros((2 * N, N))
    S[np.arange(2 * N), np.arange(2 * N) // 2] = 1.0
    A, B = S.T @ red.A[::2, ::2] @ S / th, S.T @ red.B[:, ::2] @ S / th
    C = S.T @ red.C @ S / th
    loads = {k: (S.T @ red.loads[k]["q"][::2] / th, S.T @ red.loads[k]["p"] / th)
             for k in ("normal", "tangential")}
    return A, B, C, loads


@pytest.mark.parametrize("elements", [8, 16])
def test_slab_with_u_y_held_reproduces_the_plane_strain_reduction(elements):
    """Resultants of the load cases and the stiffness of a rigid motion of the contact
    face agree with the 2-D plane-strain reduction (P1 triangles) within 0.3 %; the
    spurious normal–tangential coupling of the tetrahedral split (zero in 2-D) is O(h):
    0.47 % of the normal resultant with 8 elements, 0.21 % with 16."""
    A, B, C, loads = _plane_strain_slab(elements)
    r = reduce_problem(block_on_rigid(width=1.0, height=0.5, E=1.0, nu=0.3,
                                      elements=elements, grading=1.0, element="P1"))
    one = np.ones(r.n)
    assert one @ C @ one == pytest.approx(one @ r.C @ one, rel=3e-3)
    assert one @ A @ one == pytest.approx(one @ r.A @ one, rel=3e-3)
    coupling = 0.02 * 8 / elements
    for k, (q, p) in loads.items():
        q2, p2 = r.case(k)
        main = max(abs(p2.sum()), abs(q2.sum()))
        assert p.sum() == pytest.approx(p2.sum(), rel=3e-3, abs=coupling * main)
        assert q.sum() == pytest.approx(q2.sum(), rel=3e-3, abs=coupling * main)
    assert abs(one @ B @ one) < 0.5 * coupling * (one @ C @ one)
