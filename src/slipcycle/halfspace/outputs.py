"""Summary, Dataset and figures of a half-space run."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import xarray as xr

from slipcycle.figure_task import figure_task
from slipcycle.halfspace import profiles as pr
from slipcycle.halfspace.bed import SliderBed
from slipcycle.halfspace.history import HistoryResult
from slipcycle.halfspace.model import HalfspaceModel
from slipcycle.halfspace.profiles import RoughExponential
from slipcycle.halfspace.topography import SURFACE_UNITS
from slipcycle.halfspace.tractions import abel_operators, dissipation_density
from slipcycle.io import RunOutputs
from slipcycle.result import STEADY_STATES, RunResult, classify

__all__ = ["FLAGS", "HalfspaceResult", "package", "permanent_stick", "slips", "stick_history",
           "w_hat"]


def w_hat(W: float, model: HalfspaceModel, P0: float) -> float:
    """Ŵ = W/(λ_c γσ f² P0) of a rough contact (Putignano et al.; Barber 2012, §4.6)."""
    g = model.profile.gamma_sigma
    return W / (model.compliance_ratio * g * model.friction**2 * P0)


def stick_history(bed: SliderBed, result: HistoryResult) -> tuple[np.ndarray, np.ndarray | None]:
    """Stick load P_S (N) and stick size (m) at every step.

    The stick zone is the contact area at P_S (Barber 2012, §4.1–4.3): sliders below the lowest
    slipping one. With no slip in a step the whole contact sticks (P_S = P).
    """
    P_S, size = bed.stick_extent(result.first_slip)
    full = result.first_slip >= bed.size
    P_S = np.where(full, result.P, np.minimum(P_S, result.P))
    if size is not None:
        a_now = np.interp(result.P, bed.edge_load, bed.edge_size)
        size = np.where(full, a_now, np.minimum(size, a_now))
    return P_S, size


#: words each categorical summary entry can take
FLAGS = {
    "steady_state": ("steady", "gross_slip", "not_converged"),
    "profile": ("sphere", "cylinder", "flat_punch", "power_law", "rough_exponential",
                "tabulated"),
    "normal_control": ("force", "approach"),
    "tangential_control": ("force", "displacement"),
}

#: a slider whose total slip over the steady cycle is below this fraction of the largest
#: elastic tangential travel λ f (U_max − s_min) sticks: rounding of a slider returned
#: exactly to its limit (a load reversal) is not slip
PERMANENT_STICK_TOL = 1e-9


def _profile_name(profile) -> str:
    if isinstance(profile, pr.PowerLaw):
        return "sphere" if profile.n == 2.0 else "power_law"
    return {pr.Cylinder2D: "cylinder", pr.FlatPunch: "flat_punch",
            pr.RoughExponential: "rough_exponential", pr.Tabulated: "tabulated"}[type(profile)]


def _steady_label(result: HistoryResult) -> str:
    if result.gross_slip is not None:
        return "gross_slip"
    return "steady" if result.steady else "not_converged"


def permanent_stick(bed: SliderBed, result: HistoryResult
                    ) -> tuple[float, float | None] | None:
    """Permanently stuck region over the last (steady) cycle: its load P_D and size.

    The permanent stick zone is the contact area at P_D (Barber 2012, §4.3): the sliders
    that neither slip nor separate at any instant of the steady cycle. Slip is judged on
    the total slip Σ|Δz| of each slider over that cycle with the tolerance
    ``PERMANENT_STICK_TOL`` scaled to the problem. With no slip at all the whole contact
    at the smallest load of the cycle sticks. For constant P and Q = ±Q*, P_D = P − Q*/f
    for every profile (Ciavarella–Jäger; Mindlin–Deresiewicz for the sphere).

    Returns
    -------
    (P_D, size) or None
        P_D in N (N/m for plane contacts), the stick radius/half-width in m (None without a
        contact size); None when no cycle was completed.
    """
    if result.cycles_run == 0:
        return None
    last = result.cycle == result.cycle.max()
    U_max, P_min = float(result.U[last].max()), float(result.P[last].min())
    scale = bed.compliance_ratio * bed.friction * max(U_max - float(bed.level[0]), 0.0)
    slipping = result.slider_slip[-1] > PERMANENT_STICK_TOL * scale
    P_D = P_min
    if slipping.any():
        P_D = min(float(bed.edge_load[int(np.argmax(slipping))]), P_min)
    size = None
    if bed.edge_size is not None:
        size = float(np.interp(P_D, bed.edge_load, bed.edge_size))
    return P_D, size


def slips(bed: SliderBed, result: HistoryResult) -> bool:
    """Whether any slider slips over the last cycle run.

    Uses the test of :func:`permanent_stick`: total slip Σ|Δz| above
    ``PERMANENT_STICK_TOL`` of the largest elastic tangential travel λ f (U_max − s_min).
    """
    if result.cycles_run == 0:
        return False
    last = result.cycle == result.cycle.max()
    U_max = float(result.U[last].max())
    scale = bed.compliance_ratio * bed.friction * max(U_max - float(bed.level[0]), 0.0)
    return bool(np.any(result.slider_slip[-1] > PERMANENT_STICK_TOL * scale))


def _message(result: HistoryResult) -> str:
    if result.gross_slip is not None:
        g = result.gross_slip
        when = "during the assembly" if g.cycle < 0 else f"in cycle {g.cycle}"
        return (f"gross slip {when} at theta = {g.theta:.6g} rad (P = {g.P:.6g}, "
                f"Q = {g.Q:.6g}): the contact cannot carry the tangential load")
    if result.steady:
        return f"steady cycle reached after {result.cycles_run} cycles"
    return (f"no steady cycle within {result.cycles_run} cycles (state change "
            f"{result.state_change:.3g})")


@dataclass(frozen=True, kw_only=True, repr=False, eq=False)
class HalfspaceResult(RunResult):
    """Result of a half-space run: the shared vocabulary of :class:`~slipcycle.result.RunResult`
    over the model, its slider bed and its history.

    ``steady_state`` is ``shakedown`` (steady, no slider slips), ``cyclic_slip`` (steady,
    some slider slips every cycle), ``gross_slip`` or ``not_converged``;
    ``steady_state_detail`` is the word of the summary's ``steady_state`` (``steady``,
    ``gross_slip``, ``not_converged``).

    Attributes
    ----------
    model_input : HalfspaceModel
        The validated model that was solved.
    bed : SliderBed
        The sliders (levels, stiffnesses, capacities) the history ran on.
    history : HistoryResult
        Load path and dissipation per cycle (N, m, J; per metre for plane contacts).
    """

    model: ClassVar[str] = "halfspace"

    model_input: HalfspaceModel
    bed: SliderBed
    history: HistoryResult

    @classmethod
    def from_solution(cls, model: HalfspaceModel, bed: SliderBed, result: HistoryResult
                      ) -> HalfspaceResult:
        """Wrap the output of :func:`~slipcycle.halfspace.model.solve`.

        Parameters
        ----------
        model : HalfspaceModel
        bed : SliderBed
        result : HistoryResult

        Returns
        -------
        HalfspaceResult
        """
        gross = result.gross_slip is not None
        return cls(
            steady_state=classify(converged=bool(result.steady), gross_slip=gross,
                                  slips=slips(bed, result)),
            steady_state_detail=_steady_label(result),
            dissipation_per_cycle=None if gross else result.dissipation_per_cycle,
            cycles_run=int(result.cycles_run), residual=float(result.state_change),
            converged=bool(result.steady) and not gross, message=_message(result),
            dissipation_unit="J/m" if model.profile.plane else "J",
            model_input=model, bed=bed, history=result)

    @property
    def flags(self) -> dict[str, tuple[str, ...]]:
        """Every word of the categorical summary entries."""
        return {**FLAGS, "steady_state_class": STEADY_STATES}

    def summary(self) -> dict:
        """The ``summary.json`` dictionary (keys in docs/halfspace.md), with ``units``."""
        model, bed, result = self.model_input, self.bed, self.history
        W = result.dissipation_per_cycle
        W_s = result.slider_sum_dissipation
        per_len = "/m" if model.profile.plane else ""
        load_unit, energy_unit = "N" + per_len, "J" + per_len
        units = {"dissipation_per_cycle": energy_unit,
                 "dissipation_per_cycle_sliders": energy_unit,
                 "dissipation_relative_difference": "1", "cycles_run": "1",
                 "state_change": "1", "sliders": "1", "friction": "1", "compliance_ratio": "1"}
        summary: dict = {
            "model": "halfspace",
            "profile": model.profile_name or _profile_name(model.profile),
            "steady_state": _steady_label(result),
            "steady_state_class": self.steady_state.value,
            "dissipation_per_cycle": W if result.gross_slip is None else None,
            "dissipation_per_cycle_sliders": W_s if result.gross_slip is None else None,
            "dissipation_relative_difference": (abs(W - W_s) / max(abs(W), 1e-300)
                                                if result.cycles_run and W != 0 else 0.0)
                                                if result.gross_slip is None else None,
            "cycles_run": result.cycles_run,
            "state_change": result.state_change,
            "sliders": bed.size,
            "friction": model.friction,
            "compliance_ratio": model.compliance_ratio,
            "normal_control": model.normal_control,
            "tangential_control": model.tangential_control,
            "gross_slip": None,
            "units": units,
        }
        if model.elasticity is not None:
            summary["contact_modulus"] = model.elasticity.contact_modulus
            summary["dundurs_beta"] = model.elasticity.dundurs_beta
            units.update(contact_modulus="Pa", dundurs_beta="1")
            if abs(model.elasticity.dundurs_beta) > 0.05:
                summary["warnings"] = [f"Dundurs beta = {model.elasticity.dundurs_beta:.3f}: "
                                       "the materials are dissimilar, so the uncoupled theory "
                                       "is approximate"]
        slope = pr.slope_warning(model.profile, float(bed.edge_load[-1]))
        if slope:
            summary.setdefault("warnings", []).append(slope)
        if result.gross_slip is not None:
            g = result.gross_slip
            # when: step and cycle (-1: during the assembly path) and angle; where: P and Q
            summary["gross_slip"] = {"step": g.step, "cycle": g.cycle, "theta": g.theta,
                                     "P": g.P, "Q": g.Q}
            units.update({"gross_slip.step": "1", "gross_slip.cycle": "1",
                          "gross_slip.theta": "rad", "gross_slip.P": load_unit,
                          "gross_slip.Q": load_unit})
        stick = permanent_stick(bed, result) if result.gross_slip is None else None
        if stick is not None:
            summary["permanent_stick_load"] = stick[0]
            units["permanent_stick_load"] = load_unit
            if stick[1] is not None:
                last = result.cycle == result.cycle.max()
                summary["permanent_stick_size"] = stick[1]
                summary["contact_size_max"] = float(np.interp(result.P[last].max(),
                                                              bed.edge_load, bed.edge_size))
                units.update(permanent_stick_size="m", contact_size_max="m")
        if model.surface:
            # the measured surface behind a BEM law: which file, map and fit
            summary["surface"] = dict(model.surface)
            units.update({f"surface.{k}": u for k, u in SURFACE_UNITS.items()
                          if k in model.surface})
        if isinstance(model.profile, RoughExponential) and result.gross_slip is None:
            P0 = float(model.normal.mean[0]) if hasattr(model.normal, "mean") else None
            if P0 and model.normal_control == "force":
                summary["W_hat"] = w_hat(W, model, P0)
                units["W_hat"] = "1"
        # the shared entries (residual, converged, wall_time_s); state_change is the
        # alias of residual, kept for one release
        return self.with_shared(summary)

    def _build_dataset(self) -> xr.Dataset:
        """Histories per step, slider data per cycle and, for axisymmetric profiles, the
        tractions of the last cycle (units on every variable)."""
        model, bed, result = self.model_input, self.bed, self.history
        P_S, stick_size = stick_history(bed, result)
        load_unit = "N/m" if model.profile.plane else "N"
        stick = permanent_stick(bed, result) if result.gross_slip is None else None
        ds = _dataset(model, bed, result, P_S, stick_size)
        if stick is not None:
            ds["permanent_stick_load"] = ((), stick[0], {
                "units": load_unit, "long_name": "load P_D whose contact area never slips"})
            if stick[1] is not None:
                ds["permanent_stick_size"] = ((), stick[1], {
                    "units": "m",
                    "long_name": "radius/half-width of the permanent stick zone"})
        if result.gross_slip is not None:
            g = result.gross_slip
            ds["gross_slip_P"] = ((), g.P, {"units": load_unit,
                                            "long_name": "normal load at gross slip"})
            ds["gross_slip_Q"] = ((), g.Q, {"units": load_unit,
                                            "long_name": "tangential load at gross slip"})
        return ds

    def figures(self, dataset: xr.Dataset | None = None) -> dict:
        """Figure name -> function drawing it (``hysteresis``, ``load_path``, and where
        the data exist ``tractions``, ``dissipation_density``, ``stick_zone``).

        Each is a :class:`~slipcycle.figure_task.FigureTask` naming a
        :mod:`slipcycle.plot.halfspace` function with the Dataset: it can be pickled, so the
        command line draws the figures in worker processes, and matplotlib is imported only
        when one is drawn.
        """
        plot = "slipcycle.plot.halfspace:"
        ds = self.to_dataset() if dataset is None else dataset
        figures = {"hysteresis": figure_task(plot + "hysteresis", ds),
                   "load_path": figure_task(plot + "load_path", ds,
                                             float(self.model_input.friction))}
        if "shear_traction" in ds:
            figures["tractions"] = figure_task(plot + "tractions", ds)
            figures["dissipation_density"] = figure_task(plot + "dissipation_density", ds)
        if "stick_size" in ds and self.history.cycles_run:
            figures["stick_zone"] = figure_task(plot + "stick_zone", ds)
        return figures


def package(model: HalfspaceModel, bed: SliderBed, result: HistoryResult) -> RunOutputs:
    """Turn a solved history into summary.json numbers, a Dataset and figures.

    Parameters
    ----------
    model : HalfspaceModel
    bed : SliderBed
    result : HistoryResult
        The output of :func:`~slipcycle.halfspace.model.solve`.

    Returns
    -------
    RunOutputs
        ``HalfspaceResult.from_solution(model, bed, result).to_outputs()``.
    """
    return HalfspaceResult.from_solution(model, bed, result).to_outputs()


def _dataset(model, bed, result, P_S, stick_size) -> xr.Dataset:
    per_len = "/m" if model.profile.plane else ""
    ds = xr.Dataset(
        {
            "U": ("step", result.U, {"units": "m", "long_name": "normal approach"}),
            "V": ("step", result.V, {"units": "m", "long_name": "tangential displacement"}),
            "P": ("step", result.P, {"units": "N" + per_len, "long_name": "normal load"}),
            "Q": ("step", result.Q, {"units": "N" + per_len, "long_name": "tangential load"}),
            "theta": ("step", result.theta, {"units": "rad", "long_name": "cycle angle"}),
            "cycle": ("step", result.cycle, {"units": "1", "long_name": "cycle (-1: assembly)"}),
            "stick_load": ("step", P_S, {"units": "N" + per_len,
                                         "long_name": "load P_S whose contact area sticks"}),
            "level": ("slider", bed.level, {"units": "m", "long_name": "slider contact level"}),
            "normal_stiffness": ("slider", bed.normal_stiffness, {"units": "N/m" + per_len}),
            "slider_dissipation": (("cycle_run", "slider"), result.slider_dissipation,
                                   {"units": "J" + per_len}),
            "dissipation": ("cycle_run", result.global_dissipation,
                            {"units": "J" + per_len, "long_name": "∮Q dV per cycle"}),
        }
    )
    if stick_size is not None:
        ds["stick_size"] = ("step", stick_size, {"units": "m",
                                                 "long_name": "stick zone radius/half-width"})
    if model.profile.axisymmetric and bed.edge_size is not None and result.last_t is not None \
            and result.gross_slip is None:
        _add_tractions(ds, model, bed, result)
    return ds


def _add_tractions(ds: xr.Dataset, model, bed, result) -> None:
    ops = abel_operators(bed)
    S = model.steps_per_cycle
    theta = np.linspace(0, 2 * np.pi, S + 1)
    k = np.clip(np.round(np.asarray(model.snapshots) / (2 * np.pi) * S).astype(int), 0, S)
    U_last = result.U[result.cycle == result.cycle.max()]
    last_U = np.concatenate([U_last[-1:], U_last])   # θ = 0 repeats θ = 2π
    nforce = bed.normal_stiffness[None, :] * np.maximum(last_U[k, None] - bed.level[None, :], 0)
    ds.coords["radius"] = ("radius", ops.radius, {"units": "m"})
    ds.coords["snapshot_theta"] = ("snapshot", theta[k], {"units": "rad"})
    ds["pressure"] = (("snapshot", "radius"), nforce @ ops.traction.T, {"units": "Pa"})
    ds["shear_traction"] = (("snapshot", "radius"), result.last_t[k] @ ops.traction.T,
                            {"units": "Pa"})
    ds["dissipation_density"] = ("radius", dissipation_density(ops, result.last_t,
                                                               result.last_z),
                                 {"units": "J/m^2", "long_name": "W(r) over the last cycle"})
