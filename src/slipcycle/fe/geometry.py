"""Mesh builders for the generated geometries.

All geometries are 2-D (x along the interface, y normal to it, interface at y = 0) and
are meshed as mapped, graded tensor grids split into triangles, so that the nodes of two
bodies meeting at the interface coincide (node-to-node pairs). Element size is uniform,
``h = contact_width / elements``, across the contact zone and grows geometrically (ratio
``grading``) away from it, in x and in depth.

Each builder returns a list of :class:`Body`; boundaries are named facet sets:

``contact``
    the candidate contact surface (only facets inside the contact zone),
``top`` / ``bottom``
    the loaded or supported face away from the interface.

Units: metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from skfem import MeshTri

from slipcycle.errors import InputError

__all__ = ["Body", "Material", "Solid", "Grid", "check_number", "check_length",
           "check_proportion", "solid", "graded_spacing", "interface_grid", "depth_grid",
           "block_mesh", "cylinder_segment_mesh"]


def check_number(name: str, value: Any, *, gt: float | None = None, ge: float | None = None,
                 lt: float | None = None, le: float | None = None,
                 integer: bool = False) -> float | int:
    """Refuse a value that is not a finite (integer) number within the bounds.

    Raises
    ------
    slipcycle.errors.InputError
        Keyed by ``name``, with the messages of the case-file reader (``must be > 0, got
        -1``), so that a model file and the Python object say the same.
    """
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer
                                                 | np.floating):
        kind = "an integer" if integer else "a number"
        raise InputError(name, f"must be {kind}, got {value!r}")
    if integer and not float(value).is_integer():
        raise InputError(name, f"must be an integer, got {value!r}")
    if not math.isfinite(float(value)):
        raise InputError(name, f"must be finite, got {float(value)}")
    for bound, ok, sym in ((gt, value > (gt or 0), ">"), (ge, value >= (ge or 0), ">="),
                           (lt, value < (lt or 0), "<"), (le, value <= (le or 0), "<=")):
        if bound is not None and not ok:
            raise InputError(name, f"must be {sym} {bound:g}, got {value:g}")
    return int(value) if integer else float(value)


#: the lengths a generated finite-element geometry may have [m]: a nanometre to a
#: million kilometres; beyond, the mesh's Jacobians under- or overflow (a width of 1e-300
#: m filled the output with division warnings and blamed another key)
LENGTH_RANGE = (1e-9, 1e9)


def check_length(name: str, value: Any) -> float:
    """A length [m] of a generated geometry: a finite number within :data:`LENGTH_RANGE`
    (refused keyed ``name``, as :func:`check_number`)."""
    lo, hi = LENGTH_RANGE
    value = check_number(name, value, gt=0)
    if not lo <= value <= hi:
        raise InputError(name, f"must be between {lo:g} m and {hi:g} m, got {value:g}: "
                               "check its units (m)")
    return value


#: height / width of a generated body [1]: a block 5000 times as tall as wide reduced to
#: a numerically singular stiffness (reported as "not supported against rigid motion"),
#: one 2e7 times as tall as wide to one that was not positive definite
ASPECT_RANGE = (1e-7, 100.0)


def check_proportion(name: str, height: float, width: float) -> None:
    """Refuse (keyed ``name``, the height's key) a body whose height / ``width`` lies
    outside :data:`ASPECT_RANGE`: its mesh's stiffness is beyond double precision."""
    lo, hi = ASPECT_RANGE
    ratio = height / width
    if not lo <= ratio <= hi:
        raise InputError(name, f"must be between {lo:g} and {hi:g} times the width "
                               f"({width:g} m), got {height:g} m ({ratio:.3g} times): the "
                               "mesh of so slender a body has a numerically singular "
                               "stiffness; check the units (m)")


@dataclass(frozen=True)
class Material:
    """Isotropic linear-elastic material in plane strain.

    Attributes
    ----------
    E : float
        Young's modulus (Pa), > 0.
    nu : float
        Poisson's ratio, −1 < ν < 0.5 (thermodynamic bounds; the case file asks 0 ≤ ν).

    Raises
    ------
    slipcycle.errors.InputError
        Keyed by the field (``E`` or ``nu``).
    """

    E: float
    nu: float

    def __post_init__(self):
        check_number("E", self.E, gt=0)
        check_number("nu", self.nu, gt=-1, lt=0.5)


@dataclass(frozen=True)
class Solid(Material):
    """A generated body: its height (m, > 0) and material (:class:`Material`).

    Attributes
    ----------
    height : float
        Height of the block or cylinder segment (m), > 0.
    """

    height: float = float("nan")

    def __post_init__(self):
        check_length("height", self.height)
        super().__post_init__()

    def as_dict(self) -> dict:
        """``{"height": m, "E": Pa, "nu": 1}`` (the builders' metadata form)."""
        return {"height": self.height, "E": self.E, "nu": self.nu}


def solid(name: str, value: Solid | dict) -> Solid:
    """A :class:`Solid` from a Solid or a dict (``height``, ``E``, ``nu``), errors keyed
    ``name.field``.

    Raises
    ------
    slipcycle.errors.InputError
    """
    if isinstance(value, Solid):
        return value
    if not isinstance(value, dict):
        raise InputError(name, "must be a Solid or a dict with height, E and nu")
    unknown = sorted(set(value) - {"height", "E", "nu"})
    if unknown:
        raise InputError(f"{name}.{unknown[0]}", "unknown key")
    for k in ("height", "E", "nu"):
        if k not in value:
            raise InputError(f"{name}.{k}", "required key is missing")
    try:
        return Solid(E=value["E"], nu=value["nu"], height=value["height"])
    except InputError as exc:
        raise InputError(f"{name}.{exc.key}", exc.problem) from None


@dataclass(frozen=True)
class Grid:
    """The interface grid of a generated geometry.

    Attributes
    ----------
    width : float
        Width of the bodies (m), > 0.
    contact_width : float
        Width of the zone of contact candidates (m), 0 < contact_width ≤ width.
    elements : int
        Elements across the contact zone, ≥ 1.
    grading : float
        Geometric growth ratio of the element size away from the contact zone and with
        depth, ≥ 1 (1: uniform).
    thickness : float
        Out-of-plane thickness of the plane-strain slab (m), > 0.

    Raises
    ------
    slipcycle.errors.InputError
        Keyed by the field.
    """

    width: float
    contact_width: float
    elements: int = 20
    grading: float = 1.3
    thickness: float = 1.0

    def __post_init__(self):
        check_length("width", self.width)
        check_number("contact_width", self.contact_width, gt=0, le=self.width)
        check_number("elements", self.elements, ge=1, integer=True)
        check_number("grading", self.grading, ge=1.0)
        check_length("thickness", self.thickness)


@dataclass(frozen=True)
class Body:
    """One linear-elastic body (frozen; ``info`` is filled by the assembly).

    Attributes
    ----------
    name : str
        Name used in messages and output metadata ("block", "upper", "cylinder", ...).
    mesh : skfem.MeshTri
        Linear triangle mesh (coordinates in m); ``mesh.boundaries`` holds named facet
        index arrays.
    E : float
        Young's modulus, Pa.
    nu : float
        Poisson's ratio (plane strain, −1 < ν < 0.5).
    info : dict
        Metadata (source file, the formulation chosen by the assembly).

    Raises
    ------
    slipcycle.errors.InputError
        ``E`` or ``nu`` out of range (keyed by the field).
    """

    name: str
    mesh: MeshTri
    E: float
    nu: float
    info: dict = field(default_factory=dict)

    def __post_init__(self):
        Material(self.E, self.nu)

    def facets(self, tag: str) -> np.ndarray:
        """Facet indices of the boundary named ``tag`` (empty if absent)."""
        b = self.mesh.boundaries or {}
        return np.asarray(b.get(tag, np.zeros(0, dtype=np.int64)), dtype=np.int64)


def graded_spacing(length: float, h0: float, ratio: float, hmax: float | None = None
                   ) -> np.ndarray:
    """Node positions 0 = s_0 < s_1 < ... < s_n = ``length`` with geometric grading.

    The first interval is about ``h0``, each next one ``ratio`` times longer (capped at
    ``hmax``); all intervals are then scaled by a common factor so the last node lands
    exactly on ``length``.

    Returns
    -------
    numpy.ndarray, shape (n + 1,)
    """
    if length <= 0:
        return np.zeros(1)
    hmax = length if hmax is None else hmax
    steps = []
    h, total = h0, 0.0
    while total < length * (1 - 1e-9):
        steps.append(min(h, hmax))
        total += steps[-1]
        h *= ratio
    steps = np.asarray(steps)
    if len(steps) > 1 and total - length > 0.5 * steps[-1]:
        steps = steps[:-1]  # drop an overshooting last interval and stretch the rest
    steps *= length / steps.sum()
    return np.concatenate([[0.0], np.cumsum(steps)])


def interface_grid(width: float, contact_width: float, elements: int, ratio: float
                   ) -> np.ndarray:
    """x coordinates along the interface, centred at 0, shape (nx + 1,).

    Uniform with ``elements`` intervals over |x| <= contact_width / 2, geometrically
    graded (``ratio``) from there to the ends |x| = width / 2.
    """
    c = contact_width / 2
    h = contact_width / elements
    core = np.linspace(-c, c, elements + 1)
    rest = width / 2 - c
    if rest <= 1e-12 * width:
        return core
    out = c + graded_spacing(rest, h * ratio, ratio, hmax=max(rest / 3, h))[1:]
    return np.concatenate([-out[::-1], core, out])


def depth_grid(height: float, h0: float, ratio: float) -> np.ndarray:
    """Depth coordinates 0..height, fine (``h0``) at the interface, shape (ny + 1,)."""
    return graded_spacing(height, h0, ratio, hmax=max(height / 4, h0))


def _tensor_mesh(x: np.ndarray, y: np.ndarray) -> MeshTri:
    """Tensor grid split into triangles, mirror-symmetric about x = 0.

    Cells with centre x > 0 are cut along the diagonal (i, j)-(i+1, j+1), cells with
    x < 0 along the mirrored one, so that a symmetric x grid gives a symmetric mesh.
    """
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    nx, ny = len(x), len(y)
    X, Y = np.meshgrid(x, y, indexing="ij")
    p = np.vstack([X.ravel(), Y.ravel()])
    i, j = np.meshgrid(np.arange(nx - 1), np.arange(ny - 1), indexing="ij")
    i, j = i.ravel(), j.ravel()
    a = i * ny + j
    b = (i + 1) * ny + j
    c = (i + 1) * ny + j + 1
    d = i * ny + j + 1
    right = 0.5 * (x[i] + x[i + 1]) >= 0
    t1 = np.where(right, np.vstack([a, b, c]), np.vstack([a, b, d]))
    t2 = np.where(right, np.vstack([a, c, d]), np.vstack([b, c, d]))
    return MeshTri(p, np.hstack([t1, t2]))


def _tag(mesh: MeshTri, contact_half: float, side: str, y_far: float) -> MeshTri:
    """Name the contact facets (at y = 0, within |x| <= contact_half) and the far face."""
    tol = 1e-9 * max(np.ptp(mesh.p[0]), np.ptp(mesh.p[1]))
    far = "top" if side == "above" else "bottom"
    return mesh.with_boundaries({
        "contact": lambda p: (np.abs(p[1]) < tol) & (np.abs(p[0]) <= contact_half + tol),
        "interface": lambda p: np.abs(p[1]) < tol,
        far: lambda p: np.abs(p[1] - y_far) < tol,
    })


def block_mesh(x: np.ndarray, height: float, h0: float, ratio: float, side: str,
               contact_half: float) -> MeshTri:
    """Rectangle [x0, x1] × [0, height] (``side="above"``) or [-height, 0] (``"below"``).

    The interface face y = 0 carries the nodes ``x``; the tag ``contact`` holds its facets
    with |x| <= ``contact_half``.
    """
    y = depth_grid(height, h0, ratio)
    if side == "above":
        mesh = _tensor_mesh(x, y)
        return _tag(mesh, contact_half, side, height)
    up = _tensor_mesh(x, y)  # mirror image of the same block above the interface
    mesh = MeshTri(np.vstack([up.p[0], -up.p[1]]), up.t)
    return _tag(mesh, contact_half, side, -height)


def cylinder_segment_mesh(x: np.ndarray, radius: float, height: float, h0: float,
                          ratio: float, contact_half: float) -> tuple[MeshTri, np.ndarray]:
    """Segment of a cylinder of radius R whose lowest point touches y = 0 at x = 0.

    The body occupies ``R - sqrt(R² - x²) <= y <= height`` for x in [x0, x1] (vertical
    sides, flat top at y = ``height``). It is a mapped grid: each column of a depth grid
    is stretched between the arc and the top, so the arc nodes have the abscissae ``x``.

    Returns
    -------
    mesh : skfem.MeshTri
        Tagged ``contact`` (arc facets with |x| <= contact_half), ``interface`` (whole
        arc) and ``top``.
    gap : numpy.ndarray, shape (nx + 1,)
        Height of the arc above y = 0 at each x (the initial gap profile), m.
    """
    arc = radius - np.sqrt(radius**2 - x**2)
    eta = depth_grid(height, h0, ratio) / height  # 0..1, fine near the arc
    mesh = _tensor_mesh(x, eta)
    px, pe = mesh.p
    col = np.searchsorted(x, px)  # exact matches: px values come from x
    y0 = arc[np.clip(col, 0, len(x) - 1)]
    # keep the first layers at their physical thickness (pe * height) and absorb the
    # shortening of each column (height - y0) smoothly towards the top
    py = y0 + pe * (height - y0)
    mesh = MeshTri(np.vstack([px, py]), mesh.t)
    tol = 1e-9 * radius
    on_arc = pe == 0.0  # vertices of the lowest grid row lie on the arc
    is_arc = np.all(on_arc[mesh.facets], axis=0)
    inside = np.all(np.abs(mesh.p[0, mesh.facets]) <= contact_half + tol, axis=0)
    mesh = mesh.with_boundaries({
        "top": lambda p: np.abs(p[1] - height) < tol,
        "interface": np.nonzero(is_arc)[0],
        "contact": np.nonzero(is_arc & inside)[0],
    })
    return mesh, arc

