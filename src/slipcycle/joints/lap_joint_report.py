"""The Markdown report of a tightening-order study (``report.md`` beside summary.json).

It states what the model shows for the joint studied: whether the steady dissipation
depends on the tightening order (the spread of the protocols' dissipation against the
study's ``difference_tol``), per protocol the steady-state class, the dissipation per
cycle (total and per bolt region) and the permanently stuck area, and the mesh
convergence of each protocol's dissipation, with a warning where it is not converged.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["report_markdown", "verdict", "showcase_markdown"]

FIGURES = ("dissipation_by_protocol", "slip_maps", "dissipation_maps",
           "dissipation_by_bolt", "dissipation_history")


def _g(x, digits: int = 4) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    if isinstance(x, float) and math.isinf(x):
        return "∞"
    return f"{x:.{digits}g}"


def verdict(result) -> str:
    """One paragraph: do the tightening orders give different steady dissipation?"""
    d = result.dissipation
    names = [p.name for p in result.protocols]
    spread = result.dissipation_spread
    tol = result.settings.difference_tol
    classes = sorted({r.solution.steady_state for r in result.runs})
    if result.orders_differ:
        lo, hi = names[int(np.argmin(d))], names[int(np.argmax(d))]
        text = (f"**The tightening order changes the steady dissipation** of this joint: "
                f"from {d.min():.4g} J per cycle ({lo}) to {d.max():.4g} J ({hi}), a "
                f"spread of {100 * spread:.3g} % (above the tolerance "
                f"{100 * tol:.3g} %).")
    else:
        text = (f"**The tightening orders give the same steady dissipation** for this "
                f"joint, {d.max():.4g} J per cycle, to within {100 * spread:.3g} % (the "
                f"tolerance is {100 * tol:.3g} %).")
    text += (" Steady-state class" + ("es: " if len(classes) > 1 else ": ")
             + ", ".join(classes) + ".")
    errors = [x.relative_error for x in result.convergence
              if x is not None and not x.converged]
    if all(x is None for x in result.convergence):
        text += (" **The dissipation is not checked for mesh convergence** (one mesh): "
                 "compare the orders on this mesh only.")
    elif any(e is None for e in errors):
        # non-monotone values or meshes too close: there is no estimate to compare with
        text += (" **But the dissipation is not shown mesh-converged** and its error is not "
                 "known (see Mesh convergence): compare the orders on this mesh only.")
    elif errors and not all(math.isfinite(e) for e in errors):
        text += (" **But the dissipation vanishes under refinement** (it extrapolates to "
                 "zero): on this mesh it is a discretisation effect, not physics.")
    elif errors:
        worst = max(errors)
        text += (f" **But the dissipation is not mesh-converged** (estimated relative error "
                 f"up to {100 * worst:.3g} %)")
        text += (", larger than the spread between the orders: the mesh decides the "
                 "dissipation more than the tightening order does." if worst > spread
                 else ".")
    text += _order_against_mesh(result, spread)
    if not result.converged:
        text += " Some protocols did not reach their steady state: raise `run.cycles`."
    return text


def _rank_alike(d: np.ndarray, tol: float) -> bool:
    """Every pair of protocols that differs on the finest mesh (last row of ``d``, mesh ×
    protocol) by more than ``tol`` of its largest value differs with the same sign on
    every mesh; closer pairs (e.g. mirror images) count as ties."""
    fine = d[-1]
    gap = fine[:, None] - fine[None, :]
    apart = np.abs(gap) > tol * np.abs(fine).max()
    return bool(all(np.all(np.sign(row[:, None] - row[None, :])[apart] == np.sign(gap)[apart])
                    for row in d))


def _order_against_mesh(result, spread: float) -> str:
    """For mesh-converged orders that differ by less than the mesh error: whether the
    orders rank the same on every mesh (the error is then common to them)."""
    conv = [x for x in result.convergence if x is not None]
    if not result.orders_differ or not conv or not all(x.converged for x in conv):
        return ""
    worst = max(x.relative_error for x in conv)
    if worst <= spread:
        return ""
    d = np.asarray(result.mesh.dissipation, float)            # mesh × protocol
    spreads = ", ".join(f"{100 * (row.max() - row.min()) / row.max():.3g} %" for row in d)
    if _rank_alike(d, result.settings.difference_tol):
        return (f" The spread is below the estimated mesh error of the dissipation (up to "
                f"{100 * worst:.3g} %), but the orders rank the same on all {d.shape[0]} "
                f"meshes (spreads {spreads}, coarse → fine): the mesh error is common to "
                "them and their difference is resolved.")
    return (f" The spread is below the estimated mesh error of the dissipation (up to "
            f"{100 * worst:.3g} %) and the orders do not rank the same on every mesh "
            f"(spreads {spreads}, coarse → fine): their difference is not resolved.")


def report_markdown(result) -> str:
    """The report of ``result`` as Markdown text (figures linked from ``figures/``)."""
    s = result.settings
    c = result.contact
    lines = ["# Bolted lap joint: does the tightening order decide the damping?", "",
             verdict(result), ""]
    if c.description:
        lines += ["## Joint", "", "| parameter | value |", "|---|---|"]
        lines += [f"| `{k}` | {v} |" for k, v in c.description.items()]
        lines.append("")
    lines += [f"{c.n_nodes} contact nodes, {c.bolt_count} bolts, contact area "
              f"{c.node_area.sum() * 1e6:.4g} mm²; preload {s.preload:.4g} N per bolt, "
              f"service force {s.service_amplitude:.4g} sin θ N, friction coefficient "
              f"{s.friction:g}.", "",
              "## Protocols", "",
              "| protocol | order | steady state | dissipation per cycle [J] | per bolt "
              "region [J] | permanently stuck area [mm²] | stuck fraction | slipping nodes "
              "| cycles |",
              "|---|---|---|---|---|---|---|---|---|"]
    region = result.dissipation_per_region
    stuck = result.stuck_area
    total_area = c.node_area.sum()
    for j, (p, r) in enumerate(zip(result.protocols, result.runs, strict=True)):
        sol = r.solution
        lines.append(f"| {p.name} | {p.label} | {sol.steady_state} | "
                     f"{sol.dissipation_per_cycle:.6g} | "
                     f"{', '.join(f'{x:.4g}' for x in region[j])} | {stuck[j] * 1e6:.4g} | "
                     f"{stuck[j] / total_area:.3f} | {len(sol.slipping_nodes)} | "
                     f"{r.cycles_run} |")
    lines.append("")
    lines += _bolt_table(result)
    conv = result.convergence
    lines += ["## Mesh convergence", ""]
    if all(x is None for x in conv):
        lines += ["One mesh only (`[lap_joint.convergence] coarsening = []`): the mesh "
                  "error of the dissipation is not estimated.", ""]
    else:
        sp = result.mesh.spacing
        lines += ["| protocol | " + " | ".join(f"h = {h * 1e3:.3g} mm" for h in sp)
                  + " | extrapolated [J] | order | relative error | converged |",
                  "|---|" + "---|" * (len(sp) + 4)]
        for j, (p, x) in enumerate(zip(result.protocols, conv, strict=True)):
            vals = " | ".join(f"{v:.5g}" for v in result.mesh.dissipation[:, j])
            lines.append(f"| {p.name} | {vals} | {_g(x.extrapolated)} | "
                         f"{_g(x.observed_order, 3)} | {_g(x.relative_error, 2)} | "
                         f"{'yes' if x.converged else '**no**'} |")
        lines.append("")
        bad = [(p.name, x.message) for p, x in zip(result.protocols, conv, strict=True)
               if not x.converged]
        if bad:
            lines += ["> **Warning: the dissipation is not mesh-converged** for "
                      + ", ".join(n for n, _ in bad) + f" (tolerance {s.mesh_rtol:g}). "
                      + bad[0][1] + ". The differences between protocols are meaningful "
                      "only where they exceed the mesh error.", ""]
        else:
            lines += ["The dissipation of every protocol is mesh-converged to "
                      f"{100 * s.mesh_rtol:g} %.", ""]
    lines += ["## Figures", ""]
    lines += [f"![{name}](figures/{name}.png)" for name in FIGURES]
    lines.append("")
    if any(r.case.fields for r in result.runs):
        lines += ["Contact fields of the steady cycle of each protocol (ParaView): "
                  "`fields/<protocol>/interface.*` (listed in `fields/README.txt`).", ""]
    return "\n".join(lines)


def _bolt_table(result) -> list[str]:
    """The bolt forces of every protocol: after the assembly, least and largest over the
    steady cycle (elastic bolts change them; constant-force bolts keep their targets)."""
    F = result.bolt_force
    if np.isnan(F).all():
        return []
    lo, hi = result.bolt_force_range
    kb = result.contact.bolt_stiffness
    kind = (f"Elastic bolts, k_b = {kb:.4g} N/m" if kb > 0 else "Constant-force bolts")
    lines = ["## Bolt forces", "", f"{kind}; per bolt after the assembly, and "
             "its range over the steady cycle [N].", "",
             "| protocol | after assembly | least in the cycle | largest in the cycle |",
             "|---|---|---|---|"]
    for j, p in enumerate(result.protocols):
        lines.append(f"| {p.name} | {', '.join(f'{x:.6g}' for x in F[j])} | "
                     f"{', '.join(f'{x:.6g}' for x in lo[j])} | "
                     f"{', '.join(f'{x:.6g}' for x in hi[j])} |")
    return [*lines, ""]


def showcase_markdown(result) -> str:
    """The showcase sections of the report (:class:`~slipcycle.joints.lap_joint_showcase.
    LapJointShowcase`): the B = 0 check per protocol and mesh, and the shakedown window."""
    lines = ["", ""]
    d = result.decoupled
    if d is not None:
        sp = result.mesh.spacing
        lines += ["## B = 0: one answer for every protocol", "",
                  "The same protocols with the normal–tangential coupling removed (B = 0): "
                  "by the frictional Melan converse every protocol that ends with the same "
                  "loads has one steady dissipation (Klarbring, Ciavarella & Barber 2007); "
                  "with elastic bolts only the bolt forces the assembly leaves can differ.",
                  "", "| protocol | " + " | ".join(
                      f"D at h = {h * 1e3:.3g} mm [µJ] | D with B = 0 [µJ]" for h in sp)
                  + " | bolt forces with B = 0 [N] |",
                  "|---|" + "---|---|" * len(sp) + "---|"]
        for j, p in enumerate(result.protocols):
            vals = " | ".join(f"{1e6 * result.mesh.dissipation[m, j]:.5g} | "
                              f"{1e6 * d.mesh.dissipation[m, j]:.5g}" for m in range(len(sp)))
            forces = ", ".join(f"{x:.6g}" for x in d.bolt_force[j])
            lines.append(f"| {p.name} | {vals} | {forces} |")
        spreads, spreads0 = result.mesh_spreads()
        lines += ["", "Spread (max − min)/max over the protocols, per mesh (coarse → fine): "
                  f"coupled {', '.join(f'{100 * x:.3g} %' for x in spreads)}; B = 0 "
                  f"{', '.join(f'{100 * x:.3g} %' for x in spreads0)}.", ""]
    if result.windows:
        k = len(result.protocols)
        lines += ["## Shakedown window", "",
                  "Per mesh: λ2 with separation of each protocol's assembled state and the "
                  "bracket of the largest service amplitude at which it shakes down (the "
                  "engine on the amplitude grid, then bisected); λ1 is where every "
                  "protocol shakes down, the class window where one shakes down and "
                  "another slips (Barber 2012, §3).", "",
                  "| mesh h [mm] | protocol | λ2 [N] | shakes down at [N] | slips at [N] |",
                  "|---|---|---|---|---|"]
        for h, w in zip(result.window_spacing, result.windows, strict=True):
            for j in range(k):
                lo, hi = w.limits[j]
                lines.append(f"| {h * 1e3:.3g} | {w.labels[j]} | {w.lambda2[j]:.5g} | "
                             f"{lo:.5g} | {_g(float(hi), 5)} |")
        lines.append("")
        proto = result.protocol_class_window()
        for i, (h, w) in enumerate(zip(result.window_spacing, result.windows, strict=True)):
            win, pw = w.class_window, proto[i]
            a, b = w.lambda1_bracket
            lines.append(f"- h = {h * 1e3:.3g} mm: λ1 in [{a:.5g}, {_g(b, 5)}] N; class "
                         "window " + ("none" if win is None else
                                      f"[{win[0]:.5g}, {win[1]:.5g}] N")
                         + " (the protocols and the safe state), between the protocols "
                         + ("none" if pw is None else f"[{pw[0]:.5g}, {pw[1]:.5g}] N")
                         + f" (figure `shakedown_map_mesh{i}`).")
        lines += [""] + [f"![shakedown_map_mesh{i}](figures/shakedown_map_mesh{i}.png)"
                         for i in range(len(result.windows))] + [""]
    return "\n".join(lines)

