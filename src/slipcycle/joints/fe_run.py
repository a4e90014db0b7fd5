"""``model = "fe"`` run end to end: reduce on a sequence of meshes, solve, judge convergence.

A finite-element case (``docs/fe.md``) is reduced to its contact nodes
(:func:`slipcycle.fe.reduction.reduce_problem`) on its own mesh and on meshes with
``elements`` multiplied by each factor of ``[fe.convergence] refinements`` (default
1, 2, 4); each reduced model is driven by the ``[fe.discrete]`` combination of the basic
load cases (:func:`slipcycle.fe.loads.combined_loads`) and solved to its steady cycle by
the discrete solver (:func:`slipcycle.discrete.case.solve_model`). The dissipation per
cycle of the meshes gives the observed order and the Richardson extrapolation
(:func:`slipcycle.joints.convergence.mesh_convergence`); the result is that of the finest
mesh, with the mesh study beside it (:class:`FEResult`). A mesh file of tetrahedra
(:mod:`slipcycle.fe.meshfile3d`) is one mesh, reduced and solved by the 3-D discrete model
(:func:`slipcycle.discrete3d.case.solve_model`) under the same time functions as the
``discrete3d`` case ``slipcycle reduce --case`` writes
(:func:`slipcycle.fe.model.discrete3d_load_terms`).

Whether the dissipation converges depends on the contact: an incomplete contact (a
cylinder on a block) has bounded tractions and a slip zone of fixed width, resolved by
ever more nodes; a sharp-edged complete contact (a block on a flat) has singular edge
tractions, and its dissipation shrinks with the node spacing (docs/fe.md, "Is the
dissipation mesh-converged?").
"""

from __future__ import annotations

import copy
import logging
import time
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from slipcycle.coupled.sizes import check_memory, run_bytes, system_bytes
from slipcycle.discrete.case import (
    SUMMARY_UNITS,
    DiscreteResult,
    discrete_case,
    solve_model,
)
from slipcycle.discrete.loads import DiscreteLoad
from slipcycle.discrete.model import FrictionalSystem
from slipcycle.discrete3d.case import discrete3d_case
from slipcycle.discrete3d.case import solve_model as solve_model_3d
from slipcycle.discrete3d.loads import Load3D
from slipcycle.discrete3d.model import FrictionalSystem3D, ModelError3D
from slipcycle.errors import InputError
from slipcycle.fe.loads import combined_loads
from slipcycle.fe.meshfile3d import (
    MeshSolid,
    check_reduction_memory,
    reduce_mesh_case,
)
from slipcycle.fe.model import (
    build_problem,
    discrete3d_load_terms,
    read_convergence_table,
    read_discrete_table,
)
from slipcycle.fe.reduction import Problem, reduce_problem
from slipcycle.figure_task import figure_task
from slipcycle.io import Case, CaseError, RunOutputs
from slipcycle.io.matrices import StiffnessError, check_stiffness
from slipcycle.joints.convergence import MeshConvergence, mesh_convergence
from slipcycle.loading import HarmonicLoad
from slipcycle.loading.nodal import LoadCase
from slipcycle.result import RunResult

__all__ = ["FECase", "MeshRun", "FEResult", "read_fe_case", "solve_fe", "solve_case",
           "run_case", "FE_SUMMARY_UNITS"]

log = logging.getLogger("slipcycle")

#: largest ``elements`` of the file format (``fe.model``), also for the refined meshes
_MAX_ELEMENTS = 20000

#: units of the summary entries an FE run adds to the discrete ones
FE_SUMMARY_UNITS = {
    "elements": "1", "n_dofs": "1", "node_spacing": "m", "mesh_elements": "1",
    "mesh_n_nodes": "1", "mesh_cycles_run": "1", "dissipation_rtol": "1",
}


@dataclass(frozen=True)
class FECase:
    """A validated finite-element case of ``slipcycle run``.

    Attributes
    ----------
    case : Case
        The case as read (its text is the provenance of every mesh).
    problem : Problem
        The assembled model of the case's own mesh (refinement 1).
    geometry : str
    elements : int or None
        ``elements`` of the case (None for a mesh file).
    refinements : tuple of int
        Factors of ``elements`` solved, coarse → fine (starts at 1).
    rtol : float
        Relative error of the finest dissipation called mesh-converged.
    discrete : dict
        The ``[fe.discrete]`` table (friction, loads, cycles, steps per cycle).
    """

    case: Case
    problem: Problem
    geometry: str
    elements: int | None
    refinements: tuple[int, ...]
    rtol: float
    discrete: dict


@dataclass(frozen=True)
class MeshRun:
    """The numbers of one mesh of the study.

    Attributes
    ----------
    elements : int or None
        Elements across the contact zone (None for a mesh file).
    n_nodes : int
        Contact nodes N.
    n_dofs : int
        Degrees of freedom of the finite-element model.
    spacing : float
        Mean node spacing h over the contact zone [m].
    dissipation : float or None
        Dissipation per cycle of the steady cycle [J] (0 at shakedown).
    steady_state : str
        The discrete solver's word for the cycle reached.
    cycles_run : int
    converged : bool
        Whether the steady state was reached within the tolerance.
    reduce_seconds, solve_seconds : float
        Wall time of the reduction and of the discrete solution [s].
    """

    elements: int | None
    n_nodes: int
    n_dofs: int
    spacing: float
    dissipation: float | None
    steady_state: str
    cycles_run: int
    converged: bool
    reduce_seconds: float
    solve_seconds: float


def _refined(case: Case, elements: int) -> Case:
    """The case with ``[fe] elements`` set to ``elements`` (same text and path)."""
    data = copy.deepcopy(case.data)
    data["fe"]["elements"] = elements
    return Case(model=case.model, data=data, text=case.text, path=case.path)


def read_fe_case(case: Case) -> FECase:
    """Read and validate an ``fe`` case for ``slipcycle run``; assembles the first mesh.

    Parameters
    ----------
    case : Case
        ``model = "fe"`` with ``[fe]``, ``[fe.discrete]`` and optionally
        ``[fe.convergence]``.

    Returns
    -------
    FECase

    Raises
    ------
    CaseError
        A missing ``[fe.discrete]``, a load case it names that the model lacks, refined
        meshes beyond the file format's ``elements`` or the memory budget, or any
        error of the model file (:func:`slipcycle.fe.model.build_problem`).
    """
    fe = case.section("fe")
    if not fe.has("discrete"):
        raise fe.error("discrete", "required table is missing: `slipcycle run` solves the "
                                   "reduced model under its [fe.discrete] loads (`slipcycle "
                                   "reduce` writes the reduced model without them)")
    problem = build_problem(case)  # every key of [fe], [fe.discrete], [fe.convergence]
    geometry = fe.string("geometry")
    conv = read_convergence_table(fe, geometry)
    table = read_discrete_table(fe)
    if isinstance(problem, MeshSolid):
        discrete3d_load_terms(table, [d["name"] for d in problem.loads] + ["gap"])
        check_reduction_memory(problem, lambda n: run_bytes(
            2 * n, table["steps_per_cycle"], table["cycles"], True))
        return FECase(case, problem, geometry, None, conv["refinements"], conv["rtol"],
                      table)
    names = [c.name for c in problem.cases]
    for part in ("mean", "amplitude", "phase"):
        for k in table[part]:
            if k not in names:
                raise CaseError(f"fe.discrete.{part}.{k}", "unknown load case; the model "
                                f"has {', '.join(names)}")
    elements = None if geometry == "mesh" else fe.int("elements", 20)
    # contact nodes grow like the elements across the contact zone: (N₁ − 1) r + 1
    finest_r = conv["refinements"][-1]
    n_nodes = (len(problem.contact.nodes1) - 1) * finest_r + 1
    key = "fe.convergence.refinements" if finest_r > 1 else "fe.elements"
    if elements is not None and elements * finest_r > _MAX_ELEMENTS:
        raise CaseError(key, f"the finest mesh would have {elements * finest_r} elements "
                             f"(elements × {finest_r}); at most {_MAX_ELEMENTS}")
    check_memory(key, system_bytes(n_nodes), f"{n_nodes} contact nodes on the finest mesh")
    # the run's histories: blamed on the longer of its two counts, which the user set
    steps, cycles = table["steps_per_cycle"], table["cycles"]
    check_memory("fe.discrete.cycles" if cycles >= steps else "fe.discrete.steps_per_cycle",
                 system_bytes(n_nodes) + run_bytes(n_nodes, steps, cycles, True),
                 f"{steps:g} steps per cycle × up to {cycles:g} cycles ({n_nodes} contact "
                 "nodes on the finest mesh, every cycle recorded)")
    return FECase(case, problem, geometry, elements, conv["refinements"], conv["rtol"],
                  table)


def _spacing(coords: np.ndarray) -> float:
    """Mean node spacing along the contact [m] (the generated meshes are uniform there)."""
    x = np.sort(np.asarray(coords, float)[:, 0])
    return float((x[-1] - x[0]) / max(len(x) - 1, 1))


def _solve_solid(fc: FECase, solid: MeshSolid, progress) -> tuple[Any, MeshRun]:
    """Reduce a tetrahedral body from a mesh file and solve it as a 3-D discrete system
    under the ``[fe.discrete]`` loads: the case ``slipcycle reduce --case`` writes."""
    t0 = time.perf_counter()
    red, area = reduce_mesh_case(solid)
    t1 = time.perf_counter()
    tab, n = fc.discrete, red.n_nodes
    lam = tab["lam"]
    cases = tuple(LoadCase(red.loads[name]["p"], red.loads[name]["q"],
                           HarmonicLoad([mean], [[amplitude]], [[phase]], lam))
                  for name, mean, amplitude, phase in discrete3d_load_terms(tab, red.loads))
    zero = HarmonicLoad(np.zeros(n), np.zeros((1, n)), np.zeros((1, n)), lam)
    zero_q = HarmonicLoad(np.zeros(2 * n), np.zeros((1, 2 * n)), np.zeros((1, 2 * n)), lam)
    try:
        system = FrictionalSystem3D(red.A, red.B, red.C, np.full(n, tab["friction"]),
                                    coordinates=red.coordinates, normals=red.normals,
                                    tangents=red.tangents, area=area)
    except ModelError3D as exc:
        raise _system_error(exc, "") from None
    dc = discrete3d_case(system, Load3D(p=zero, q=zero_q, cases=cases),
                         {"cycles": tab["cycles"], "steps_per_cycle": tab["steps_per_cycle"]},
                         fields=())
    res = solve_model_3d(dc)
    t2 = time.perf_counter()
    d = res.dissipation_per_cycle
    if res.steady_state_detail == "shakedown":
        d = 0.0            # as for 2-D meshes: nothing slips, the solver's D is round-off
    run = MeshRun(elements=None, n_nodes=n, n_dofs=solid.n_dofs,
                  spacing=float(np.sqrt(np.mean(area))),
                  dissipation=None if d is None else float(d),
                  steady_state=res.steady_state_detail, cycles_run=res.cycles_run,
                  converged=res.converged, reduce_seconds=t1 - t0, solve_seconds=t2 - t1)
    return res, run


def _system_error(exc: InputError, where: str) -> CaseError:
    """The case-file error of a reduced system the discrete model refuses: its friction
    is ``fe.discrete.friction``; its matrices A, B, C come from the mesh (``fe``): a
    block a thousand times as tall as wide reduced to a numerically singular A, which
    was reported as a friction coefficient that "must be positive definite"."""
    if exc.key in ("A", "B", "C"):
        return CaseError("fe", f"the reduced stiffness {exc.key} {exc.problem}{where}: the "
                         "mesh is numerically singular; check the geometry's proportions "
                         "and units")
    return CaseError("fe.discrete.friction", f"{exc.problem}{where}")


def _solve_mesh(fc: FECase, problem: Problem, elements: int | None, progress
                ) -> tuple[DiscreteResult, MeshRun]:
    """Reduce ``problem`` and solve it under the ``[fe.discrete]`` loads."""
    if isinstance(problem, MeshSolid):
        return _solve_solid(fc, problem, progress)
    t0 = time.perf_counter()
    try:
        reduced = reduce_problem(problem)
        check_stiffness({"A": reduced.A, "B": reduced.B, "C": reduced.C})
    except StiffnessError as exc:
        raise CaseError("fe", f"reduced stiffness {exc.problem}") from None
    except ValueError as exc:
        raise CaseError("fe", str(exc)) from None
    t1 = time.perf_counter()
    tab = fc.discrete
    p, q = combined_loads(reduced, tab["mean"], tab["amplitude"], tab["phase"], tab["lam"])
    try:
        system = FrictionalSystem(reduced.A, reduced.B, reduced.C, tab["friction"])
    except InputError as exc:
        where = f" (mesh of {elements} elements)" if elements is not None else ""
        raise _system_error(exc, where) from None
    dc = discrete_case(system, DiscreteLoad(p, q), {"cycles": tab["cycles"],
                                                    "steps_per_cycle": tab["steps_per_cycle"]})
    res = solve_model(dc, progress=progress)
    t2 = time.perf_counter()
    d = res.dissipation_per_cycle
    # shakedown: nothing slips, so the dissipation is zero (the solver's is round-off)
    dissipation = 0.0 if res.steady_state_detail == "shakedown" else (
        None if d is None else float(d))
    run = MeshRun(elements=elements, n_nodes=reduced.n, n_dofs=int(problem.ndofs),
                  spacing=_spacing(reduced.coords), dissipation=dissipation,
                  steady_state=res.steady_state_detail, cycles_run=res.cycles_run,
                  converged=res.converged, reduce_seconds=t1 - t0, solve_seconds=t2 - t1)
    return res, run


def solve_fe(fc: FECase, progress=None) -> FEResult:
    """Solve a validated FE case on every mesh of its study.

    Parameters
    ----------
    fc : FECase
    progress : callable, optional
        ``progress(cycles_done, cycles_total)`` over all meshes.

    Returns
    -------
    FEResult
    """
    t0 = time.perf_counter()
    total = fc.discrete["cycles"] * len(fc.refinements)
    runs, finest = [], None
    for i, r in enumerate(fc.refinements):
        elements = None if fc.elements is None else fc.elements * r
        problem = fc.problem if r == 1 else build_problem(_refined(fc.case, elements))
        offset = i * fc.discrete["cycles"]
        step = None if progress is None else (
            lambda done, _n, o=offset: progress(o + done, total))
        finest, run = _solve_mesh(fc, problem, elements, step)
        runs.append(run)
    return FEResult.build(fc, finest, tuple(runs), time.perf_counter() - t0)


def _study(fc: FECase, runs: tuple[MeshRun, ...]) -> tuple[MeshConvergence | None, str]:
    """The mesh convergence of the dissipation and the sentence that reports it."""
    if len(runs) < 2:
        how = ("run finer meshes of your own as separate cases to assess it"
               if fc.elements is None else
               "set [fe.convergence] refinements = [1, 2, 4] to assess it")
        return None, f"mesh convergence of the dissipation not assessed (one mesh; {how})"
    values = [r.dissipation for r in runs]
    if any(v is None for v in values):
        return None, ("mesh convergence of the dissipation not assessed: no steady cycle "
                      "on some mesh")
    mc = mesh_convergence([r.spacing for r in runs], values, rtol=fc.rtol, unit="J")
    text = f"dissipation {mc.message}"
    unsteady = [r.elements for r in runs if not r.converged]
    if unsteady:
        text += f" (no steady state within the cycles allowed on meshes {unsteady})"
    return mc, text


@dataclass(frozen=True, kw_only=True, repr=False, eq=False)
class FEResult(RunResult):
    """Result of an FE run: the finest mesh's discrete result and the mesh study.

    The shared fields (``steady_state``, ``dissipation_per_cycle``, ``cycles_run``,
    ``residual``, ``converged``) are those of the finest mesh; ``message`` adds whether
    its dissipation is mesh-converged (a warning when it is not).

    Attributes
    ----------
    fe_case : FECase
    finest : DiscreteResult
        The discrete result of the finest mesh.
    meshes : tuple of MeshRun
        Every mesh, coarse → fine.
    mesh_convergence : MeshConvergence or None
        The study of the dissipation (None with one mesh or without a steady cycle).
    wall_time_s : float
        Seconds for every reduction and solution (the shared field).
    """

    model: ClassVar[str] = "fe"

    fe_case: FECase
    finest: DiscreteResult
    meshes: tuple[MeshRun, ...]
    mesh_convergence: MeshConvergence | None

    @classmethod
    def build(cls, fc: FECase, finest: DiscreteResult, meshes: tuple[MeshRun, ...],
              wall: float) -> FEResult:
        """Assemble the result and log a warning when the dissipation is not converged."""
        mc, text = _study(fc, meshes)
        ok = mc is not None and mc.converged
        if not ok:
            log.warning("%s", text)
        return cls(steady_state=finest.steady_state,
                   steady_state_detail=finest.steady_state_detail,
                   dissipation_per_cycle=meshes[-1].dissipation,
                   cycles_run=finest.cycles_run, residual=finest.residual,
                   converged=finest.converged,
                   message=f"{finest.message}; " + (text if ok else f"WARNING: {text}"),
                   fe_case=fc, finest=finest, meshes=meshes, mesh_convergence=mc,
                   wall_time_s=wall)

    @property
    def flags(self) -> dict[str, tuple[str, ...]]:
        """Every word of the categorical summary entries (those of the discrete model
        that solved the finest mesh)."""
        return dict(self.finest.flags)

    def summary(self) -> dict:
        """The finest mesh's discrete summary, with the mesh study and ``units``.

        Added entries: ``geometry``, ``elements``, ``n_dofs``, ``node_spacing`` [m] of
        the finest mesh; ``mesh_elements``, ``mesh_n_nodes``, ``mesh_cycles_run`` per
        mesh; ``dissipation_mesh_spacing`` [m], ``dissipation_mesh_values`` [J],
        ``dissipation_observed_order`` [1], ``dissipation_extrapolated`` [J],
        ``dissipation_relative_error`` [1], ``dissipation_mesh_converged`` (bool, None
        when not assessed), ``dissipation_mesh_order_assumed``,
        ``dissipation_mesh_message``, ``dissipation_rtol`` [1] and ``message``.
        """
        out = self.finest.summary()
        units = dict(out.pop("units"))
        last = self.meshes[-1]
        out.update(model="fe", geometry=self.fe_case.geometry, elements=last.elements,
                   n_dofs=last.n_dofs, node_spacing=last.spacing,
                   dissipation_per_cycle=last.dissipation,
                   wall_time_s=self.wall_time_s)
        out.update(mesh_elements=[m.elements for m in self.meshes],
                   mesh_n_nodes=[m.n_nodes for m in self.meshes],
                   mesh_cycles_run=[m.cycles_run for m in self.meshes])
        mc = self.mesh_convergence
        if mc is not None:
            study = mc.summary("dissipation_")
            units.update(study.pop("units"))
        else:
            study = {"dissipation_mesh_spacing": [m.spacing for m in self.meshes],
                     "dissipation_mesh_values": [m.dissipation for m in self.meshes],
                     "dissipation_observed_order": None, "dissipation_extrapolated": None,
                     "dissipation_relative_error": None, "dissipation_mesh_converged": None,
                     "dissipation_mesh_order_assumed": False,
                     "dissipation_mesh_message": _study(self.fe_case, self.meshes)[1]}
            units.update({"dissipation_mesh_spacing": "m", "dissipation_mesh_values": "J",
                          "dissipation_observed_order": "1",
                          "dissipation_extrapolated": "J",
                          "dissipation_relative_error": "1"})
        out.update(study)
        out["dissipation_rtol"] = self.fe_case.rtol
        out["message"] = self.message
        units.update(FE_SUMMARY_UNITS)
        units.update({k: v for k, v in SUMMARY_UNITS.items() if k in out})
        out["units"] = units
        return out

    def _build_dataset(self):
        """The finest mesh's histories and, along ``mesh``, the study: elements, nodes,
        spacing [m], dissipation [J], cycles run, steady flag; the extrapolation and
        the observed order as scalars."""
        ds = self.finest.to_dataset()
        mesh = np.arange(len(self.meshes))
        diss = np.array([np.nan if m.dissipation is None else m.dissipation
                         for m in self.meshes])
        ds = ds.assign_coords(mesh=("mesh", mesh, {"units": "1", "long_name":
                                                   "mesh of the study, coarse to fine"}))
        el = [-1 if m.elements is None else m.elements for m in self.meshes]
        ds["mesh_elements"] = ("mesh", np.array(el, np.int64), {
            "units": "1", "long_name": "elements across the contact zone (-1: mesh file)"})
        ds["mesh_n_nodes"] = ("mesh", np.array([m.n_nodes for m in self.meshes], np.int64),
                              {"units": "1", "long_name": "contact nodes"})
        ds["mesh_spacing"] = ("mesh", np.array([m.spacing for m in self.meshes]), {
            "units": "m", "long_name": "mean node spacing h over the contact"})
        ds["mesh_dissipation"] = ("mesh", diss, {
            "units": "J", "long_name": "dissipation per cycle of the steady cycle"})
        ds["mesh_cycles_run"] = ("mesh", np.array([m.cycles_run for m in self.meshes],
                                                  np.int64), {"units": "1",
                                                              "long_name": "cycles run"})
        mc = self.mesh_convergence
        ext = np.nan if mc is None or mc.extrapolated is None else mc.extrapolated
        order = np.nan if mc is None or mc.observed_order is None else mc.observed_order
        ds["dissipation_extrapolated"] = ((), float(ext), {
            "units": "J", "long_name": "Richardson extrapolation of the dissipation, h -> 0"})
        ds["dissipation_observed_order"] = ((), float(order), {
            "units": "1", "long_name": "observed order of the dissipation in h"})
        ds.attrs["dissipation_mesh_converged"] = str(mc is not None and mc.converged).lower()
        ds.attrs["dissipation_mesh_message"] = self.message
        return ds

    def figures(self, dataset=None) -> dict[str, Any]:
        """The finest mesh's figures and ``mesh_convergence`` (dissipation vs spacing)."""
        ds = self.to_dataset() if dataset is None else dataset
        figs = dict(self.finest.figures(ds))
        mc = self.mesh_convergence
        figs["mesh_convergence"] = figure_task(
            "slipcycle.plot.fe:mesh_convergence", [m.spacing for m in self.meshes],
            [m.dissipation for m in self.meshes],
            observed_order=None if mc is None else mc.observed_order,
            extrapolated=None if mc is None else mc.extrapolated,
            converged=None if mc is None else mc.converged,
            title=f"{self.fe_case.geometry}: dissipation per cycle")
        return figs


def solve_case(case: Case, progress=None) -> FEResult:
    """Validate an ``fe`` case completely (CaseError first), then solve every mesh.

    Parameters
    ----------
    case : Case
    progress : callable, optional
        ``progress(cycles_done, cycles_total)``.

    Returns
    -------
    FEResult
    """
    return solve_fe(read_fe_case(case), progress=progress)


def run_case(case: Case) -> RunOutputs:
    """``solve_case(case).to_outputs()``: summary, Dataset and figures."""
    return solve_case(case).to_outputs()

