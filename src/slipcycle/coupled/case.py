"""The run result and the solve template shared by the two discrete models.

``discrete`` and ``discrete3d`` cases are read by their own readers (the matrices, the
load and the node geometry differ); from the validated case on, the path is one:
:func:`solve` runs the model's steady-state driver with the case's :class:`RunSettings`
and wraps the outcome in the model's :class:`CoupledResult`, whose summary holds the
entries shared by both models (:meth:`CoupledResult.shared_summary`, units
:data:`SHARED_UNITS`) and the model's own.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from slipcycle.coupled.driver import ACCELERATIONS
from slipcycle.coupled.settings import RunSettings
from slipcycle.coupled.solution import CYCLE_CLASSES
from slipcycle.io import Section
from slipcycle.io.loads import protocol_states
from slipcycle.result import STEADY_MESSAGES, STEADY_STATES, RunResult, SteadyState

__all__ = ["CoupledResult", "SHARED_UNITS", "SHARED_FLAGS", "solve", "finite_or_none",
           "read_start", "certificate_entries"]

#: unit of every numeric summary entry shared by the discrete models (node indices,
#: counts, flags and ratios: "1")
SHARED_UNITS = {
    "n_nodes": "1", "converged": "1", "residual": "1", "cycles_run": "1",
    "dissipation_per_cycle": "J", "dissipation_per_node": "J",
    "work_of_loads_per_cycle": "J", "energy_balance_error": "1", "slipping_nodes": "1",
    "permanently_stuck_nodes": "1", "separating_nodes": "1", "separation": "1",
    "ratchet_per_cycle": "m", "memory_erased": "1", "f_crit": "1",
    "f_crit_lower_bound": "1", "friction_max": "1", "well_posed": "1", "wall_time_s": "s",
    "certified_residual": "1", "memory_distance": "1", "dissipation_distance": "1",
}

#: every word of the categorical summary entries shared by the discrete models
#: (position = code in sweep stores)
SHARED_FLAGS = {"steady_state": CYCLE_CLASSES, "steady_state_class": STEADY_STATES,
                "acceleration": ACCELERATIONS}


def finite_or_none(x) -> float | None:
    """``float(x)``, or None for None, nan and inf (JSON has no infinity)."""
    return None if x is None or not np.isfinite(x) else float(x)


@dataclass(frozen=True, kw_only=True, repr=False, eq=False)
class CoupledResult(RunResult):
    """Result of a discrete (2-D or 3-D) run: the shared vocabulary of
    :class:`~slipcycle.result.RunResult` over the validated case and the steady-state
    solution (:class:`~slipcycle.coupled.solution.CycleSolution`).

    ``steady_state`` is the driver's word (already one of
    :class:`~slipcycle.result.SteadyState`); ``steady_state_detail`` repeats it.

    Attributes
    ----------
    case
        The validated case (``system``, ``load``, ``run``: :class:`RunSettings`).
    solution : CycleSolution
        Histories of the cycles run and the classification of the last one.
    wall_time_s : float
        Seconds the simulation took.
    """

    #: units and words of the summary (the shared ones and the model's own)
    SUMMARY_UNITS: ClassVar[dict] = SHARED_UNITS
    SUMMARY_FLAGS: ClassVar[dict] = SHARED_FLAGS

    case: Any
    solution: Any

    @property
    def wall_time(self) -> float:
        """Deprecated alias (one release) of :attr:`wall_time_s` [s]."""
        return self.wall_time_s

    @classmethod
    def from_solution(cls, case, solution, wall_time_s: float) -> CoupledResult:
        """Wrap the outcome of the model's steady-state driver.

        Parameters
        ----------
        case
            The validated case.
        solution : CycleSolution
        wall_time_s : float
            Seconds the simulation took.
        """
        word = solution.steady_state
        msg = (f"{STEADY_MESSAGES[word]} ({solution.cycles_run} cycles, residual "
               f"{solution.residual:.3g})")
        return cls(steady_state=SteadyState(word), steady_state_detail=word,
                   dissipation_per_cycle=solution.dissipation_per_cycle,
                   cycles_run=int(solution.cycles_run), residual=float(solution.residual),
                   converged=bool(solution.steady_converged), message=msg, case=case,
                   solution=solution, wall_time_s=wall_time_s)

    @property
    def flags(self) -> dict[str, tuple[str, ...]]:
        """Every word of the categorical summary entries (:attr:`SUMMARY_FLAGS`)."""
        return dict(self.SUMMARY_FLAGS)

    def critical_friction(self):
        """The case's critical friction (``f_crit``, ``lower_bound``, ``method``)."""
        return self.case.system.critical_friction

    def ratchet(self) -> np.ndarray:
        """The ratchet per cycle as the summary gives it [m]."""
        return self.solution.ratchet_per_cycle

    def shared_summary(self) -> dict:
        """The summary entries both discrete models have (units: :data:`SHARED_UNITS`)."""
        system, res = self.case.system, self.solution
        fc = self.critical_friction()
        fmax = float(np.max(system.friction))
        return {
            "model": self.model,
            "n_nodes": system.n_nodes,
            "steady_state": res.steady_state,
            "steady_state_class": SteadyState(res.steady_state).value,
            "converged": res.steady_converged,
            "residual": res.residual,
            "cycles_run": res.cycles_run,
            "dissipation_per_cycle": res.dissipation_per_cycle,
            "dissipation_per_node": res.dissipation_per_node,
            "work_of_loads_per_cycle": res.work_of_loads,
            "energy_balance_error": res.energy_balance_error,
            "slipping_nodes": res.slipping_nodes,
            "permanently_stuck_nodes": res.permanently_stuck_nodes,
            "separating_nodes": res.separating_nodes,
            "separation": bool(res.separating_nodes),
            "ratchet_per_cycle": self.ratchet() if res.steady_state == "ratcheting" else None,
            "memory_erased": res.all_slip_or_separated,
            "f_crit": finite_or_none(fc.f_crit),
            "f_crit_lower_bound": finite_or_none(fc.lower_bound),
            "f_crit_method": fc.method,
            "friction_max": fmax,
            "well_posed": bool(fmax < fc.f_crit),
            "wall_time_s": self.wall_time_s,
            **certificate_entries(res.certificate),
        }

    def own_summary(self) -> dict:
        """The model's own summary entries (units in :attr:`SUMMARY_UNITS`)."""
        return {}

    def summary(self) -> dict:
        """The summary dictionary (keys documented in docs/discrete.md and
        docs/discrete3d.md), with ``units``."""
        return {**self.shared_summary(), **self.own_summary(),
                "units": dict(self.SUMMARY_UNITS)}


def certificate_entries(cert) -> dict:
    """The summary entries of a run's certificate
    (:class:`~slipcycle.coupled.driver.Certificate`; None where the solution has none)."""
    if cert is None:
        return {"acceleration": "none", "certified_residual": None,
                "memory_distance": None, "dissipation_distance": None}
    return {"acceleration": cert.acceleration,
            "certified_residual": finite_or_none(cert.certified_residual),
            "memory_distance": finite_or_none(cert.memory_distance),
            "dissipation_distance": finite_or_none(cert.dissipation_distance)}


def solve(result_cls: type[CoupledResult], case_cls: type, system_cls: type,
          make_case: Callable, simulate: Callable, dc, load=None,
          run: Mapping | None = None, progress=None, **kwargs) -> CoupledResult:
    """The solve_model template of the discrete models.

    Parameters
    ----------
    result_cls, case_cls, system_cls : type
        The model's result, validated case and system classes.
    make_case : callable
        ``make_case(system, load, run, **kwargs)``: the case of a system built in Python.
    simulate : callable
        The model's steady-state driver, ``simulate(system, load, *, initial_slip,
        protocol, **settings)``.
    dc : case_cls or system_cls
        A validated case, or a system (then ``load`` is required).
    load : optional
        The periodic loads of ``dc`` when it is a system.
    run : mapping, optional
        Run settings for a system (:class:`RunSettings` names and aliases).
    progress : callable, optional
        ``progress(cycles_done, cycles)`` after each cycle (where the driver reports it).
    **kwargs
        Further arguments of ``make_case`` (``initial_slip``, ``protocol``, ...).

    Returns
    -------
    CoupledResult
    """
    name = system_cls.__name__
    if isinstance(dc, system_cls):
        if load is None:
            raise TypeError(f"a {name} needs its load: (system, load[, run])")
        dc = make_case(dc, load, run, **kwargs)
    elif not isinstance(dc, case_cls) or load is not None or run or kwargs:
        raise TypeError(f"expected a {case_cls.__name__}, or a {name} with its load")
    extra = {} if progress is None else {"progress": progress}
    t0 = time.perf_counter()
    res = simulate(dc.system, dc.load, initial_slip=dc.initial_slip, protocol=dc.protocol,
                   **extra, **dc.run)
    return result_cls.from_solution(dc, res, time.perf_counter() - t0)


def settings_of(run: Mapping | None, defaults: RunSettings) -> RunSettings:
    """The :class:`RunSettings` of a case built in Python (``defaults`` for those not
    given); a TypeError names an unknown setting."""
    return RunSettings.of(run, defaults)


def read_start(sec: Section, n: int, components: int = 1):
    """How a discrete case starts: ``initial_slip`` [m] ((n,), or (n, components) with
    more than one tangential component) or the assembly protocol
    (:func:`~slipcycle.io.loads.protocol_states`), not both; None for one not given."""
    shape = (n,) if components == 1 else (n, components)
    init = sec.array("initial_slip", None, shape=shape)
    protocol = protocol_states(sec, n, components)
    if init is not None and protocol is not None:
        raise sec.error("protocol", "give either initial_slip or an assembly protocol, "
                                    "not both")
    return init, protocol
