"""Figures of two-rod runs (SPEC §5): loops, histories, regularisation, regime maps."""

from __future__ import annotations

import numpy as np
from matplotlib.colors import TwoSlopeNorm
from matplotlib.figure import Figure

__all__ = ["hysteresis", "time_history", "regularisation", "limit_curve", "regime_map",
           "position_map"]


def hysteresis(ds) -> Figure:
    """Interface torque against relative rotation: dynamic steady cycle and quasi-static."""
    fig = Figure(figsize=(5.5, 4.2))
    ax = fig.add_subplot()
    ax.plot(ds.delta_qs * 1e3, ds.T_qs, color="0.4", lw=1.5, ls="--", label="quasi-static")
    ax.plot(ds.delta_dyn * 1e3, ds.T_dyn, color="C0", lw=1.5, label="dynamic")
    ax.set_xlabel("interface relative rotation δ [mrad]")
    ax.set_ylabel("interface torque T [N m]")
    ax.grid(alpha=0.3)
    ax.legend()
    return fig


def time_history(ds) -> Figure:
    """Interface torque over the steady cycle, dynamic and quasi-static, and N(t)."""
    fig = Figure(figsize=(6, 4.5))
    ax, ax2 = fig.subplots(2, 1, sharex=True)
    t = ds.time.values / ds.time.values[-1]
    ax.plot(t, ds.T_dyn, label="dynamic")
    ax.plot(t, ds.T_qs, ls="--", color="0.4", label="quasi-static")
    ax.set_ylabel("T [N m]")
    ax.legend()
    ax.grid(alpha=0.3)
    ax2.plot(t, ds.N, color="C2")
    ax2.set_ylabel("N [N]")
    ax2.set_xlabel("t / period")
    ax2.grid(alpha=0.3)
    return fig


def regularisation(reg: dict) -> Figure:
    """Quasi-static dissipation per cycle versus amplitude, log–log, per interface model."""
    fig = Figure(figsize=(10, 4.2))
    ax1, ax2 = fig.subplots(1, 2)
    for m, style in (("distributed", "-o"), ("jenkins", "-s"), ("coulomb", "-^"),
                     ("iwan", "-d")):
        r = reg[m]
        ok = r["dissipation"] > 0
        s = r["slope_microslip"]
        lab = f"{m} (micro {s:.2f})" if s is not None else f"{m} (no microslip)"
        ax1.loglog(r["T_amp"][ok] / reg["gross_slip_torque"], r["dissipation"][ok], style,
                   ms=3, label=lab)
        sm = r["slope_macroslip"]
        ax2.loglog(reg["amplitude"][ok] / reg["theta_gross"], r["dissipation"][ok], style,
                   ms=3, label=f"{m} (macro {sm:.2f})" if sm is not None else m)
    ax1.axvline(0.75, color="0.6", lw=0.8, ls=":")
    ax1.set_xlabel("torque amplitude T* / T_g")
    ax1.set_ylabel("dissipation per cycle [J]")
    ax1.set_title("partial slip (rim slips at T*/T_g = 3/4)")
    ax2.set_xlabel("drive amplitude Θa / Θg")
    ax2.set_title("up to gross slip")
    for a in (ax1, ax2):
        a.grid(alpha=0.3, which="both")
        a.legend(fontsize=7)
    fig.tight_layout()
    return fig


def limit_curve(lim: dict, tolerance: float) -> Figure:
    """Torque and dissipation ratios dynamic/quasi-static versus Ω/ω1 at the case amplitude."""
    fig = Figure(figsize=(6, 4.2))
    ax = fig.add_subplot()
    r = lim["ratios"]
    ax.semilogx(r, lim["torque_ratio"], "-o", ms=3, label="T_dyn / T_qs")
    ax.semilogx(r, lim["dissipation_ratio"], "-s", ms=3, label="D_dyn / D_qs")
    ax.axhspan(1 - tolerance, 1 + tolerance, color="C2", alpha=0.15, label=f"±{tolerance:g}")
    x = lim["qs_limit_frequency_ratio"]
    ax.axvline(x, color="C0", ls="--", lw=1, label=f"limit (torque) {x:.3g}")
    xd = lim["qs_limit_frequency_ratio_dissipation"]
    if xd is not None:
        ax.axvline(xd, color="C1", ls=":", lw=1, label=f"limit (dissipation) {xd:.3g}")
    ax.set_yscale("log")
    ax.set_xlabel("Ω / ω1")
    ax.set_ylabel("dynamic / quasi-static")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    return fig


def _map(ax, x, y, Z, tolerance, title):
    Zl = np.log10(np.clip(np.where(np.isfinite(Z), Z, np.nan), 1e-3, 1e3))
    lim = max(float(np.nanmax(np.abs(Zl))) if np.isfinite(Zl).any() else 1.0, 0.05)
    pc = ax.pcolormesh(x, y, Zl.T, shading="nearest", cmap="RdBu_r",
                       norm=TwoSlopeNorm(0.0, -lim, lim))
    if np.isfinite(Zl).any() and x.size > 1 and y.size > 1:
        ax.contour(x, y, np.abs(Z.T - 1.0), levels=[tolerance], colors="k", linewidths=1.2)
    ax.set_xscale("log")
    ax.set_title(title, fontsize=9)
    return pc


def regime_map(m: dict, tolerance: float) -> Figure:
    """Maps of log10(T_dyn/T_qs) and log10(D_dyn/D_qs) over Ω/ω1 × Θa/Θg.

    The black contour |ratio − 1| = ε separates the stiffness-dominated (quasi-static valid,
    left) from the inertia-dominated region; dashed lines mark resonances of the stuck system.
    """
    fig = Figure(figsize=(11, 4.5))
    axs = fig.subplots(1, 2)
    x, y = m["ratios"], m["amplitude_factors"]
    for ax, key, title in ((axs[0], "torque_ratio", "log10 T_dyn/T_qs"),
                           (axs[1], "dissipation_ratio", "log10 D_dyn/D_qs")):
        pc = _map(ax, x, y, m[key], tolerance, title + f"  (contour: ±{tolerance:g})")
        for w in m["resonances"]:
            ax.axvline(w, color="0.2", ls="--", lw=0.8)
        ax.set_xlabel("Ω / ω1")
        ax.set_ylabel("Θa / Θg (stick < 0.75 < microslip < 1 ≲ gross slip)")
        ax.set_yscale("log")
        ax.text(0.02, 0.95, "stiffness-dominated", transform=ax.transAxes, fontsize=8,
                va="top")
        ax.text(0.98, 0.95, "inertia-dominated", transform=ax.transAxes, fontsize=8,
                va="top", ha="right")
        fig.colorbar(pc, ax=ax)
    fig.tight_layout()
    return fig


def position_map(p: dict, tolerance: float) -> Figure:
    """log10(T_dyn/T_qs) and log10(D_dyn/D_qs) over Ω/ω1 × L1/(L1 + L2)."""
    fig = Figure(figsize=(11, 4.5))
    axs = fig.subplots(1, 2)
    for ax, key, title in ((axs[0], "torque_ratio", "log10 T_dyn/T_qs"),
                           (axs[1], "dissipation_ratio", "log10 D_dyn/D_qs")):
        pc = _map(ax, p["ratios"], p["fractions"], p[key].T, tolerance, title)
        ax.set_xlabel("Ω / ω1")
        ax.set_ylabel("interface position L1 / (L1 + L2)")
        fig.colorbar(pc, ax=ax)
    fig.tight_layout()
    return fig
