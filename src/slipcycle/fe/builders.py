"""Generated geometries as ready-to-reduce :class:`~slipcycle.fe.reduction.Problem` s.

Every generated geometry has its interface on y = 0, body 1 above it (n = (0, 1),
t = (1, 0)), and is loaded through the top face of body 1 in one of three ways
(``top``):

``"platen"``
    a rigid platen bonded to the top face, free to translate (not to rotate); basic
    load cases ``normal`` (1 N pressing body 1 down, i.e. force −n) and ``tangential``
    (1 N along +t), unit "N";
``"traction"``
    uniform tractions on the top face with the same resultants (1 N);
``"displacement"``
    the top face moves rigidly by 1 m down (``normal``) or along +t (``tangential``),
    unit "m".

Forces are per ``thickness`` (m) of the plane-strain slab. Body 2 (when there is one)
is clamped on its bottom face. Geometries with an initial gap add the case ``gap``.
"""

from __future__ import annotations

import numpy as np

from slipcycle.fe.assembly import BodyDofs, assemble, traction_load
from slipcycle.fe.contact import contact_on_flat, contact_pairs
from slipcycle.fe.geometry import (
    Body,
    Grid,
    Solid,
    block_mesh,
    check_length,
    check_proportion,
    cylinder_segment_mesh,
    interface_grid,
    solid,
)
from slipcycle.fe.reduction import LoadCase, Problem

__all__ = ["TOP_MODES", "block_on_rigid", "two_blocks", "cylinder_on_block", "from_mesh",
           "top_loading"]

TOP_MODES = ("platen", "traction", "displacement")


def top_loading(dofs: list[BodyDofs], body: int, top: str, thickness: float,
                fixed: list[np.ndarray], tag: str = "top") -> tuple[list, list[LoadCase]]:
    """Ties and the two basic load cases of a body loaded through its ``tag`` face.

    ``fixed`` (list of global DOF arrays) is extended in place for ``"displacement"``;
    the returned cases' ``u_fixed`` refer to the concatenation of ``fixed``.
    """
    bd = dofs[body]
    nodes = bd.boundary_nodes(tag)
    if top == "platen":
        ties = [(bd.ux[nodes], "platen_x"), (bd.uy[nodes], "platen_y")]
        cases = [
            LoadCase("normal", "N", "1 N pressing the platen towards the interface",
                     f_master=np.array([0.0, -1.0])),
            LoadCase("tangential", "N", "1 N on the platen along +t",
                     f_master=np.array([1.0, 0.0])),
        ]
        return ties, cases
    if top == "traction":
        facets = bd.body.facets(tag)
        xs = bd.body.mesh.p[0, bd.body.mesh.facets[:, facets]]
        length = float(np.sum(np.abs(xs[1] - xs[0])))
        n = bd.ndofs

        def full(local):
            f = np.zeros(sum(d.ndofs for d in dofs))
            f[bd.offset:bd.offset + n] = local
            return f

        per = 1.0 / (length * thickness)
        cases = [
            LoadCase("normal", "N", "uniform pressure on the top face, resultant 1 N",
                     f=full(traction_load(bd.basis, facets, (0.0, -per), thickness))),
            LoadCase("tangential", "N", "uniform shear on the top face, resultant 1 N along +t",
                     f=full(traction_load(bd.basis, facets, (per, 0.0), thickness))),
        ]
        return [], cases
    if top == "displacement":
        start = sum(len(f) for f in fixed)
        fixed.append(np.concatenate([bd.ux[nodes], bd.uy[nodes]]))
        total = start + 2 * len(nodes)
        un, ut = np.zeros(total), np.zeros(total)
        un[start + len(nodes):] = -1.0
        ut[start:start + len(nodes)] = 1.0
        cases = [
            LoadCase("normal", "m", "top face moved 1 m towards the interface", u_fixed=un),
            LoadCase("tangential", "m", "top face moved 1 m along +t", u_fixed=ut),
        ]
        return [], cases
    raise ValueError(f"top must be one of {TOP_MODES}, got {top!r}")


def _pad_cases(cases: list[LoadCase], n_fixed: int) -> None:
    for c in cases:
        if c.u_fixed is not None and len(c.u_fixed) < n_fixed:
            c.u_fixed = np.concatenate([c.u_fixed, np.zeros(n_fixed - len(c.u_fixed))])


def _bottom_fixed(bd: BodyDofs) -> np.ndarray:
    nodes = bd.boundary_nodes("bottom")
    return np.concatenate([bd.ux[nodes], bd.uy[nodes]])


def _finish(K, dofs, contact, fixed_groups, ties, cases, info) -> Problem:
    fixed = np.concatenate(fixed_groups) if fixed_groups else np.zeros(0, dtype=np.int64)
    _pad_cases(cases, len(fixed))
    return Problem(K=K, dofs=dofs, contact=contact, fixed=fixed.astype(np.int64), ties=ties,
                   cases=cases, info=info)


def block_on_rigid(*, width: float, height: float, E: float, nu: float,
                   contact_width: float | None = None, elements: int = 20,
                   grading: float = 1.3, element: str = "P2", top: str = "displacement",
                   thickness: float = 1.0, formulation: str = "auto") -> Problem:
    """Rectangular block (width × height, m) resting on a rigid flat.

    Contact candidates are the bottom-face nodes with |x| <= contact_width/2 (default:
    the whole face, complete contact); ``elements`` elements span the contact zone.

    Parameters
    ----------
    width : float
        Block width (m): x ∈ [−width/2, width/2].
    height : float
        Block height (m): y ∈ [0, height], the flat at y = 0.
    E : float
        Young's modulus (Pa).
    nu : float
        Poisson's ratio (plane strain), 0 ≤ ν < 0.5.
    contact_width : float, optional
        Width (m) of the zone of contact candidates, |x| ≤ contact_width/2; default
        ``width``.
    elements : int
        Elements across the contact zone, of uniform size h = contact_width/elements (m);
        the zone holds 2·elements + 1 contact nodes with ``P2``, elements + 1 with ``P1``.
    grading : float
        Geometric growth ratio (> 1) of the element size away from the contact zone and
        with depth.
    element : {"P2", "P1"}
        Quadratic or linear Lagrange triangles.
    top : {"displacement", "platen", "traction"}
        How body 1 is loaded through its top face (module docstring): moved rigidly by
        1 m (cases in m), a bonded rigid platen free to translate, or uniform tractions
        (cases of 1 N resultant). With ``"platen"`` or ``"traction"`` body 1 is supported
        only through its contact: the reduced stiffness keeps its rigid-body modes
        (positive semi-definite), which ``slipcycle reduce`` refuses.
    thickness : float
        Out-of-plane thickness of the plane-strain slab (m); forces and stiffnesses are
        per this thickness (N, N/m).
    formulation : {"auto", "displacement", "mixed"}
        Displacement elements, the P2–P0 mixed element with the pressure condensed out
        (no volumetric locking as ν → 0.5), or ``"auto"``: mixed for ``P2`` with ν > 0.4.

    Returns
    -------
    Problem
        ``K`` the stiffness (n, n) (N/m), ``dofs``, ``contact`` the N contact nodes on
        the rigid flat (n = (0, 1), t = (1, 0), ordered by x, initial gap 0), ``fixed``
        the prescribed DOFs, ``ties`` (platen), ``cases`` ``normal`` and ``tangential``,
        and ``info`` (the arguments, for the output metadata).

    Raises
    ------
    slipcycle.errors.InputError
        A size, element count, grading or material out of range, keyed by the argument
        (``upper.E`` for a body's field; :class:`~slipcycle.fe.geometry.Grid`,
        :class:`~slipcycle.fe.geometry.Solid`).
    ValueError
        An unknown ``top`` or ``formulation``.

    References
    ----------
    Gustafsson, T. & McBain, G. D. (2020). scikit-fem: A Python package for finite element
    assembly. J. Open Source Softw. 5(52), 2369. Boffi, D., Brezzi, F. & Fortin, M. (2013).
    Mixed Finite Element Methods and Applications, Springer, §8.6 (P2–P0). Dundurs, J. (1969).
    J. Appl. Mech. 36, 650–652 (β = (1 − 2ν)/(2(1 − ν)) on a rigid flat: normal–tangential
    coupling).
    """
    cw = width if contact_width is None else contact_width
    Grid(width, cw, elements, grading, thickness)
    Solid(E=E, nu=nu, height=height)
    check_proportion("height", height, width)
    x = interface_grid(width, cw, elements, grading)
    h0 = cw / elements
    mesh = block_mesh(x, height, h0, grading, "above", cw / 2)
    body = Body("block", mesh, E, nu)
    K, dofs = assemble([body], element, thickness, formulation)
    contact = contact_on_flat(dofs, 0, "contact", (0.0, 1.0), gap=None)
    contact.gap = np.zeros(contact.n)
    fixed: list[np.ndarray] = []
    ties, cases = top_loading(dofs, 0, top, thickness, fixed)
    info = {"geometry": "block_on_rigid", "width": width, "height": height, "E": E, "nu": nu,
            "contact_width": cw, "elements": elements, "grading": grading,
            "element": element, "top": top, "thickness": thickness,
            "formulation": formulation}
    return _finish(K, dofs, contact, fixed, ties, cases, info)


def two_blocks(*, width: float, upper: dict, lower: dict, contact_width: float | None = None,
               elements: int = 20, grading: float = 1.3, element: str = "P2",
               top: str = "displacement", thickness: float = 1.0,
               formulation: str = "auto") -> Problem:
    """Two rectangular blocks of equal width, ``upper`` (body 1) on ``lower`` (body 2).

    ``upper`` and ``lower`` are dicts with ``height`` (m), ``E`` (Pa), ``nu``. The lower
    block is clamped on its bottom face; the meshes match node to node on y = 0 (the
    lower mesh is the mirror image of an upper one).

    Parameters
    ----------
    width : float
        Width of both blocks (m): x ∈ [−width/2, width/2].
    upper : dict or Solid
        Body 1, y ∈ [0, height]: ``{"height": m, "E": Pa, "nu": -}``.
    lower : dict
        Body 2, y ∈ [−height, 0], clamped at y = −height: same keys.
    contact_width : float, optional
        Width (m) of the zone of contact pairs, |x| ≤ contact_width/2; default ``width``.
    elements : int
        Elements across the contact zone, of uniform size h = contact_width/elements (m);
        the zone holds 2·elements + 1 contact nodes with ``P2``, elements + 1 with ``P1``.
    grading : float
        Geometric growth ratio (> 1) of the element size away from the contact zone and
        with depth.
    element : {"P2", "P1"}
        Quadratic or linear Lagrange triangles.
    top : {"displacement", "platen", "traction"}
        How body 1 is loaded through its top face (module docstring): moved rigidly by
        1 m (cases in m), a bonded rigid platen free to translate, or uniform tractions
        (cases of 1 N resultant). With ``"platen"`` or ``"traction"`` body 1 is supported
        only through its contact: the reduced stiffness keeps its rigid-body modes
        (positive semi-definite), which ``slipcycle reduce`` refuses.
    thickness : float
        Out-of-plane thickness of the plane-strain slab (m); forces and stiffnesses are
        per this thickness (N, N/m).
    formulation : {"auto", "displacement", "mixed"}
        Displacement elements, the P2–P0 mixed element with the pressure condensed out
        (no volumetric locking as ν → 0.5), or ``"auto"``: mixed for ``P2`` with ν > 0.4.

    Returns
    -------
    Problem
        ``K`` the block-diagonal stiffness (n, n) (N/m), ``dofs`` per body, ``contact``
        the N node pairs (n = (0, 1) from body 2 into body 1, t = (1, 0), ordered by x,
        initial gap 0), ``fixed`` the prescribed DOFs, ``ties`` (platen), ``cases``
        ``normal`` and ``tangential``, and ``info`` (the arguments, for the metadata).

    Raises
    ------
    slipcycle.errors.InputError
        A size, element count, grading or material out of range, keyed by the argument
        (``upper.E`` for a body's field; :class:`~slipcycle.fe.geometry.Grid`,
        :class:`~slipcycle.fe.geometry.Solid`).
    ValueError
        An unknown ``top`` or ``formulation``.

    References
    ----------
    Gustafsson, T. & McBain, G. D. (2020). scikit-fem: A Python package for finite element
    assembly. J. Open Source Softw. 5(52), 2369. Boffi, D., Brezzi, F. & Fortin, M. (2013).
    Mixed Finite Element Methods and Applications, Springer, §8.6 (P2–P0). Dundurs, J. (1969).
    J. Appl. Mech. 36, 650–652 (β of the pair: B = 0 for identical blocks).
    """
    cw = width if contact_width is None else contact_width
    Grid(width, cw, elements, grading, thickness)
    upper, lower = solid("upper", upper).as_dict(), solid("lower", lower).as_dict()
    for name, body in (("upper", upper), ("lower", lower)):
        check_proportion(f"{name}.height", body["height"], width)
    x = interface_grid(width, cw, elements, grading)
    h0 = cw / elements
    b1 = Body("upper", block_mesh(x, upper["height"], h0, grading, "above", cw / 2),
              upper["E"], upper["nu"])
    b2 = Body("lower", block_mesh(x, lower["height"], h0, grading, "below", cw / 2),
              lower["E"], lower["nu"])
    K, dofs = assemble([b1, b2], element, thickness, formulation)
    contact = contact_pairs(dofs, 0, "contact", 1, "contact", (0.0, 1.0))
    contact.gap = np.zeros(contact.n)
    fixed = [_bottom_fixed(dofs[1])]
    ties, cases = top_loading(dofs, 0, top, thickness, fixed)
    info = {"geometry": "two_blocks", "width": width, "upper": upper, "lower": lower,
            "contact_width": cw, "elements": elements, "grading": grading,
            "element": element, "top": top, "thickness": thickness,
            "formulation": formulation}
    return _finish(K, dofs, contact, fixed, ties, cases, info)


def cylinder_on_block(*, radius: float, cylinder: dict, block: dict, width: float,
                      contact_width: float, elements: int = 40, grading: float = 1.3,
                      element: str = "P2", top: str = "displacement", thickness: float = 1.0,
                      formulation: str = "auto") -> Problem:
    """A cylinder (body 1) of radius R pressed on a block (body 2): 2-D Hertzian contact.

    The cylinder is the segment R − √(R² − x²) <= y <= ``cylinder["height"]``,
    |x| <= width/2 (so width < 2R), loaded through its flat top; the block is
    width × ``block["height"]``, clamped at its bottom. Contact candidates: |x| <=
    contact_width/2, paired node to node at equal x; the initial gap g_j is the height
    of the (piecewise straight) cylinder surface above the block at x_j (≈ x²/2R) and
    enters the load case ``gap``.

    Parameters
    ----------
    radius : float
        R (m), > width/2.
    cylinder : dict or Solid
        Body 1: ``{"height": m, "E": Pa, "nu": -}``; ``height`` is the y of its flat top
        (the arc touches y = 0 at x = 0).
    block : dict
        Body 2, y ∈ [−height, 0], clamped at its bottom: same keys.
    width : float
        Width of both bodies (m): x ∈ [−width/2, width/2], width < 2R.
    contact_width : float
        Width (m) of the zone of contact pairs, |x| ≤ contact_width/2 (required: it should
        exceed the Hertzian contact width 2a of the loads to be applied).
    elements : int
        Elements across the contact zone, of uniform size h = contact_width/elements (m);
        the zone holds 2·elements + 1 contact nodes with ``P2``, elements + 1 with ``P1``.
    grading : float
        Geometric growth ratio (> 1) of the element size away from the contact zone and
        with depth.
    element : {"P2", "P1"}
        Quadratic or linear Lagrange triangles.
    top : {"displacement", "platen", "traction"}
        How body 1 is loaded through its top face (module docstring): moved rigidly by
        1 m (cases in m), a bonded rigid platen free to translate, or uniform tractions
        (cases of 1 N resultant). With ``"platen"`` or ``"traction"`` body 1 is supported
        only through its contact: the reduced stiffness keeps its rigid-body modes
        (positive semi-definite), which ``slipcycle reduce`` refuses.
    thickness : float
        Out-of-plane thickness of the plane-strain slab (m); forces and stiffnesses are
        per this thickness (N, N/m).
    formulation : {"auto", "displacement", "mixed"}
        Displacement elements, the P2–P0 mixed element with the pressure condensed out
        (no volumetric locking as ν → 0.5), or ``"auto"``: mixed for ``P2`` with ν > 0.4.

    Returns
    -------
    Problem
        ``K`` the block-diagonal stiffness (n, n) (N/m), ``dofs`` per body, ``contact``
        the N node pairs (n = (0, 1) from body 2 into body 1, t = (1, 0), ordered by x,
        initial gaps g_j in m), ``fixed`` the prescribed DOFs, ``ties`` (platen),
        ``cases`` ``normal``, ``tangential`` and ``gap`` (apply it with factor 1), and
        ``info`` (the arguments, for the metadata).

    Raises
    ------
    ValueError
        ``width`` ≥ 2 ``radius``, an unknown ``top`` or ``formulation``.

    References
    ----------
    Gustafsson, T. & McBain, G. D. (2020). scikit-fem: A Python package for finite element
    assembly. J. Open Source Softw. 5(52), 2369. Boffi, D., Brezzi, F. & Fortin, M. (2013).
    Mixed Finite Element Methods and Applications, Springer, §8.6 (P2–P0). Johnson, K. L.
    (1985). Contact Mechanics, §4.2 and §7.6 (the 2-D Hertz and Cattaneo–Mindlin
    solutions the model is checked against).
    """
    check_length("radius", radius)
    if width >= 2 * radius:
        raise ValueError("cylinder_on_block: width must be smaller than 2 * radius")
    cw = contact_width
    Grid(width, cw, elements, grading, thickness)
    cylinder, block = solid("cylinder", cylinder).as_dict(), solid("block", block).as_dict()
    for name, body in (("cylinder", cylinder), ("block", block)):
        check_proportion(f"{name}.height", body["height"], width)
    x = interface_grid(width, cw, elements, grading)
    h0 = cw / elements
    mesh1, _ = cylinder_segment_mesh(x, radius, cylinder["height"], h0, grading, cw / 2)
    b1 = Body("cylinder", mesh1, cylinder["E"], cylinder["nu"])
    b2 = Body("block", block_mesh(x, block["height"], h0, grading, "below", cw / 2),
              block["E"], block["nu"])
    K, dofs = assemble([b1, b2], element, thickness, formulation)
    contact = contact_pairs(dofs, 0, "contact", 1, "contact", (0.0, 1.0))
    fixed = [_bottom_fixed(dofs[1])]
    ties, cases = top_loading(dofs, 0, top, thickness, fixed)
    cases.append(LoadCase("gap", "1", "initial gap g_j (profile of the cylinder)", gap=True))
    info = {"geometry": "cylinder_on_block", "radius": radius, "cylinder": cylinder,
            "block": block, "width": width, "contact_width": cw, "elements": elements,
            "grading": grading, "element": element, "top": top, "thickness": thickness,
            "formulation": formulation}
    return _finish(K, dofs, contact, fixed, ties, cases, info)


def from_mesh(body: Body, *, contact: str = "contact", normal=(0.0, 1.0),
              clamped: tuple[str, ...] = (), loads: list[dict] = (), element: str = "P2",
              thickness: float = 1.0, formulation: str = "auto") -> Problem:
    """A body read from a mesh file, on a rigid flat perpendicular to ``normal``.

    The flat passes through the contact node lowest along ``normal``; the other contact
    nodes get the initial gap g_j = n·(x_j − x_lowest) ≥ 0 (m), which enters a load case
    ``gap`` when any is positive.

    Parameters
    ----------
    body : Body
        With boundaries named ``contact``, the ``clamped`` ones and those of ``loads``
        (e.g. from :func:`~slipcycle.fe.meshfile.read_mesh_body`); E (Pa), ν, mesh in m.
    contact : str
        Name of the boundary whose nodes are the contact candidates.
    normal : (2,) array_like
        Normal of the flat pointing into the body (normalised here); t = (n_y, −n_x).
    clamped : tuple of str
        Names of boundaries held at u = 0 in every case.
    loads : list of dict
        Basic load cases, each ``{"name", "boundary", "traction": (t_x, t_y)}`` (the
        case is per unit of that traction, unit "Pa") or ``{"name", "boundary",
        "displacement": (u_x, u_y)}`` (m; the boundary is then held in every other case).
    element : {"P2", "P1"}
        Quadratic or linear Lagrange triangles.
    thickness : float
        Out-of-plane thickness of the plane-strain slab (m).
    formulation : {"auto", "displacement", "mixed"}
        As for :func:`block_on_rigid`: ``"auto"`` is the P2–P0 mixed element for ``P2``
        with ν > 0.4.

    Returns
    -------
    Problem
        ``K`` (n, n) (N/m), ``dofs``, ``contact`` (N nodes against the rigid flat, ordered
        along t, gaps g_j), ``fixed`` (DOFs of the clamped and displacement-loaded
        boundaries; a node on two of them keeps the value of the first), ``ties`` (none),
        ``cases`` in the order of ``loads`` (then ``gap``) and ``info``.

    Raises
    ------
    slipcycle.io.case.CaseError
        No nodes on the ``contact`` boundary.
    ValueError
        An unknown ``formulation``.

    References
    ----------
    Gustafsson, T. & McBain, G. D. (2020). scikit-fem: A Python package for finite element
    assembly. J. Open Source Softw. 5(52), 2369. Boffi, D., Brezzi, F. & Fortin, M. (2013).
    Mixed Finite Element Methods and Applications, Springer, §8.6 (P2–P0).
    """
    K, dofs = assemble([body], element, thickness, formulation)
    cs = contact_on_flat(dofs, 0, contact, normal)
    bd = dofs[0]
    fixed = [np.concatenate([bd.ux[bd.boundary_nodes(t)], bd.uy[bd.boundary_nodes(t)]])
             for t in clamped]
    held = {}  # boundary -> (start in the fixed list, nodes); held in every case
    for spec in loads:
        if "displacement" in spec and spec["boundary"] not in held:
            nodes = bd.boundary_nodes(spec["boundary"])
            held[spec["boundary"]] = (sum(len(g) for g in fixed), nodes)
            fixed.append(np.concatenate([bd.ux[nodes], bd.uy[nodes]]))
    n_fixed = sum(len(g) for g in fixed)
    cases = []
    for spec in loads:
        if "traction" in spec:
            f = traction_load(bd.basis, body.facets(spec["boundary"]), spec["traction"],
                              thickness)
            cases.append(LoadCase(spec["name"], "Pa", f"traction {tuple(spec['traction'])} Pa "
                                  f"on {spec['boundary']!r}", f=f))
        else:
            start, nodes = held[spec["boundary"]]
            u = np.zeros(n_fixed)
            ux, uy = spec["displacement"]
            u[start:start + len(nodes)] = ux
            u[start + len(nodes):start + 2 * len(nodes)] = uy
            cases.append(LoadCase(spec["name"], "m", f"displacement {tuple(spec['displacement'])}"
                                  f" m of {spec['boundary']!r}", u_fixed=u))
    if np.any(cs.gap > 0):
        cases.append(LoadCase("gap", "1", "initial gap of the contact nodes", gap=True))
    fixed_all = np.concatenate(fixed) if fixed else np.zeros(0, dtype=np.int64)
    fixed_all, first = np.unique(fixed_all, return_index=True)
    for c in cases:  # a node on two held boundaries keeps the value of the first
        if c.u_fixed is not None:
            c.u_fixed = c.u_fixed[first]
    info = {"geometry": "mesh", "file": body.info.get("file", ""), "E": body.E,
            "nu": body.nu, "element": element, "thickness": thickness,
            "formulation": formulation, "normal": list(map(float, normal))}
    return Problem(K=K, dofs=dofs, contact=cs, fixed=fixed_all.astype(np.int64), ties=[],
                   cases=cases, info=info)
