"""Figures of two-rod runs: loops, histories, regularisation, limit curve, regime maps.

Non-finite values (undamped poles, points without a steady state) are masked, never drawn
as numbers; points that did not converge are marked with a legend entry; axes whose data
vary by less than round-off get a range set by the data's size, not by the noise.
"""

from __future__ import annotations

import numpy as np
from matplotlib.colors import TwoSlopeNorm
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, LogLocator, MaxNLocator, NullFormatter

_PREFIX = ((1.0, ""), (1e-3, "m"), (1e-6, "µ"), (1e-9, "n"))


def _scaled(values, unit: str):
    """``values`` rescaled to an SI prefix so that tick labels stay short; (array, label)."""
    v = np.asarray(values, dtype=float)
    big = float(np.nanmax(np.abs(v))) if np.isfinite(v).any() else 0.0
    for f, p in _PREFIX:
        if big >= f or f == _PREFIX[-1][0]:
            return v / f, f"{p}{unit}"
    return v, unit  # pragma: no cover


def _floor_range(ax, values, axis="y", rel=0.01):
    """Give a (nearly) constant curve a range of ±rel of its size instead of its round-off."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return
    mid, span = 0.5 * (v.max() + v.min()), float(np.ptp(v))
    half = rel * max(abs(mid), float(np.max(np.abs(v))), 1e-300)
    if span < half:
        (ax.set_ylim if axis == "y" else ax.set_xlim)(mid - half, mid + half)

__all__ = ["hysteresis", "time_history", "regularisation", "limit_curve", "regime_map",
           "position_map"]


def hysteresis(ds) -> Figure:
    """Interface torque against relative rotation: dynamic steady cycle and quasi-static."""
    fig = Figure(figsize=(5.5, 4.2))
    ax = fig.add_subplot()
    both = np.concatenate([ds.delta_qs.values, ds.delta_dyn.values])
    _, unit = _scaled(both, "rad")
    f = dict((p + "rad", k) for k, p in _PREFIX)[unit]
    ax.plot(ds.delta_qs / f, ds.T_qs, color="0.4", lw=1.5, ls="--", label="quasi-static")
    ax.plot(ds.delta_dyn / f, ds.T_dyn, color="C0", lw=1.5, label="dynamic")
    ax.set_xlabel(f"interface relative rotation δ [{unit}]")
    ax.set_ylabel("interface torque T [N m]")
    ax.xaxis.set_major_locator(MaxNLocator(nbins=6))
    ax.yaxis.set_major_locator(MaxNLocator(nbins=7))
    ax.ticklabel_format(useOffset=False)
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    return fig


def time_history(ds) -> Figure:
    """Interface torque over the steady cycle, dynamic and quasi-static, and N(t).

    A constant normal force (no axial excitation) gets no panel of its own: its value is
    given in the title; a varying one is drawn below the torque.
    """
    t = ds.time.values / ds.time.values[-1]
    N = np.asarray(ds.N.values, float)
    constant = bool(np.ptp(N) <= 1e-12 * max(float(np.max(np.abs(N))), 1e-300))
    fig = Figure(figsize=(6, 3.2 if constant else 4.5))
    ax, ax2 = (fig.subplots(), None) if constant else fig.subplots(2, 1, sharex=True)
    ax.plot(t, ds.T_dyn, label="dynamic")
    ax.plot(t, ds.T_qs, ls="--", color="0.4", label="quasi-static")
    ax.set_ylabel("T [N m]")
    ax.legend()
    ax.grid(alpha=0.3)
    if constant:
        ax.set_title(f"interface torque; normal force N = {N[0]:.6g} N (constant)",
                     fontsize=10)
        ax.set_xlabel("t / period")
    else:
        ax2.plot(t, N, color="C2")
        _floor_range(ax2, N)
        ax2.ticklabel_format(axis="y", useOffset=False)
        ax2.set_ylabel("N [N]")
        ax2.set_xlabel("t / period")
        ax2.grid(alpha=0.3)
    fig.tight_layout()
    return fig


#: the markers of the interface models in :func:`regularisation`
_REG_STYLES = (("distributed", "-o", "C0"), ("jenkins", "-s", "C1"), ("coulomb", "-^", "C2"),
               ("iwan", "-d", "C3"))


def regularisation(reg: dict) -> Figure:
    """Quasi-static dissipation per cycle versus amplitude, log–log, per interface model.

    Left: partial slip only, the drive amplitudes Θa < Θg (beyond, T* = T_g for every
    amplitude: the gross-slip points would stack on one vertical line); a model that
    dissipates nothing below T_g (Jenkins, Coulomb: stick, then gross slip) is said so,
    not drawn. The legend gives each model's log–log slope d log D / d log T* (fitted
    over T* < 0.95 T_g, :func:`slipcycle.rods.regularisation.regularisation_study`); the
    rings have no power law (D ∝ (T* − T_s)² past the rim's threshold T_s = ¾ T_g), so
    theirs is not quoted as one. Right: every amplitude, with the slope d log D / d log Θa
    over the largest amplitudes (→ 1 in gross slip, where the models coincide).
    """
    fig = Figure(figsize=(11, 4.4))
    ax1, ax2 = fig.subplots(1, 2)
    none_below = []
    below = np.asarray(reg["amplitude"]) / reg["theta_gross"] < 1.0
    for m, style, color in _REG_STYLES:
        r = reg[m]
        D, T = np.asarray(r["dissipation"]), np.asarray(r["T_amp"]) / reg["gross_slip_torque"]
        ok = D > 0
        partial = ok & below
        s = r["slope_microslip"]
        if not partial.any():
            none_below.append(m)
        elif m == "distributed":
            ax1.loglog(T[partial], D[partial], style, ms=3, color=color,
                       label=f"{m}: D ∝ (T* − T_s)², no power law")
        else:
            slope = f"log–log slope {s:.2f}" if s is not None else "too few points to fit"
            ax1.loglog(T[partial], D[partial], style, ms=3, color=color,
                       label=f"{m}: {slope}")
        sm = r["slope_macroslip"]
        ax2.loglog(reg["amplitude"][ok] / reg["theta_gross"], D[ok], style, ms=3, color=color,
                   label=f"{m}: slope {sm:.2f} at large Θa" if sm is not None else m)
    ax1.axvline(0.75, color="0.6", lw=0.8, ls=":", label="rim slips: T_s = ¾ T_g")
    if none_below:
        ax1.text(0.02, 0.02, f"{', '.join(none_below)}: no dissipation below T_g\n"
                 "(stick, then gross slip)", transform=ax1.transAxes, fontsize=7,
                 va="bottom")
    ax1.set_xlabel("torque amplitude T* / T_g")
    ax1.set_ylabel("dissipation per cycle [J]")
    ax1.set_title("partial slip (Θa < Θg)")
    ax2.set_xlabel("drive amplitude Θa / Θg")
    ax2.set_title("every amplitude (the models coincide in gross slip)")
    for a in (ax1, ax2):
        a.grid(alpha=0.3, which="both")
        a.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    return fig


def limit_curve(lim: dict, tolerance: float) -> Figure:
    """Torque and dissipation ratios dynamic/quasi-static versus Ω/ω1 at the case amplitude.

    Poles (undamped resonances of the welded system) are dotted vertical lines; points
    without a periodic steady state are marked ×; NaN values are gaps.
    """
    fig = Figure(figsize=(6.4, 4.4))
    ax = fig.add_subplot()
    r = np.asarray(lim["ratios"])
    ok = np.asarray(lim["converged"], dtype=bool)
    TR = np.where(ok, lim["torque_ratio"], np.nan)
    DR = np.where(ok, lim["dissipation_ratio"], np.nan)
    ax.semilogx(r, TR, "-o", ms=3, label="T_dyn / T_qs")
    if np.isfinite(DR).any():
        ax.semilogx(r, DR, "-s", ms=3, label="D_dyn / D_qs")
    ax.axhspan(1 - tolerance, 1 + tolerance, color="C2", alpha=0.15, label=f"±{tolerance:g}")
    x = lim["qs_limit_frequency_ratio"]
    ax.axvline(x, color="C0", ls="--", lw=1, label=f"limit (torque) {x:.3g}")
    xd = lim["qs_limit_frequency_ratio_dissipation"]
    if xd is not None:
        ax.axvline(xd, color="C1", ls=":", lw=1, label=f"limit (dissipation) {xd:.3g}")
    for k, w in enumerate(lim.get("poles", ())):
        ax.axvline(w, color="C3", ls=(0, (1, 2)), lw=1.2,
                   label="pole (undamped resonance)" if k == 0 else None)
    bad = ~ok & ~np.asarray(lim.get("pole", np.zeros(r.size, bool)), dtype=bool)
    if bad.any():
        ax.plot(r[bad], np.ones(bad.sum()), "x", color="k", ms=7, ls="none",
                label=f"not converged ({int(bad.sum())})")
    vals = np.concatenate([TR[np.isfinite(TR)], DR[np.isfinite(DR)]])
    if vals.size and vals.min() > 0 and vals.max() / vals.min() > 5.0:
        ax.set_yscale("log")  # resonance peaks: decades
    _plain_log_ticks(ax.xaxis)
    ax.set_xlabel("frequency ratio Ω / ω1")
    ax.set_ylabel("dynamic / quasi-static")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def _plain_log_ticks(axis):
    """Plain numbers (0.1, 1, 2) on a log axis instead of 10-power minor labels."""
    axis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
    axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    axis.set_minor_formatter(NullFormatter())


def _mark_unconverged(ax, x, y, CV, PL=None):
    """× on every cell without a periodic steady state (○ at poles); legend entries."""
    X, Y = np.meshgrid(x, y, indexing="ij")
    PL = np.zeros(CV.shape, bool) if PL is None else PL
    bad = ~CV & ~PL
    if bad.any():
        ax.plot(X[bad], Y[bad], "x", color="k", ms=5, mew=1.0, ls="none",
                label=f"not converged ({int(bad.sum())})")
    if PL.any():
        ax.plot(X[PL], Y[PL], "o", mfc="none", color="k", ms=5, ls="none",
                label=f"pole ({int(PL.sum())})")
    if bad.any() or PL.any():
        ax.legend(fontsize=7, loc="lower left", framealpha=0.8)


def _map(ax, x, y, Z, tolerance, title, CV=None, PL=None):
    """One log10-ratio panel; Z and the masks have shape (len(x), len(y))."""
    Z = np.asarray(Z, dtype=float)
    if CV is not None:
        Z = np.where(CV, Z, np.nan)  # no colour for a point without a steady state
    Zl = np.log10(np.clip(np.where(np.isfinite(Z), Z, np.nan), 1e-3, 1e3))
    lim = max(float(np.nanmax(np.abs(Zl))) if np.isfinite(Zl).any() else 1.0, 0.05)
    pc = ax.pcolormesh(x, y, Zl.T, shading="nearest", cmap="RdBu_r",
                       norm=TwoSlopeNorm(0.0, -lim, lim))
    if np.isfinite(Zl).sum() >= 4 and x.size > 1 and y.size > 1:
        err = np.abs(Z.T - 1.0)
        if np.nanmin(err) < tolerance < np.nanmax(err):
            ax.contour(x, y, err, levels=[tolerance], colors="k", linewidths=1.2)
    ax.set_xscale("log")
    _plain_log_ticks(ax.xaxis)
    ax.set_title(title, fontsize=9)
    if CV is not None:
        _mark_unconverged(ax, x, y, np.asarray(CV, bool),
                          None if PL is None else np.asarray(PL, bool))
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
                           (axs[1], "dissipation_ratio", "log10 D_dyn/D_qs\n(blank: no "
                            "quasi-static loss)")):
        pc = _map(ax, x, y, m[key], tolerance, title + f"  (contour: ±{tolerance:g})",
                  m.get("converged"), m.get("pole"))
        for w in m["resonances"]:
            ax.axvline(w, color="0.2", ls="--", lw=0.8)
        ax.set_xlabel("Ω / ω1   (stiffness-dominated ← → inertia-dominated)")
        ax.set_ylabel("Θa / Θg  (stick < 0.75 < microslip < 1 ≲ gross)")
        ax.set_yscale("log")
        _plain_log_ticks(ax.yaxis)
        fig.colorbar(pc, ax=ax)
    fig.tight_layout()
    return fig


def position_map(p: dict, tolerance: float) -> Figure:
    """log10(T_dyn/T_qs) and log10(D_dyn/D_qs) over Ω/ω1 × L1/(L1 + L2)."""
    fig = Figure(figsize=(11, 4.5))
    axs = fig.subplots(1, 2)
    for ax, key, title in ((axs[0], "torque_ratio", "log10 T_dyn/T_qs"),
                           (axs[1], "dissipation_ratio", "log10 D_dyn/D_qs\n(blank: no "
                            "quasi-static loss)")):
        pc = _map(ax, p["ratios"], p["fractions"], p[key].T, tolerance, title,
                  None if "converged" not in p else np.asarray(p["converged"]).T,
                  None if "pole" not in p else np.asarray(p["pole"]).T)
        ax.set_xlabel("Ω / ω1")
        ax.set_ylabel("interface position L1 / (L1 + L2)")
        fig.colorbar(pc, ax=ax)
    fig.tight_layout()
    return fig
