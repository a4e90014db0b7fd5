"""``model = "discrete3d"``: case file → model → steady state → results.

Every key is read and checked (:func:`read_discrete3d_case`) before any computation;
:func:`solve_case` then solves and returns a :class:`DiscreteResult3D`. Keys are documented
in ``docs/discrete3d.md``; they mirror the 2-D ``discrete`` case with two tangential
components per node (node-major: ``q0 = [[q_t1, q_t2], ...]``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np
import xarray as xr

from slipcycle.coupled.case import SHARED_FLAGS, SHARED_UNITS, CoupledResult, read_start, solve
from slipcycle.coupled.settings import RunSettings
from slipcycle.coupled.sizes import check_case_sizes
from slipcycle.discrete3d.fields import write_fields
from slipcycle.discrete3d.loads import Load3D
from slipcycle.discrete3d.model import STATE_NAMES, FrictionalSystem3D, ModelError3D
from slipcycle.discrete3d.steady import (
    InadmissibleInitialState3D,
    initial_state_3d,
    simulate3d,
)
from slipcycle.errors import CaseError, InputError
from slipcycle.figure_task import figure_task
from slipcycle.io import Case, RunOutputs, Section
from slipcycle.io.case import case_error_of
from slipcycle.io.loads import (
    check_load_scale,
    check_run,
    check_some_contact,
    load_cases,
    periodic_load,
    run_settings,
    step_tolerance,
)
from slipcycle.io.matrices import read_case_stiffness
from slipcycle.loading.protocol import Step, read_step, step_states

__all__ = ["Discrete3DCase", "DiscreteResult3D", "read_discrete3d_case", "discrete3d_case",
           "solve_case", "solve_model", "run_case", "SUMMARY_UNITS", "SUMMARY_FLAGS",
           "RUN_DEFAULTS", "assembly_states"]

#: run settings of a case built in Python (the defaults of the ``[run]`` table)
RUN_DEFAULTS = RunSettings(step_tol=1e-7, replay=False)
FIELD_FORMATS = ("xdmf", "pvd")


@dataclass(frozen=True)
class Discrete3DCase:
    """A validated 3-D discrete case.

    Attributes
    ----------
    system : FrictionalSystem3D
    load : Load3D
    run : RunSettings
        ``cycles``, ``steps_per_cycle``, ``tol``, ``min_cycles``, ``step_tol``, ``replay``.
    initial_slip : (N, 2) array or None
    protocol : (S, 3N) array or None
    fields : tuple of str
        Field file formats to write (``"xdmf"``, ``"pvd"``; empty: none).
    """

    system: FrictionalSystem3D
    load: Load3D
    run: RunSettings
    initial_slip: np.ndarray | None = None
    protocol: np.ndarray | None = None
    fields: tuple = FIELD_FORMATS


def _matrices(case: Case, sec: Section) -> tuple[dict, dict]:
    """A, B, C and node geometry, inline or from ``stiffness_file``; (values, key of each)."""
    if sec.has("stiffness_file"):
        for k in ("A", "B", "C"):
            if sec.has(k):
                raise sec.error(k, "give either stiffness_file or A, B, C inline, not both")
        path = sec.path("stiffness_file")
        red = read_case_stiffness(sec, path, 2)
        key = sec.key("stiffness_file")
        vals = {"A": red.A, "B": red.B, "C": red.C, "coordinates": red.coordinates,
                "normals": red.normals, "tangents": red.tangents, "loads": red.loads}
        return vals, {k: f"{key} (matrix {k})" for k in ("A", "B", "C")}
    C = sec.array("C", shape=(None, None))
    n = C.shape[0]
    try:
        A = sec.array("A", shape=(2 * n, 2 * n))
        B = sec.array("B", shape=(n, 2 * n))
    except CaseError as exc:
        # C fixes the node count: a mismatch may as well be C's fault, so say where N is from
        raise CaseError(exc.key, f"{exc.problem} (N = {n} nodes, from the {n}×{n} C)") \
            from None
    return ({"A": A, "B": B, "C": C, "coordinates": None, "normals": None, "tangents": None,
             "loads": {}}, {k: sec.key(k) for k in ("A", "B", "C")})


def _read_steps(sec: Section) -> tuple | None:
    """``steps``: the assembly protocol as a list of steps (None if not given)."""
    raw = sec.raw("steps", None)
    if raw is None:
        return None
    if not isinstance(raw, list) or not raw:
        raise sec.error("steps", "must be a non-empty list of steps, e.g. "
                                 "[{tighten = [0]}, {service = 0.5}, {tighten = [1, 2]}]")
    return tuple(read_step(sec.key(f"steps[{j}]"), item, what="node")
                 for j, item in enumerate(raw))


def assembly_states(steps, load: Load3D) -> np.ndarray:
    """The load states (S, 3N) of an assembly protocol given as steps
    (:func:`~slipcycle.loading.protocol.step_states`: nodes play the bolts, the service
    level multiplies the tangential load at θ = 0).

    Parameters
    ----------
    steps : sequence of Step
    load : Load3D

    Returns
    -------
    (S, 3N) array
        [q^w, p^w] [N].
    """
    r0 = load(np.array([0.0]))[0]
    n = r0.size // 3
    return step_states(steps, r0[:2 * n].reshape(n, 2), r0[2 * n:])


def read_discrete3d_case(case: Case) -> Discrete3DCase:
    """Read and validate every key of a ``discrete3d`` case; no computation beyond checks.

    Parameters
    ----------
    case : Case

    Returns
    -------
    Discrete3DCase

    Raises
    ------
    CaseError
        Naming the offending key and the problem.
    """
    sec = case.section("discrete3d")
    mats, mkeys = _matrices(case, sec)
    n = np.asarray(mats["C"]).shape[0]
    friction = sec.array("friction", shape=(n,), scalar_ok=True)
    accept = sec.bool("accept_ill_posed", False)
    coords = sec.array("coordinates", mats["coordinates"], shape=(n, 3))
    area = sec.array("area", 1.0, shape=(n,), scalar_ok=True, gt=0.0)
    init, protocol = read_start(sec, n, 2)
    steps = _read_steps(sec)
    if steps is not None and (init is not None or protocol is not None):
        raise sec.error("steps", "give one of initial_slip, [[protocol]] load states or "
                                 "steps, not two")

    ld = case.section("loading")
    lam = ld.float("lam", 1.0, ge=0.0)

    def file_case(cs: Section):
        name = cs.string("file_case")
        if name not in mats["loads"]:
            known = ", ".join(mats["loads"]) or "none"
            raise cs.error("file_case", f"the stiffness_file has no load case {name!r} "
                                        f"(it has: {known})")
        return (np.asarray(mats["loads"][name]["p"], float),
                np.asarray(mats["loads"][name]["q"], float))

    load = Load3D(p=periodic_load(ld, "p", n, lam, 2), q=periodic_load(ld, "q", n, lam, 2),
                  cases=load_cases(ld, n, lam, 2, file_case))
    rn = case.section("run", required=False)
    run = RunSettings(**run_settings(rn, step_tol=("step_tolerance", step_tolerance),
                                     replay=("replay", lambda s, k: s.bool(k, False))))
    check_run(rn, run)
    out = case.section("output", required=False)
    fields = out.raw("fields", list(FIELD_FORMATS))
    if isinstance(fields, str):
        fields = [fields]
    if not isinstance(fields, list) or any(f not in FIELD_FORMATS for f in fields):
        raise out.error("fields", f"must be a list of {', '.join(FIELD_FORMATS)} (or [] for "
                                  f"no field files), got {fields!r}")
    case.finish()
    # a 3-D node's two tangential directions: the 2-D estimates for 2N nodes
    check_case_sizes(sec, rn, "C", n, run, dofs_per_node=2)

    try:
        system = FrictionalSystem3D(mats["A"], mats["B"], mats["C"], friction,
                                    coordinates=coords, normals=mats["normals"],
                                    tangents=mats["tangents"], area=area,
                                    accept_ill_posed=accept)
    except ModelError3D as exc:
        keys = {**{k: sec.key(k) for k in ("friction", "accept_ill_posed", "coordinates",
                                           "area")}, **mkeys}
        raise case_error_of(exc, keys) from None
    samples = load.cycle_samples(run.steps_per_cycle)[1]
    check_load_scale(ld, samples if protocol is None else np.vstack([samples, protocol]),
                     system.stiffness_scale())
    check_some_contact(ld, samples[:, -n:])
    if steps is not None:
        try:
            protocol = assembly_states(steps, load)
        except InputError as exc:
            raise CaseError(sec.key(exc.key), exc.problem) from None
    if init is not None:
        r0 = load(np.array([0.0]))[0]
        F = max(float(np.max(np.abs(load.cycle_samples(run.steps_per_cycle)[1]))), 1e-300)
        try:
            initial_state_3d(system, r0, init, 1e-10 * F)
        except InadmissibleInitialState3D as exc:
            raise sec.error("initial_slip", f"inadmissible at θ = 0: {exc}") from None
    return Discrete3DCase(system, load, run, init, protocol, tuple(fields))


def discrete3d_case(system: FrictionalSystem3D, load: Load3D, run: Mapping | None = None, *,
                    initial_slip=None, protocol=None, fields=FIELD_FORMATS) -> Discrete3DCase:
    """A :class:`Discrete3DCase` from Python objects.

    Parameters
    ----------
    system : FrictionalSystem3D
    load : Load3D
    run : mapping, optional
        ``cycles``, ``steps_per_cycle``, ``tol`` (or ``tolerance``), ``min_cycles``,
        ``step_tol``; :data:`RUN_DEFAULTS` for the others.
    initial_slip : (N, 2) array, optional
    protocol : (S, 3N) array or sequence of Step, optional
        Assembly load states, or the steps that give them (:func:`assembly_states`).
    fields : tuple of str
        Field formats written by ``to_outputs`` (``"xdmf"``, ``"pvd"``).

    Returns
    -------
    Discrete3DCase
    """
    if protocol is not None and not len(protocol):
        raise InputError("protocol", "needs at least one load state or step (None: plain "
                                     "loading)")
    if protocol is not None and isinstance(protocol[0], Step):
        protocol = assembly_states(protocol, load)
    for name, value in (("initial_slip", initial_slip), ("protocol", protocol)):
        if value is not None and not np.all(np.isfinite(np.asarray(value, float))):
            raise InputError(name, "must contain only finite numbers (found nan or inf)")
    return Discrete3DCase(system, load, RunSettings.of(run, RUN_DEFAULTS),
                          None if initial_slip is None else np.asarray(initial_slip, float),
                          None if protocol is None else np.asarray(protocol, float),
                          tuple(fields))


#: unit of every numeric summary entry
SUMMARY_UNITS = {
    **SHARED_UNITS, "dissipation_per_area": "J m-2", "steps_last_cycle": "1",
    "refinements_last_cycle": "1", "unresolved_steps": "1", "newton_iterations": "1",
}

#: every word of the categorical summary entries
SUMMARY_FLAGS = SHARED_FLAGS


@dataclass(frozen=True, kw_only=True, repr=False, eq=False)
class DiscreteResult3D(CoupledResult):
    """Result of a ``discrete3d`` run (:class:`~slipcycle.coupled.case.CoupledResult` over
    a :class:`Discrete3DCase` and the :class:`~slipcycle.discrete3d.steady.SteadyResult3D`
    of :func:`~slipcycle.discrete3d.steady.simulate3d`).

    Attributes
    ----------
    case : Discrete3DCase
        The validated case (system, load, run settings).
    solution : SteadyResult3D
        Histories of the cycles run and the classification of the last one.
    wall_time_s : float
        Seconds the simulation took.
    """

    model: ClassVar[str] = "discrete3d"
    SUMMARY_UNITS: ClassVar[dict] = SUMMARY_UNITS
    SUMMARY_FLAGS: ClassVar[dict] = SUMMARY_FLAGS

    def ratchet(self) -> np.ndarray:
        """The ratchet per cycle of each node, (N, 2) [m]."""
        return self.solution.ratchet_per_cycle.reshape(-1, 2)

    def own_summary(self) -> dict:
        """Dissipation per area and the step control's counts."""
        s, res = self.case.system, self.solution
        return {
            "dissipation_per_area": res.dissipation_per_node / s.area,
            "steps_last_cycle": int(res.steps_per_cycle_taken[-1]),
            "refinements_last_cycle": int(res.refinements_per_cycle[-1]),
            "unresolved_steps": int(res.unresolved_steps),
            "newton_iterations": int(res.solver_stats.get("newton_iterations", 0)),
        }

    def _build_dataset(self) -> xr.Dataset:
        """States, reactions and node states of every cycle, with the node coordinates
        and frames (every variable has ``units`` and ``long_name``)."""
        s, res = self.case.system, self.solution
        n = s.n_nodes
        c = res.x.shape[0]
        S = len(res.theta)
        loads = self.case.load(res.theta)
        loads[-1] = loads[0]
        v = res.x[:, :, :2 * n].reshape(c, S, n, 2)
        q = res.r[:, :, :2 * n].reshape(c, S, n, 2)
        stuck = np.zeros(n, np.int8)
        stuck[res.permanently_stuck_nodes] = 1
        d4 = ("cycle", "theta", "node", "component")
        d3 = ("cycle", "theta", "node")

        def var(dims, data, units, long_name, **extra):
            return (dims, data, {"units": units, "long_name": long_name, **extra})

        ds = xr.Dataset(
            {
                "slip": var(d4, v, "m", "tangential slip v (local t1, t2 components)"),
                "slip_global": var(d3 + ("xyz",), np.einsum("ctna,nad->ctnd", v,
                                                            s.tangents),
                                   "m", "tangential slip v (global x, y, z components)"),
                "separation": var(d3, res.x[:, :, 2 * n:], "m", "normal separation w"),
                "tangential_reaction": var(d4, q, "N", "tangential reaction q"),
                "normal_reaction": var(d3, res.r[:, :, 2 * n:], "N",
                                       "normal reaction p (compressive > 0)"),
                "friction_limit": var(d3, s.friction * res.r[:, :, 2 * n:], "N",
                                      "friction limit f p"),
                "node_state": var(d3, res.modes, "1",
                                  "node state at the end of the step reaching the sample",
                                  flag_values=np.arange(3, dtype=np.int8),
                                  flag_meanings=" ".join(STATE_NAMES)),
                "q_w": var(("theta", "node", "component"),
                           loads[:, :2 * n].reshape(S, n, 2), "N", "tangential load q^w"),
                "p_w": var(("theta", "node"), loads[:, 2 * n:], "N", "normal load p^w"),
                "dissipation_per_node": var(("node",), res.dissipation_per_node, "J",
                                            "dissipation D_j of the last cycle"),
                "dissipation_per_area": var(("node",), res.dissipation_per_node / s.area,
                                            "J m-2", "dissipation of the last cycle per "
                                            "unit area"),
                "dissipation_history": var(("cycle",), np.array(res.dissipation_history),
                                           "J", "total dissipation of each cycle"),
                "steps": var(("cycle",), np.array(res.steps_per_cycle_taken), "1",
                             "load steps taken in each cycle"),
                "slip_length": var(("node",), res.slip_length, "m",
                                   "slip length over the last cycle"),
                "permanently_stuck": var(("node",), stuck, "1",
                                         "node stuck over the whole last cycle",
                                         flag_values=np.array([0, 1], np.int8),
                                         flag_meanings="slips_or_separates "
                                                       "permanently_stuck"),
                "area": var(("node",), s.area, "m2", "node area"),
                "friction": var(("node",), s.friction, "1", "friction coefficient f"),
                "normal": var(("node", "xyz"), s.normals, "1", "unit normal n"),
                "tangent": var(("node", "component", "xyz"), s.tangents, "1",
                               "unit tangents t1, t2"),
            },
            coords={
                "cycle": ("cycle", np.arange(1, c + 1), {"units": "1",
                                                         "long_name": "cycle"}),
                "theta": ("theta", res.theta, {"units": "rad", "long_name": "cycle angle"}),
                "node": ("node", np.arange(n), {"units": "1", "long_name": "node (from 0)"}),
                "component": ("component", ["t1", "t2"], {"units": "1",
                                                          "long_name": "tangent direction"}),
                "xyz": ("xyz", ["x", "y", "z"], {"units": "1",
                                                 "long_name": "global axis"}),
                "x": ("node", s.coordinates[:, 0], {"units": "m",
                                                    "long_name": "node coordinate x"}),
                "y": ("node", s.coordinates[:, 1], {"units": "m",
                                                    "long_name": "node coordinate y"}),
                "z": ("node", s.coordinates[:, 2], {"units": "m",
                                                    "long_name": "node coordinate z"}),
            },
        )
        ds.attrs["slip_tolerance"] = float(res.slip_tolerance)
        ds.attrs["slip_tolerance_units"] = "m"
        ds.attrs["node_numbering"] = "from 0 (node j: rows 2j, 2j+1 of A, row j of B and C)"
        return ds

    def figures(self, dataset: xr.Dataset | None = None) -> dict:
        """``interface_states``, ``dissipation_map``, ``slip_directions``,
        ``dissipation_history``."""
        ds = self.to_dataset() if dataset is None else dataset
        if ds.sizes["cycle"] == 0:
            return {}
        # plot functions named by string (the model does not import slipcycle.plot):
        # picklable, so drawn by the CLI's workers; matplotlib only when drawn
        plot = "slipcycle.plot.interface3d:"
        return {
            "interface_states": figure_task(plot + "state_map", ds),
            "dissipation_map": figure_task(plot + "dissipation_map", ds),
            "slip_directions": figure_task(plot + "slip_directions", ds),
            "dissipation_history": figure_task(plot + "dissipation_history", ds),
        }

    def write_fields(self, directory: str | Path, formats=None) -> list[Path]:
        """Write the last cycle's contact fields for ParaView (XDMF and/or VTU series).

        Parameters
        ----------
        directory : str or Path
        formats : tuple of str, optional
            ``"xdmf"``, ``"pvd"`` (default: the case's ``output.fields``).

        Returns
        -------
        list of Path
        """
        res = self.solution
        if res.x.shape[0] == 0:
            return []
        return write_fields(Path(directory), self.case.system, res.theta, res.x[-1],
                            res.r[-1], res.modes[-1], res.dissipation_per_node,
                            tuple(self.case.fields if formats is None else formats))

    def to_outputs(self) -> RunOutputs:
        """Summary, Dataset, figures, flags, and the field files under ``fields/``."""
        out = super().to_outputs()
        if self.case.fields and self.solution.x.shape[0]:
            first = "interface.xdmf" if "xdmf" in self.case.fields else "interface.pvd"
            out.extra_files[f"fields/{first}"] = lambda path: self.write_fields(path.parent)
        return out


def solve_model(dc, load: Load3D | None = None, run: Mapping | None = None, **kwargs
                ) -> DiscreteResult3D:
    """Solve a 3-D discrete system to its steady state.

    Parameters
    ----------
    dc : Discrete3DCase or FrictionalSystem3D
        A validated case, or a system (then ``load`` is required).
    load : Load3D, optional
    run : mapping, optional
        Run settings for a system (:func:`discrete3d_case`).
    **kwargs
        ``initial_slip``, ``protocol``, ``fields`` of :func:`discrete3d_case`.

    Returns
    -------
    DiscreteResult3D
    """
    return solve(DiscreteResult3D, Discrete3DCase, FrictionalSystem3D, discrete3d_case,
                 simulate3d, dc, load, run, **kwargs)


def solve_case(case: Case) -> DiscreteResult3D:
    """Validate a ``discrete3d`` case completely, then solve it."""
    return solve_model(read_discrete3d_case(case))


def run_case(case: Case) -> RunOutputs:
    """``solve_case(case).to_outputs()``."""
    return solve_case(case).to_outputs()
