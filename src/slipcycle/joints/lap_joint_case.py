"""``model = "lap_joint"``: case file → bolted lap joint → every tightening protocol.

:func:`read_lap_joint_case` reads and checks every key before any computation (each bad
key is one :class:`~slipcycle.io.CaseError`); :func:`solve_model` reduces the joint
(:func:`slipcycle.fe.lap_joint.lap_joint_model`) on the case's mesh and on the coarser
meshes of ``[lap_joint.convergence]``, and runs the study
(:func:`slipcycle.joints.lap_joint_study.lap_joint_study`). Keys (docs/lap_joint.md):

- ``[lap_joint]``: the fields of :class:`slipcycle.fe.lap_joint.LapJoint` (geometry [m],
  material [Pa], bolts, mesh size at the interface [m]), ``friction`` and
  ``accept_ill_posed`` (run even if f reaches the critical friction coefficient);
- ``[lap_joint.loading]``: ``preload`` [N] per bolt, ``service_amplitude`` [N];
- ``[lap_joint]`` also takes the lower plate's ``E_lower``, ``nu_lower`` [Pa, 1]
  (dissimilar plates) and elastic bolts: ``bolt_modulus`` [Pa] (0: constant-force bolts),
  ``bolt_shank_diameter``, ``bolt_length`` [m];
- ``[lap_joint.protocols]``: ``names`` (standard patterns ``sequential``, ``star``,
  ``reversed``, ``simultaneous``, labels of ``orders`` or of ``steps``) and optional
  ``orders`` (per protocol a list of bolt numbers, or lists of numbers tightened together)
  or ``[lap_joint.protocols.steps]`` (per protocol a list of steps, each a table with one
  action: ``tighten``/``loosen``/``turn`` = bolt numbers with ``force`` [N, one or one per
  bolt] or ``by`` [m], ``service``/``overload`` = load [N], ``offset`` = grip offset [m],
  ``release`` = true; :mod:`slipcycle.joints.lap_joint_protocol`);
- ``[lap_joint.convergence]``: ``coarsening`` (factors > 1 of the mesh size of extra,
  coarser meshes; ``[]``: the case's mesh only; with ``refine`` = k, a factor 2^j ≤ 2^k
  removes j refinements, so the meshes are nested: :func:`coarser_joint`), ``rtol``;
- ``[run]``: ``cycles``, ``steps_per_cycle``, ``steady_tol``, ``min_cycles``,
  ``step_tolerance``, ``replay`` (freeze the step subdivision once the slip pattern
  repeats, :func:`~slipcycle.discrete3d.steady.simulate3d`), ``accelerate`` (the
  accelerated steady state with its certificate, reported per protocol; default false:
  plain cycling), ``difference_tol``;
- ``[output]``: ``fields`` (``["xdmf"]``, ``["xdmf", "pvd"]`` or ``[]``).
"""

from __future__ import annotations

import dataclasses
import typing
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from slipcycle.errors import InputError, ModelError
from slipcycle.io import Case, CaseError, RunOutputs, Section
from slipcycle.io.case import case_error_of, read_steady_tol
from slipcycle.io.loads import step_tolerance
from slipcycle.joints.lap_joint_protocol import (
    STANDARD_PROTOCOLS,
    JointContact,
    Protocol,
    protocol_name_problem,
    standard_protocol,
)
from slipcycle.joints.lap_joint_result import LapJointResult
from slipcycle.joints.lap_joint_showcase import WindowOptions, lap_joint_showcase
from slipcycle.joints.lap_joint_study import StudySettings, lap_joint_study
from slipcycle.loading.protocol import MAX_FORCE, read_step

__all__ = ["LapJointCase", "read_lap_joint_case", "joint_contact", "solve_model",
           "solve_case", "run_case", "FIELD_FORMATS"]

FIELD_FORMATS = ("xdmf", "pvd")
#: keys of ``[lap_joint]`` that are not fields of LapJoint
_STUDY_KEYS = ("friction", "accept_ill_posed", "melan_check")


@dataclass(frozen=True)
class LapJointCase:
    """A validated tightening-order study of a bolted lap joint.

    Attributes
    ----------
    joint : slipcycle.fe.lap_joint.LapJoint
        Geometry, material, bolts and the (finest) mesh size.
    protocols : tuple of Protocol
    settings : StudySettings
    coarsening : tuple of float
        Factors (> 1, decreasing) of the mesh size of the coarser meshes of the mesh
        convergence; empty: the joint's mesh only.
    fields : tuple of str
        Field formats written per protocol (``"xdmf"``, ``"pvd"``).
    melan_check : bool
        Also run every protocol with B = 0 (``[lap_joint] melan_check``).
    window : WindowOptions or None
        The shakedown window of the protocols on every mesh (``[lap_joint.window]``).
    """

    joint: typing.Any
    protocols: tuple
    settings: StudySettings
    coarsening: tuple = ()
    fields: tuple = ("xdmf",)
    melan_check: bool = False
    window: WindowOptions | None = None

    def __post_init__(self):
        factors = tuple(float(f) for f in self.coarsening)
        if any(f <= 1.0 for f in factors) or len(set(factors)) != len(factors):
            raise InputError("coarsening", f"factors must be distinct and > 1, got {factors}")
        object.__setattr__(self, "coarsening", tuple(sorted(factors, reverse=True)))
        bad = [f for f in self.fields if f not in FIELD_FORMATS]
        if bad:
            raise InputError("fields", f"unknown field format {bad[0]!r} (known: "
                             f"{', '.join(FIELD_FORMATS)})")
        for p in self.protocols:
            p.check(self.joint.bolt_count, self.settings.preload)


def _lap_joint():
    """slipcycle.fe.lap_joint (imported on first use: gmsh and scikit-fem load with it)."""
    from slipcycle.fe import lap_joint

    return lap_joint


_REQUIRED = object()


def _field_reader(sec: Section, f: dataclasses.Field):
    """Read the ``[lap_joint]`` key of LapJoint field ``f`` by the type of its default
    (or its annotation); the default where the key is absent."""
    name = f.name
    if f.default is not dataclasses.MISSING:
        default = f.default
    elif f.default_factory is not dataclasses.MISSING:
        default = f.default_factory()
    else:
        default = _REQUIRED
    if not sec.has(name):
        if default is _REQUIRED:
            raise sec.error(name, "required key is missing")
        sec.accept([name])      # a known key, offered for a typo of it
        return default
    kind = _kind(f, default)
    if kind is bool:
        return sec.bool(name)
    if kind is int:
        return sec.int(name)
    if kind is str:
        return sec.string(name)
    if kind in (tuple, list):   # bolt positions: pairs (x, y) [m]
        return tuple(tuple(row) for row in sec.array(name, shape=(None, 2)).tolist())
    return sec.float(name)


def _kind(f: dataclasses.Field, default) -> type:
    """The Python type of a LapJoint field: from its default, else its annotation."""
    if default is not None and default is not _REQUIRED:
        return type(default)
    ann = f.type if isinstance(f.type, str) else getattr(f.type, "__name__", "float")
    first = ann.split("|")[0].strip()
    return {"int": int, "bool": bool, "str": str, "tuple": tuple}.get(first, float)


def _read_joint(sec: Section):
    """LapJoint from ``[lap_joint]``; its own InputError under the key of the field."""
    mod = _lap_joint()
    kw = {f.name: _field_reader(sec, f) for f in dataclasses.fields(mod.LapJoint) if f.init}
    try:
        return mod.LapJoint(**kw)
    except InputError as exc:
        key = sec.key(exc.key) if exc.key in kw else sec.prefix
        raise CaseError(key, exc.problem) from None


def _order(ps: Section, key: str, raw, bolt_count: int) -> tuple:
    """One tightening order: bolt numbers, or lists of numbers tightened together."""
    if not isinstance(raw, list) or not raw:
        raise ps.error(key, f"each order must be a non-empty list of bolt numbers (or of "
                            f"lists of them), got {raw!r}")
    steps = []
    for item in raw:
        group = item if isinstance(item, list) else [item]
        if not group or any(isinstance(b, bool) or not isinstance(b, int) for b in group):
            raise ps.error(key, f"bolt numbers must be integers, got {item!r}")
        steps.append(tuple(group))
    return tuple(steps)


def _read_steps(ps: Section, names: list) -> dict:
    """``[lap_joint.protocols.steps]``: protocol name → tuple of Step."""
    steps_sec = ps.table("steps", {})
    out = {}
    for name in steps_sec.data:
        if name not in names:
            raise steps_sec.error(name, f"protocol {name!r} is not in names {names}")
        raw = steps_sec.raw(name)
        if not isinstance(raw, list) or not raw:
            raise steps_sec.error(name, "must be a non-empty list of steps, e.g. "
                                        "[{tighten = [0]}, {tighten = [1]}]")
        out[name] = tuple(read_step(ps.key(f"steps.{name}[{j}]"), item)
                          for j, item in enumerate(raw))
    steps_sec.finish()
    return out


def _read_protocols(ps: Section, joint, preload: float) -> tuple:
    bolt_count = joint.bolt_count
    names_raw = ps.raw("names", list(STANDARD_PROTOCOLS))
    if (not isinstance(names_raw, list) or not names_raw
            or not all(isinstance(n, str) and n for n in names_raw)):
        raise ps.error("names", f"must be a non-empty list of protocol names, got "
                                f"{names_raw!r}")
    problem = next(filter(None, map(protocol_name_problem, names_raw)), None)
    if problem is not None:
        raise ps.error("names", problem)
    if len(set(names_raw)) != len(names_raw):
        raise ps.error("names", f"protocol names must be distinct, got {names_raw}")
    orders = ps.raw("orders", None)
    steps = _read_steps(ps, names_raw)
    if orders is not None and steps:
        raise ps.error("steps", "give either orders or steps, not both")
    protocols = []
    if orders is None:
        for name in names_raw:
            if name in steps:
                protocols.append(Protocol(name, steps[name]))
                continue
            if name not in STANDARD_PROTOCOLS:
                raise ps.error("names", f"{name!r} is no standard protocol (known: "
                                        f"{', '.join(STANDARD_PROTOCOLS)}); give its order "
                                        "in orders or its steps in steps")
            protocols.append(standard_protocol(name, bolt_count))
    else:
        if not isinstance(orders, list) or len(orders) != len(names_raw):
            raise ps.error("orders", f"must be a list of {len(names_raw)} orders, one per "
                                     "name")
        for name, raw in zip(names_raw, orders, strict=True):
            protocols.append(Protocol(name, _order(ps, "orders", raw, bolt_count)))
    for p in protocols:
        try:
            p.check(bolt_count, preload)
            if not joint.bolt_modulus and any(s.action == "turn" for s in p.step_list):
                raise InputError("protocols", f"{p.name}: a turn needs elastic bolts "
                                              "(lap_joint.bolt_modulus > 0)")
        except InputError as exc:
            key = "steps" if p.name in steps else ("orders" if orders is not None
                                                  else "names")
            if getattr(exc, "step", None) and p.name in steps:
                j, field = exc.step          # the step and its key
                key = f"steps.{p.name}[{j}].{field}"
            raise ps.error(key, exc.problem) from None
    return tuple(protocols)


def _read_window(ws: Section | None, n_meshes: int) -> WindowOptions | None:
    """``[lap_joint.window]``: ``lam_points`` (5), ``lam_max`` [N] (1.1 × the largest
    λ2), ``lam_tol`` (0.05), ``meshes`` (every mesh; 0 the coarsest)."""
    if ws is None:
        return None
    lam_max = ws.float("lam_max", None, gt=0.0)
    meshes = ws.raw("meshes", None)
    if meshes is not None and (
            not isinstance(meshes, list) or not meshes or len(set(meshes)) != len(meshes)
            or any(isinstance(m, bool) or not isinstance(m, int) or not 0 <= m < n_meshes
                   for m in meshes)):
        raise ws.error("meshes", f"must be distinct mesh numbers in 0 … {n_meshes - 1} "
                                 f"(0 the coarsest), got {meshes!r}")
    opts = WindowOptions(lam_points=ws.int("lam_points", 5, ge=2), lam_max=lam_max,
                         lam_tol=ws.float("lam_tol", 0.05, gt=0.0, le=1.0),
                         meshes=None if meshes is None else tuple(sorted(meshes)))
    ws.finish()
    return opts


def read_lap_joint_case(case: Case) -> LapJointCase:
    """Read and validate every key of a ``lap_joint`` case; no computation beyond checks.

    Parameters
    ----------
    case : Case

    Returns
    -------
    LapJointCase

    Raises
    ------
    CaseError
        Naming the offending key and the problem.
    """
    sec = case.section("lap_joint")
    friction = sec.float("friction", gt=0.0)
    accept = sec.bool("accept_ill_posed", False)
    ld = sec.table("loading")
    ps = sec.table("protocols", {})
    cv = sec.table("convergence", {})
    melan = sec.bool("melan_check", False)
    ws = sec.table("window", None)
    geometry = Section({k: v for k, v in sec.data.items()
                        if k not in ("loading", "protocols", "convergence", "window",
                                     *_STUDY_KEYS)},
                       sec.prefix, sec.base_dir)
    # the keys read beside the geometry are offered for a typo found among it
    geometry.accept(("loading", "protocols", "convergence", "window", *_STUDY_KEYS))
    joint = _read_joint(geometry)
    geometry.finish()
    sec.accept(geometry.data)

    preload = ld.float("preload", gt=0.0, le=MAX_FORCE)
    service = ld.float("service_amplitude", ge=0.0, le=MAX_FORCE)
    ld.finish()
    protocols = _read_protocols(ps, joint, preload)
    ps.finish()
    coarsening = cv.array("coarsening", [2.0], shape=(None,), gt=1.0)
    if len(set(coarsening.tolist())) != coarsening.size:
        raise cv.error("coarsening", f"factors must be distinct, got {coarsening.tolist()}")
    rtol = cv.float("rtol", 0.05, gt=0.0, lt=1.0)
    cv.finish()
    window = _read_window(ws, coarsening.size + 1)

    rn = case.section("run", required=False)
    run = {"cycles": rn.int("cycles", 40, ge=1),
           "steps_per_cycle": rn.int("steps_per_cycle", 40, ge=4),
           "tol": read_steady_tol(rn, 1e-8),
           "min_cycles": rn.int("min_cycles", 1, ge=1),
           "step_tol": step_tolerance(rn, default=1e-4),
           "replay": rn.bool("replay", False),
           "accelerate": rn.bool("accelerate", False)}
    difference_tol = rn.float("difference_tol", 1e-3, gt=0.0, lt=1.0)
    out = case.section("output", required=False)
    fields = out.raw("fields", ["xdmf"])
    if isinstance(fields, str):
        fields = [fields]
    if not isinstance(fields, list) or any(f not in FIELD_FORMATS for f in fields):
        raise out.error("fields", f"must be a list of {', '.join(FIELD_FORMATS)} (or [] for "
                                  f"no field files), got {fields!r}")
    case.finish()
    settings = StudySettings(preload=preload, service_amplitude=service, friction=friction,
                             run=run, difference_tol=difference_tol, mesh_rtol=rtol,
                             accept_ill_posed=accept)
    return LapJointCase(joint, protocols, settings, tuple(coarsening.tolist()),
                        tuple(fields), melan_check=melan, window=window)


def coarser_joint(joint, factor: float):
    """The joint on a mesh ``factor`` times coarser: with ``refine`` = k > 0 and factor
    2^j (j ≤ k), the same mesh refined k − j times (nested meshes); otherwise a new mesh
    of size ``factor`` × ``mesh_size``."""
    j = round(np.log2(factor))
    if joint.refine > 0 and 1 <= j <= joint.refine and abs(factor - 2.0 ** j) < 1e-9:
        return dataclasses.replace(joint, refine=joint.refine - j)
    return dataclasses.replace(joint, mesh_size=joint.mesh_size * factor)


def joint_contact(joint) -> JointContact:
    """Reduce ``joint`` (:class:`slipcycle.fe.lap_joint.LapJoint`) to its contact nodes.

    Returns
    -------
    JointContact
        The reduced stiffness with the bolt and service load cases, node areas, bolt
        regions and the node spacing (the joint's interface mesh size) [m].
    """
    model = _lap_joint().lap_joint_model(joint)
    # the bolt centres [m] with the geometry: the figures outline holes and washers
    description = dict(model.description,
                       bolt_centres_m=np.asarray(model.bolt_centres, float).tolist())
    return JointContact(model.reduced, model.node_area, model.bolt_region,
                        float(model.spacing), description,
                        bolt_stiffness=float(model.bolt_stiffness),
                        bolt_shortening=dict(model.bolt_shortening))


def solve_model(lc: LapJointCase, *, progress=None, workers: int | None = None
                ) -> LapJointResult:
    """Reduce the joint on every mesh (coarse → fine) and run every protocol.

    Parameters
    ----------
    lc : LapJointCase
    progress : callable, optional
        ``progress(done, total)`` after each protocol run.
    workers : int, optional
        Processes running the protocol runs side by side
        (:func:`~slipcycle.joints.lap_joint_study.protocol_runs`; default 1, this
        process; ``slipcycle run`` uses every core). The results do not depend on it.

    Returns
    -------
    LapJointResult
    """
    if not isinstance(lc, LapJointCase):
        raise TypeError(f"expected a LapJointCase, not {type(lc).__name__}")
    joints = [coarser_joint(lc.joint, f) for f in lc.coarsening] + [lc.joint]
    contacts = [joint_contact(j) for j in joints]
    spacing = [c.spacing for c in contacts]
    if any(b >= a * (1 - 1e-6) for a, b in zip(spacing, spacing[1:], strict=False)):
        # the holes and washer circles set a smallest mesh: coarser requests can give the
        # same mesh (or, unstructured, a finer one)
        shown = ", ".join(f"{1e3 * h:.3g}" for h in spacing)
        raise CaseError("lap_joint.convergence.coarsening",
                        f"the meshes come out with node spacings {shown} mm (coarse → "
                        "fine), not strictly decreasing: the holes and washers fix the "
                        "coarsest mesh; use a smaller mesh_size or refine = 1 with "
                        "coarsening = [2.0]")
    if lc.melan_check or lc.window is not None:
        return lap_joint_showcase(contacts, lc.protocols, lc.settings,
                                  melan_check=lc.melan_check, window=lc.window,
                                  fields=lc.fields, progress=progress,
                                  workers=workers)
    return lap_joint_study(contacts, lc.protocols, lc.settings, fields=lc.fields,
                           progress=progress, workers=workers)


def solve_case(case: Case, *, progress=None, workers: int | None = None
               ) -> LapJointResult:
    """Validate a ``lap_joint`` case completely, then solve it (``workers`` as
    :func:`solve_model`)."""
    lc = read_lap_joint_case(case)
    with case_keys():
        return solve_model(lc, progress=progress, workers=workers)


@contextmanager
def case_keys():
    """A model error of the reduced joint (f ≥ f_crit) under its ``[lap_joint]`` keys."""
    try:
        yield
    except ModelError as exc:
        raise case_error_of(exc, {k: f"lap_joint.{k}" for k in _STUDY_KEYS}) from None


def run_case(case: Case) -> RunOutputs:
    """``solve_case(case).to_outputs()``."""
    return solve_case(case).to_outputs()

