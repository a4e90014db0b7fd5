"""A bolted lap joint reduced to the contact nodes of its overlap.

Two identical plates (length L, width W, thickness t) overlap over the length c; K bolts
pass through clearance holes in the overlap. Coordinates: x along the plates, y across,
z through the thickness; the interface is the plane z = 0 over the overlap
x ∈ [−c/2, c/2], |y| ≤ W/2 (holes excluded). Body 1 is the *upper* plate (z ∈ [0, t],
x ∈ [−c/2, L − c/2]), body 2 the *lower* plate (z ∈ [−t, 0], x ∈ [c/2 − L, c/2]).

Supports: each plate's far end face is clamped in a rigid grip (all three displacement
components). The lower grip (x = c/2 − L) is held; the upper grip (x = L − c/2) moves
rigidly in the service cases. The two grips hold each plate against rigid motion when the
interface is free, so the reduced stiffness is positive definite.

Load cases (``loads`` of the reduced model, reactions with every contact node held at
v = w = 0, i.e. with the interface stuck and closed):

=================== ==== ============================================================
case                unit what
=================== ==== ============================================================
``bolt_k``          N    preload of bolt k: a uniform pressure on its washer annulus
                         (hole radius to washer radius) pushing the upper plate down
                         (−z, on z = t) and the lower plate up (+z, on z = −t), 1 N
                         resultant on each plate; the bolt is a constant force (its
                         own stiffness is not modelled)
``service``         N    upper grip moved along +x (along the plates: the lap-shear
                         load), scaled to 1 N grip force on the upper plate while the
                         interface is stuck
``service_y``       N    the same along +y (in plane, across the plates)
``service_z``       N    the same along +z (out of plane: bends the joint)
=================== ==== ============================================================

The service cases are displacement-controlled (a testing machine's grip) but normalised
per newton: with the interface stuck the grip force along the motion is exactly 1 N,
whence Σ q_x = −1 N for ``service`` (the interface holds the upper plate back). Once the
interface slips the grip force per unit of the case drops below 1 N. The grips are
clamped, so a grip moved along one axis also draws reactions along the others: small for
``service`` (Σ p ≈ −0.04 N per N for the example), large for ``service_z``, where the
eccentric lap joint between two clamped grips carries ≈ 9 N of axial force per newton of
transverse force (Σ q_x ≈ −9 N per N for the example). For a bolt case the
interface carries Σ p = 1 N less the small share taken by the clamped grips, recorded in
``LapJointModel.grip_share``.

Contact conventions (:mod:`slipcycle.fe.contact3d`): n = (0, 0, −1) is the outward normal
of the upper plate, t1 = x, t2 = y; v = (u¹ − u²)·t is the slip of the upper plate on the
lower, w = (u¹ − u²)·z the opening, q and p the forces of the lower plate on the upper
along t and +z (p > 0 compressive).

Why the contact is incomplete. A bolt clamps the plates over a region only somewhat wider
than its washer; farther out the plates bend apart (Fernlund 1961). The candidate contact
region is the whole overlap, so the solver finds where the plates open. With the overlap
edges farther from the washers than the clamped region reaches
(:attr:`LapJoint.edge_distance`, washer rim to plate end: a few plate thicknesses; the
example has 3 t, and its region closed under preload ends ≈ 0.4 t beyond the washer rims
along x, at h = 2 mm and at h = 1 mm) the plate ends x = ±c/2 lift off. They are the
only places where a sharp body corner could press on the other plate (a complete contact
with a stress singularity; Hills, Nowell & Sackfield 1993). The hole walls and the side
faces y = ±W/2 run through both plates as one flat free surface, which for identical
plates leaves the interface tractions bounded. Slip then starts at a contact edge where
the pressure falls smoothly to zero, the situation in which the microslip dissipation of
a discretised contact has a limit under refinement (as for Cattaneo–Mindlin, Johnson
1985, §7.2); the dissipation itself on several meshes is studied in
:mod:`slipcycle.joints`.

References
----------
Fernlund, I. (1961). A method to calculate the pressure between bolted or riveted plates.
Trans. Chalmers Univ. Technol. 245.
Hills, D. A., Nowell, D. & Sackfield, A. (1993). *Mechanics of Elastic Contacts*.
Butterworth-Heinemann.
Johnson, K. L. (1985). *Contact Mechanics*. Cambridge University Press.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from slipcycle.errors import InputError
from slipcycle.fe.geometry import check_number
from slipcycle.io.matrices import ReducedStiffness

__all__ = ["LapJoint", "LapJointModel", "LapJointMesh", "lap_joint_model", "lap_joint_mesh",
           "bolt_centres", "EXAMPLE"]

#: linear tetrahedra only: node-to-node friction needs positive consistent nodal forces
#: of a pressure (those of quadratic faces vanish at the vertices)
_ELEMENTS = ("P1",)


@dataclass(frozen=True)
class LapJoint:
    """Geometry, material, bolts and mesh of a bolted lap joint (module docstring).

    Parameters
    ----------
    plate_length : float
        Length L of each plate, grip to free end, m.
    plate_width : float
        Width W of both plates, m.
    thickness : float
        Thickness t of each plate, m.
    overlap : float
        Length c of the overlap, m (0 < c < L).
    E, nu : float
        Young's modulus (Pa) and Poisson's ratio of both plates.
    bolt_count : int
        Number K of bolts, 2 … 6.
    bolt_diameter : float
        Diameter of the (clearance) bolt holes, m.
    washer_diameter : float
        Outer diameter of the washers (the clamped annulus), m.
    mesh_size : float
        Element size h in the overlap (the node spacing of the interface), m.
    element : str
        ``"P1"`` (linear tetrahedra), the only choice: node-to-node friction needs the
        positive consistent nodal forces of a pressure, which quadratic faces do not give.
    bolt_positions : tuple of (x, y) pairs, optional
        Bolt centres relative to the centre of the overlap, m. Default: one row across
        the width at x = 0, pitch W/K, y_k = −W/2 + (k + ½) W/K.
    layers : int, optional
        Elements through each plate's thickness; default max(2, ⌈t/h⌉). Linear
        tetrahedra are too stiff in bending until t/h ≳ 2 (the contact stiffness then
        converges with an observed order ≈ 1, tests/test_fe_lap_joint.py); coarser meshes
        are pre-asymptotic.
    growth : float
        Element size far from the overlap as a multiple of h (≥ 1).
    """

    plate_length: float = 0.1
    plate_width: float = 0.04
    thickness: float = 0.004
    overlap: float = 0.04
    E: float = 210e9
    nu: float = 0.3
    bolt_count: int = 2
    bolt_diameter: float = 0.009
    washer_diameter: float = 0.016
    mesh_size: float = 0.002
    element: str = "P1"
    bolt_positions: tuple | None = None
    layers: int | None = None
    growth: float = 4.0
    _centres: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        for name in ("plate_length", "plate_width", "thickness", "overlap", "E",
                     "bolt_diameter", "washer_diameter", "mesh_size"):
            check_number(name, getattr(self, name), gt=0.0)
        check_number("nu", self.nu, ge=0.0, lt=0.5)
        check_number("bolt_count", self.bolt_count, ge=2, le=6, integer=True)
        check_number("growth", self.growth, ge=1.0, le=20.0)
        if self.layers is not None:
            check_number("layers", self.layers, ge=1, le=200, integer=True)
        if self.overlap >= self.plate_length:
            raise InputError("overlap", f"must be < plate_length ({self.plate_length:g} m), "
                             f"got {self.overlap:g}")
        if self.washer_diameter <= self.bolt_diameter:
            raise InputError("washer_diameter", "must exceed bolt_diameter "
                             f"({self.bolt_diameter:g} m), got {self.washer_diameter:g}")
        if self.mesh_size > self.washer_diameter - self.bolt_diameter:
            raise InputError("mesh_size", "must be ≤ washer_diameter − bolt_diameter "
                             f"({self.washer_diameter - self.bolt_diameter:g} m) to resolve "
                             f"the washer annulus, got {self.mesh_size:g}")
        if self.mesh_size > min(self.overlap, self.plate_width) / 4:
            raise InputError("mesh_size", "must be ≤ a quarter of the overlap and of the "
                             f"width, got {self.mesh_size:g}")
        if self.element not in _ELEMENTS:
            raise InputError("element", "must be 'P1' (node-to-node friction needs the "
                             "positive nodal forces of linear faces), got "
                             f"{self.element!r}")
        object.__setattr__(self, "_centres", self._check_bolts())

    def _check_bolts(self) -> np.ndarray:
        K, W, c = int(self.bolt_count), self.plate_width, self.overlap
        rw = self.washer_diameter / 2
        key = "bolt_positions"
        if self.bolt_positions is None:
            key = "plate_width"
            pitch = W / K
            centres = np.stack([np.zeros(K), -W / 2 + (np.arange(K) + 0.5) * pitch], 1)
        else:
            try:
                centres = np.asarray(self.bolt_positions, float)
            except (TypeError, ValueError):
                raise InputError(key, "must be K pairs (x, y) in m") from None
            if centres.shape != (K, 2) or not np.all(np.isfinite(centres)):
                raise InputError(key, f"must be bolt_count = {K} finite pairs (x, y), got "
                                 f"shape {centres.shape}")
            object.__setattr__(self, "bolt_positions",      # hashable, plain floats
                               tuple((float(x), float(y)) for x, y in centres))
        margin = 0.25 * self.mesh_size        # a washer rim keeps clear of the edges
        if np.any(np.abs(centres[:, 0]) + rw > c / 2 - margin):
            raise InputError("overlap" if key == "plate_width" else key,
                             f"every washer (diameter {self.washer_diameter:g} m) must lie "
                             f"inside the overlap (length {c:g} m) with h/4 to spare")
        if np.any(np.abs(centres[:, 1]) + rw > W / 2 - margin):
            raise InputError(key, f"every washer must lie inside the width ({W:g} m) with "
                             "h/4 to spare: the washers do not fit")
        d = np.linalg.norm(centres[:, None] - centres[None], axis=-1) + np.eye(K) * 1e30
        if d.min() < self.washer_diameter + margin:
            raise InputError(key, "washers must not touch: centres at least washer_diameter"
                             " + mesh_size/4 apart")
        return centres

    @property
    def centres(self) -> np.ndarray:
        """Bolt centres (K, 2), m, relative to the centre of the overlap."""
        return self._centres.copy()

    @property
    def edge_distance(self) -> float:
        """Distance from the nearest washer rim to an overlap edge x = ±c/2, m."""
        return float(self.overlap / 2 - np.max(np.abs(self._centres[:, 0]))
                     - self.washer_diameter / 2)

    @property
    def layer_count(self) -> int:
        """Elements through each plate's thickness."""
        if self.layers is not None:
            return int(self.layers)
        return max(2, math.ceil(self.thickness / self.mesh_size - 1e-9))


#: the example joint: two 4 mm steel plates, two M8 bolts in a row across, h = 2 mm
EXAMPLE = LapJoint()


def bolt_centres(joint: LapJoint) -> np.ndarray:
    """Bolt centres (K, 2) of ``joint``, m (x along the plates, y across)."""
    return joint.centres


@dataclass(frozen=True)
class LapJointModel:
    """The reduced lap joint and what a study of it needs besides the stiffness.

    Attributes
    ----------
    reduced : ReducedStiffness
        A (2N, 2N), B (N, 2N), C (N, N) (N/m) of the N contact nodes of the overlap,
        coordinates (N, 3) (m, z = 0), normals (0, 0, −1), tangents x, y; loads
        ``bolt_0`` … ``bolt_{K-1}``, ``service``, ``service_y``, ``service_z`` (N per N,
        module docstring).
    node_area : numpy.ndarray, shape (N,)
        Tributary area of each contact node, m² (sums to the overlap area less the holes,
        up to the polygonal holes).
    bolt_region : numpy.ndarray of int, shape (N,)
        The nearest bolt of each node, 0 … K−1.
    bolt_centres : numpy.ndarray, shape (K, 2)
        Bolt centres, m.
    spacing : float
        Node spacing h at the interface (``joint.mesh_size``), m.
    grip_share : numpy.ndarray, shape (K,)
        Part of each bolt's 1 N preload carried by the clamped grips instead of the
        interface while it is stuck: Σ p^w = 1 − grip_share[k], N.
    description : dict
        Geometry, mesh and timings (name → value) for reports; with
        ``<case>_grip_stiffness_N_per_m``, the grip force per metre of grip motion of each
        service case while the interface is stuck (the factor the case was divided by).
    """

    reduced: ReducedStiffness
    node_area: np.ndarray
    bolt_region: np.ndarray
    bolt_centres: np.ndarray
    spacing: float
    grip_share: np.ndarray
    description: dict

    @property
    def n_nodes(self) -> int:
        """N, the number of contact nodes."""
        return self.reduced.n_nodes


@dataclass(frozen=True)
class LapJointMesh:
    """The two plates in one tetrahedral mesh, interface nodes duplicated.

    Attributes
    ----------
    mesh : skfem.MeshTet
        Both plates, m; the upper plate's vertices and elements come first.
    element_body : numpy.ndarray of int, shape (n_elements,)
        0 for the upper plate, 1 for the lower.
    plan_points : numpy.ndarray, shape (n, 2)
        The plan-view nodes (x, y), m.
    interface_triangles : numpy.ndarray of int, shape (m, 3)
        Plan triangles of the overlap (indices into ``plan_points``).
    ranges : tuple of float
        x of the lower grip, of the overlap edges −c/2, c/2 and of the upper grip, m.
    """

    mesh: object
    element_body: np.ndarray
    plan_points: np.ndarray
    interface_triangles: np.ndarray
    ranges: tuple


def lap_joint_mesh(joint: LapJoint) -> LapJointMesh:
    """Tetrahedral mesh of both plates with duplicated (coincident) interface nodes
    (:mod:`slipcycle.fe.lap_joint_mesh`)."""
    from skfem import MeshTet

    from slipcycle.fe.lap_joint_mesh import extrude_tets, plan_mesh

    L, c, t, h = joint.plate_length, joint.overlap, joint.thickness, joint.mesh_size
    a, b = -c / 2, c / 2
    x0, x1 = b - L, L - c / 2
    h_far = min(joint.growth * h, joint.plate_width / 2, L - c)
    pts, tri = plan_mesh((x0, x1), joint.plate_width, (a, b), joint.centres,
                         joint.bolt_diameter / 2, joint.washer_diameter / 2, h,
                         max(h, h_far))
    xc = pts[tri].mean(axis=1)[:, 0]
    upper, lower = tri[xc > a], tri[xc < b]
    z = np.linspace(0.0, t, joint.layer_count + 1)
    p1, t1 = extrude_tets(pts, upper, z)
    p2, t2 = extrude_tets(pts, lower, z - t)
    p = np.hstack([p1, p2])
    tets = np.hstack([t1, t2 + p1.shape[1]])
    body = np.concatenate([np.zeros(t1.shape[1], int), np.ones(t2.shape[1], int)])
    interface = tri[(xc > a) & (xc < b)]
    return LapJointMesh(MeshTet(p, tets), body, pts, interface, (x0, a, b, x1))


def _washer_forces(basis, mesh, joint: LapJoint, k: int, dofs: np.ndarray) -> np.ndarray:
    """Nodal forces (n_nodes, 3) of bolt k's washer pressures, 1 N on each plate, N."""
    from skfem import FacetBasis, LinearForm, asm

    t = joint.thickness
    cx, cy = joint.centres[k]
    rh, rw = joint.bolt_diameter / 2, joint.washer_diameter / 2
    f = mesh.boundary_facets()
    mid = mesh.p[:, mesh.facets[:, f]].mean(axis=1)
    r = np.hypot(mid[0] - cx, mid[1] - cy)
    in_annulus = (r > rh) & (r < rw)
    scale = 1e-9 * t
    out = np.zeros((dofs.shape[0], 3))
    for face_z, sign in ((t, -1.0), (-t, 1.0)):
        sel = f[in_annulus & (np.abs(mid[2] - face_z) < scale)]
        fb = FacetBasis(mesh, basis.elem, facets=sel)

        @LinearForm
        def pressure(v, w, sign=sign):
            return sign * v[2]

        vec = asm(pressure, fb)
        vec *= 1.0 / abs(vec.sum())            # 1 N resultant on the polygonal annulus
        out += vec[dofs]
    return out


def _node_area(tri_xy: np.ndarray, coords: np.ndarray) -> np.ndarray:
    """Tributary area (N,) of the contact nodes at ``coords`` (N, 3): a third of each
    adjacent interface triangle (corners ``tri_xy``, (m, 3, 2)), m²."""
    _, idx = cKDTree(coords[:, :2]).query(tri_xy.reshape(-1, 2))
    e1 = tri_xy[:, 1] - tri_xy[:, 0]
    e2 = tri_xy[:, 2] - tri_xy[:, 0]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    out = np.zeros(coords.shape[0])
    np.add.at(out, idx, np.repeat(area / 3, 3))
    return out


def lap_joint_model(joint: LapJoint) -> LapJointModel:
    """Mesh the lap joint, reduce it to the contact nodes of its overlap (one factorisation).

    Parameters
    ----------
    joint : LapJoint
        Geometry (m), material (Pa), bolts and mesh.

    Returns
    -------
    LapJointModel
        The reduced stiffness with the load cases of the module docstring, the tributary
        area and nearest bolt of each contact node.

    Notes
    -----
    The condensation is :func:`slipcycle.fe.contact3d.reduce_contact_3d` (Guyan 1965: one
    sparse factorisation, :func:`slipcycle.condensation.schur_complement`). The service
    cases are reduced per metre of grip motion and rescaled per newton of grip force with
    the equilibrium of the upper plate (its only supports are the grip and the stuck
    interface): F_grip = −Σ q (in plane) or −Σ p (out of plane).
    """
    from skfem import Basis, ElementTetP1, ElementVector

    from slipcycle.fe.contact3d import Case3D, mesh_nodes, node_dofs_3d, reduce_contact_3d

    t0 = time.perf_counter()
    m = lap_joint_mesh(joint)
    t_mesh = time.perf_counter() - t0
    mesh, element = m.mesh, joint.element
    xyz = mesh_nodes(mesh, element)
    x0, a, b, x1 = m.ranges
    tol = 1e-9 * joint.plate_length
    # body of each node: the upper plate's vertices come first in the mesh
    n_upper_vertices = int(m.mesh.t[:, m.element_body == 0].max()) + 1
    body = (np.arange(mesh.p.shape[1]) >= n_upper_vertices).astype(int)
    on_plane = np.abs(xyz[:, 2]) < tol
    in_overlap = (xyz[:, 0] > a - tol) & (xyz[:, 0] < b + tol)
    c1 = np.flatnonzero(on_plane & in_overlap & (body == 0))
    c2 = np.flatnonzero(on_plane & in_overlap & (body == 1))
    dist, match = cKDTree(xyz[c2]).query(xyz[c1])
    if c1.size != c2.size or dist.max() > tol:
        raise RuntimeError("the plates' interface nodes do not coincide")
    order = np.lexsort((xyz[c1, 0], xyz[c1, 1]))
    pairs = np.stack([c1[order], c2[match[order]]], axis=1)
    grip_upper = np.abs(xyz[:, 0] - x1) < tol
    grip_lower = np.abs(xyz[:, 0] - x0) < tol
    fixed = np.zeros_like(xyz, bool)
    fixed[grip_upper | grip_lower] = True
    basis = Basis(mesh, ElementVector(ElementTetP1()))
    dofs, _ = node_dofs_3d(basis)
    cases = [Case3D(f"bolt_{k}", "N", force=_washer_forces(basis, mesh, joint, k, dofs),
                    description=f"washer pressures of bolt {k}, 1 N")
             for k in range(joint.bolt_count)]
    services = (("service", 0), ("service_y", 1), ("service_z", 2))
    for name, comp in services:
        u = np.zeros_like(xyz)
        u[grip_upper, comp] = 1.0
        cases.append(Case3D(name, "m", displacement=u))
    t1 = time.perf_counter()
    red = reduce_contact_3d(mesh, materials=[(joint.E, joint.nu)], pairs=pairs,
                            normals=(0.0, 0.0, -1.0),
                            tangents=((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)), fixed=fixed,
                            cases=cases, element=element,
                            source=f"slipcycle.fe lap_joint_model {joint!r}")
    t_reduce = time.perf_counter() - t1
    N = red.n_nodes
    loads = {}
    grip_share = np.zeros(joint.bolt_count)
    for k in range(joint.bolt_count):
        case = red.loads[f"bolt_{k}"]
        loads[f"bolt_{k}"] = case
        grip_share[k] = 1.0 - float(np.sum(case["p"]))
    grip_stiffness = {}
    for name, comp in services:
        case = red.loads[name]
        total = (-np.sum(case["q"][comp::2]) if comp < 2 else -np.sum(case["p"]))
        grip_stiffness[f"{name}_grip_stiffness_N_per_m"] = float(total)
        loads[name] = {"q": case["q"] / total, "p": case["p"] / total}
    reduced = ReducedStiffness(A=red.A, B=red.B, C=red.C, tangential_dims=2,
                               nodes=red.nodes, coordinates=red.coordinates,
                               normals=red.normals, tangents=red.tangents, loads=loads,
                               source=red.source)
    coords = red.coordinates
    centres = joint.centres
    tri_xy = m.plan_points[m.interface_triangles]
    area = _node_area(tri_xy, coords)
    region = np.argmin(np.linalg.norm(coords[:, None, :2] - centres[None], axis=-1),
                       axis=1)
    description = {
        "plate_length_m": joint.plate_length, "plate_width_m": joint.plate_width,
        "thickness_m": joint.thickness, "overlap_m": joint.overlap, "E_Pa": joint.E,
        "nu": joint.nu, "bolt_count": joint.bolt_count,
        "bolt_diameter_m": joint.bolt_diameter, "washer_diameter_m": joint.washer_diameter,
        "mesh_size_m": joint.mesh_size, "element": element,
        "layers": joint.layer_count, "contact_nodes": N, "dofs": 3 * xyz.shape[0],
        "tetrahedra": int(mesh.t.shape[1]), "mesh_s": t_mesh, "reduction_s": t_reduce,
        **grip_stiffness,
    }
    return LapJointModel(reduced=reduced, node_area=area, bolt_region=region.astype(int),
                         bolt_centres=centres, spacing=float(joint.mesh_size),
                         grip_share=grip_share, description=description)
