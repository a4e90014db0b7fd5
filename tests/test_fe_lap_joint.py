"""The bolted lap joint reduced to its overlap (slipcycle.fe.lap_joint).

Independent references: the full (unreduced) FE model of the bonded joint solved directly
for the grip reactions (global equilibrium of the upper plate), the exact mirror symmetry
of a symmetric bolt pattern, the spectrum of K, and a mesh-refinement study of the
interface compliance with its observed order.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.sparse.linalg import spsolve
from scipy.spatial import cKDTree
from skfem import Basis, ElementTetP1, ElementVector, MeshTet

from slipcycle.discrete3d.model import FrictionalSystem3D
from slipcycle.discrete3d.steady import initial_state_3d
from slipcycle.errors import InputError
from slipcycle.fe.assembly import stiffness
from slipcycle.fe.lap_joint import LapJoint, lap_joint_mesh, lap_joint_model

#: a small M6 joint, coarse enough for unit tests (≈ 100 contact nodes)
SMALL = LapJoint(plate_length=0.06, plate_width=0.03, thickness=0.003, overlap=0.03,
                 bolt_diameter=0.0066, washer_diameter=0.012, mesh_size=0.003)


@pytest.fixture(scope="module", params=["P1", "H8I"])
def small(request):
    """The small joint reduced with linear tetrahedra and with incompatible-mode
    hexahedra: every test that takes it holds for both elements."""
    return lap_joint_model(dataclasses.replace(SMALL, element=request.param))


@pytest.fixture(scope="module")
def small_p1():
    return lap_joint_model(SMALL)


def _bonded_grip_reactions(joint: LapJoint, k: int):
    """Grip reactions (3,) on the upper plate of the bonded joint, straight from the full FE
    model: interface nodes merged, grips clamped, (a) bolt k's washer pressures (1 N per
    plate, P1 consistent loads: a third of each loaded triangle to its corners), (b) the
    upper grip moved 1 m along x. Returns (R_bolt, R_service) in N and N/m."""
    m = lap_joint_mesh(joint)
    p = m.mesh.p
    n_up = int(m.mesh.t[:, m.element_body == 0].max()) + 1
    on_plane = np.abs(p[2]) < 1e-12
    lower = np.flatnonzero(on_plane & (np.arange(p.shape[1]) >= n_up))
    upper = np.flatnonzero(on_plane & (np.arange(p.shape[1]) < n_up))
    dist, idx = cKDTree(p[:, upper].T).query(p[:, lower].T)
    merge = np.arange(p.shape[1])
    merge[lower[dist < 1e-12]] = upper[idx[dist < 1e-12]]
    t = merge[m.mesh.t]
    used = np.unique(t)
    new = np.full(p.shape[1], -1)
    new[used] = np.arange(used.size)
    mesh = MeshTet(p[:, used], new[t])
    basis = Basis(mesh, ElementVector(ElementTetP1()))
    K = stiffness(basis, joint.E, joint.nu)
    x0, _, _, x1 = m.ranges
    xyz = mesh.p
    dofs = basis.nodal_dofs                               # (3, n_vertices)
    grip_up = np.abs(xyz[0] - x1) < 1e-12
    grip_lo = np.abs(xyz[0] - x0) < 1e-12
    held = np.concatenate([dofs[:, grip_up].ravel(), dofs[:, grip_lo].ravel()])
    free = np.setdiff1d(np.arange(basis.N), held)
    # washer loads: P1 consistent nodal forces of a uniform pressure
    f = np.zeros(basis.N)
    cx, cy = joint.centres[k]
    faces = mesh.facets[:, mesh.boundary_facets()]
    mid = xyz[:, faces].mean(axis=1)
    r = np.hypot(mid[0] - cx, mid[1] - cy)
    for zf, sign in ((joint.thickness, -1.0), (-joint.thickness, 1.0)):
        sel = faces[:, (r > joint.bolt_diameter / 2) & (r < joint.washer_diameter / 2)
                    & (np.abs(mid[2] - zf) < 1e-12)]
        a = 0.5 * np.linalg.norm(np.cross(*(xyz[:, sel[j]] - xyz[:, sel[0]] for j in (1, 2)),
                                          axis=0), axis=0)
        for j in range(3):
            np.add.at(f, dofs[2, sel[j]], sign * a / 3 / a.sum())
    Kc = sp.csr_matrix(K)
    out = []
    for load, ug in ((f, 0.0), (np.zeros(basis.N), 1.0)):
        u = np.zeros(basis.N)
        u[dofs[0, grip_up]] = ug
        u[free] = spsolve(Kc[free][:, free].tocsc(), load[free] - Kc[free] @ u)
        react = Kc @ u - load
        out.append(np.array([react[dofs[c, grip_up]].sum() for c in range(3)]))
    return out


def test_bolt_and_service_cases_balance_the_grip_reactions_of_the_full_bonded_model(
        small_p1):
    """Upper-plate equilibrium: Σp^w(bolt) + R_z = 1 N, Σq^w + R = 0, with R the grip
    reactions of the full FE model solved directly; the service scale (N per m of grip
    motion) equals the full model's grip stiffness."""
    small = small_p1
    red = small.reduced
    r_bolt, r_service = _bonded_grip_reactions(SMALL, 0)
    case = red.loads["bolt_0"]
    assert np.sum(case["p"]) + r_bolt[2] == pytest.approx(1.0, abs=1e-8)
    assert np.sum(case["q"][0::2]) + r_bolt[0] == pytest.approx(0.0, abs=1e-8)
    assert np.sum(case["q"][1::2]) + r_bolt[1] == pytest.approx(0.0, abs=1e-8)
    assert small.grip_share[0] == pytest.approx(r_bolt[2], abs=1e-8)
    assert abs(small.grip_share[0]) < 0.01          # the clamping reaches the interface
    assert small.description["service_grip_stiffness_N_per_m"] == pytest.approx(
        r_service[0], rel=1e-8)


@pytest.mark.parametrize(("case", "component"),
                         [("service", 0), ("service_y", 1), ("service_z", 2)])
def test_service_cases_carry_one_newton_across_the_stuck_interface(small, case, component):
    """Σ over the contact nodes of the interface force along the grip motion is −1 N."""
    loads = small.reduced.loads[case]
    total = np.sum(loads["p"]) if component == 2 else np.sum(loads["q"][component::2])
    assert total == pytest.approx(-1.0, abs=1e-12)


def test_every_bolt_case_puts_its_preload_on_the_interface(small):
    for k in range(SMALL.bolt_count):
        p = small.reduced.loads[f"bolt_{k}"]["p"]
        assert np.sum(p) == pytest.approx(1.0 - small.grip_share[k], abs=1e-12)
        assert np.sum(p) == pytest.approx(1.0, abs=0.01)


def test_symmetric_bolt_row_gives_mirror_symmetric_preload_reactions(small):
    """Bolts at y = ±W/4: bolt 0 at (x, y) is bolt 1 at (x, −y); q_y changes sign."""
    red = small.reduced
    xy = red.coordinates[:, :2]
    dist, image = cKDTree(xy).query(xy * np.array([1.0, -1.0]))
    assert dist.max() < 1e-12                       # the mesh itself is mirror-symmetric
    b0, b1 = red.loads["bolt_0"], red.loads["bolt_1"]
    scale = np.abs(b0["p"]).max()
    assert np.abs(b0["p"][image] - b1["p"]).max() < 1e-8 * scale
    assert np.abs(b0["q"][0::2][image] - b1["q"][0::2]).max() < 1e-8 * scale
    assert np.abs(b0["q"][1::2][image] + b1["q"][1::2]).max() < 1e-8 * scale
    off_axis = np.abs(xy[:, 1]) > 1e-12            # y = 0 is equidistant: a tie
    assert np.array_equal(small.bolt_region[image][off_axis],
                          1 - small.bolt_region[off_axis])


def test_odd_bolt_row_cut_by_the_mirror_plane_gives_mirror_symmetric_reactions():
    """K = 3: the middle hole straddles y = 0 (meshed as two halves); bolt 1 is its own
    mirror image, bolts 0 and 2 swap."""
    joint = dataclasses.replace(SMALL, bolt_count=3, plate_width=0.045)
    red = lap_joint_model(joint).reduced
    xy = red.coordinates[:, :2]
    dist, image = cKDTree(xy).query(xy * np.array([1.0, -1.0]))
    assert dist.max() < 1e-12
    for a, b in ((0, 2), (1, 1)):
        pa, pb = red.loads[f"bolt_{a}"]["p"], red.loads[f"bolt_{b}"]["p"]
        assert np.abs(pa[image] - pb).max() < 1e-8 * np.abs(pa).max()


def test_unsymmetric_bolt_pattern_is_meshed_whole_and_balances():
    """Staggered bolts (no mirror symmetry): the full plan is meshed; each bolt case still
    puts its preload on the interface and the service case carries 1 N."""
    joint = dataclasses.replace(SMALL, bolt_positions=((-0.003, -0.0075), (0.003, 0.0075)))
    model = lap_joint_model(joint)
    red = model.reduced
    xy = red.coordinates[:, :2]
    dist, _ = cKDTree(xy).query(xy * np.array([1.0, -1.0]))
    assert dist.max() > 1e-6                          # not a mirrored mesh
    for k in range(2):
        assert np.sum(red.loads[f"bolt_{k}"]["p"]) == pytest.approx(
            1.0 - model.grip_share[k], abs=1e-12)
        assert abs(model.grip_share[k]) < 0.01
    assert np.sum(red.loads["service"]["q"][0::2]) == pytest.approx(-1.0, abs=1e-12)
    assert set(np.unique(model.bolt_region)) == {0, 1}


def test_plates_are_conforming_tetrahedral_meshes_of_the_right_volume():
    """Every boundary face lies on a face of a plate or on a hole wall (no internal cracks
    from inconsistent prism splits), all tetrahedra are positive, and the volume is t times
    the plan area of each plate."""
    m = lap_joint_mesh(SMALL)
    mesh, t = m.mesh, SMALL.thickness
    p = mesh.p
    e1, e2, e3 = (p[:, mesh.t[j]] - p[:, mesh.t[0]] for j in (1, 2, 3))
    vol = np.einsum("ij,ij->j", e1, np.cross(e2, e3, axis=0)) / 6
    assert vol.min() > 0
    x0, a, b, x1 = m.ranges
    faces = mesh.facets[:, mesh.boundary_facets()]
    c = p[:, faces].mean(axis=1)
    r = np.min(np.linalg.norm(c[:2].T[:, None] - SMALL.centres[None], axis=-1), axis=1)
    on_face = (np.isclose(np.abs(c[2]), t) | np.isclose(c[2], 0.0)
               | np.isclose(np.abs(c[1]), SMALL.plate_width / 2)
               | np.any(np.isclose(c[0][:, None], [x0, a, b, x1]), axis=1)
               | (r < SMALL.bolt_diameter / 2))
    assert on_face.all()
    tri = m.plan_points[m.interface_cells]
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    overlap_area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]).sum()
    plate_area = (SMALL.plate_length - SMALL.overlap) * SMALL.plate_width + overlap_area
    for body in (0, 1):
        assert vol[m.element_body == body].sum() == pytest.approx(t * plate_area, rel=1e-12)


def test_reduced_stiffness_is_symmetric_positive_definite(small):
    red = small.reduced
    K = np.block([[red.A, red.B.T], [red.B, red.C]])
    assert np.abs(K - K.T).max() <= 1e-12 * np.abs(K).max()
    lam = np.linalg.eigvalsh(K)
    assert lam[0] > 1e-8 * lam[-1]


def test_node_areas_partition_the_overlap_and_regions_are_nearest_bolts(small):
    red = small.reduced
    holes = SMALL.bolt_count * np.pi * (SMALL.bolt_diameter / 2) ** 2
    exact = SMALL.overlap * SMALL.plate_width - holes
    # polygonal holes (inscribed polygons of ≥ 6 sides lose at most 1 − 3√3/(2π) of a disc)
    assert exact <= small.node_area.sum() <= exact + (1 - 3 * np.sqrt(3) / (2 * np.pi)) * holes
    d = np.linalg.norm(red.coordinates[:, None, :2] - small.bolt_centres[None], axis=-1)
    assert np.array_equal(small.bolt_region, np.argmin(d, axis=1))
    assert np.all(np.abs(red.coordinates[:, 2]) < 1e-15)
    assert red.n_nodes == small.node_area.size == small.bolt_region.size


def test_preload_leaves_the_overlap_edges_open_and_clamps_around_the_washers(small):
    """Incomplete contact: with the slip held at zero (tightening, stuck interface), the
    normal contact problem under both preloads (the one 3-D engine,
    :func:`slipcycle.discrete3d.steady.initial_state_3d`) closes a region around the
    washers only; the plate ends x = ±c/2 lift off, and the pressure falls towards zero
    at the edge of the closed region."""
    red = small.reduced
    N = red.n_nodes
    system = FrictionalSystem3D(red.A, red.B, red.C, 0.3, accept_ill_posed=True)
    r_w = sum(small.reduced.loads[f"bolt_{k}"]["q"] for k in range(2))
    p_w = sum(small.reduced.loads[f"bolt_{k}"]["p"] for k in range(2))
    x = initial_state_3d(system, np.concatenate([r_w, p_w]), np.zeros(2 * N), np.inf)
    p = p_w + red.B @ x[:2 * N] + red.C @ x[2 * N:]
    closed = x[2 * N:] <= 0.0
    xy = red.coordinates[:, :2]
    edge = np.abs(np.abs(xy[:, 0]) - SMALL.overlap / 2) < 1e-12
    assert not closed[edge].any()
    assert 0.1 < small.node_area[closed].sum() / small.node_area.sum() < 0.9
    assert np.sum(p) == pytest.approx(2.0, abs=0.01)   # the grips take < 0.5 %
    assert np.all(p[closed] > 0.0)
    pressure = p / small.node_area
    r = np.min(np.linalg.norm(xy[:, None] - small.bolt_centres[None], axis=-1), axis=1)
    rim = closed & (r > np.quantile(r[closed], 0.9))    # the outermost closed nodes
    inner = closed & (r < SMALL.washer_diameter / 2)
    assert pressure[rim].mean() < 0.35 * pressure[inner].mean()


def _total_contact_stiffness(model) -> tuple[float, float]:
    """Force to slide the whole interface rigidly by 1 m along x with the opening held,
    1ᵀA1 (N/m), and to open it uniformly by 1 m with the slip held, 1ᵀC1 (N/m)."""
    red = model.reduced
    N = red.n_nodes
    ones_x = np.zeros(2 * N)
    ones_x[0::2] = 1.0
    return float(ones_x @ red.A @ ones_x), float(red.C.sum())


def test_total_contact_stiffness_converges_under_mesh_refinement():
    """6 mm plates, h = 3, 2.12, 1.5 mm with 2, 3, 4 layers (t/h = 2, 2.8, 4: linear
    tetrahedra are stiff in bending until t/h ≳ 2): both totals fall monotonically by
    decreasing amounts with observed order p = log(Δ₁/Δ₂)/log √2 > 0.5 (measured ≈ 0.9
    tangential, ≈ 1.1 normal) and the tangential one changes < 5 % in the last step."""
    values = []
    for h, layers in ((0.003, 2), (0.003 / np.sqrt(2), 3), (0.0015, 4)):
        joint = dataclasses.replace(SMALL, thickness=0.006, mesh_size=h, layers=layers)
        values.append(_total_contact_stiffness(lap_joint_model(joint)))
    values = np.array(values)
    for j in range(2):
        d1, d2 = np.diff(values[:, j])
        assert d1 < 0 and d2 < 0                   # a stiff discretisation softens
        order = np.log(d1 / d2) / np.log(np.sqrt(2))
        assert order > 0.5
    assert abs(d2) < 0.15 * values[-1, 1]
    assert abs(np.diff(values[:, 0])[-1]) < 0.05 * values[-1, 0]


def test_hexahedral_plates_are_positive_and_fill_the_plates_volume():
    """H8I meshes: every hexahedron has a positive Jacobian at its eight Gauss points and
    the volumes (∑ det J over them) add up to t times the plan area of each plate."""
    joint = dataclasses.replace(SMALL, element="H8I")
    m = lap_joint_mesh(joint)
    assert m.cells.shape[0] == 8 and m.interface_cells.shape[1] == 4
    X = m.points[:, m.cells].transpose(2, 1, 0)                  # (elements, 8, 3)
    corners = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                        [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], float)
    vol = np.zeros(X.shape[0])
    for pt in corners / np.sqrt(3.0):                  # the 2×2×2 Gauss points, weight 1
        grad = np.empty((8, 3))
        for d in range(3):
            o1, o2 = (k for k in range(3) if k != d)
            grad[:, d] = (corners[:, d] / 8 * (1 + corners[:, o1] * pt[o1])
                          * (1 + corners[:, o2] * pt[o2]))
        det = np.linalg.det(np.einsum("kd,mkc->mcd", grad, X))
        assert det.min() > 0
        vol += det
    quads = m.plan_points[m.plan_cells]
    x, y = quads[..., 0], quads[..., 1]
    area = 0.5 * np.sum(x * np.roll(y, -1, 1) - np.roll(x, -1, 1) * y, axis=1)
    assert area.min() > 0
    centre_x = x.mean(axis=1)
    _, a, b, _ = m.ranges
    for body, cells in ((0, centre_x > a), (1, centre_x < b)):
        assert vol[m.element_body == body].sum() == pytest.approx(
            joint.thickness * area[cells].sum(), rel=1e-12)


def test_rounded_plate_ends_open_an_initial_gap_tangent_to_the_flat_face():
    """g = δ (1 − s/d)² within d of each plate end: δ at the ends x = ∓c/2 of the upper
    and lower plates, zero with zero slope where the relief starts, zero elsewhere; the
    reduced joint carries the gap's reactions −[Bᵀg; Cg] as its load case ``gap``."""
    joint = dataclasses.replace(SMALL, end_relief=0.003, end_relief_depth=2e-5)
    c, d, depth = joint.overlap, joint.end_relief, joint.end_relief_depth
    x = np.array([-c / 2, -c / 2 + d / 2, -c / 2 + d, 0.0, c / 2 - d, c / 2])
    assert np.allclose(joint.end_gap(x), [depth, depth / 4, 0, 0, 0, depth], rtol=1e-12,
                       atol=1e-12 * depth)
    eps = 1e-7
    # the secant slope over ε is δ ε/d², a vanishing fraction of the end slope 2δ/d
    assert joint.end_gap(np.array([-c / 2 + d - eps]))[0] / eps < 1e-4 * depth / d
    red = lap_joint_model(joint).reduced
    g = joint.end_gap(red.coordinates[:, 0])
    assert g.max() == pytest.approx(depth) and np.count_nonzero(g) < g.size / 2
    scale = np.abs(red.C).max() * depth
    assert np.abs(red.loads["gap"]["p"] + red.C @ g).max() < 1e-12 * scale
    assert np.abs(red.loads["gap"]["q"] + red.B.T @ g).max() < 1e-12 * scale
    assert "gap" not in lap_joint_model(SMALL).reduced.loads      # sharp ends: none


@pytest.mark.parametrize(("changes", "key"), [
    ({"plate_length": -0.1}, "plate_length"),
    ({"nu": 0.5}, "nu"),
    ({"E": float("nan")}, "E"),
    ({"bolt_count": 7}, "bolt_count"),
    ({"bolt_count": 1}, "bolt_count"),
    ({"bolt_count": 2.5}, "bolt_count"),
    ({"overlap": 0.2}, "overlap"),
    ({"washer_diameter": 0.005}, "washer_diameter"),
    ({"mesh_size": 0.02}, "mesh_size"),
    ({"element": "Q1"}, "element"),
    ({"element": "P2"}, "element"),
    ({"bolt_count": 6}, "plate_width"),
    ({"overlap": 0.012}, "overlap"),
    ({"bolt_positions": ((0.0, 0.0),)}, "bolt_positions"),
    ({"bolt_positions": ((0.0, -0.002), (0.0, 0.002))}, "bolt_positions"),
    ({"bolt_positions": ((0.0, -0.01), (0.014, 0.01))}, "bolt_positions"),
    ({"layers": 0}, "layers"),
    ({"end_relief": 0.003}, "end_relief_depth"),
    ({"end_relief_depth": 1e-5}, "end_relief"),
    ({"end_relief": -0.001, "end_relief_depth": 1e-5}, "end_relief"),
    ({"end_relief": 0.012, "end_relief_depth": 1e-5}, "end_relief"),
])
def test_bad_joint_inputs_give_one_line_errors_naming_the_field(changes, key):
    with pytest.raises(InputError) as err:
        dataclasses.replace(SMALL, **changes)
    assert err.value.key == key
    assert "\n" not in str(err.value)


@settings(max_examples=60, deadline=None)
@given(width=st.floats(0.005, 0.2), overlap=st.floats(0.005, 0.1),
       count=st.integers(2, 6), washer=st.floats(0.004, 0.03), h=st.floats(5e-4, 0.01))
def test_any_joint_is_either_valid_with_washers_inside_or_refused_with_a_named_field(
        width, overlap, count, washer, h):
    try:
        joint = LapJoint(plate_width=width, overlap=overlap, bolt_count=count,
                         washer_diameter=washer, bolt_diameter=washer / 2, mesh_size=h)
    except InputError as exc:
        assert exc.key in {f.name for f in dataclasses.fields(LapJoint)}
        return
    c = joint.centres
    assert c.shape == (count, 2)
    assert np.all(np.abs(c[:, 1]) + washer / 2 < width / 2)
    assert np.all(np.abs(c[:, 0]) + washer / 2 < overlap / 2)
    assert joint.edge_distance > 0
