"""The demonstration report of ``slipcycle demo``: shipped example cases, each run by
its model, and a small rough-surface dissipation map Ŵ(φ) (Barber, *Frictional systems
under periodic loads*, Fig. 7) with the cubic law at small amplitude.
"""

from __future__ import annotations

import json
import logging
import time
import tomllib
from collections.abc import Callable, Mapping
from pathlib import Path

from slipcycle._version import __version__
from slipcycle.api import apply_overrides, run, toml_text
from slipcycle.examples import example_text

__all__ = ["DEMO_CASES", "DEMO_FILES", "write_report"]

log = logging.getLogger("slipcycle")

#: case name -> (title, shipped example file) of the demonstration report
DEMO_FILES = {
    "mindlin_sphere": ("Hertzian sphere, constant P, oscillating Q (Mindlin–Deresiewicz)",
                       "halfspace_sphere"),
    "sphere_out_of_phase": ("Sphere with normal and tangential loads a quarter-cycle apart",
                            "halfspace_sphere_out_of_phase"),
    "rough_contact": ("Rough nominally flat contact, dP/dU = P/(γσ)", "halfspace_rough"),
    "discrete_two_node": ("Coupled two-node system under out-of-phase loads",
                          "discrete_two_node"),
    "rods_microslip": ("Two steel rods, distributed interface, just past slip inception",
                       "rods_microslip"),
}

#: case name -> (title, TOML text) of the demonstration report, read from the example
#: cases shipped with the package (:mod:`slipcycle.examples`)
DEMO_CASES = {name: (title, example_text(file)) for name, (title, file) in DEMO_FILES.items()}

#: the bolted lap-joint example at a size that keeps the demo short (its mesh unrefined,
#: two protocols, no mesh-convergence meshes): dotted case keys -> values
LAP_JOINT_DEMO = {"lap_joint.refine": 0, "lap_joint.convergence.coarsening": [],
                  "lap_joint.protocols.names": ["sequential", "simultaneous"],
                  "run.steps_per_cycle": 12, "output.fields": []}
DEMO_CASES["bolted_lap_joint"] = (
    "Bolted lap joint: does the tightening order decide the damping? (two bolts, coarse "
    "mesh)",
    toml_text(apply_overrides(tomllib.loads(example_text("bolted_lap_joint")),
                              LAP_JOINT_DEMO)))


def write_report(out: Path, cases: Mapping[str, tuple[str, str]] | None = None, *,
                 progress: Callable[[float, float], None] | None = None) -> Path:
    """Run every demo case into ``out`` and write ``out/report.md``.

    Parameters
    ----------
    out : Path
        Report directory (created by the caller); each case's results go to
        ``out/<case>/`` (summary.json, result.nc, figures/), a small Ŵ map to
        ``out/rough_w_map/``.
    cases : mapping, optional
        Case name -> (title, TOML text); default :data:`DEMO_CASES`. Each case is run by
        its model through :func:`slipcycle.run`.

    progress : callable, optional
        ``progress(done, total)`` after each case (and the map).

    Returns
    -------
    Path
        ``out/report.md``. One diagnostic line per case goes to the ``slipcycle`` logger
        (INFO).
    """
    # solvers, xarray and matplotlib load here, not when `slipcycle --help` lists commands
    import numpy as np

    from slipcycle.io import parse_case_text, write_outputs
    from slipcycle.io.results import to_jsonable
    from slipcycle.studies.w_hat_map import w_hat_map_study

    cases = DEMO_CASES if cases is None else cases
    lines = [f"# slipcycle demo report (version {__version__})", ""]
    for i, (name, (title, text)) in enumerate(cases.items(), 1):
        t0 = time.perf_counter()
        case = parse_case_text(text.strip() + "\n")
        outputs = run(case).to_outputs()
        write_outputs(out / name, outputs, case.text, None)
        dt = time.perf_counter() - t0
        s = to_jsonable(outputs.summary)
        unit = s.get("units", {}).get("dissipation_per_cycle", "")
        log.info("[%d/%d] %s: dissipation_per_cycle = %s %s (%.1f s)", i, len(cases) + 1,
                 name, s.get("dissipation_per_cycle"), unit, dt)
        if progress is not None:
            progress(i, len(cases) + 1)
        # steady_state_class: the class in the words every model shares (a rods summary
        # has no steady_state of its own)
        keys = [k for k in ("steady_state", "steady_state_class", "dissipation_per_cycle",
                            "cycles_run",
                            "permanent_stick_size", "W_hat", "slipping_nodes", "f_crit",
                            "omega1", "torque_ratio", "dissipation_per_cycle_qs",
                            "protocols", "protocol_dissipation_per_cycle",
                            "dissipation_spread", "orders_differ")
                if k in s]
        units = s.get("units", {})
        lines += [f"## {title}", "", f"Case `{name}` ({dt:.2f} s):", "", "```toml",
                  case.text.strip(), "```", "", "| quantity | value | unit |", "|---|---|---|"]
        lines += [f"| `{k}` | {json.dumps(s[k])} | {units.get(k, '')} |" for k in keys]
        lines.append("")
        # a warning of the run (e.g. a dissipation not checked for mesh convergence) is
        # part of its answer: the report shows it beside the numbers
        warning = str(s.get("message", "")).partition("WARNING: ")[2]
        if warning:
            lines += [f"**WARNING: {warning}**", ""]
        for fig in sorted((out / name / "figures").glob("*.png")):
            lines.append(f"![{fig.stem}]({name}/figures/{fig.name})")
        lines.append("")

    # A small Ŵ map against the phase, and the cubic law at small amplitude: the study of
    # `slipcycle map` (its result builds the Dataset and names the figures)
    t0 = time.perf_counter()
    Q1 = np.array([0.2, 0.4, 0.6, 0.8])
    study = w_hat_map_study(np.array([0.4]), Q1, np.linspace(-np.pi, np.pi, 37), 0.4, Q1, {})
    write_outputs(out / "rough_w_map", study.to_outputs())
    log.info("[%d/%d] rough_w_map (%.1f s)", len(cases) + 1, len(cases) + 1,
             time.perf_counter() - t0)
    if progress is not None:
        progress(len(cases) + 1, len(cases) + 1)
    lines += ["## Rough-surface dissipation map Ŵ(φ) (Barber, Frictional systems under "
              "periodic loads, Fig. 7)", "",
              "Ŵ = W/(λ γσ f² P0) against the phase φ at P̂1 = 0.4; gaps are load paths that "
              "reach gross slip. Second figure: Ŵ against Q̂1 with the law (2/3)Q̂1³.", "",
              "![w_hat_vs_phase](rough_w_map/figures/w_hat_vs_phase.png)",
              "![w_hat_cubic_law](rough_w_map/figures/w_hat_cubic_law.png)", ""]
    report = out / "report.md"
    report.write_text("\n".join(lines), encoding="utf-8")
    return report
