"""Figures of the rough-interface study (``slipcycle roughness``); no physics here.

Each function takes the study's Dataset (and the few numbers it quotes) and returns a
matplotlib Figure.
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.ticker import NullFormatter, ScalarFormatter

__all__ = ["normal_law", "cutoff_study", "dissipation_vs_phase", "fretting_map"]


def normal_law(ds: xr.Dataset, gamma_sigma: float, fit_range: tuple[float, float],
               rms_height: float) -> Figure:
    """BEM law p̄(U) on a log axis with the exponential fit, and the local γσ/σ."""
    fig = Figure(figsize=(9.5, 4.0))
    ax1, ax2 = fig.subplots(1, 2)
    p, U = ds.bem_pressure.values, ds.approach.values
    ax1.semilogy(U * 1e6, p, "o-", ms=3, label="BEM")
    lo, hi = fit_range
    if np.isfinite(gamma_sigma) and np.isfinite(lo):
        sel = (p >= lo) & (p <= hi)
        k = np.argmax(sel)
        Uf = np.linspace(U.min(), U.max(), 50)
        ax1.semilogy(Uf * 1e6, p[k] * np.exp((Uf - U[k]) / gamma_sigma), "--", color="C3",
                     label=f"exp(U/γσ), γσ = {gamma_sigma * 1e6:.3g} µm")
        ax1.axhspan(lo, hi, color="C3", alpha=0.08, label="fit window")
    ax1.set_xlabel("approach U from first touch [µm]")
    ax1.set_ylabel("nominal pressure p̄ [Pa]")
    ax1.legend(fontsize=8)
    ax1.grid(alpha=0.3)
    ax2.semilogx(p, ds.local_gamma_sigma.values / rms_height, "o-", ms=3)
    if np.isfinite(gamma_sigma):
        ax2.axhline(gamma_sigma / rms_height, color="C3", ls="--", label="fitted γ")
        ax2.legend(fontsize=8)
    ax2.set_xlabel("nominal pressure p̄ [Pa]")
    ax2.set_ylabel("local γ = (dU/d ln p̄)/σ")
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def cutoff_study(ds: xr.Dataset, dissipation: float, stiffness: float,
                 tolerance: float) -> Figure:
    """W and dP/dU relative to the unfiltered surface against the cut-off wavelengths."""
    fig = Figure(figsize=(9.5, 4.0))
    ax1, ax2 = fig.subplots(1, 2, sharey=True)
    for ax, dim, title in ((ax1, "short", "wavelengths < λ_s removed"),
                           (ax2, "long", "wavelengths > λ_l removed")):
        lam = ds[f"{dim}_cutoff"].values * 1e6
        ax.semilogx(lam, ds[f"dissipation_{dim}"].values / dissipation, "o-",
                    label="dissipation per cycle")
        ax.semilogx(lam, ds[f"stiffness_{dim}"].values / stiffness, "s--",
                    label="dP/dU at P0")
        ax.axhspan(1 - tolerance, 1 + tolerance, color="0.85", label=f"±{tolerance:.0%}")
        ax.xaxis.set_major_formatter(ScalarFormatter())
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel(f"cut-off λ_{dim[0]} [µm]")
        ax.set_title(title, fontsize=10)
        ax.grid(alpha=0.3)
    ax1.set_ylabel("relative to the unfiltered surface")
    ax1.legend(fontsize=8)
    fig.tight_layout()
    return fig


def dissipation_vs_phase(ds: xr.Dataset) -> Figure:
    """Dissipation per cycle against the phase lag of Q behind P."""
    fig = Figure(figsize=(5.5, 4.0))
    ax = fig.add_subplot()
    ax.plot(ds.phase.values, ds.dissipation_phase.values * 1e6, "o-")
    ax.set_xlabel("phase φ [rad]")
    ax.set_ylabel("dissipation per cycle [µJ]")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def fretting_map(ds: xr.Dataset, mean_density: float, smooth: float) -> Figure:
    """Local dissipation per unit area over the punch radius, rough law against smooth."""
    fig = Figure(figsize=(5.5, 4.0))
    ax = fig.add_subplot()
    r = ds.ring_radius.values * 1e3
    ax.step(r, ds.ring_dissipation.values, where="mid", label="rough law, per ring")
    ax.axhline(mean_density, color="C1", ls="--", label="rough joint, W/A")
    ax.axhline(0.0, color="k", lw=0.8,
               label=f"smooth punch (W = {smooth:.3g} J)")
    ax.set_xlabel("radius r [mm]")
    ax.set_ylabel("dissipation per cycle per area [J/m²]")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig
