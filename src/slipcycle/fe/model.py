"""Model files for ``slipcycle reduce`` (``model = "fe"``); see ``docs/fe.md``.

Every key is validated before any meshing; problems are :class:`CaseError` naming the
dotted key. The reader only translates keys: the checks of values live in the frozen model
objects (:class:`~slipcycle.fe.geometry.Material`, :class:`~slipcycle.fe.geometry.Solid`,
:class:`~slipcycle.fe.geometry.Grid`), whose :class:`~slipcycle.errors.InputError` is
re-keyed to the TOML key (the file format also asks 0 ≤ ν and caps ``elements`` and
``grading``). :func:`build_problem` returns the assembled
:class:`~slipcycle.fe.reduction.Problem`; :func:`discrete_case_text` turns the optional
``[fe.discrete]`` table into a ready-to-run discrete case file.
"""

from __future__ import annotations

import numpy as np

from slipcycle.errors import InputError
from slipcycle.fe import builders
from slipcycle.fe.geometry import Grid, Material, Solid, check_proportion
from slipcycle.fe.loads import combined_loads
from slipcycle.fe.meshfile3d import MeshSolid
from slipcycle.fe.reduction import Problem, ReducedModel
from slipcycle.io.case import Case, CaseError, Section, read_friction

__all__ = ["GEOMETRIES", "build_problem", "discrete_case_text", "discrete3d_case_text",
           "discrete3d_load_terms", "read_discrete_table",
           "read_convergence_table", "DEFAULT_REFINEMENTS"]

GEOMETRIES = ("block_on_rigid", "two_blocks", "cylinder_on_block", "mesh")


def _make(sec: Section, cls, **kw):
    """``cls(**kw)``, its InputError re-keyed to the key of ``sec``."""
    try:
        return cls(**kw)
    except InputError as exc:
        raise sec.error(exc.key, exc.problem) from None


def _material(sec: Section) -> dict:
    E = sec.float("E")
    _make(sec, Material, E=E, nu=0.0)
    nu = sec.float("nu", ge=0)  # the file format asks 0 <= nu
    m = _make(sec, Material, E=E, nu=nu)
    return {"E": m.E, "nu": m.nu}


def _body(sec: Section) -> dict:
    height = sec.float("height")
    _make(sec, Solid, E=1.0, nu=0.0, height=height)
    mat = _material(sec)
    return _make(sec, Solid, height=height, **mat).as_dict()


def build_problem(case: Case) -> Problem | MeshSolid:
    """Validate the ``[fe]`` table of ``case`` and assemble the problem.

    A 2-D model gives the assembled :class:`~slipcycle.fe.reduction.Problem`; a mesh file
    of tetrahedra gives the :class:`~slipcycle.fe.meshfile3d.MeshSolid` to reduce with
    :func:`~slipcycle.fe.meshfile3d.reduce_mesh_solid`.
    """
    fe = case.section("fe")
    geometry = fe.string("geometry", choices=GEOMETRIES)
    common = {
        "element": fe.string("element", "P2", choices=("P1", "P2")),
        "thickness": fe.float("thickness", 1.0),
        "formulation": fe.string("formulation", "auto",
                                 choices=("auto", "displacement", "mixed")),
    }
    _make(fe, Grid, width=1.0, contact_width=1.0, thickness=common["thickness"])
    read_discrete_table(fe)  # validate now, used after the reduction
    read_convergence_table(fe, geometry)  # used by `slipcycle run` (slipcycle.joints)
    if geometry == "mesh":
        return _mesh_problem(fe, common, case)
    common["top"] = fe.string("top", "displacement", choices=("displacement",))
    width = fe.float("width")
    _make(fe, Grid, width=width, contact_width=width)
    elements = fe.int("elements", 20, le=20000)
    grading = fe.float("grading", 1.3, le=3.0)
    g = _make(fe, Grid, width=width, contact_width=width, elements=elements, grading=grading,
              thickness=common["thickness"])
    grid = {"elements": g.elements, "grading": g.grading}
    if geometry == "cylinder_on_block":
        radius = fe.float("radius", gt=0)
        if width >= 2 * radius:
            raise fe.error("width", f"must be < 2 * radius = {2 * radius:g}, got {width:g}")
        cw = fe.float("contact_width")
        _make(fe, Grid, width=width, contact_width=cw)
        cyl, blk = fe.table("cylinder"), fe.table("block")
        cyl_d, blk_d = _body(cyl), _body(blk)
        _proportion(cyl, cyl_d, width)
        _proportion(blk, blk_d, width)
        ymin = radius - np.sqrt(radius**2 - (width / 2) ** 2)
        if cyl_d["height"] <= 1.5 * ymin:
            raise cyl.error("height", f"must exceed 1.5 × the arc height at the sides "
                                      f"({1.5 * ymin:g} m), got {cyl_d['height']:g}")
        cyl.finish()
        blk.finish()
        case.finish()
        return builders.cylinder_on_block(radius=radius, cylinder=cyl_d, block=blk_d,
                                          width=width, contact_width=cw, **grid, **common)
    cw = fe.float("contact_width", width)
    _make(fe, Grid, width=width, contact_width=cw)
    if geometry == "block_on_rigid":
        body = _body(fe)
        _proportion(fe, body, width)
        case.finish()
        return builders.block_on_rigid(width=width, contact_width=cw, **body, **grid, **common)
    up, lo = fe.table("upper"), fe.table("lower")
    up_d, lo_d = _body(up), _body(lo)
    _proportion(up, up_d, width)
    _proportion(lo, lo_d, width)
    up.finish()
    lo.finish()
    case.finish()
    return builders.two_blocks(width=width, contact_width=cw, upper=up_d, lower=lo_d,
                               **grid, **common)


def _proportion(sec: Section, body: dict, width: float) -> None:
    """:func:`~slipcycle.fe.geometry.check_proportion` of a body table's ``height``,
    keyed by the table's key."""
    try:
        check_proportion("height", body["height"], width)
    except InputError as exc:
        raise sec.error("height", exc.problem) from None


def _load_specs(fe: Section, dims: int) -> list[dict]:
    """The ``[[fe.load_case]]`` tables of a mesh-file model (``dims`` components)."""
    axes = "xyz"[:dims]
    t_text = "[" + ", ".join(f"t{a}" for a in axes) + "]"
    u_text = "[" + ", ".join(f"u{a}" for a in axes) + "]"
    loads = []
    for sec in fe.tables("load_case", []):
        name = sec.string("name")
        if name == "gap" or any(name == d["name"] for d in loads):
            raise sec.error("name", f"load case name {name!r} is reserved or used twice")
        spec = {"name": name, "boundary": sec.string("boundary")}
        has_t, has_u = sec.has("traction"), sec.has("displacement")
        if has_t == has_u:
            raise sec.error("traction", f"give exactly one of traction = {t_text} (Pa) "
                                        f"or displacement = {u_text} (m)")
        if has_t:
            spec["traction"] = tuple(sec.array("traction", shape=(dims,)))
        else:
            spec["displacement"] = tuple(sec.array("displacement", shape=(dims,)))
        sec.finish()
        loads.append(spec)
    return loads


def _refuse_void_loads(loads: list[dict], clamped: list[str]) -> None:
    """Refuse a load case that cannot put any force on the contact.

    A boundary held in every case (clamped, or moved by a displacement case) carries a
    traction on it into the support, and a displacement case on a clamped boundary is held
    at 0 (the first held boundary wins): the case would be identically zero, and so would a
    zero vector. Each is refused naming the key of the load case.
    """
    moved = {d["boundary"]: i for i, d in enumerate(loads) if "displacement" in d}
    for i, d in enumerate(loads):
        key = f"fe.load_case[{i}]"
        kind = "traction" if "traction" in d else "displacement"
        b = d["boundary"]
        if not np.any(np.asarray(d[kind], float)):
            raise CaseError(f"{key}.{kind}", "is zero in every component: the case puts no "
                            "force on the contact")
        if kind == "displacement" and b in clamped:
            raise CaseError(f"{key}.boundary", f"{b!r} is also clamped (fe.mesh.clamped), "
                            "so it is held at 0: the displacement case puts no force on the "
                            "contact")
        if kind == "traction" and (b in clamped or b in moved):
            by = ("clamped (fe.mesh.clamped)" if b in clamped else
                  f"held by the displacement case fe.load_case[{moved[b]}]")
            raise CaseError(f"{key}.traction", f"acts on {b!r}, which is {by}: the support "
                            "carries it and the case puts no force on the contact")


def _mesh_problem(fe: Section, common: dict, case: Case) -> Problem | MeshSolid:
    from slipcycle.fe.meshfile import check_planar, is_solid_mesh, read_meshio

    ms = fe.table("mesh")
    path = ms.path("file")
    data = read_meshio(path, ms.key("file"))
    solid = is_solid_mesh(data)
    if not solid:  # before the loads' shapes, which follow from the mesh's dimension
        check_planar(data, path, ms.key("file"))
    if solid and fe.has("thickness"):
        raise fe.error("thickness", "not used with a 3-D (tetrahedral) mesh file")
    dims = 3 if solid else 2
    contact = ms.string("contact")
    raw = ms._get("clamped", [])  # a list of strings: no typed accessor in Section
    if not isinstance(raw, list) or not all(isinstance(t, str) for t in raw):
        raise ms.error("clamped", "must be a list of boundary tag names")
    normal = ms.array("normal", [0.0, 0.0, 1.0][-dims:], shape=(dims,))
    if np.linalg.norm(normal) == 0:
        raise ms.error("normal", "must be a non-zero vector")
    scale = ms.float("scale", 1.0, gt=0)
    mat = _material(ms)
    loads = _load_specs(fe, dims)
    ms.finish()
    case.finish()
    _refuse_void_loads(loads, raw)  # after the unknown keys, which may be its cause
    tags = {"contact": contact}
    tags.update({t: t for t in raw})
    tags.update({d["boundary"]: d["boundary"] for d in loads})
    # a tag error names the key that lists the tag, not the tag itself (fe.mesh.nosuch)
    blame = {ms.key(t): ms.key("clamped") for t in raw if t != "contact"}
    blame.update({ms.key(d["boundary"]): f"fe.load_case[{i}].boundary"
                  for i, d in enumerate(loads)
                  if d["boundary"] not in raw and d["boundary"] != "contact"})
    try:
        return _read_mesh(ms, path, data, solid, tags, mat, normal, raw, loads, scale,
                          common)
    except CaseError as exc:
        if exc.key in blame:
            raise CaseError(blame[exc.key], exc.problem) from None
        raise


def _read_mesh(ms, path, data, solid, tags, mat, normal, raw, loads, scale, common):
    """The body of a mesh file (tags named: ``tags``), 3-D solid or 2-D plane."""
    from slipcycle.fe.meshfile import read_mesh_body

    if solid:
        from slipcycle.fe.meshfile3d import read_mesh_solid

        mesh, surfaces = read_mesh_solid(path, tags, key=ms.key("file"), scale=scale,
                                         data=data)
        return MeshSolid(mesh, surfaces, mat["E"], mat["nu"],
                         normal / np.linalg.norm(normal), tuple(raw), tuple(loads),
                         common["element"], common["formulation"],
                         {"geometry": "mesh", "file": str(path), "E": mat["E"],
                          "nu": mat["nu"], "element": common["element"],
                          "formulation": common["formulation"],
                          "normal": [float(v) for v in normal]})
    body = read_mesh_body(path, tags, mat["E"], mat["nu"], key=ms.key("file"), scale=scale,
                          data=data)
    return builders.from_mesh(body, contact="contact", normal=normal, clamped=tuple(raw),
                              loads=loads, **common)


def read_discrete_table(fe: Section) -> dict | None:
    """Validate the optional ``[fe.discrete]`` table.

    Keys: ``friction`` (scalar or per node), ``mean`` and ``amplitude`` (tables: load
    case name → multiplier), ``phase`` (table: load case name → rad), ``lam``,
    ``cycles``, ``steps_per_cycle``, ``stiffness_file`` (name written into the case).
    """
    sec = fe.table("discrete", None)
    if sec is None:
        return None
    out = {
        "friction": read_friction(sec, ge=0),
        "lam": sec.float("lam", 1.0),
        "cycles": sec.int("cycles", 40, ge=1),
        "steps_per_cycle": sec.int("steps_per_cycle", 400, ge=4),
    }
    for name in ("mean", "amplitude", "phase"):
        t = sec.table(name, {})
        out[name] = {k: t.float(k) for k in list(t.data)}
        t.finish()
    sec.finish()
    return out


#: refinements of ``elements`` that ``slipcycle run`` solves without ``[fe.convergence]``
DEFAULT_REFINEMENTS = (1, 2, 4)


def read_convergence_table(fe: Section, geometry: str) -> dict:
    """Validate the optional ``[fe.convergence]`` table (mesh study of ``slipcycle run``).

    Keys: ``refinements``, strictly increasing integers starting at 1 that multiply
    ``elements`` (default :data:`DEFAULT_REFINEMENTS`; ``[1]`` solves the case's mesh
    only; a mesh file cannot be refined, its default is ``[1]``), and ``rtol``, the
    largest estimated relative error of the finest dissipation called mesh-converged
    (default 0.05). Returns ``{"refinements": tuple of int, "rtol": float}``.
    """
    sec = fe.table("convergence", {})
    default = (1,) if geometry == "mesh" else DEFAULT_REFINEMENTS
    raw = sec.array("refinements", list(default), shape=(None,), ge=1)
    if raw.size == 0 or raw[0] != 1 or np.any(raw != np.round(raw)) \
            or np.any(np.diff(raw) <= 0):
        raise sec.error("refinements", "must be strictly increasing integers starting at "
                                       f"1 (e.g. [1, 2, 4]), got {raw.tolist()}")
    if geometry == "mesh" and raw.size > 1:
        raise sec.error("refinements", "a mesh file cannot be refined: give [1] and run "
                                       "finer meshes of your own as separate cases")
    rtol = sec.float("rtol", 0.05, gt=0, lt=1)
    sec.finish()
    return {"refinements": tuple(int(r) for r in raw), "rtol": rtol}


def discrete_case_text(table: dict, reduced: ReducedModel, stiffness_file: str,
                       key: str = "fe.discrete") -> str:
    """A discrete case file (docs/discrete.md) driven by combinations of the basic load cases.

    p^w(θ) = Σ_c mean_c p_c + λ Re[Σ_c amplitude_c e^{i phase_c} p_c e^{iθ}] per node
    (the gap case enters the mean with factor 1 unless set), and likewise q^w; written
    as p0, p1, p1_phase (and q0, q1, q1_phase): the text form of
    :func:`slipcycle.fe.loads.combined_loads`.
    """
    names = reduced.load_cases
    for part in ("mean", "amplitude", "phase"):
        for k in table[part]:
            if k not in names:
                raise CaseError(f"{key}.{part}.{k}", f"unknown load case; the model has "
                                f"{', '.join(names)}")
    p, q = combined_loads(reduced, table["mean"], table["amplitude"], table["phase"],
                          table["lam"])

    def arr(x):
        return "[" + ", ".join(f"{v:.12g}" for v in np.asarray(x, float)) + "]"

    friction = table["friction"]
    lines = [
        "# written by `slipcycle reduce`: discrete model of the reduced finite-element model",
        'model = "discrete"',
        "[discrete]",
        f'stiffness_file = "{stiffness_file}"',
        f"friction = {friction:.12g}",
        "[loading]",
        f"lam = {p.lam:.12g}",
        f"p0 = {arr(p.mean)}",
        f"q0 = {arr(q.mean)}",
        f"p1 = {arr(p.amplitudes[0])}",
        f"p1_phase = {arr(p.phases[0])}",
        f"q1 = {arr(q.amplitudes[0])}",
        f"q1_phase = {arr(q.phases[0])}",
        "[run]",
        f"cycles = {table['cycles']}",
        f"steps_per_cycle = {table['steps_per_cycle']}",
    ]
    return "\n".join(lines) + "\n"


def discrete3d_load_terms(table: dict, names, key: str = "fe.discrete"
                          ) -> list[tuple[str, float, float, float]]:
    """The time functions of the basic load cases ``names`` under ``[fe.discrete]``:
    (name, mean, amplitude, phase [rad]) of g(θ) = mean + λ amplitude cos(θ + phase) for
    every case that is not identically zero (the gap case with mean 1 unless set)."""
    names = list(names)
    for part in ("mean", "amplitude", "phase"):
        for k in table[part]:
            if k not in names:
                raise CaseError(f"{key}.{part}.{k}", f"unknown load case; the model has "
                                f"{', '.join(names)}")
    terms = []
    for name in names:
        mean = table["mean"].get(name, 1.0 if name == "gap" else 0.0)
        amplitude = table["amplitude"].get(name, 0.0)
        if mean != 0.0 or amplitude != 0.0:
            terms.append((name, float(mean), float(amplitude),
                          float(table["phase"].get(name, 0.0))))
    return terms


def discrete3d_case_text(table: dict, reduced, stiffness_file: str, area=None,
                         key: str = "fe.discrete") -> str:
    """A ``discrete3d`` case file (docs/discrete3d.md) of a reduced 3-D model.

    Each basic load case of the stiffness file enters as a ``[[loading.load_case]]`` with
    ``file_case`` and its time function (:func:`discrete3d_load_terms`), the same
    combination as :func:`discrete_case_text` writes out node by node in 2-D. ``area``
    (N,), m², the tributary areas of the nodes, is written when given.
    """
    terms = discrete3d_load_terms(table, reduced.loads, key)
    lines = [
        "# written by `slipcycle reduce`: discrete 3-D model of the reduced "
        "finite-element model",
        'model = "discrete3d"',
        "[discrete3d]",
        f'stiffness_file = "{stiffness_file}"',
        f"friction = {table['friction']:.17g}",
    ]
    if area is not None:
        lines.append("area = [" + ", ".join(f"{a:.17g}" for a in area) + "]")
    lines += ["[loading]", f"lam = {table['lam']:.17g}", "p0 = 0.0"]
    for name, mean, amplitude, phase in terms:
        lines += ["[[loading.load_case]]", f'file_case = "{name}"', f"mean = {mean:.17g}",
                  f"amplitude = {amplitude:.17g}", f"phase = {phase:.17g}"]
    lines += ["[run]", f"cycles = {table['cycles']}",
              f"steps_per_cycle = {table['steps_per_cycle']}"]
    return "\n".join(lines) + "\n"
