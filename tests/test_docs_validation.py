"""Every number of the validation tables in docs/validation.md, recomputed.

Each row of the page's tables has an id; :data:`CHECKS` maps it to a function returning
(reference, slipcycle): the independent reference (closed form, brute force, exact
transfer-matrix solution) and slipcycle's value. The tests parse the page and check that
its reference, its slipcycle value and its relative difference are what the code gives
today, to the printed digits, and that the difference is within the row's tolerance, so
the page cannot drift. ``python tests/test_docs_validation.py`` prints the rows to paste.
"""

from __future__ import annotations

import math
import re
import sys
from itertools import combinations
from pathlib import Path

import numpy as np
import pytest

import slipcycle
from slipcycle.discrete import DiscreteLoad, FrictionalSystem, simulate
from slipcycle.discrete.case import read_discrete_case
from slipcycle.discrete.shakedown import lambda1, lambda2, safe_region
from slipcycle.halfspace import (
    ContactElasticity,
    Cylinder2D,
    HalfspaceModel,
    RoughExponential,
    make_bed,
    run_history,
    solve,
    sphere,
)
from slipcycle.halfspace.tractions import abel_operators, dissipation_density
from slipcycle.io import read_case
from slipcycle.rods import interface_torque_frf
from slipcycle.rods.case import parse_case as parse_rods_case

PAGE = Path(__file__).resolve().parents[1] / "docs" / "validation.md"
STEEL = ContactElasticity.from_materials((200e9, 200e9), (0.3, 0.3), plane=False)
STEEL_2D = ContactElasticity.from_materials((200e9, 200e9), (0.3, 0.3), plane=True)


# -- half-space ------------------------------------------------------------------------------

def _stick_ratio(profile, lam, f, P, ratio, n=4000, steps=400):
    """Cattaneo: constant P, Q ramped to ratio·fP; stick size / contact size at the end."""
    bed = make_bed(profile, friction=f, compliance_ratio=lam, P_max=P, n_sliders=n)
    an = np.concatenate([np.linspace(0, P, 51)[1:], np.full(steps, P)])
    at = np.concatenate([np.zeros(50), np.linspace(0, ratio * f * P, steps + 1)[1:]])
    res = run_history(bed, an, at, np.full(4, P), np.full(4, ratio * f * P), max_cycles=1)
    c = bed.stick_extent(np.array([res.first_slip[an.size - 1]]))[1][0]
    return c / float(profile.contact_size(P))


def cattaneo_sphere():
    """c/a = (1 − Q/fP)^{1/3} (Cattaneo 1938; Mindlin 1949), Q/fP = 0.5."""
    prof = sphere(0.01, STEEL.contact_modulus)
    return 0.5 ** (1 / 3), _stick_ratio(prof, STEEL.compliance_ratio, 0.5, 100.0, 0.5)


def cattaneo_cylinder():
    """c/a = (1 − Q/fP)^{1/2} for the plane (2-D) cylinder, Q/fP = 0.5."""
    prof = Cylinder2D(0.02, STEEL_2D.contact_modulus)
    return 0.5 ** 0.5, _stick_ratio(prof, 1.0, 0.4, 1e5, 0.5)


def _mindlin_model(ratio, P=100.0, f=0.5, **settings):
    return HalfspaceModel.harmonic(sphere(0.01, STEEL.contact_modulus), f,
                                   STEEL.compliance_ratio, P0=P, Q1=ratio * f * P,
                                   elasticity=STEEL, **settings)


def mindlin_loss():
    """Mindlin–Deresiewicz loss per cycle [J], P = 100 N, f = 0.5, Q* = 30 N:
    W = 18 λ f² P²/(5 E* a) [1 − (1 − x)^{5/3} − (5x/6)(1 + (1 − x)^{2/3})], x = Q*/fP."""
    P, f, x = 100.0, 0.5, 0.6
    model = _mindlin_model(x, P, f, max_cycles=3)
    a = float(model.profile.contact_size(P))
    ref = (18 * STEEL.compliance_ratio * f**2 * P**2 / (5 * STEEL.contact_modulus * a)
           * (1 - (1 - x) ** (5 / 3) - 5 * x / 6 * (1 + (1 - x) ** (2 / 3))))
    _, res = solve(model)
    return ref, float(res.global_dissipation[-1])


def permanent_stick_load():
    """P_D = P − Q*/f [N] for constant P and Q = ±Q* (P = 100 N, Q* = 30 N, f = 0.5)."""
    res = slipcycle.run(slipcycle.example_path("halfspace_sphere"))
    return 100.0 - 30.0 / 0.5, float(res.summary()["permanent_stick_load"])


def _masing_rough(q):
    """Rough law U = γσ ln P, constant P, Q = ±q fP: Ŵ by the Masing construction."""
    return -4 * q * math.log(1 - q) - 8 * ((1 - q) * math.log(1 - q) + q)


def _rough_w_hat(q, P0=250.0, f=0.4, gs=2e-6, lam=1.2):
    model = HalfspaceModel.harmonic(RoughExponential(gs), f, lam, P0=P0,
                                    Q1=q * f * P0, max_cycles=3, steps_per_cycle=200,
                                    n_sliders=1000)
    _, res = solve(model)
    return float(res.global_dissipation[-1]) / (lam * gs * f**2 * P0)


def rough_masing_07():
    """Ŵ = W/(λ γσ f² P0) of the rough law at Q̂1 = 0.7, P̂1 = 0."""
    return _masing_rough(0.7), _rough_w_hat(0.7)


def rough_masing_09():
    """The same at Q̂1 = 0.9."""
    return _masing_rough(0.9), _rough_w_hat(0.9)


def dissipation_peak():
    """Fraction of the slip annulus at which W(r) peaks, Q*/fP = 0.6 (docs/theory)."""
    from scipy.optimize import brentq

    x = 0.6
    g = (1 - x) ** (1 / 3)

    def cond(rho):
        s = math.sqrt(rho**2 - g**2)
        return (g * s * (3 * rho**2 - 2)
                + rho**2 * (3 * rho**2 - 2 - 2 * g**2) * math.acos(g / rho))

    rho = brentq(cond, g * (1 + 1e-12), 1.0, xtol=1e-14)
    model = _mindlin_model(x, max_cycles=3, steps_per_cycle=64)
    bed, res = solve(model)
    ops = abel_operators(bed, n_radii=4000)
    W = dissipation_density(ops, res.last_t, res.last_z)
    r = ops.radius / float(model.profile.contact_size(100.0))
    k = int(np.argmax(W))
    y0, y1, y2 = W[k - 1:k + 2]
    r_peak = r[k] + 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2) * (r[1] - r[0])
    return (rho - g) / (1 - g), (r_peak - g) / (1 - g)


# -- coupled systems -----------------------------------------------------------------------

def jenkins_loss():
    """One uncoupled node (a Jenkins element): D = 4 fP (Q1 − fP)/k [J]."""
    k, P0, f, Q1 = 2.0, 1.0, 0.4, 0.7
    system = FrictionalSystem([[k]], [[0.0]], [[2.0 * k]], f)
    load = DiscreteLoad.harmonic([P0], [0.0], [0.0], [Q1], [0.0], [0.0])
    res = simulate(system, load, cycles=20, steps_per_cycle=64, tol=1e-12)
    return 4 * f * P0 * (Q1 - f * P0) / k, float(res.dissipation_per_cycle)


def _triangle_region():
    dc = read_discrete_case(read_case(slipcycle.example_path("shakedown_triangle")))
    return safe_region(dc.system, dc.load)


def _edges_brute_force(region, lam, tol=1e-9):
    """Vertices of S(λ) by intersecting every pair of constraint lines (no LP), and the
    number of constraints that carry an edge (two distinct vertices on their line)."""
    G, h = region.G, region.h(lam)
    scale = np.abs(h).max() + 1.0
    verts = []
    for i, j in combinations(range(len(h)), 2):
        M = G[[i, j]]
        if abs(np.linalg.det(M)) < 1e-14:
            continue
        v = np.linalg.solve(M, h[[i, j]])
        if np.all(G @ v <= h + tol * scale):
            verts.append(v)
    verts = np.array(verts).reshape(-1, 2)
    edges = 0
    for k in range(len(h)):
        on = verts[np.abs(G[k] @ verts.T - h[k]) <= tol * scale] if len(verts) else verts
        if len(on) >= 2 and np.ptp(on, axis=0).max() > 1e-9 * (np.ptp(verts) + 1e-300):
            edges += 1
    return verts, edges


def _bisect(pred, lo, hi, tol=1e-10):
    """Largest λ in [lo, hi] at which pred holds (pred(lo) true, pred(hi) false)."""
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if pred(mid) else (lo, mid)
    return lo


def triangle_lambda1():
    """λ1 of the triangle example: last λ with all four constraints active (Ahn et al. 2008);
    reference: vertex enumeration and bisection, no linear program."""
    region = _triangle_region()
    ref = _bisect(lambda lam: _edges_brute_force(region, lam)[1] == 4, 0.0, 1.5)
    return ref, float(lambda1(region, lambda2(region)[0])["lambda1"])


def triangle_lambda2():
    """λ2 of the triangle example: last λ with a non-empty safe region."""
    region = _triangle_region()
    ref = _bisect(lambda lam: len(_edges_brute_force(region, lam)[0]) > 0, 0.0, 3.0)
    return ref, float(lambda2(region)[0])


# -- rods ----------------------------------------------------------------------------------

def rods_torque_ratio_stuck():
    """T_dyn/T_qs of the stuck rods example at Ω = 0.3 ω1: modal solution (50 modes per rod)
    against the exact transfer-matrix solution with the interface stiffness k_t J_a."""
    text = slipcycle.example_path("rods_spec").read_text() + "[run]\nregularisation = false\n"
    res = slipcycle.run(text)
    rc = parse_rods_case(read_case(slipcycle.example_path("rods_spec")))
    k = rc.rods.interface_torsional_stiffness
    T = interface_torque_frf(rc.rods, rc.exc.frequency, k, 0.0)["T"]
    return abs(T) * (rc.rods.rods_compliance + 1 / k), float(res.summary()["torque_ratio"])


def rods_inception_ratio():
    """Slip-inception over gross-slip torque of the uniform-pressure rings: 3/4."""
    rc = parse_rods_case(read_case(slipcycle.example_path("rods_spec")))
    N = rc.exc.axial_force
    return 0.75, rc.rods.slip_inception_torque(N) / rc.rods.gross_slip_torque(N)


CHECKS = {
    "cattaneo_sphere": cattaneo_sphere,
    "cattaneo_cylinder": cattaneo_cylinder,
    "mindlin_loss": mindlin_loss,
    "permanent_stick_load": permanent_stick_load,
    "rough_masing_0.7": rough_masing_07,
    "rough_masing_0.9": rough_masing_09,
    "dissipation_peak": dissipation_peak,
    "jenkins_loss": jenkins_loss,
    "triangle_lambda1": triangle_lambda1,
    "triangle_lambda2": triangle_lambda2,
    "rods_torque_ratio": rods_torque_ratio_stuck,
    "rods_inception_ratio": rods_inception_ratio,
}


# -- the page --------------------------------------------------------------------------------

ROW = re.compile(r"^\|\s*`(?P<id>[^`]+)`\s*\|(?P<rest>.*)\|\s*$")


def page_rows() -> dict[str, dict]:
    """Rows of the page's tables: id -> reference, slipcycle, relative difference, tolerance
    (the last four cells of the row)."""
    rows = {}
    for line in PAGE.read_text(encoding="utf-8").splitlines():
        m = ROW.match(line)
        if not m:
            continue
        cells = [c.strip() for c in m["rest"].split("|")]
        ref, val, diff, tol = cells[-4:]
        rows[m["id"]] = {"reference": float(ref), "slipcycle": float(val),
                         "difference": float(diff), "tolerance": float(tol)}
    return rows


def relative_difference(ref: float, val: float) -> float:
    return (val - ref) / abs(ref) if ref != 0 else val


def fmt_row(key: str) -> str:
    ref, val = CHECKS[key]()
    return f"`{key}` | {ref:.6g} | {val:.6g} | {relative_difference(ref, val):.1e}"


def test_every_check_is_on_the_page_and_every_row_is_checked():
    assert set(page_rows()) == set(CHECKS)


def _same_printed(page: float, value: float, digits: int = 6) -> bool:
    """``page`` is ``value`` printed to ``digits`` significant digits (±1 in the last)."""
    if value == 0.0:
        return page == 0.0
    unit = 10.0 ** (math.floor(math.log10(abs(value))) - digits + 1)
    return abs(page - value) <= 1.01 * unit


@pytest.mark.parametrize("key", sorted(CHECKS))
def test_validation_page_number_is_what_the_code_computes(key):
    row = page_rows()[key]
    ref, val = CHECKS[key]()
    diff = relative_difference(ref, val)
    assert _same_printed(row["reference"], ref), (key, "reference", ref)
    assert _same_printed(row["slipcycle"], val), (key, "slipcycle", val)
    # the difference is printed with 2 digits; round-off of a tiny difference may move it
    assert abs(row["difference"] - diff) <= 0.06 * abs(diff) + 1e-15, (key, diff)
    assert abs(diff) <= row["tolerance"], (key, diff)


if __name__ == "__main__":  # print the rows to paste into docs/validation.md
    for name in (sys.argv[1:] or CHECKS):
        print(fmt_row(name))
