"""Summary, Dataset and figures of a half-space run."""

from __future__ import annotations

import numpy as np
import xarray as xr

from slipcycle.halfspace.bed import SliderBed
from slipcycle.halfspace.history import HistoryResult
from slipcycle.halfspace.model import HalfspaceModel
from slipcycle.halfspace.profiles import RoughExponential
from slipcycle.io import RunOutputs

__all__ = ["package", "stick_history", "w_hat"]


def w_hat(W: float, model: HalfspaceModel, P0: float) -> float:
    """Ŵ = W/(λ_c γσ f² P0) of a rough contact (Putignano et al.; seed 001 §4.6)."""
    g = model.profile.gamma_sigma
    return W / (model.compliance_ratio * g * model.friction**2 * P0)


def stick_history(bed: SliderBed, result: HistoryResult) -> tuple[np.ndarray, np.ndarray | None]:
    """Stick load P_S (N) and stick size (m) at every step.

    The stick zone is the contact area at P_S (seed 001 §4.1–4.3): sliders below the lowest
    slipping one. With no slip in a step the whole contact sticks (P_S = P).
    """
    P_S, size = bed.stick_extent(result.first_slip)
    full = result.first_slip >= bed.size
    P_S = np.where(full, result.P, np.minimum(P_S, result.P))
    if size is not None:
        a_now = np.interp(result.P, bed.edge_load, bed.edge_size)
        size = np.where(full, a_now, np.minimum(size, a_now))
    return P_S, size


def _steady_label(result: HistoryResult) -> str:
    if result.gross_slip is not None:
        return "gross_slip"
    return "steady" if result.steady else "not_converged"


def package(model: HalfspaceModel, bed: SliderBed, result: HistoryResult) -> RunOutputs:
    """Turn a solved history into summary.json numbers, a Dataset and figures."""
    from slipcycle.plot import halfspace as hplot

    P_S, stick_size = stick_history(bed, result)
    last = result.cycle == result.cycle.max() if result.cycles_run else np.zeros(0, bool)
    W = result.dissipation_per_cycle
    W_s = result.slider_sum_dissipation
    summary: dict = {
        "model": "halfspace",
        "profile": model.profile_name or type(model.profile).__name__,
        "steady_state": _steady_label(result),
        "dissipation_per_cycle": W if result.gross_slip is None else None,
        "dissipation_per_cycle_sliders": W_s if result.gross_slip is None else None,
        "dissipation_relative_difference": (abs(W - W_s) / max(abs(W), 1e-300)
                                            if result.cycles_run and W != 0 else 0.0),
        "cycles_run": result.cycles_run,
        "state_change": result.state_change,
        "sliders": bed.size,
        "friction": model.friction,
        "compliance_ratio": model.compliance_ratio,
        "normal_control": model.normal_control,
        "tangential_control": model.tangential_control,
        "gross_slip": None,
        "units": {"dissipation_per_cycle": "J" + ("/m" if model.profile.plane else ""),
                  "load": "N" + ("/m" if model.profile.plane else ""), "length": "m"},
    }
    if model.elasticity is not None:
        summary["contact_modulus"] = model.elasticity.contact_modulus
        summary["dundurs_beta"] = model.elasticity.dundurs_beta
        if abs(model.elasticity.dundurs_beta) > 0.05:
            summary["warnings"] = [f"Dundurs beta = {model.elasticity.dundurs_beta:.3f}: the "
                                   "materials are dissimilar, so the uncoupled theory is "
                                   "approximate"]
    if result.gross_slip is not None:
        g = result.gross_slip
        summary["gross_slip"] = {"step": g.step, "cycle": g.cycle, "theta": g.theta,
                                 "P": g.P, "Q": g.Q}
    if last.any():
        summary["permanent_stick_load"] = float(P_S[last].min())  # P_D of seed 001 §4.3
        if stick_size is not None:
            summary["permanent_stick_size"] = float(stick_size[last].min())
            summary["contact_size_max"] = float(np.interp(result.P[last].max(), bed.edge_load,
                                                          bed.edge_size))
    if isinstance(model.profile, RoughExponential) and result.gross_slip is None:
        P0 = float(model.normal.mean[0]) if hasattr(model.normal, "mean") else None
        if P0 and model.normal_control == "force":
            summary["W_hat"] = w_hat(W, model, P0)

    ds = _dataset(model, bed, result, P_S, stick_size)
    figures = {"hysteresis": lambda: hplot.hysteresis(ds),
               "load_path": lambda: hplot.load_path(ds, model.friction)}
    if "shear_traction" in ds:
        figures["tractions"] = lambda: hplot.tractions(ds)
        figures["dissipation_density"] = lambda: hplot.dissipation_density(ds)
    if stick_size is not None:
        figures["stick_zone"] = lambda: hplot.stick_zone(ds)
    return RunOutputs(summary=summary, dataset=ds, figures=figures)


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
    if model.profile.axisymmetric and bed.edge_size is not None and result.last_t is not None:
        _add_tractions(ds, model, bed, result)
    return ds


def _add_tractions(ds: xr.Dataset, model, bed, result) -> None:
    from slipcycle.halfspace.tractions import abel_operators, dissipation_density

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
