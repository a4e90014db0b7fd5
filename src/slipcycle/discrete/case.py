"""``model = "discrete"``: case file → model → steady state → results.

Everything in the case is read and checked (:func:`read_discrete_case`) before any
computation; :func:`run_case` then solves and returns the summary, the dataset and the
figures. Keys are documented in ``docs/discrete.md``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import xarray as xr

from slipcycle.coupled.case import SHARED_FLAGS, SHARED_UNITS, CoupledResult, read_start, solve
from slipcycle.coupled.settings import RunSettings
from slipcycle.discrete.loads import DiscreteLoad
from slipcycle.discrete.model import STATE_NAMES, FrictionalSystem, ModelError
from slipcycle.discrete.shakedown import extreme_constraints, safe_vertices
from slipcycle.discrete.steady import (
    InadmissibleInitialState,
    initial_state,
    simulate,
)
from slipcycle.discrete.wellposed import critical_friction
from slipcycle.figure_task import figure_task
from slipcycle.io import Case, CaseError, RunOutputs, Section
from slipcycle.io.case import case_error_of
from slipcycle.io.loads import (
    check_load_scale,
    check_run,
    check_some_contact,
    load_cases,
    periodic_load,
    run_settings,
)

__all__ = ["run_case", "read_discrete_case", "DiscreteCase", "DiscreteResult", "discrete_case",
           "solve_case", "solve_model", "SUMMARY_UNITS", "SUMMARY_FLAGS"]


class DiscreteCase:
    """A fully validated discrete case (model, load, run settings)."""

    def __init__(self, system, load, f_crit, run, initial_slip, protocol):
        self.system = system
        self.load = load
        self.f_crit = f_crit
        self.run = run
        self.initial_slip = initial_slip
        self.protocol = protocol


def _matrices(sec: Section) -> tuple[dict, dict]:
    """A, B, C inline or from ``stiffness_file``; returns (matrices, key of each)."""
    if sec.has("stiffness_file"):
        for k in ("A", "B", "C"):
            if sec.has(k):
                raise sec.error(k, "give either stiffness_file or A, B, C inline, not both")
        path = sec.path("stiffness_file")
        from slipcycle.coupled.sizes import check_memory, system_bytes
        from slipcycle.io.matrices import read_case_stiffness, stiffness_nodes

        n_file = stiffness_nodes(path)
        if n_file is not None:
            check_memory(sec.key("stiffness_file"), system_bytes(n_file),
                         f"{n_file} contact nodes")
        # every format (npz, mtx, Abaqus, CalculiX, HB, .mat, DMIG), 2-D: one tangent
        mats = read_case_stiffness(sec, path, tangential_dims=1).to_arrays()
        keys = {k: sec.key("stiffness_file") + f" (matrix {k})" for k in ("A", "B", "C", "K")}
        return mats, keys
    A = sec.array("A", shape=(None, None))
    n = A.shape[0]
    if A.size == 0 or A.shape[1] != n:  # B and C take their shape from A: blame A first
        raise sec.error("A", f"must be a square N×N matrix with N >= 1, got "
                        f"{A.shape[0]}×{A.shape[1]}")
    B = sec.array("B", shape=(n, n))
    C = sec.array("C", shape=(n, n))
    return {"A": A, "B": B, "C": C}, {k: sec.key(k) for k in ("A", "B", "C")}


#: per-node keys whose length states the number of nodes the case was written for
_PER_NODE_KEYS = (("discrete", "initial_slip"), ("discrete", "friction"), ("loading", "p0"),
                  ("loading", "q0"), ("loading", "p1"), ("loading", "q1"))


def _check_file_nodes(case: Case, sec: Section, n: int) -> None:
    """Refuse a stiffness file whose node count disagrees with every per-node key.

    When all the per-node lists of the case agree with each other but not with the file,
    the file is the odd one out: say so (naming ``stiffness_file``), instead of blaming the
    first per-node key read.
    """
    lengths = {}
    for table, key in _PER_NODE_KEYS:
        raw = case.data.get(table, {})
        val = raw.get(key) if isinstance(raw, dict) else None
        if isinstance(val, list) and val:
            last = val[-1]
            size = len(last) if isinstance(last, list) else len(val)
            lengths[f"{table}.{key}"] = size
    sizes = set(lengths.values())
    if len(sizes) == 1 and n not in sizes:
        m = sizes.pop()
        keys = ", ".join(lengths)
        raise sec.error("stiffness_file",
                        f"the file holds a model of {n} contact nodes, but the case gives "
                        f"{m} values per node ({keys}): use the stiffness file of the "
                        f"{m}-node model, or give {n} values per node")


def _initial_state_error(sec: Section, ld: Section, exc, r0: np.ndarray, n: int) -> CaseError:
    """The key to blame for an initial state that is inadmissible at θ = 0.

    A node that is open at θ = 0 because its normal load is tensile carries no friction
    force, so the slip imposed on it cannot hold the tangential reaction: the load is at
    fault (``loading.p0`` for a tensile mean), not ``initial_slip``.
    """
    j = exc.node
    pw = float(r0[n + j])
    if exc.separated and pw < 0:
        raw = ld.data.get("p0")
        p0 = np.broadcast_to(np.asarray(raw, float), (n,))[j] if raw is not None else pw
        key = "p0" if p0 < 0 else ("p1" if ld.has("p1") else "p_table" if ld.has("p_table")
                                   else "load_case")
        return ld.error(key, f"node {j} is open at θ = 0: its normal load p^w = {pw:.6g} N "
                             f"is tensile (p0 = {p0:.6g} N; compressive is positive), so it "
                             "carries no friction force and cannot hold the slip that "
                             "discrete.initial_slip imposes; make the normal load "
                             "compressive, or remove initial_slip (the node then opens "
                             "freely as the load is applied)")
    if np.broadcast_to(np.asarray(sec.data.get("friction", 1.0), float), (n,))[j] == 0:
        # frictionless: no tangential reaction can be held, the slip is the equilibrium one
        return sec.error("initial_slip", f"node {j} has friction = 0, so it holds no "
                         "tangential reaction and only the slip in equilibrium with the "
                         "loads is admissible at θ = 0; remove initial_slip (the run then "
                         "starts from that equilibrium)")
    return sec.error("initial_slip", f"inadmissible at θ = 0: {exc}")


#: fields of :class:`FrictionalSystem` that are keys of ``[discrete]`` of the same name
_SYSTEM_KEYS = ("A", "B", "C", "friction", "accept_ill_posed", "f_crit_exact_max_nodes")


def read_discrete_case(case: Case, *, record: bool = True) -> DiscreteCase:
    """Read and validate every key of a discrete case; no computation beyond checks.

    ``record``: the histories of every cycle will be kept (``slipcycle run``); their
    memory is then part of the size check. Many-run analyses (shakedown, basins) keep
    only numbers per run and pass ``False``.

    Raises
    ------
    CaseError
        Naming the offending key and the problem.
    """
    sec = case.section("discrete")
    mats, mkeys = _matrices(sec)
    n = np.asarray(mats["A"]).shape[0] if np.ndim(mats["A"]) == 2 else 0
    if sec.has("stiffness_file"):
        _check_file_nodes(case, sec, n)
    friction = sec.array("friction", shape=(n,), scalar_ok=True)
    accept = sec.bool("accept_ill_posed", False)
    exact_max = sec.int("f_crit_exact_max_nodes", 10)
    init, protocol = read_start(sec, n)

    ld = case.section("loading")
    lam = ld.float("lam", 1.0, ge=0.0)

    def file_case(cs: Section):
        k = cs.int("file_case", ge=0)
        if "p_w" not in mats or "q_w" not in mats:
            raise cs.error("file_case", "the stiffness_file holds no load cases "
                                        "(arrays p_w, q_w)")
        pw = np.atleast_2d(mats["p_w"])
        qw = np.atleast_2d(mats["q_w"])
        if k >= pw.shape[0]:
            raise cs.error("file_case", f"must be < {pw.shape[0]} (load cases in file)")
        pvec, qvec = np.asarray(pw[k], float), np.asarray(qw[k], float)
        if pvec.shape != (n,) or qvec.shape != (n,):
            raise cs.error("file_case", f"load case vectors must have {n} entries")
        return pvec, qvec

    load = DiscreteLoad(periodic_load(ld, "p", n, lam), periodic_load(ld, "q", n, lam),
                        load_cases(ld, n, lam, 1, file_case))
    rn = case.section("run", required=False)
    run = RunSettings(**run_settings(rn))
    check_run(rn, run)
    case.finish()

    # -- sizes: refuse what cannot be allocated, before any work --------------------------
    from slipcycle.coupled.sizes import check_case_sizes

    check_case_sizes(sec, rn, "A", n, run, record=record)

    # -- model checks (no solving yet): the model's own, under the keys of the case ------
    try:
        system = FrictionalSystem(mats["A"], mats["B"], mats["C"], friction,
                                  accept_ill_posed=accept, f_crit_exact_max_nodes=exact_max)
    except ModelError as exc:
        raise case_error_of(exc, {**{k: sec.key(k) for k in _SYSTEM_KEYS}, **mkeys}) from None
    fc = system.critical_friction
    samples = load.cycle_samples(run.steps_per_cycle)[1]
    check_load_scale(ld, samples if protocol is None else np.vstack([samples, protocol]),
                     system.stiffness_scale())
    check_some_contact(ld, samples[:, -n:])
    if init is not None:
        r0 = load(np.array([0.0]))[0]
        F = max(float(np.max(np.abs(load.cycle_samples(run.steps_per_cycle)[1]))), 1e-300)
        try:
            initial_state(system, r0, init, 1e-10 * F)
        except InadmissibleInitialState as exc:
            raise _initial_state_error(sec, ld, exc, r0, n) from None
    return DiscreteCase(system, load, fc, run, init, protocol)


def _dataset(dc: DiscreteCase, res) -> xr.Dataset:
    n = dc.system.n_nodes
    theta = res.theta
    loads = dc.load(theta)
    loads[-1] = loads[0]
    cyc = np.arange(1, res.cycles_run + 1)
    dims = ("cycle", "theta", "node")
    stuck = np.zeros(n, np.int8)
    stuck[res.permanently_stuck_nodes] = 1
    ds = xr.Dataset(
        {
            "slip": (dims, res.x[:, :, :n], {"units": "m", "long_name": "tangential slip v"}),
            "separation": (dims, res.x[:, :, n:], {"units": "m",
                                                   "long_name": "normal separation w"}),
            "tangential_reaction": (dims, res.r[:, :, :n], {"units": "N",
                                                            "long_name": "q"}),
            "normal_reaction": (dims, res.r[:, :, n:], {"units": "N",
                                                        "long_name": "p (compressive > 0)"}),
            "node_state": (dims, res.modes, {
                "units": "1",
                "long_name": "node state on the last event piece before the sample",
                "flag_values": np.arange(4, dtype=np.int8),
                "flag_meanings": " ".join(STATE_NAMES)}),
            "q_w": (("theta", "node"), loads[:, :n], {"units": "N",
                                                      "long_name": "tangential load q^w"}),
            "p_w": (("theta", "node"), loads[:, n:], {"units": "N",
                                                      "long_name": "normal load p^w"}),
            "friction_limit": (dims, dc.system.friction * res.r[:, :, n:],
                               {"units": "N", "long_name": "f p"}),
            "dissipation_per_node": (("node",), res.dissipation_per_node,
                                     {"units": "J", "long_name": "D_j of the last cycle"}),
            "dissipation_history": (("cycle",), np.array(res.dissipation_history),
                                    {"units": "J", "long_name": "total D of each cycle"}),
            "events": (("cycle",), np.array(res.events_per_cycle),
                       {"units": "1", "long_name": "events located in each cycle"}),
            "slip_length": (("node",), np.asarray(res.slip_length), {
                "units": "m", "long_name": "∫|dv_j| over the last cycle"}),
            "permanently_stuck": (("node",), stuck, {
                "units": "1", "long_name": "node stuck over the whole last cycle (slip "
                "length <= slip_tolerance)", "flag_values": np.array([0, 1], np.int8),
                "flag_meanings": "slips_or_separates permanently_stuck"}),
        },
        coords={
            "cycle": ("cycle", cyc, {"units": "1"}),
            "theta": ("theta", theta, {"units": "rad", "long_name": "cycle angle"}),
            "node": ("node", np.arange(n), {"units": "1"}),
        },
    )
    ds.attrs["slip_tolerance"] = float(res.slip_tolerance)
    ds.attrs["slip_tolerance_units"] = "m"
    ds.attrs["node_numbering"] = "from 0 (node j is row j of A, B, C)"
    return ds


#: unit of every numeric summary entry (node indices, counts, flags and ratios: "1")
SUMMARY_UNITS = {**SHARED_UNITS, "events_total": "1", "events_last_cycle": "1"}

#: every word of the categorical summary entries (position = code in sweep stores)
SUMMARY_FLAGS = {**SHARED_FLAGS, "f_crit_method": ("exact", "bound")}


def _v_space_geometry(dc: DiscreteCase):
    """Constraints at their extreme positions and the safe region's vertices (N = 2)."""
    G, h = extreme_constraints(dc.system, dc.load)
    return G, h, safe_vertices(G, h)


#: run settings of a discrete case built in Python (the defaults of the ``[run]`` table)
RUN_DEFAULTS = RunSettings()


def discrete_case(system: FrictionalSystem, load, run: Mapping | None = None, *,
                  initial_slip=None, protocol=None,
                  f_crit_exact_max_nodes: int = 10) -> DiscreteCase:
    """A :class:`DiscreteCase` from Python objects (what :func:`read_discrete_case` builds).

    Parameters
    ----------
    system : FrictionalSystem
        A, B, C (N/m) and the friction coefficients of the N nodes.
    load : DiscreteLoad or callable
        ``load(theta) -> (n, 2N)`` array of [q^w, p^w] (N) with ``cycle_samples``.
    run : mapping, optional
        ``cycles``, ``steps_per_cycle``, ``tol`` (or ``steady_tol``, ``tolerance``),
        ``min_cycles``;
        :data:`RUN_DEFAULTS` for those not given.
    initial_slip : (N,) array, optional
        Slip state at θ = 0 (m); else the load is applied from the unloaded state.
    protocol : (M, 2N) array, optional
        Assembly states [q^w, p^w] (N) before the first cycle.
    f_crit_exact_max_nodes : int, optional
        Largest system for which the critical friction is computed exactly.

    Returns
    -------
    DiscreteCase
    """
    settings = RunSettings.of(run, RUN_DEFAULTS)
    fc = system.critical_friction if f_crit_exact_max_nodes == \
        system.f_crit_exact_max_nodes else critical_friction(
            system.A, system.B, system.friction, exact_max_nodes=f_crit_exact_max_nodes)
    return DiscreteCase(system, load, fc, settings,
                        None if initial_slip is None else np.asarray(initial_slip, float),
                        None if protocol is None else np.asarray(protocol, float))


@dataclass(frozen=True, kw_only=True, repr=False, eq=False)
class DiscreteResult(CoupledResult):
    """Result of a discrete run (:class:`~slipcycle.coupled.case.CoupledResult` over a
    :class:`DiscreteCase` and the :class:`~slipcycle.discrete.steady.SteadyResult` of
    :func:`~slipcycle.discrete.steady.simulate`).

    Attributes
    ----------
    case : DiscreteCase
        The validated case (system, load, run settings).
    solution : SteadyResult
        Histories of the cycles run and the classification of the last one.
    wall_time_s : float
        Seconds the simulation took.
    """

    model: ClassVar[str] = "discrete"
    SUMMARY_UNITS: ClassVar[dict] = SUMMARY_UNITS
    SUMMARY_FLAGS: ClassVar[dict] = SUMMARY_FLAGS

    def critical_friction(self):
        """The case's critical friction (exact up to its ``f_crit_exact_max_nodes``)."""
        return self.case.f_crit

    def own_summary(self) -> dict:
        """``events_total`` and ``events_last_cycle`` of the exact event-driven engine."""
        res = self.solution
        return {"events_total": int(sum(res.events_per_cycle)),
                "events_last_cycle": int(res.events_per_cycle[-1])}

    def _build_dataset(self) -> xr.Dataset:
        """States, reactions and node states of every cycle run; loads, dissipation and
        slip lengths (units on every variable)."""
        return _dataset(self.case, self.solution)

    def figures(self, dataset: xr.Dataset | None = None) -> dict:
        """``slip_and_tractions``, ``hysteresis`` and, for two nodes, ``v_space``."""
        ds = self.to_dataset() if dataset is None else dataset
        dc, res = self.case, self.solution
        # plot functions named by string (the model does not import slipcycle.plot):
        # picklable, so drawn by the CLI's workers; matplotlib only when drawn
        plot = "slipcycle.plot.discrete:"
        figures = {
            "slip_and_tractions": figure_task(plot + "slip_and_tractions", ds),
            "hysteresis": figure_task(plot + "hysteresis", ds),
        }
        if dc.system.n_nodes == 2:
            figures["v_space"] = figure_task(plot + "v_space", res, *_v_space_geometry(dc))
        return figures


def solve_model(dc, load=None, run: Mapping | None = None, *, progress=None,
                **kwargs) -> DiscreteResult:
    """Solve a discrete system to its steady state.

    Parameters
    ----------
    dc : DiscreteCase or FrictionalSystem
        A validated case, or a system (then ``load`` is required).
    load : DiscreteLoad, optional
        The periodic loads of ``dc`` when it is a system.
    run : mapping, optional
        Run settings for a system (see :func:`discrete_case`).
    progress : callable, optional
        ``progress(cycles_done, cycles)`` after each cycle (:func:`slipcycle.run` passes
        the command line's progress bar).
    **kwargs
        ``initial_slip``, ``protocol``, ``f_crit_exact_max_nodes`` of :func:`discrete_case`.

    Returns
    -------
    DiscreteResult
    """
    return solve(DiscreteResult, DiscreteCase, FrictionalSystem, discrete_case, simulate, dc,
                 load, run, progress, **kwargs)


def solve_case(case: Case, progress=None) -> DiscreteResult:
    """Validate a discrete case completely (CaseError before any computation), then solve.

    Parameters
    ----------
    case : Case
        A ``model = "discrete"`` case.
    progress : callable, optional
        ``progress(cycles_done, cycles)`` after each cycle.

    Returns
    -------
    DiscreteResult
    """
    return solve_model(read_discrete_case(case), progress=progress)


def run_case(case: Case) -> RunOutputs:
    """Validate the whole case, solve to the steady state, return summary/dataset/figures
    (``solve_case(case).to_outputs()``)."""
    return solve_case(case).to_outputs()
