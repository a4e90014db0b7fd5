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
                         resultant on each plate; with elastic bolts
                         (``bolt_modulus`` > 0) the study adds each bolt's shank as a
                         spring between its washer faces (``bolt_shortening`` below)
``service``         N    upper grip moved along +x (along the plates: the lap-shear
                         load), scaled to 1 N grip force on the upper plate while the
                         interface is stuck
``service_y``       N    the same along +y (in plane, across the plates)
``service_z``       N    the same along +z (out of plane: bends the joint)
``gap``             1    only with rounded ends (``end_relief``): the reactions
                         −[Bᵀ g; C g] of the initial gap g, applied once (the
                         separation w includes g)
=================== ==== ============================================================

Elastic bolts. The grip shortening s_k = f_kᵀ u of bolt k (f_k its washer forces per
newton, u the displacement field: the approach of its two washer faces, work-conjugate to
its force) is, by the reciprocal theorem, s_k = Σ_j Φ_kj α_j − r_kᵀ d_true for load
amplitudes α_j, load-case reactions r_j = [q_j; p_j] and the interface displacement
d_true = [v; w − g]; Φ_kj (m per unit of case j) is the shortening with the interface
bonded (d_true = 0), computed here by one extra bonded solve (``bolt_shortening``). A
shank of stiffness k_b = E_b π d_b²/4 / L_b (``bolt_modulus``, ``bolt_shank_diameter``,
``bolt_length``) carries T_k = k_b (e_k − s_k), e_k the shortening of its free length by
the nut (the pretension dof of FE codes); eliminating the locked bolts adds
R D Rᵀ to the reduced stiffness, D = (k_b⁻¹ I + Φ)⁻¹
(:mod:`slipcycle.joints.lap_joint_protocol`).

Dissimilar plates. ``E``, ``nu`` are the upper plate's, ``E_lower``, ``nu_lower`` the
lower plate's (default: the same): an aluminium plate on a steel one has Dundurs' β ≠ 0.

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
along x, at h = 2 mm and at h = 1 mm) the plate ends x = ±c/2 lift off under the preload.
A reversed service load bends them back: in its compressive half the eccentricity of the
single lap presses each plate's end on the other plate. A sharp-cornered end then makes a
complete contact with a stress singularity (Hills, Nowell & Sackfield 1993), whose
microslip dissipation has no limit under refinement; rounded ends (``end_relief``: the
interface face recedes by δ (1 − s/d)² over the last d of each plate, tangent to the
flat face) keep that contact incomplete. The hole walls and the side faces y = ±W/2 run
through both plates as one flat free surface, which for identical plates leaves the
interface tractions bounded. Slip then starts at a contact edge where the pressure falls
smoothly to zero, the situation in which the microslip dissipation of a discretised
contact has a limit under refinement (as for Cattaneo–Mindlin, Johnson 1985, §7.2); the
dissipation itself on several meshes is studied in :mod:`slipcycle.joints`.

Why hexahedra. The plates bend; linear tetrahedra lock in bending until the element size
is about half the thickness, so their dissipation is pre-asymptotic on any mesh the
study can afford. Hexahedra with incompatible modes (``element = "H8I"``,
:mod:`slipcycle.fe.hex8i`) represent pure bending exactly with one element through the
thickness, and their bilinear faces keep the consistent nodal forces of a pressure
positive, which node-to-node friction needs.

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
import scipy.sparse as sp
from scipy.spatial import cKDTree
from skfem import Basis, ElementTetP1, ElementVector, MeshTet

from slipcycle.condensation import factorize
from slipcycle.errors import InputError
from slipcycle.fe.assembly import stiffness
from slipcycle.fe.contact3d import Case3D, condense_contact_3d, node_dofs_3d
from slipcycle.fe.geometry import check_length, check_number
from slipcycle.fe.hex8i import hex8i_stiffness
from slipcycle.fe.lap_joint_mesh import cell_weights, extrude_hexes, extrude_tets, plan_mesh
from slipcycle.io.matrices import ReducedStiffness

__all__ = ["LapJoint", "LapJointModel", "LapJointMesh", "LapJointFE", "lap_joint_model",
           "lap_joint_mesh", "lap_joint_fe", "bonded_shortening", "bolt_centres"]

#: elements with positive consistent nodal forces of a pressure, which node-to-node friction
#: needs (those of quadratic triangles vanish at the vertices): linear tetrahedra and
#: hexahedra with incompatible modes (bilinear faces)
_ELEMENTS = ("P1", "H8I")
#: largest ratio of the two plates' moduli (E_lower / E or its inverse; steel on a polymer
#: is about 100; 1e14 made the reduction singular)
MODULUS_RATIO = 1e6


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
        ``"H8I"``: hexahedra with incompatible modes (:mod:`slipcycle.fe.hex8i`), exact in
        pure bending, on a quadrilateral plan mesh; ``"P1"``: linear tetrahedra, which
        lock in bending until t/h ≳ 2. Quadratic elements are not offered: node-to-node
        friction needs the positive consistent nodal forces of a pressure, which quadratic
        faces do not give.
    bolt_positions : tuple of (x, y) pairs, optional
        Bolt centres relative to the centre of the overlap, m. Default: one row across
        the width at x = 0, pitch W/K, y_k = −W/2 + (k + ½) W/K.
    layers : int, optional
        Elements through each plate's thickness; default max(2, ⌈t/h⌉). Linear
        tetrahedra are too stiff in bending until t/h ≳ 2 (the contact stiffness then
        converges with an observed order ≈ 1, tests/test_fe_lap_joint.py); coarser P1
        meshes are pre-asymptotic.
    growth : float
        Element size far from the overlap as a multiple of h (≥ 1).
    refine : int
        Uniform refinements of the mesh of size ``mesh_size`` (0 … 3): each splits every
        plan cell into four and doubles the default layers, so the meshes of one
        ``mesh_size`` with refine = 0, 1, 2 are nested, spacing h, h/2, h/4 (the
        families of :mod:`slipcycle.joints.convergence` studies).
    end_relief : float
        Length d of the rounded plate ends, m (0: sharp-cornered ends). Over the last d
        of the overlap each plate's interface face recedes from the other plate, by
        δ (1 − s/d)² at the distance s < d from its end: an initial gap, tangent to the
        flat face where the relief starts (module docstring, "Why the contact is
        incomplete").
    end_relief_depth : float
        The recess δ at the plate end, m (> 0 exactly when ``end_relief`` > 0).
    E_lower, nu_lower : float, optional
        Young's modulus (Pa) and Poisson's ratio of the lower plate (default ``E``,
        ``nu``: identical plates); ``E``, ``nu`` are then the upper plate's.
    bolt_modulus : float
        Young's modulus E_b of the bolt shanks, Pa; 0 (default): constant-force bolts
        (the limit of a soft bolt, whose force does not change once applied).
    bolt_shank_diameter : float, optional
        Diameter d_b of the shanks, m (default ``bolt_diameter``/1.1, the medium
        clearance hole of ISO 273).
    bolt_length : float, optional
        Free length L_b of the shanks between the washer faces, m (default the grip,
        2 ``thickness``).
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
    refine: int = 0
    end_relief: float = 0.0
    end_relief_depth: float = 0.0
    E_lower: float | None = None
    nu_lower: float | None = None
    bolt_modulus: float = 0.0
    bolt_shank_diameter: float | None = None
    bolt_length: float | None = None
    _centres: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        for name in ("plate_length", "plate_width", "thickness", "overlap",
                     "bolt_diameter", "washer_diameter", "mesh_size"):
            check_length(name, getattr(self, name))
        check_number("E", self.E, gt=0.0)
        check_number("nu", self.nu, ge=0.0, lt=0.5)
        check_number("bolt_count", self.bolt_count, ge=2, le=6, integer=True)
        check_number("growth", self.growth, ge=1.0, le=20.0)
        if self.layers is not None:
            check_number("layers", self.layers, ge=1, le=200, integer=True)
        check_number("refine", self.refine, ge=0, le=3, integer=True)
        if self.nu_lower is not None:
            check_number("nu_lower", self.nu_lower, ge=0.0, lt=0.5)
        self._check_moduli()
        for name in ("bolt_shank_diameter", "bolt_length"):
            if getattr(self, name) is not None:
                check_number(name, getattr(self, name), gt=0.0)
                if not self.bolt_modulus:
                    raise InputError(name, "describes an elastic bolt shank: give "
                                     "bolt_modulus > 0 too (0 is a constant-force bolt, "
                                     "which has no shank)")
        if self.bolt_shank_diameter is not None and \
                self.bolt_shank_diameter > self.bolt_diameter:
            raise InputError("bolt_shank_diameter", "must not exceed the hole diameter "
                             f"bolt_diameter ({self.bolt_diameter:g} m), got "
                             f"{self.bolt_shank_diameter:g}")
        check_number("end_relief", self.end_relief, ge=0.0)
        check_number("end_relief_depth", self.end_relief_depth, ge=0.0)
        if (self.end_relief > 0) != (self.end_relief_depth > 0):
            raise InputError("end_relief_depth" if self.end_relief > 0 else "end_relief",
                             "end_relief and end_relief_depth must both be positive (rounded"
                             " ends) or both zero (sharp ends), got "
                             f"{self.end_relief:g} m and {self.end_relief_depth:g} m")
        if self.overlap >= self.plate_length:
            raise InputError("overlap", f"must be < plate_length ({self.plate_length:g} m), "
                             f"got {self.overlap:g}")
        if self.bolt_diameter >= min(self.plate_width, self.overlap):
            raise InputError("bolt_diameter", "the hole must fit in the plate: it must be "
                             f"< plate_width ({self.plate_width:g} m) and overlap "
                             f"({self.overlap:g} m), got {self.bolt_diameter:g}")
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
            raise InputError("element", "must be 'H8I' or 'P1' (node-to-node friction "
                             "needs the positive nodal forces of linear faces), got "
                             f"{self.element!r}")
        object.__setattr__(self, "_centres", self._check_bolts())
        if self.end_relief > 0 and self.end_relief >= self.edge_distance:
            raise InputError("end_relief", "the rounded ends must stop short of the "
                             f"washers: end_relief < {self.edge_distance:g} m (washer rim to "
                             f"plate end), got {self.end_relief:g}")
        self._check_size()

    def _check_moduli(self) -> None:
        """The lower plate's modulus within ``MODULUS_RATIO`` of the upper one's (beyond
        it the reduced stiffness is singular to double precision), and the bolts' ≥ 0."""
        check_number("bolt_modulus", self.bolt_modulus, ge=0.0)
        if self.E_lower is None:
            return
        check_number("E_lower", self.E_lower, gt=0.0)
        ratio = self.E_lower / self.E
        if not 1.0 / MODULUS_RATIO <= ratio <= MODULUS_RATIO:
            raise InputError("E_lower", f"must lie within a factor {MODULUS_RATIO:g} of E "
                             f"({self.E:g} Pa: beyond it the reduction of the softer plate "
                             f"is singular to double precision), got {self.E_lower:g} Pa")

    def _check_size(self) -> None:
        """Refuse, before meshing, a mesh whose estimated memory exceeds the budget
        (:func:`slipcycle.io.sizes.check_memory`): the sparse stiffness of both plates
        (about 81 nonzeros per row of 3 dofs per node) and the dense reduced matrices of
        the interface nodes (3 dofs each), in the message with the node counts."""
        from slipcycle.io.sizes import check_memory

        h = self.mesh_size / 2 ** self.refine
        along = math.ceil(self.plate_width / h) + 1
        nodes = 2 * (math.ceil(self.plate_length / h) + 1) * along * (self.layer_count + 1)
        contact = (math.ceil(self.overlap / h) + 1) * along
        nbytes = 3 * nodes * 81 * 12 + 2 * (3 * contact) ** 2 * 8
        check_memory("mesh_size", nbytes, f"about {nodes:.3g} nodes ({contact:.3g} on the "
                     f"interface) at mesh_size {self.mesh_size:g} m and refine = "
                     f"{self.refine}", advice="use a larger mesh_size or a smaller refine")

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
    def materials(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """((E, ν) of the upper plate, (E, ν) of the lower plate), Pa and 1."""
        lower = (self.E if self.E_lower is None else self.E_lower,
                 self.nu if self.nu_lower is None else self.nu_lower)
        return (float(self.E), float(self.nu)), (float(lower[0]), float(lower[1]))

    @property
    def bolt_stiffness(self) -> float:
        """Axial stiffness k_b = E_b π d_b²/4 / L_b of each bolt shank, N/m (0: constant-
        force bolts)."""
        d = self.bolt_diameter / 1.1 if self.bolt_shank_diameter is None \
            else self.bolt_shank_diameter
        length = 2 * self.thickness if self.bolt_length is None else self.bolt_length
        return float(self.bolt_modulus * math.pi * d ** 2 / 4 / length)

    @property
    def layer_count(self) -> int:
        """Elements through each plate's thickness."""
        if self.layers is not None:
            return int(self.layers)
        return max(2, math.ceil(self.thickness / self.mesh_size - 1e-9)) * 2 ** self.refine


    def end_gap(self, x: np.ndarray) -> np.ndarray:
        """Initial gap (m) between the plates at the interface points x (m, along the
        plates) from the rounded ends: δ (1 − s/d)² within s < d of either plate end
        (the upper plate ends at x = −c/2, the lower at x = c/2), 0 elsewhere."""
        d, depth = self.end_relief, self.end_relief_depth
        x = np.asarray(x, float)
        if d == 0:
            return np.zeros_like(x)
        s_upper = x + self.overlap / 2            # distance from the upper plate's end
        s_lower = self.overlap / 2 - x
        return depth * (np.clip(1 - s_upper / d, 0, None) ** 2
                        + np.clip(1 - s_lower / d, 0, None) ** 2)



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
        Representative node spacing of the interface, (A/N)^{1/2} with A the contact
        area of the N nodes (Celik et al. 2008, J. Fluids Eng. 130, 078001), m: the h of
        mesh-convergence studies (it follows the mesh, where ``joint.mesh_size`` is only
        the request: the quadrilateral meshes come out finer than asked near the holes).
    grip_share : numpy.ndarray, shape (K,)
        Part of each bolt's 1 N preload carried by the clamped grips instead of the
        interface while it is stuck: Σ p^w = 1 − grip_share[k], N.
    description : dict
        Geometry, mesh and timings (name → value) for reports; with
        ``<case>_grip_stiffness_N_per_m``, the grip force per metre of grip motion of each
        service case while the interface is stuck (the factor the case was divided by).
    bolt_shortening : dict
        Load case name → (K,) grip shortening Φ_kj of every bolt per unit of the case with
        the interface bonded, m per unit (module docstring, "Elastic bolts"); the rows
        of the ``bolt_j`` cases form the bonded joint's bolt compliance (K, K), m/N,
        symmetric. Empty for constant-force bolts (``bolt_stiffness`` 0), which do not
        use it.
    bolt_stiffness : float
        k_b of each bolt shank, N/m (0: constant-force bolts).
    """

    reduced: ReducedStiffness
    node_area: np.ndarray
    bolt_region: np.ndarray
    bolt_centres: np.ndarray
    spacing: float
    grip_share: np.ndarray
    description: dict
    bolt_shortening: dict = field(default_factory=dict)
    bolt_stiffness: float = 0.0

    @property
    def n_nodes(self) -> int:
        """N, the number of contact nodes."""
        return self.reduced.n_nodes


@dataclass(frozen=True)
class LapJointMesh:
    """The two plates in one mesh, interface nodes duplicated.

    Attributes
    ----------
    points : numpy.ndarray, shape (3, n_nodes)
        Node coordinates, m; the upper plate's nodes come first.
    cells : numpy.ndarray of int, shape (4, n_elements) or (8, n_elements)
        Tetrahedra (P1) or hexahedra (H8I, vertex order of
        :func:`slipcycle.fe.lap_joint_mesh.extrude_hexes`); the upper plate's first.
    element_body : numpy.ndarray of int, shape (n_elements,)
        0 for the upper plate, 1 for the lower.
    plan_points : numpy.ndarray, shape (n, 2)
        The plan-view nodes (x, y), m.
    interface_cells : numpy.ndarray of int, shape (m, 3) or (m, 4)
        Plan triangles or quadrilaterals of the overlap (indices into ``plan_points``).
    plan_cells : numpy.ndarray of int, shape (m', 3) or (m', 4)
        Every plan cell of both plates.
    ranges : tuple of float
        x of the lower grip, of the overlap edges −c/2, c/2 and of the upper grip, m.
    """

    points: np.ndarray
    cells: np.ndarray
    element_body: np.ndarray
    plan_points: np.ndarray
    interface_cells: np.ndarray
    plan_cells: np.ndarray
    ranges: tuple

    @property
    def mesh(self) -> MeshTet:
        """The tetrahedra as a :class:`skfem.MeshTet` (P1 meshes only)."""
        if self.cells.shape[0] != 4:
            raise ValueError("a hexahedral lap-joint mesh has no MeshTet")
        return MeshTet(self.points, self.cells)


def lap_joint_mesh(joint: LapJoint) -> LapJointMesh:
    """Tetrahedral (P1) or hexahedral (H8I) mesh of both plates with duplicated
    (coincident) interface nodes (:mod:`slipcycle.fe.lap_joint_mesh`)."""
    L, c, t, h = joint.plate_length, joint.overlap, joint.thickness, joint.mesh_size
    a, b = -c / 2, c / 2
    x0, x1 = b - L, L - c / 2
    h_far = min(joint.growth * h, joint.plate_width / 2, L - c)
    pts, tri = plan_mesh((x0, x1), joint.plate_width, (a, b), joint.centres,
                         joint.bolt_diameter / 2, joint.washer_diameter / 2, h,
                         max(h, h_far), quads=joint.element == "H8I",
                         refine=int(joint.refine))
    extrude = extrude_hexes if joint.element == "H8I" else extrude_tets
    xc = pts[tri].mean(axis=1)[:, 0]
    upper, lower = tri[xc > a], tri[xc < b]
    z = np.linspace(0.0, t, joint.layer_count + 1)
    p1, t1 = extrude(pts, upper, z)
    p2, t2 = extrude(pts, lower, z - t)
    p = np.hstack([p1, p2])
    cells = np.hstack([t1, t2 + p1.shape[1]])
    body = np.concatenate([np.zeros(t1.shape[1], int), np.ones(t2.shape[1], int)])
    interface = tri[(xc > a) & (xc < b)]
    return LapJointMesh(p, cells, body, pts, interface, tri, (x0, a, b, x1))


def _washer_forces(m: LapJointMesh, xyz: np.ndarray, joint: LapJoint, k: int) -> np.ndarray:
    """Nodal forces (n_nodes, 3) of bolt k's washer pressures, 1 N on each plate, N: the
    consistent forces of a uniform pressure on the plan cells of the annulus (hole radius
    to washer radius; the washer circle is a mesh line) on the faces z = ±t."""
    t = joint.thickness
    cx, cy = joint.centres[k]
    rh, rw = joint.bolt_diameter / 2, joint.washer_diameter / 2
    mid = m.plan_points[m.plan_cells].mean(axis=1)
    r = np.hypot(mid[:, 0] - cx, mid[:, 1] - cy)
    weights = cell_weights(m.plan_points, m.plan_cells[(r > rh) & (r < rw)])
    loaded = np.flatnonzero(weights)
    weights = weights[loaded] / weights.sum()          # 1 N on the polygonal annulus
    out = np.zeros((xyz.shape[0], 3))
    scale = 1e-9 * t
    for face_z, sign in ((t, -1.0), (-t, 1.0)):
        on_face = np.flatnonzero(np.abs(xyz[:, 2] - face_z) < scale)
        dist, idx = cKDTree(xyz[on_face, :2]).query(m.plan_points[loaded])
        if dist.max() > scale:
            raise RuntimeError("a washer node is missing from the plate face")
        out[on_face[idx], 2] += sign * weights
    return out


def _node_area(m: LapJointMesh, coords: np.ndarray) -> np.ndarray:
    """Tributary area (N,) of the contact nodes at ``coords`` (N, 3): ∫ N_a dA over the
    interface cells (a third of each triangle, the bilinear share of each quadrilateral),
    m²."""
    weights = cell_weights(m.plan_points, m.interface_cells)
    _, idx = cKDTree(m.plan_points).query(coords[:, :2])
    return weights[idx]


@dataclass(frozen=True)
class LapJointFE:
    """The finite-element problem of the joint before its reduction.

    Attributes
    ----------
    mesh : LapJointMesh
    stiffness : scipy.sparse.csr_matrix, shape (n, n)
        Both plates, unsupported, N/m (each plate its own material).
    dofs : numpy.ndarray of int, shape (n_nodes, 3)
        DOF indices (x, y, z) of every node.
    element : str
        The element's label for the provenance.
    pairs : numpy.ndarray of int, shape (N, 2)
        Upper and lower node of each contact pair, ordered by (y, x).
    fixed : numpy.ndarray of bool, shape (n_nodes, 3)
        The held components (both grips).
    cases : tuple of Case3D
        ``bolt_k`` (washer forces, 1 N) and the service grip motions (1 m).
    gap : numpy.ndarray, shape (N,)
        Initial gap of the rounded ends, m.
    """

    mesh: LapJointMesh
    stiffness: sp.csr_matrix
    dofs: np.ndarray
    element: str
    pairs: np.ndarray
    fixed: np.ndarray
    cases: tuple
    gap: np.ndarray


#: the service cases: name and the grip's direction of motion (x, y, z)
_SERVICES = (("service", 0), ("service_y", 1), ("service_z", 2))


def _assemble(m: LapJointMesh, joint: LapJoint) -> tuple[sp.csr_matrix, np.ndarray]:
    """Stiffness of both plates (each with its material) and the DOFs of every node."""
    (E1, nu1), (E2, nu2) = joint.materials
    upper = m.element_body == 0
    if joint.element == "H8I":
        same = (E1, nu1) == (E2, nu2)
        E = E1 if same else np.where(upper, E1, E2)
        nu = nu1 if same else np.where(upper, nu1, nu2)
        dofs = np.arange(3 * m.points.shape[1]).reshape(-1, 3)
        return hex8i_stiffness(m.points, m.cells, E, nu), dofs
    mesh, elem = m.mesh, ElementVector(ElementTetP1())
    # P1: constant strains, one quadrature point integrates the stiffness exactly
    basis = Basis(mesh, elem, intorder=1)
    if (E1, nu1) == (E2, nu2):
        K = stiffness(basis, E1, nu1)
    else:
        K = sum(stiffness(Basis(mesh, elem, elements=np.flatnonzero(sel), intorder=1), E, nu)
                for sel, (E, nu) in ((upper, (E1, nu1)), (~upper, (E2, nu2))))
    return K.tocsr(), node_dofs_3d(basis)[0]


def lap_joint_fe(joint: LapJoint) -> LapJointFE:
    """Mesh and assemble the joint: stiffness, contact pairs, grips and load cases.

    Returns
    -------
    LapJointFE
    """
    m = lap_joint_mesh(joint)
    xyz = m.points.T
    x0, a, b, x1 = m.ranges
    tol = 1e-9 * joint.plate_length
    # body of each node: the upper plate's nodes come first in the mesh
    n_upper = int(m.cells[:, m.element_body == 0].max()) + 1
    body = (np.arange(xyz.shape[0]) >= n_upper).astype(int)
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
    cases = [Case3D(f"bolt_{k}", "N", force=_washer_forces(m, xyz, joint, k),
                    description=f"washer pressures of bolt {k}, 1 N")
             for k in range(joint.bolt_count)]
    for name, comp in _SERVICES:
        u = np.zeros_like(xyz)
        u[grip_upper, comp] = 1.0
        cases.append(Case3D(name, "m", displacement=u))
    K, dofs = _assemble(m, joint)
    return LapJointFE(m, K, dofs, joint.element, pairs, fixed, tuple(cases),
                      joint.end_gap(xyz[pairs[:, 0], 0]))


def bonded_shortening(fe: LapJointFE, bolts: int) -> dict[str, np.ndarray]:
    """Grip shortening of every bolt per unit of each load case, the interface bonded.

    The contact pairs are tied (v = w = 0 with no gap), the grips held or moved as the
    case prescribes; then s_k = f_kᵀ u with f_k bolt k's washer forces (1 N), the
    approach of its two washer faces (module docstring, "Elastic bolts"). One sparse
    factorisation of the tied stiffness, symmetric positive definite:
    :func:`slipcycle.condensation.factorize` (symmetric ordering, no pivoting), with about
    half the fill and CPU time of a general LU on the example joint.

    Parameters
    ----------
    fe : LapJointFE
    bolts : int
        K, the number of bolts (the cases ``bolt_0`` … ``bolt_{K-1}``).

    Returns
    -------
    dict
        Case name → (K,) shortening, m per unit of the case (m/N for the bolts, m/m for
        the grip motions).
    """
    K, dofs = fe.stiffness, fe.dofs
    n = K.shape[0]
    target = np.arange(n)
    target[dofs[fe.pairs[:, 1]].ravel()] = dofs[fe.pairs[:, 0]].ravel()   # the ties
    held = dofs[fe.fixed]
    free = np.ones(n, bool)
    free[held] = False
    free[dofs[fe.pairs[:, 1]].ravel()] = False
    col = np.full(n, -1)
    col[free] = np.arange(int(free.sum()))
    rows = np.flatnonzero(col[target] >= 0)
    P = sp.csr_matrix((np.ones(rows.size), (rows, col[target[rows]])),
                      shape=(n, int(free.sum())))
    solve = factorize((P.T @ K @ P).tocsc()).solve
    washers = np.zeros((n, bolts))
    fields = np.zeros((n, len(fe.cases)))
    for j, case in enumerate(fe.cases):
        f, u0 = np.zeros(n), np.zeros(n)
        if case.force is not None:
            np.add.at(f, dofs.ravel(), np.asarray(case.force, float).ravel())
        if case.displacement is not None:
            u0[held] = np.asarray(case.displacement, float)[fe.fixed]
        fields[:, j] = P @ solve(P.T @ (f - K @ u0)) + u0
        if j < bolts:
            washers[:, j] = f
    return {case.name: washers.T @ fields[:, j] for j, case in enumerate(fe.cases)}


def lap_joint_model(joint: LapJoint) -> LapJointModel:
    """Mesh the lap joint, reduce it to the contact nodes of its overlap (one factorisation).

    Parameters
    ----------
    joint : LapJoint
        Geometry (m), materials (Pa), bolts and mesh.

    Returns
    -------
    LapJointModel
        The reduced stiffness with the load cases of the module docstring, the tributary
        area and nearest bolt of each contact node, and the bonded bolt shortenings.

    Notes
    -----
    The condensation is :func:`slipcycle.fe.contact3d.condense_contact_3d` (Guyan 1965:
    one sparse factorisation, :func:`slipcycle.condensation.schur_complement`). The
    service cases are reduced per metre of grip motion and rescaled per newton of grip
    force with the equilibrium of the upper plate (its only supports are the grip and the
    stuck interface): F_grip = −Σ q (in plane) or −Σ p (out of plane).
    """
    t0 = time.perf_counter()
    fe = lap_joint_fe(joint)
    t_mesh = time.perf_counter() - t0
    t1 = time.perf_counter()
    red = condense_contact_3d(lambda: (fe.stiffness, fe.element), fe.dofs, fe.mesh.points,
                              pairs=fe.pairs, normals=(0.0, 0.0, -1.0), gap=fe.gap,
                              tangents=((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)), fixed=fe.fixed,
                              cases=fe.cases,
                              source=f"slipcycle.fe lap_joint_model {joint!r}")
    # only elastic bolts need the bonded shortenings (a second factorisation of the model)
    shortening = bonded_shortening(fe, joint.bolt_count) if joint.bolt_stiffness > 0 else {}
    t_reduce = time.perf_counter() - t1
    N = red.n_nodes
    loads = {}
    grip_share = np.zeros(joint.bolt_count)
    for k in range(joint.bolt_count):
        case = red.loads[f"bolt_{k}"]
        loads[f"bolt_{k}"] = case
        grip_share[k] = 1.0 - float(np.sum(case["p"]))
    grip_stiffness = {}
    for name, comp in _SERVICES:
        case = red.loads[name]
        total = (-np.sum(case["q"][comp::2]) if comp < 2 else -np.sum(case["p"]))
        grip_stiffness[f"{name}_grip_stiffness_N_per_m"] = float(total)
        loads[name] = {"q": case["q"] / total, "p": case["p"] / total}
        if shortening:
            shortening[name] = shortening[name] / total
    if joint.end_relief > 0:
        loads["gap"] = red.loads["gap"]
    if joint.end_relief > 0 and shortening:
        # the gap enters as d_true = d − [0; g]: s_k gains p_kᵀ g (module docstring)
        shortening["gap"] = np.array([float(loads[f"bolt_{k}"]["p"] @ fe.gap)
                                      for k in range(joint.bolt_count)])
    reduced = ReducedStiffness(A=red.A, B=red.B, C=red.C, tangential_dims=2,
                               nodes=red.nodes, coordinates=red.coordinates,
                               normals=red.normals, tangents=red.tangents, loads=loads,
                               source=red.source)
    coords = red.coordinates
    centres = joint.centres
    area = _node_area(fe.mesh, coords)
    region = np.argmin(np.linalg.norm(coords[:, None, :2] - centres[None], axis=-1),
                       axis=1)
    spacing = float(np.sqrt(area.sum() / N))
    (E1, nu1), (E2, nu2) = joint.materials
    description = {
        "plate_length_m": joint.plate_length, "plate_width_m": joint.plate_width,
        "thickness_m": joint.thickness, "overlap_m": joint.overlap, "E_Pa": E1,
        "nu": nu1, "E_lower_Pa": E2, "nu_lower": nu2, "bolt_count": joint.bolt_count,
        "bolt_diameter_m": joint.bolt_diameter, "washer_diameter_m": joint.washer_diameter,
        "bolt_stiffness_N_per_m": joint.bolt_stiffness,
        "end_relief_m": joint.end_relief, "end_relief_depth_m": joint.end_relief_depth,
        "mesh_size_m": joint.mesh_size, "refine": joint.refine, "node_spacing_m": spacing,
        "element": joint.element,
        "layers": joint.layer_count, "contact_nodes": N, "dofs": int(fe.stiffness.shape[0]),
        "elements": int(fe.mesh.cells.shape[1]), "mesh_s": t_mesh, "reduction_s": t_reduce,
        **grip_stiffness,
    }
    return LapJointModel(reduced=reduced, node_area=area, bolt_region=region.astype(int),
                         bolt_centres=centres, spacing=spacing, grip_share=grip_share,
                         description=description, bolt_shortening=shortening,
                         bolt_stiffness=joint.bolt_stiffness)
