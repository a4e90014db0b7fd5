"""The run/result contract shared by every model.

Every solver reached through :func:`slipcycle.run` returns a :class:`RunResult`: one object
that carries the same vocabulary for every model and builds, on request, what
``slipcycle run`` writes.

Shared fields (the same names, meanings and units for every model):

- ``steady_state`` (:class:`SteadyState`): the class of the cycle reached, one enumeration
  across models; ``steady_state_detail`` keeps the model's own word.
- ``dissipation_per_cycle``: friction dissipation over the last cycle run [J, or J/m for
  plane contacts]; None where no cycle could be completed (gross slip).
- ``cycles_run``: load cycles run after the assembly.
- ``residual``: the model's relative steadiness residual of the last cycle [1].
- ``converged``: whether the periodic steady state was reached within the tolerance.
- ``message``: one sentence saying what happened.

Methods: :meth:`RunResult.summary` (the ``summary.json`` dictionary, with ``units``),
:meth:`RunResult.to_dataset` (the result's :class:`xarray.Dataset`, completed to CF),
:meth:`RunResult.figures` (name -> function drawing a matplotlib Figure),
:meth:`RunResult.to_outputs` (all of it as :class:`~slipcycle.io.RunOutputs`), and a
one-line ``repr`` and a small HTML table for notebooks.

How the words of each model map onto :class:`SteadyState`:

==============  ====================================  ======================================
model           model word (``steady_state_detail``)  ``steady_state``
==============  ====================================  ======================================
halfspace       ``steady``, no slider slips           ``shakedown``
halfspace       ``steady``, some slider slips         ``cyclic_slip``
halfspace       ``gross_slip``                        ``gross_slip``
halfspace       ``not_converged``                     ``not_converged``
discrete        ``shakedown`` / ``cyclic_slip`` /     the same word
                ``ratcheting`` / ``not_converged``
rods            ``stuck`` (converged, no slip)        ``shakedown``
rods            ``slipping`` (converged, slip)        ``cyclic_slip``
rods            ``not_converged``                     ``not_converged``
==============  ====================================  ======================================

A half-space slider "slips" when its total slip over the steady cycle exceeds
``PERMANENT_STICK_TOL`` of the largest elastic tangential travel (the same test as the
permanent stick zone, Barber 2012, §4.3); a rod interface slips when its dissipation
exceeds 1e-12 of max|T| · ptp(δ) over the cycle. ``inadmissible`` is the class of an
assembly state that cannot be held at θ = 0 (discrete basin maps).

Every analysis (the discrete shakedown study and basin maps, the half-space Ŵ map, the
rods limits) returns a :class:`StudyResult` with the same methods: ``summary()``,
``to_dataset()``, ``figures()``, ``flags``, ``to_outputs()`` (what its command writes), a
one-line ``repr`` of its headline numbers and a small HTML table.
"""

from __future__ import annotations

import html
import math
from dataclasses import dataclass
from enum import StrEnum
from typing import TYPE_CHECKING, Any, ClassVar

if TYPE_CHECKING:  # pragma: no cover
    import xarray as xr

    from slipcycle.io.results import RunOutputs

__all__ = ["SteadyState", "STEADY_STATES", "STEADY_MESSAGES", "RunResult", "StudyResult",
           "classify"]


class SteadyState(StrEnum):
    """Class of the cycle a run reached; one enumeration for every model.

    ``shakedown``: nothing slips in the steady cycle (separation may still occur);
    ``cyclic_slip``: some of the interface slips back and forth every cycle, the rest
    sticks; ``ratcheting``: slip accumulates by the same amount every cycle;
    ``gross_slip``: the contact cannot carry the tangential load (no periodic state);
    ``not_converged``: no periodic state within the cycles allowed; ``inadmissible``: the
    initial or assembly state cannot be held; ``failed``: a run of a study that stopped
    with a solver error.

    :attr:`code` is the position in this order: the integer stored for the class in basin
    maps, λ scans and sweep stores (``flag_values`` / ``flag_meanings``). The discrete
    models' classes come first in their order of severity (a study reports the worst class
    of its runs: :meth:`worst`), then the classes of a start that cannot be held or a run
    that failed, and last ``gross_slip`` (half-space contacts only).
    """

    SHAKEDOWN = "shakedown"
    CYCLIC_SLIP = "cyclic_slip"
    RATCHETING = "ratcheting"
    NOT_CONVERGED = "not_converged"
    INADMISSIBLE = "inadmissible"
    FAILED = "failed"
    GROSS_SLIP = "gross_slip"

    @property
    def code(self) -> int:
        """The integer code of the class (its position in :data:`STEADY_STATES`)."""
        return STEADY_STATES.index(self.value)

    @property
    def converged(self) -> bool:
        """Whether the class is that of a periodic (or ratcheting) state reached."""
        return self in (SteadyState.SHAKEDOWN, SteadyState.CYCLIC_SLIP,
                        SteadyState.RATCHETING)

    @classmethod
    def of_code(cls, code: int) -> SteadyState:
        """The class of an integer code (inverse of :attr:`code`)."""
        return cls(STEADY_STATES[int(code)])

    @classmethod
    def worst(cls, words) -> SteadyState:
        """The most severe class among ``words`` (the largest :attr:`code`)."""
        return cls(max((cls(w) for w in words), key=lambda s: s.code))


#: every word of :class:`SteadyState`, in order (position = code in every store); the
#: one list of steady-state words of the project
STEADY_STATES: tuple[str, ...] = tuple(s.value for s in SteadyState)

#: the sentence a run result's ``message`` starts with, per class
STEADY_MESSAGES: dict[str, str] = {
    "shakedown": "shakedown: no node slips in the steady cycle",
    "cyclic_slip": "cyclic slip: nodes slip every cycle (any others stay stuck)",
    "ratcheting": "ratcheting: slip accumulates by the same amount every cycle",
    "gross_slip": "gross slip: the contact cannot carry the tangential load",
    "not_converged": "no steady cycle within the cycles allowed",
    "inadmissible": "the initial state cannot be held at θ = 0",
    "failed": "the run stopped with a solver error",
}


def classify(*, converged: bool, slips: bool, gross_slip: bool = False,
             ratcheting: bool = False) -> SteadyState:
    """The :class:`SteadyState` of a run from its outcome.

    Parameters
    ----------
    converged : bool
        Whether a periodic (or ratcheting) state was reached within the tolerance.
    slips : bool
        Whether any part of the interface slips in the last cycle (tested by the model
        with a tolerance scaled to the problem).
    gross_slip : bool, optional
        The contact could not carry the load (takes precedence).
    ratcheting : bool, optional
        The state drifts by the same amount every cycle.

    Returns
    -------
    SteadyState
    """
    if gross_slip:
        return SteadyState.GROSS_SLIP
    if not converged:
        return SteadyState.NOT_CONVERGED
    if ratcheting:
        return SteadyState.RATCHETING
    return SteadyState.CYCLIC_SLIP if slips else SteadyState.SHAKEDOWN


def _fmt(value: Any) -> str:
    if value is None:
        return "None"
    if isinstance(value, bool):
        return str(value)
    if isinstance(value, float):
        return "nan" if math.isnan(value) else f"{value:.6g}"
    if hasattr(value, "tolist") and not isinstance(value, str):  # NumPy arrays, scalars
        return _fmt(value.tolist())
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_fmt(v) for v in value) + "]"
    return str(value)


def _html_table(caption: str, rows: list[tuple[str, Any, str]]) -> str:
    """A small HTML table (quantity, value, unit) for notebooks."""
    body = "".join(
        f"<tr><th style='text-align:left'>{html.escape(k)}</th>"
        f"<td>{html.escape(_fmt(v))}</td><td>{html.escape(u)}</td></tr>"
        for k, v, u in rows)
    return (f"<table><caption>{html.escape(caption)}</caption>"
            f"<tr><th>quantity</th><th>value</th><th>unit</th></tr>{body}</table>")


class _Contract:
    """The output methods shared by run results and analysis results.

    A subclass implements :meth:`summary`, :meth:`_build_dataset` (the one place its
    Dataset is built), :meth:`figures` and :attr:`flags`. :meth:`to_dataset` completes the
    built Dataset to the CF conventions (coordinate variables for every dimension,
    ``long_name`` and ``units`` from the summary's units, flag attributes:
    :func:`slipcycle.io.metadata.cf_complete`), so ``to_dataset()`` in Python is what
    ``result.nc`` holds; :meth:`to_outputs` packs them as ``RunOutputs`` with one call of
    :meth:`summary` and one CF completion.
    """

    @property
    def flags(self) -> dict[str, tuple[str, ...]]:
        """Every word each categorical summary entry can take (see ``RunOutputs.flags``)."""
        return {}

    def summary(self) -> dict:
        """The ``summary.json`` dictionary, with its ``units`` map."""
        raise NotImplementedError

    def _build_dataset(self) -> xr.Dataset:
        """The result's Dataset as the subclass builds it (before the CF completion)."""
        raise NotImplementedError

    def to_dataset(self, summary: dict | None = None) -> xr.Dataset:
        """The result as an :class:`xarray.Dataset` (every variable has units), completed
        to the CF conventions; a new Dataset on each call.

        Parameters
        ----------
        summary : dict, optional
            The result of :meth:`summary`, if already built (its ``units`` complete the
            Dataset; else built here).
        """
        from slipcycle.io.metadata import cf_complete

        units = (self.summary() if summary is None else summary).get("units")
        return cf_complete(self._build_dataset(), units, dict(self.flags))

    def figures(self, dataset: xr.Dataset | None = None) -> dict[str, Any]:
        """Figure name -> function returning a matplotlib Figure (drawn when called)."""
        return {}

    def to_outputs(self) -> RunOutputs:
        """Summary, Dataset, figures and flags, as the command line writes them.

        Returns
        -------
        RunOutputs
        """
        from slipcycle.io.results import RunOutputs

        summary = self.summary()
        ds = self.to_dataset(summary)
        return RunOutputs(summary=summary, dataset=ds, figures=self.figures(ds),
                          flags=dict(self.flags), cf_completed=True)


@dataclass(frozen=True, kw_only=True, repr=False, eq=False)
class RunResult(_Contract):
    """Base of every model's result: the shared vocabulary and the output methods.

    Subclasses (one per model: :class:`slipcycle.halfspace.outputs.HalfspaceResult`,
    :class:`slipcycle.discrete.case.DiscreteResult`, :class:`slipcycle.rods.case.RodsResult`)
    add the solver's own results as fields and implement :meth:`summary`,
    :meth:`_build_dataset` and :meth:`figures`, and set :attr:`flags`.

    Attributes
    ----------
    steady_state : SteadyState
        Class of the cycle reached (see the module docstring for each model's mapping).
    steady_state_detail : str
        The model's own word for it (the ``steady_state`` of a half-space summary).
    dissipation_per_cycle : float or None
        Friction dissipation over the last cycle run [``dissipation_unit``]; None when no
        cycle was completed.
    cycles_run : int
        Load cycles run after the assembly.
    residual : float
        Relative steadiness residual of the last cycle [1] (model-specific norm).
    converged : bool
        Whether the periodic steady state was reached within the tolerance.
    message : str
        One sentence saying what happened.
    dissipation_unit : str
        ``"J"``, or ``"J/m"`` for plane (per unit length) contacts.
    wall_time_s : float or None
        Seconds the solution took (None for a result built without timing it).
    """

    #: the ``model = "..."`` name of the result's model
    model: ClassVar[str] = ""

    steady_state: SteadyState
    steady_state_detail: str
    dissipation_per_cycle: float | None
    cycles_run: int
    residual: float
    converged: bool
    message: str
    dissipation_unit: str = "J"
    wall_time_s: float | None = None

    # -- what each model provides --------------------------------------------------------
    @property
    def flags(self) -> dict[str, tuple[str, ...]]:
        """Every word each categorical summary entry can take (see ``RunOutputs.flags``)."""
        return {"steady_state_class": STEADY_STATES}

    def summary(self) -> dict:
        """The ``summary.json`` dictionary of the run, with its ``units`` map.

        Returns
        -------
        dict
            The numbers a user quotes; ``summary()["units"]`` gives the unit of every
            numeric entry. Always holds ``steady_state_class`` (a :class:`SteadyState`
            word).
        """
        raise NotImplementedError

    def _build_dataset(self) -> xr.Dataset:
        """The full histories as an :class:`xarray.Dataset` (every variable has units).

        The only place the Dataset of this result is built (:meth:`to_dataset` completes
        it to the CF conventions).
        """
        raise NotImplementedError

    def figures(self, dataset: xr.Dataset | None = None) -> dict[str, Any]:
        """Figure name -> function returning a matplotlib Figure (drawn when called).

        Parameters
        ----------
        dataset : xarray.Dataset, optional
            The result of :meth:`to_dataset`, if already built (else built here).
        """
        return {}

    # -- shared ----------------------------------------------------------------------------
    def shared_summary(self) -> dict:
        """The summary entries every model's summary holds under the same names (the
        shared fields), with their ``units``.

        Returns
        -------
        dict
            ``steady_state_class``, ``dissipation_per_cycle`` [``dissipation_unit``],
            ``cycles_run``, ``residual`` [1], ``converged``, ``wall_time_s`` [s], and
            ``units`` for them.
        """
        return {"steady_state_class": self.steady_state.value,
                "dissipation_per_cycle": self.dissipation_per_cycle,
                "cycles_run": self.cycles_run, "residual": self.residual,
                "converged": self.converged, "wall_time_s": self.wall_time_s,
                "units": {"dissipation_per_cycle": self.dissipation_unit, "cycles_run": "1",
                          "residual": "1", "converged": "1", "wall_time_s": "s"}}

    def _shared(self) -> list[tuple[str, Any, str]]:
        return [("steady_state", f"{self.steady_state.value} ({self.steady_state_detail})", ""),
                ("dissipation_per_cycle", self.dissipation_per_cycle, self.dissipation_unit),
                ("cycles_run", self.cycles_run, ""),
                ("residual", self.residual, "1"),
                ("converged", self.converged, ""),
                ("message", self.message, "")]

    def with_shared(self, summary: dict) -> dict:
        """``summary`` completed with the shared entries it lacks (:meth:`shared_summary`)
        and their units; the model's own entries are kept."""
        shared = self.shared_summary()
        units = summary.setdefault("units", {})
        for key, unit in shared.pop("units").items():
            units.setdefault(key, unit)
        for key, value in shared.items():
            summary.setdefault(key, value)
        return summary

    def __repr__(self) -> str:
        d = self.dissipation_per_cycle
        diss = "None" if d is None else f"{_fmt(float(d))} {self.dissipation_unit}"
        return (f"<{type(self).__name__} {self.model}: {self.steady_state.value} "
                f"({self.steady_state_detail}), dissipation_per_cycle={diss}, "
                f"cycles_run={self.cycles_run}, residual={_fmt(float(self.residual))}, "
                f"converged={self.converged}>")

    def _repr_html_(self) -> str:
        return _html_table(f"{type(self).__name__} ({self.model})", self._shared())


@dataclass(frozen=True, kw_only=True, repr=False, eq=False)
class StudyResult(_Contract):
    """Base of every analysis result (a study of many runs), with the output methods.

    Subclasses (one per analysis: :class:`slipcycle.studies.shakedown.ShakedownResult`,
    :class:`slipcycle.studies.basins.BasinsResult`,
    :class:`slipcycle.studies.w_hat_map.WHatMapResult`,
    :class:`slipcycle.studies.limits.LimitsResult` and the other studies of
    :mod:`slipcycle.studies`) hold the analysis' numbers as fields and
    implement :meth:`summary`, :meth:`_build_dataset` (the one place the analysis' Dataset
    is built), :meth:`figures` and :meth:`headline`; they set :attr:`model`,
    :attr:`analysis` and :attr:`FLAGS`.

    Attributes
    ----------
    wall_time_s : float
        Wall-clock time of the analysis in the call that returned it [s].
    """

    #: the model of the analysed case
    model: ClassVar[str] = ""
    #: the ``analysis`` word of the summary
    analysis: ClassVar[str] = ""
    #: every word of the categorical summary entries (see ``RunOutputs.flags``)
    FLAGS: ClassVar[dict[str, tuple[str, ...]]] = {}

    wall_time_s: float

    @property
    def flags(self) -> dict[str, tuple[str, ...]]:
        """Every word each categorical summary entry can take (see ``RunOutputs.flags``)."""
        return dict(self.FLAGS)

    def headline(self) -> list[tuple[str, Any, str]]:
        """The numbers a user quotes first, as (name, value, unit) rows.

        Returns
        -------
        list of tuple
            ``(name, value, unit)``; shown by ``repr`` and the notebook table.
        """
        return [("wall_time_s", self.wall_time_s, "s")]

    def __repr__(self) -> str:
        parts = ", ".join(f"{k}={_fmt(v)}" + (f" {u}" if u not in ("", "1") else "")
                          for k, v, u in self.headline())
        return f"<{type(self).__name__} {self.model} {self.analysis}: {parts}>"

    def _repr_html_(self) -> str:
        return _html_table(f"{type(self).__name__} ({self.model} {self.analysis})",
                           self.headline())
