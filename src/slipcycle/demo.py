"""The demonstration report of ``slipcycle demo``: the embedded example cases, each run by
its model, and a small rough-surface dissipation map Ŵ(φ) (Barber, *Frictional systems
under periodic loads*, Fig. 7) with the cubic law at small amplitude.
"""

from __future__ import annotations

import json
import time
from collections.abc import Mapping
from pathlib import Path

from slipcycle._version import __version__
from slipcycle.api import run

__all__ = ["DEMO_CASES", "write_report"]

#: case name -> (title, TOML text) of the embedded examples
DEMO_CASES = {
    "mindlin_sphere": ("Hertzian sphere, constant P, oscillating Q (Mindlin–Deresiewicz)", """
model = "halfspace"
[halfspace]
profile = "sphere"
radius = 0.01
E = [200e9, 200e9]
nu = [0.3, 0.3]
friction = 0.5
[loading]
P0 = 100.0
Q1 = 30.0
[run]
cycles = 3
steps_per_cycle = 400
"""),
    "sphere_out_of_phase": ("Sphere with normal and tangential loads a quarter-cycle apart", """
model = "halfspace"
[halfspace]
profile = "sphere"
radius = 0.01
E = [200e9, 200e9]
nu = [0.3, 0.3]
friction = 0.5
[loading]
P0 = 100.0
P1 = 40.0
Q0 = 5.0
Q1 = 25.0
phase = 1.5707963267948966
[run]
cycles = 4
steps_per_cycle = 400
"""),
    "rough_contact": ("Rough nominally flat contact, dP/dU = P/(γσ)", """
model = "halfspace"
[halfspace]
profile = "rough_exponential"
gamma_sigma = 1.0e-6
nu = [0.3, 0.3]
friction = 0.6
[loading]
P0 = 1000.0
P1 = 400.0
Q1 = 300.0
phase = 1.0
[run]
cycles = 4
steps_per_cycle = 400
"""),
    "discrete_two_node": ("Coupled two-node system under out-of-phase loads", """
model = "discrete"
[discrete]
A = [[1.0, -0.3], [-0.3, 0.8]]
B = [[0.4, 0.1], [-0.2, 0.3]]
C = [[1.0, -0.2], [-0.2, 1.0]]
friction = 0.5
initial_slip = [0.0, 0.0]
[loading]
lam = 1.0
p0 = [1.0, 1.0]
q0 = [0.0, 0.0]
p1 = [0.3, 0.2]
p1_phase = [0.0, 1.0]
q1 = [0.4, 0.5]
q1_phase = [0.5, 2.0]
[run]
cycles = 40
steps_per_cycle = 400
"""),
    "rods_microslip": ("Two steel rods, distributed interface, just past slip inception", """
model = "rods"
[rods]
L = [0.5, 0.5]
radius = [0.01, 0.01]
E = [200e9, 200e9]
nu = [0.3, 0.3]
density = [7850.0, 7850.0]
friction = 0.3
axial_force = 1.0e4
interface = "distributed"
interface_stiffness = 1.0e13
damping_ratio = 0.01
modes = 50
[loading]
rotation_amplitude = 0.014
frequency_ratio = 0.3
"""),
}



def write_report(out: Path, cases: Mapping[str, tuple[str, str]] | None = None) -> Path:
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

    Returns
    -------
    Path
        ``out/report.md``. Progress lines (one per case) go to stdout.
    """
    # solvers, xarray and matplotlib load here, not when `slipcycle --help` lists commands
    import numpy as np
    import xarray as xr

    from slipcycle.halfspace.wmap import w_hat_map
    from slipcycle.io import RunOutputs, parse_case_text, write_outputs
    from slipcycle.io.results import to_jsonable
    from slipcycle.plot.halfspace import w_hat_cubic_law, w_hat_vs_phase

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
        print(f"[{i}/{len(cases) + 1}] {name}: dissipation_per_cycle = "
              f"{s.get('dissipation_per_cycle')} {unit} ({dt:.1f} s)", flush=True)
        keys = [k for k in ("steady_state", "dissipation_per_cycle", "cycles_run",
                            "permanent_stick_size", "W_hat", "slipping_nodes", "f_crit",
                            "omega1", "torque_ratio", "dissipation_per_cycle_qs")
                if k in s]
        units = s.get("units", {})
        lines += [f"## {title}", "", f"Case `{name}` ({dt:.2f} s):", "", "```toml",
                  case.text.strip(), "```", "", "| quantity | value | unit |", "|---|---|---|"]
        lines += [f"| `{k}` | {json.dumps(s[k])} | {units.get(k, '')} |" for k in keys]
        lines.append("")
        for fig in sorted((out / name / "figures").glob("*.png")):
            lines.append(f"![{fig.stem}]({name}/figures/{fig.name})")
        lines.append("")

    # A small Ŵ map against the phase, and the cubic law at small amplitude
    t0 = time.perf_counter()
    phase = np.linspace(-np.pi, np.pi, 37)
    Q1 = np.array([0.2, 0.4, 0.6, 0.8])
    W = w_hat_map([0.4], Q1, phase)
    q = np.geomspace(0.01, 0.5, 10)
    Wq = w_hat_map([0.0], q, [0.0])[0, :, 0]
    ds = xr.Dataset(
        {"W_hat": (("P1_hat", "Q1_hat", "phase"), W,
                   {"units": "1", "long_name": "W / (lam gamma_sigma f^2 P0)"})},
        coords={"P1_hat": ("P1_hat", [0.4], {"units": "1", "long_name": "P1 / P0"}),
                "Q1_hat": ("Q1_hat", Q1, {"units": "1", "long_name": "Q1 / (f P0)"}),
                "phase": ("phase", phase, {"units": "rad",
                                           "long_name": "lag of Q behind P"})})
    write_outputs(out / "rough_w_map", RunOutputs(
        summary={"model": "halfspace", "analysis": "w_hat_map",
                 "units": {"W_hat": "1", "P1_hat": "1", "Q1_hat": "1", "phase": "rad"}},
        dataset=ds, figures={"w_hat_vs_phase": lambda: w_hat_vs_phase(ds, 0.4),
                             "w_hat_cubic_law": lambda: w_hat_cubic_law(q, Wq, "P̂1 = 0")}))
    print(f"[{len(cases) + 1}/{len(cases) + 1}] rough_w_map "
          f"({time.perf_counter() - t0:.1f} s)", flush=True)
    lines += ["## Rough-surface dissipation map Ŵ(φ) (Barber, Frictional systems under "
              "periodic loads, Fig. 7)", "",
              "Ŵ = W/(λ γσ f² P0) against the phase φ at P̂1 = 0.4; gaps are load paths that "
              "reach gross slip. Second figure: Ŵ against Q̂1 with the law (2/3)Q̂1³.", "",
              "![w_hat_vs_phase](rough_w_map/figures/w_hat_vs_phase.png)",
              "![w_hat_cubic_law](rough_w_map/figures/w_hat_cubic_law.png)", ""]
    report = out / "report.md"
    report.write_text("\n".join(lines), encoding="utf-8")
    return report
