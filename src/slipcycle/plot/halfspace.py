"""Figures of half-space runs; each function takes the result Dataset, returns a Figure.

matplotlib is imported when a figure is drawn, not with this module: a run prepares its
figures (:meth:`slipcycle.halfspace.outputs.HalfspaceResult.figures`) without drawing them,
and the command line draws them in a process that has matplotlib loaded already.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    import xarray as xr
    from matplotlib.figure import Figure

__all__ = ["hysteresis", "load_path", "tractions", "dissipation_density", "stick_zone",
           "w_hat_vs_phase", "w_hat_cubic_law"]


def _figure(width: float, height: float) -> Figure:
    """A Figure of ``width`` x ``height`` inches, not managed by pyplot."""
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height))


def _last_cycle(ds: xr.Dataset) -> xr.Dataset:
    """The last *completed* cycle (empty when none completed)."""
    n_done = ds.sizes.get("cycle_run", 0)
    return ds.isel(step=np.flatnonzero(ds.cycle.values == n_done - 1) if n_done else [])


def _closed_last_cycle(ds: xr.Dataset) -> xr.Dataset:
    """The last completed cycle with the state it starts from (θ = 0, the step before its
    first sample θ = 2π/S): the loop drawn through it is closed, with no gap between the
    last sample θ = 2π and the first."""
    n_done = ds.sizes.get("cycle_run", 0)
    if not n_done:
        return _last_cycle(ds)
    steps = np.flatnonzero(ds.cycle.values == n_done - 1)
    return ds.isel(step=np.r_[steps[0] - 1, steps] if steps[0] > 0 else steps)


def _partial_cycle(ds: xr.Dataset) -> xr.Dataset:
    """Steps of a cycle cut short by gross slip (empty otherwise)."""
    n_done = ds.sizes.get("cycle_run", 0)
    return ds.isel(step=np.flatnonzero(ds.cycle.values == n_done))


def _mark_gross_slip(ax, ds: xr.Dataset, x: str) -> None:
    """Cross at the state where gross slip was reached (x: "V" or "P")."""
    if "gross_slip_Q" not in ds:
        return
    if x == "P":
        xv = float(ds.gross_slip_P)
    else:  # the last displacement reached before gross slip
        xv = float(ds.V.values[-1]) * 1e6 if ds.sizes["step"] else 0.0
    ax.plot([xv], [float(ds.gross_slip_Q)], "x", color="C3", ms=9, mew=2,
            label="gross slip (first state with |Q| ≥ fP)")


def hysteresis(ds: xr.Dataset) -> Figure:
    """Tangential load Q against displacement V: assembly, last completed cycle (closed:
    drawn from the state it starts from, :func:`_closed_last_cycle`), gross slip."""
    fig = _figure(5.5, 4.2)
    ax = fig.add_subplot()
    asm = ds.isel(step=np.flatnonzero(ds.cycle.values < 0))
    last, part = _closed_last_cycle(ds), _partial_cycle(ds)
    ax.plot(np.r_[0.0, asm.V.values] * 1e6, np.r_[0.0, asm.Q.values], color="0.6", lw=1,
            label="assembly")
    if last.sizes["step"]:
        ax.plot(last.V * 1e6, last.Q, color="C0", lw=1.8, label="last cycle")
    if part.sizes["step"]:
        ax.plot(part.V * 1e6, part.Q, color="C1", lw=1.2, label="cycle cut by gross slip")
    _mark_gross_slip(ax, ds, "V")
    if "gross_slip_Q" in ds:
        ax.set_title("Hysteresis: gross slip, no steady cycle")
    elif ds.sizes.get("cycle_run", 0):
        W = float(ds.dissipation.values[-1])
        ax.set_title(f"Hysteresis loop  (∮Q dV = {W:.4g} {ds.dissipation.attrs['units']})")
    ax.set_xlabel("tangential displacement V [µm]")
    ax.set_ylabel(f"tangential load Q [{ds.Q.attrs['units']}]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def load_path(ds: xr.Dataset, friction: float) -> Figure:
    """Load path in the P–Q plane with the friction cone |Q| = fP."""
    fig = _figure(5.5, 4.2)
    ax = fig.add_subplot()
    Pmax = max(float(ds.P.max()) if ds.sizes["step"] else 0.0,
               float(ds.gross_slip_P) if "gross_slip_P" in ds else 0.0) * 1.1 or 1.0
    ax.fill_between([0, Pmax], [0, friction * Pmax], [0, -friction * Pmax], color="C2",
                    alpha=0.08, label=f"partial slip |Q| < fP (f = {friction:g})")
    asm = ds.isel(step=np.flatnonzero(ds.cycle.values < 0))
    last, part = _closed_last_cycle(ds), _partial_cycle(ds)
    # the assembly starts unloaded; if it ends in gross slip, it ends at that state
    P_a, Q_a = np.r_[0.0, asm.P.values], np.r_[0.0, asm.Q.values]
    if "gross_slip_P" in ds and not ds.sizes.get("cycle_run", 0) \
            and not _partial_cycle(ds).sizes["step"]:
        P_a, Q_a = np.r_[P_a, float(ds.gross_slip_P)], np.r_[Q_a, float(ds.gross_slip_Q)]
    ax.plot(P_a, Q_a, color="0.6", lw=1, label="assembly")
    if last.sizes["step"]:
        ax.plot(last.P, last.Q, color="C0", lw=1.8, label="periodic cycle")
    if part.sizes["step"]:
        ax.plot(part.P, part.Q, color="C1", lw=1.2, label="cycle cut by gross slip")
    _mark_gross_slip(ax, ds, "P")
    ax.set_xlabel(f"normal load P [{ds.P.attrs['units']}]")
    ax.set_ylabel(f"tangential load Q [{ds.Q.attrs['units']}]")
    ax.set_xlim(0, Pmax)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    return fig


def tractions(ds: xr.Dataset) -> Figure:
    """Pressure and shear traction over the radius at the snapshot instants.

    Every curve is in the legend: the shear tractions q(r) (solid) and the pressures p(r)
    (dashed; one curve where the pressure is the same at every snapshot, as under a
    constant normal load). The permanent stick radius c of the steady cycle is marked.

    A kink of q(r) inside the permanent stick zone is the load path's, not the grid's.
    The default assembly loads P and Q proportionally from zero (no slip while
    Q/P < f, so q = (Q/P) p; Ciavarella 1998), and the first reversal of Q then slips an
    annulus b < r < a with (b/a)³ = 1 − ΔQ/((f + Q/P) P) (Cattaneo's solution with
    f + Q/P in place of f). That annulus is deeper than the steady one,
    (c/a)³ = 1 − ΔQ/(2fP) (Mindlin & Deresiewicz 1953), and the traction it leaves at
    r = b is locked in by the stick of every later cycle. For the sphere of the
    ``halfspace_sphere`` example (P = 100 N, Q = ±30 N, f = 0.5) b = 0.63 a = 0.12 mm
    inside c = 0.74 a = 0.14 mm; an assembly that applies P before Q leaves no kink
    (``tests/test_figures_content.py`` checks both against these closed forms).
    """
    fig = _figure(8.2, 4.4)
    ax = fig.add_subplot()
    r = ds.radius.values * 1e3
    p = ds.pressure.values / 1e6
    thetas = ds.snapshot_theta.values
    for i, th in enumerate(thetas):
        ax.plot(r, ds.shear_traction.values[i] / 1e6, color=f"C{i}", lw=1.6,
                label=f"q, θ = {th:.2f} rad")
    # one dashed curve per distinct pressure (equal P, equal p), named by its instants
    drawn = np.zeros(len(thetas), bool)
    for i in range(len(thetas)):
        if drawn[i]:
            continue
        same = ~drawn & np.all(np.isclose(p, p[i], rtol=1e-12, atol=0.0), axis=1)
        drawn |= same
        when = ("the same at every θ" if same.all() else
                "θ = " + ", ".join(f"{th:.2f}" for th in thetas[same]) + " rad")
        ax.plot(r, p[i], color="0.3" if same.all() else f"C{i}", lw=0.8, ls="--",
                label=f"p, {when}")
    if "permanent_stick_size" in ds:
        c = float(ds.permanent_stick_size) * 1e3
        ax.axvline(c, color="0.4", ls=":", lw=1,
                   label=f"permanent stick radius {c:.3g} mm")
    ax.axhline(0, color="k", lw=0.5)
    ax.set_xlabel("radius r [mm]")
    ax.set_ylabel("traction [MPa]")
    ax.set_title("Shear traction q(r) and pressure p(r) in the last cycle")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    return fig


def _contact_edge(radius: np.ndarray) -> float:
    """The outer edge a of the radii of :func:`slipcycle.halfspace.tractions.abel_operators`
    (the midpoints of equal intervals of [0, a])."""
    return float(radius[-1] + 0.5 * (radius[-1] - radius[-2])) if radius.size > 1 \
        else float(2 * radius[0])


def dissipation_density(ds: xr.Dataset) -> Figure:
    """Local dissipation per unit area W(r) over the last cycle.

    The Dataset holds W at the midpoints of equal intervals of [0, a]; the curve is closed
    at the contact edge r = a with W(a) = 0, exact there (the pressure vanishes at the edge
    and |q| ≤ f p, so no work is done), instead of ending at the last midpoint half an
    interval inside, on the steep flank of W.
    """
    fig = _figure(5.5, 4.0)
    ax = fig.add_subplot()
    radius = ds.radius.values
    a = _contact_edge(radius)
    ax.plot(np.r_[radius, a] * 1e3, np.r_[ds.dissipation_density.values, 0.0], color="C3",
            label="W(r), closed by W(a) = 0")
    ax.axvline(a * 1e3, color="0.6", ls="--", lw=0.8, label=f"contact edge a = {a * 1e3:.3g} mm")
    if "permanent_stick_size" in ds:
        c = float(ds.permanent_stick_size) * 1e3
        ax.axvline(c, color="0.4", ls=":", label=f"permanent stick radius {c:.3g} mm")
    ax.legend(fontsize=8, loc="upper left")
    ax.set_xlabel("radius r [mm]")
    ax.set_ylabel("W(r) [J/m²]")
    ax.set_title("Local frictional dissipation per cycle")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def stick_zone(ds: xr.Dataset) -> Figure:
    """Stick-zone size against the cycle angle in the last cycle."""
    fig = _figure(5.5, 3.6)
    ax = fig.add_subplot()
    last = _last_cycle(ds)
    ax.plot(last.theta, last.stick_size * 1e3, label="stick zone")
    ax.set_xlabel("cycle angle θ [rad]")
    ax.set_ylabel("stick radius / half-width [mm]")
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def w_hat_vs_phase(ds: xr.Dataset, P1_hat: float) -> Figure:
    """Ŵ against the phase φ for several Q̂1 at fixed P̂1 (Barber 2012, Fig. 7)."""
    fig = _figure(6.0, 4.2)
    ax = fig.add_subplot()
    sub = ds.W_hat.sel(P1_hat=P1_hat, method="nearest")
    for q in sub.Q1_hat.values:
        ax.plot(sub.phase, sub.sel(Q1_hat=q), label=f"Q̂1 = {q:.2g}")
    ax.set_xlabel("phase φ [rad]")
    ax.set_ylabel("Ŵ = W / (λ γσ f² P0)")
    ax.set_title(f"Rough-contact dissipation, P̂1 = {float(sub.P1_hat):.2g}")
    ax.set_xticks(np.pi * np.array([-1, -0.5, 0, 0.5, 1]), ["-π", "-π/2", "0", "π/2", "π"])
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def w_hat_cubic_law(Q1_hat: np.ndarray, W_hat: np.ndarray, label: str) -> Figure:
    """log–log Ŵ against Q̂1 with the small-amplitude law (2/3) Q̂1³."""
    fig = _figure(5.5, 4.2)
    ax = fig.add_subplot()
    ax.loglog(Q1_hat, W_hat, "o-", label=label)
    ax.loglog(Q1_hat, 2 / 3 * Q1_hat**3, "k--", label="(2/3) Q̂1³")
    ax.set_xlabel("Q̂1 = Q1 / (f P0)")
    ax.set_ylabel("Ŵ")
    ax.grid(alpha=0.3, which="both")
    ax.legend()
    fig.tight_layout()
    return fig
