"""Case file → two-rod analysis → results (``model = "rods"``, SPEC §5, §6).

Keys of ``[rods]``: L, radius, E, nu, density (two values each: rod 1 clamped, rod 2
driven), friction, axial_force (F0, N; may also sit in [loading]), interface (welded |
distributed | coulomb | jenkins | iwan), interface_stiffness (k_t, N/m³), damping_ratio (ζ,
default 0.01), modes (per rod, default 50), rings (default 100; also the number of Iwan
elements), static_correction (default true), iwan_chi / iwan_beta (optional: Segalman
parameters instead of the fit).
Keys of ``[loading]``: rotation_amplitude (Θ_a, rad), frequency_ratio (Ω/ω1) or frequency
(Ω, rad/s), axial_amplitude (F_a, N, default 0), axial_phase (ψ, rad, default 0).
Keys of ``[run]``: steps_per_cycle (default 400), cycles (maximum, default 300), steady_tol
(default 1e-6), regularisation (bool, default true), regularisation_points (default 25).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from slipcycle.io import Case, RunOutputs, Section
from slipcycle.rods.model import INTERFACES, Excitation, Rod, TwoRods

__all__ = ["RodsCase", "parse_case", "run_case", "analyse"]


@dataclass
class RodsCase:
    rods: TwoRods
    exc: Excitation
    frequency_ratio: float
    omega1: float
    modes: int
    rings: int
    static_correction: bool
    steps_per_cycle: int
    cycles: int
    steady_tol: float
    regularisation: bool
    regularisation_points: int
    iwan_chi: float | None = None
    iwan_beta: float | None = None


def _either(sec: Section, other: Section, key: str, default, **bounds) -> float:
    if sec.has(key) and other.has(key):
        raise sec.error(key, f"given in both [{sec.prefix}] and [{other.prefix}]; keep one")
    where = other if other.has(key) else sec
    return where.float(key, default, **bounds)


def parse_case(case: Case, *, finish: bool = True) -> RodsCase:
    """Validate a rods case completely (raises CaseError naming the key)."""
    from slipcycle.rods.welded import omega1

    sec = case.section("rods")
    load = case.section("loading")
    run = case.section("run", required=False)
    L = sec.array("L", shape=(2,), gt=0.0)
    r = sec.array("radius", shape=(2,), gt=0.0)
    E = sec.array("E", shape=(2,), gt=0.0)
    nu = sec.array("nu", shape=(2,), gt=-1.0, le=0.5)
    rho = sec.array("density", shape=(2,), gt=0.0)
    f = sec.float("friction", ge=0.0)
    iface = sec.string("interface", "distributed", choices=INTERFACES)
    kt = sec.float("interface_stiffness", None, gt=0.0)
    if kt is None and iface in ("distributed", "jenkins", "iwan"):
        raise sec.error("interface_stiffness", f"required for interface = {iface!r}")
    zeta = sec.float("damping_ratio", 0.01, ge=0.0, lt=1.0)
    modes = sec.int("modes", 50, ge=1, le=2000)
    rings = sec.int("rings", 100, ge=2, le=100000)
    static_corr = sec.bool("static_correction", True)
    chi = sec.float("iwan_chi", None, gt=-1.0, le=5.0)
    beta = sec.float("iwan_beta", None, ge=0.0)
    if (chi is None) != (beta is None):
        raise sec.error("iwan_beta" if beta is None else "iwan_chi",
                        "give both iwan_chi and iwan_beta, or neither (then they are fitted)")
    if chi is not None and iface != "iwan":
        raise sec.error("iwan_chi", "only used with interface = 'iwan'")
    F0 = _either(sec, load, "axial_force", None, ge=0.0)
    if F0 is None:
        raise sec.error("axial_force", "required key is missing (mean compressive force F0, N)")
    if F0 <= 0.0 and iface != "welded":
        raise sec.error("axial_force", f"must be > 0 for a frictional interface, got {F0:g}")
    Fa = _either(sec, load, "axial_amplitude", 0.0, ge=0.0)
    psi = _either(sec, load, "axial_phase", 0.0)
    amp = load.float("rotation_amplitude", gt=0.0)
    has_r, has_w = load.has("frequency_ratio"), load.has("frequency")
    if has_r == has_w:
        raise load.error("frequency_ratio", "give exactly one of frequency_ratio (Ω/ω1) and "
                         "frequency (Ω, rad/s)")
    ratio = load.float("frequency_ratio", None, gt=0.0, le=1000.0)
    W = load.float("frequency", None, gt=0.0)
    K = run.int("steps_per_cycle", 400, ge=32, le=200000)
    cycles = run.int("cycles", 300, ge=1, le=100000)
    tol = run.float("steady_tol", 1e-6, gt=0.0, lt=1.0)
    reg = run.bool("regularisation", True)
    reg_pts = run.int("regularisation_points", 25, ge=8, le=400)
    if "limits" in case.data:  # read by `slipcycle limits`; ignored by `slipcycle run`
        case.section("limits").data.clear()
    if finish:
        case.finish()
    try:
        rods = TwoRods(Rod(L[0], r[0], E[0], nu[0], rho[0]), Rod(L[1], r[1], E[1], nu[1], rho[1]),
                       f, iface, kt if kt is not None else math.inf, zeta)
    except ValueError as exc:  # pragma: no cover - all checked above
        key, _, problem = str(exc).partition(": ")
        raise sec.error(key, problem) from None
    if reg and kt is None:
        reg = False  # no interface stiffness: the study needs the rings model
    w1 = omega1(rods)
    if ratio is None:
        ratio = W / w1
    else:
        W = ratio * w1
    exc = Excitation(amp, W, F0, Fa, psi)
    return RodsCase(rods, exc, ratio, w1, modes, rings, static_corr, K, cycles, tol, reg,
                    reg_pts, chi, beta)


def analyse(rc: RodsCase) -> dict:
    """Dynamic steady state, quasi-static loop, slip inception and regularisation study."""
    from slipcycle.rods.interfaces import SegalmanIwan, iwan_bed, make_bed
    from slipcycle.rods.modal import modal_basis, modal_frf, steady_state
    from slipcycle.rods.quasistatic import (
        qs_normal_force,
        quasi_static_loop,
        slip_inception_amplitude,
    )
    from slipcycle.rods.regularisation import regularisation_study
    from slipcycle.rods.welded import natural_frequencies, normal_force_history

    rods, exc = rc.rods, rc.exc
    N0 = exc.axial_force
    iw = None
    if rods.interface == "iwan":
        params = None
        if rc.iwan_chi is not None:
            params = SegalmanIwan(2.0 / 3.0 * rods.friction * N0 * rods.contact_radius,
                                  rods.interface_stiffness * rods.contact_J, rc.iwan_chi,
                                  rc.iwan_beta)
        bed, iw = iwan_bed(rods, N0, rc.rings, params)
    else:
        bed = make_bed(rods, N0, rc.rings)
    basis = modal_basis(rods, rc.modes, rc.static_correction)
    dyn = steady_state(rods, exc, bed, basis, rc.steps_per_cycle, rc.cycles, rc.steady_tol)
    qs = quasi_static_loop(rods, exc, bed, rc.steps_per_cycle)
    # slip inception: stuck response per unit amplitude against the first-slip torque(t)
    K = rc.steps_per_cycle
    tt = np.arange(K) * exc.period / K
    Tdyn_unit = np.real(modal_frf(basis, exc.frequency, bed.stiffness) * (-1j)
                        * np.exp(1j * exc.frequency * tt))
    k0 = bed.stiffness
    C_qs = rods.rods_compliance + (1.0 / k0 if math.isfinite(k0) else 0.0)
    Tqs_unit = np.sin(exc.frequency * tt) / C_qs
    fs_unit = bed.first_slip_torque(1.0)
    N_dyn = np.maximum(normal_force_history(rods, exc, tt), 0.0)
    N_qs = np.maximum(qs_normal_force(exc, tt), 0.0)
    inc_dyn = slip_inception_amplitude(Tdyn_unit, fs_unit * N_dyn)
    inc_qs = slip_inception_amplitude(Tqs_unit, fs_unit * N_qs)
    nat = natural_frequencies(rods.with_(interface="welded"), 5)
    reg = None
    if rc.regularisation:
        reg = regularisation_study(rods, exc, rc.rings, iw, rc.regularisation_points,
                                   rc.steps_per_cycle)
    return {"dyn": dyn, "qs": qs, "bed": bed, "basis": basis, "iwan": iw,
            "inception_dyn": inc_dyn, "inception_qs": inc_qs, "natural": nat, "reg": reg}


def _none_if_inf(x: float):
    return None if not math.isfinite(x) else float(x)


def run_case(case: Case) -> RunOutputs:
    """Validate, solve and package a rods case."""
    import xarray as xr

    from slipcycle.plot import rods as plots

    rc = parse_case(case)
    res = analyse(rc)
    rods, exc, dyn, qs = rc.rods, rc.exc, res["dyn"], res["qs"]
    N0 = exc.axial_force
    sep = bool(np.min(dyn.N) < 0.0)
    summary = {
        "model": "rods",
        "interface": rods.interface,
        "omega1": rc.omega1,
        "omega1_hz": rc.omega1 / (2 * math.pi),
        "natural_frequencies": res["natural"],
        "frequency": exc.frequency,
        "frequency_ratio": rc.frequency_ratio,
        "rotation_amplitude": exc.rotation_amplitude,
        "T_dyn_max": dyn.T_max,
        "T_qs_max": qs.T_max,
        "torque_ratio": dyn.T_max / qs.T_max,
        "dissipation_per_cycle": dyn.dissipation,
        "dissipation_per_cycle_qs": qs.dissipation,
        "dissipation_ratio": (dyn.dissipation / qs.dissipation if qs.dissipation > 0 else None),
        "damping_loss_per_cycle": dyn.damping_loss,
        "input_work_per_cycle": dyn.input_work,
        "energy_balance_error": ((dyn.input_work - dyn.dissipation - dyn.damping_loss)
                                 / max(abs(dyn.input_work), 1e-300)),
        "slip_inception_amplitude_dyn": _none_if_inf(res["inception_dyn"]),
        "slip_inception_amplitude_qs": _none_if_inf(res["inception_qs"]),
        "slip_inception_torque": _none_if_inf(res["bed"].first_slip_torque(N0)),
        "gross_slip_torque": _none_if_inf(res["bed"].capacity(N0)),
        "slipped": dyn.slipped,
        "separation": sep,
        "min_normal_force": float(np.min(dyn.N)),
        "steady_state_reached": dyn.converged,
        "cycles_run": dyn.cycles,
        "steady_residual": dyn.residual,
        "modes_per_rod": rc.modes,
        "rings": rc.rings if rods.interface in ("distributed", "iwan") else None,
        "units": {"omega1": "rad/s", "T_dyn_max": "N m", "dissipation_per_cycle": "J",
                  "slip_inception_amplitude_dyn": "rad"},
    }
    if res["iwan"] is not None:
        iw = res["iwan"]
        summary["iwan"] = {"F_S": iw.F_S, "K_T": iw.K_T, "chi": iw.chi, "beta": iw.beta}
    reg = res["reg"]
    if reg is not None:
        summary["regularisation"] = {
            m: {"slope_microslip": reg[m]["slope_microslip"],
                "slope_macroslip": reg[m]["slope_macroslip"]}
            for m in ("distributed", "jenkins", "coulomb", "iwan")}
        summary["regularisation"]["iwan_fit"] = reg["iwan_params"]
    tatt = {"units": "s"}
    ds = xr.Dataset(
        {"theta": ("time", dyn.theta, {"units": "rad", "long_name": "drive rotation"}),
         "T_dyn": ("time", dyn.T, {"units": "N m", "long_name": "interface torque, dynamic"}),
         "delta_dyn": ("time", dyn.delta, {"units": "rad",
                                            "long_name": "interface relative rotation"}),
         "N": ("time", dyn.N, {"units": "N", "long_name": "normal force (closed contact)"}),
         "T_qs": ("time", qs.T, {"units": "N m", "long_name": "interface torque, quasi-static"}),
         "delta_qs": ("time", qs.delta, {"units": "rad"})},
        coords={"time": ("time", dyn.t, tatt)})
    if reg is not None:
        ds = ds.assign_coords(amplitude=("amplitude", reg["amplitude"], {"units": "rad"}))
        for m in ("distributed", "jenkins", "coulomb", "iwan"):
            ds[f"reg_T_{m}"] = ("amplitude", reg[m]["T_amp"], {"units": "N m"})
            ds[f"reg_D_{m}"] = ("amplitude", reg[m]["dissipation"], {"units": "J"})
    figures = {"hysteresis": lambda: plots.hysteresis(ds),
               "time_history": lambda: plots.time_history(ds)}
    if reg is not None:
        figures["regularisation"] = lambda: plots.regularisation(reg)
    return RunOutputs(summary=summary, dataset=ds, figures=figures)
