"""Cross-check of the two theories (issue 6, item 4).

A 2-D Hertzian contact (:func:`~slipcycle.fe.builders.cylinder_on_block`, steel-like
E = 210 GPa, ν = 0.49 for both bodies, mixed P2–P0 formulation) is reduced to A, B, C and
run through the coupled discrete solver :func:`slipcycle.discrete.steady.simulate`:
the top face of the cylinder is pressed down by a constant δ_n (with the initial gap
g ≈ x²/2R, the contact is incomplete: nodes outside |x| < a separate), then moved
tangentially by δ_t(θ) = δ_t* sin θ. The model has thickness 1 m, so every force is per
unit length (N/m), as in the plane half-space module.

Three meshes are compared (``elements`` = 20, 40, 80 quadratic elements across the
candidate zone |x| <= 0.5 mm, i.e. node spacing h = 25, 12.5, 6.25 µm; a ≈ 0.317 mm):

(a) contact half-width against Hertz a_H² = 4PR/(πE*), E* = E/(2(1 − ν²)), from a
    frictionless normal solve; (b) the Cattaneo stick zone c/a = (1 − Q/fP)^{1/2} along the
    first (monotonic) quarter cycle; (c) the steady dissipation per cycle against the
    half-space slider bed (:class:`~slipcycle.halfspace.Cylinder2D`, λ_c = 1) driven by the
    same P(θ), Q(θ) (force control; the bulk compliance of the finite bodies in series
    adds no loop area).

The displacement-controlled top gives the tangential load through the elastic bodies;
Q(θ) = −Σ q_j is recorded from the discrete run and replayed in the half-space model.
Observed numbers are in the docstrings of the tests and in docs/fe.md.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipcycle.discrete.lcp import lemke
from slipcycle.discrete.loads import DiscreteLoad
from slipcycle.discrete.model import SLIP_NEG, SLIP_POS, STICK, FrictionalSystem
from slipcycle.discrete.steady import simulate
from slipcycle.fe.builders import cylinder_on_block
from slipcycle.fe.reduction import reduce_problem
from slipcycle.halfspace import ContactElasticity, Cylinder2D, make_bed, run_history

R, E, NU, F = 0.01, 210e9, 0.49, 0.3
CONTACT_WIDTH = 1e-3          # m, candidate zone |x| <= 0.5 mm
DELTA_N = 20e-6               # m, approach of the top face: a ≈ 0.32 mm, P ≈ 1.09 MN/m
TARGET_RATIO = 0.85           # δ_t* chosen for Q*/fP ≈ 0.85 if fully stuck (≈ 0.78 achieved)
STEPS = 400
LEVELS = (20, 40, 80)
E_STAR = E / (2 * (1 - NU**2))


def frictionless_normal(r, delta_n):
    """Frictionless contact under the top approach ``delta_n``: (p, q) per node.

    q = 0 at every node gives v = −A⁻¹(q^w + Bᵀw), and the normal problem becomes the LCP
    w ≥ 0, p = p^w − B A⁻¹ q^w + (C − B A⁻¹ Bᵀ) w ≥ 0, wᵀp = 0.
    """
    qw, pw = r.combine(normal=delta_n)
    Ainv_Bt = np.linalg.solve(r.A, r.B.T)
    M = r.C - r.B @ Ainv_Bt
    w = lemke(M, pw - r.B @ np.linalg.solve(r.A, qw))
    v = -np.linalg.solve(r.A, qw + r.B.T @ w)
    return pw + r.B @ v + r.C @ w, qw + r.A @ v + r.B.T @ w


def hertz_half_width(P):
    """a = (4PR/(πE*))^{1/2} for a load P per unit length."""
    return math.sqrt(4 * P * R / (math.pi * E_STAR))


def _run_level(elements):
    pr = cylinder_on_block(radius=R, cylinder={"height": 0.01, "E": E, "nu": NU},
                           block={"height": 0.01, "E": E, "nu": NU}, width=0.016,
                           contact_width=CONTACT_WIDTH, elements=elements, thickness=1.0)
    r = reduce_problem(pr)
    N, x = r.n, r.coords[:, 0]
    out = {"elements": elements, "h": CONTACT_WIDTH / (2 * elements), "x": x,
           "formulations": r.info["formulations"]}
    # (a) frictionless normal solve
    p, q = frictionless_normal(r, DELTA_N)
    P = p.sum()
    inside = p > 1e-9 * p.max()
    out.update(P_normal=P, a_hertz=hertz_half_width(P),
               a_last=np.abs(x[inside]).max(), a_first_out=np.abs(x[~inside]).min(),
               a_moment=2 * math.sqrt(np.sum(p * x**2) / P), q_normal=q)
    # (b, c) constant top approach, oscillating tangential top displacement
    q0, p0 = r.combine(normal=DELTA_N)
    qt, pt = r.case("tangential")
    dt = TARGET_RATIO * F * P / abs(qt.sum())
    load = DiscreteLoad.harmonic(p0, q0, p1=dt * pt, q1=dt * qt, p1_phase=-np.pi / 2,
                                 q1_phase=-np.pi / 2)
    system = FrictionalSystem(r.A, r.B, r.C, F)
    res = simulate(system, load, cycles=6, steps_per_cycle=STEPS,
                   protocol=np.concatenate([q0, p0])[None], tol=1e-10)
    out["result"] = res
    # stick zone along the first quarter cycle (monotonic loading from Q = 0)
    rows = []
    for k in range(1, STEPS // 4 + 1):
        qk, pk, mk = -res.r[0, k, :N], res.r[0, k, N:], res.modes[0, k]
        ratio = qk.sum() / (F * pk.sum())
        if not 0.1 <= ratio <= 0.75:
            continue
        # Cattaneo: f p − q is the stick correction ∝ (c² − x²)^{1/2}, so its second
        # moment is c²/4 (exact for P2 nodal forces, which integrate x² exactly)
        g = F * pk - qk
        c_moment = 2 * math.sqrt(np.sum(g * x**2) / np.sum(g))
        contact = pk > 0
        stuck = contact & (mk == STICK)
        slipping = contact & ((mk == SLIP_POS) | (mk == SLIP_NEG))
        rows.append((ratio, c_moment, np.abs(x[stuck]).max(), np.abs(x[slipping]).min()))
    out["cattaneo"] = np.array(rows)
    # half-space reference: replay P(θ), Q(θ) of the steady cycle, force controlled
    Pc = res.r[-1, 1:, N:].sum(axis=1)
    Qc = -res.r[-1, 1:, :N].sum(axis=1)
    el = ContactElasticity.from_materials((E, E), (NU, NU), plane=True)
    bed = make_bed(Cylinder2D(R, el.contact_modulus), friction=F,
                   compliance_ratio=el.compliance_ratio, P_max=1.001 * Pc.max(),
                   n_sliders=4000)
    an = np.concatenate([np.linspace(0, Pc[-1], 51)[1:], np.full(50, Pc[-1])])
    at = np.concatenate([np.zeros(50), np.linspace(0, Qc[-1], 51)[1:]])
    hs = run_history(bed, an, at, Pc, Qc, max_cycles=5)
    out.update(P_cycle=Pc, Q_cycle=Qc, halfspace=hs, el=el)
    return out


@pytest.fixture(scope="module")
def levels():
    return {el: _run_level(el) for el in LEVELS}


def test_model_is_nearly_incompressible_and_nearly_uncoupled(levels):
    """Both bodies use the locking-free mixed formulation; similar materials: β = 0."""
    for lv in levels.values():
        assert lv["formulations"] == {"cylinder": "mixed", "block": "mixed"}
        assert lv["el"].dundurs_beta == 0.0 and lv["el"].compliance_ratio == 1.0
        # frictionless solve: q = 0 holds to round-off
        assert np.abs(lv["q_normal"]).max() < 1e-9 * lv["P_normal"]


def test_contact_half_width_matches_hertz(levels):
    """Contact edge a from a frictionless normal solve against Hertz a_H = (4PR/πE*)^{1/2}.

    Tolerance: a_H lies between the last node in contact and the first separated node
    (an interval of one node spacing h = 25, 12.5, 6.25 µm, i.e. 0.079, 0.039, 0.020 a_H),
    widened by 0.5 % of a_H; observed brackets [0.948, 1.027], [0.987, 1.026],
    [0.987, 1.006] a_H. The second-moment estimate a = 2(Σ p x² / Σ p)^{1/2} (exact for an
    elliptical pressure with P2 nodal forces) is within 0.3 % of a_H at every level
    (observed 1.0003, 1.0011, 1.0000: the remainder is the finite size of the bodies,
    a/height = 0.03).
    """
    widths = []
    for lv in levels.values():
        aH = lv["a_hertz"]
        assert lv["a_last"] - 0.005 * aH <= aH <= lv["a_first_out"] + 0.005 * aH, lv
        assert lv["a_first_out"] - lv["a_last"] <= lv["h"] * 1.0001
        assert lv["a_moment"] / aH == pytest.approx(1.0, abs=3e-3)
        widths.append((lv["a_first_out"] - lv["a_last"]) / aH)
    assert widths[0] > widths[1] > widths[2]


def test_cattaneo_stick_zone(levels):
    """Stick half-width c/a against (1 − Q/fP)^{1/2} along monotonic Q, 0.1 ≤ Q/fP ≤ 0.75.

    c from the second moment of the stick correction f p − q (a = a_H). Tolerance per
    level: max |c/a − (1 − Q/fP)^{1/2}| ≤ 0.25 h/a_H (2.0 %, 1.0 %, 0.5 %); observed
    maximum errors 0.92 %, 0.33 %, 0.11 % (about 75 load samples each); they must
    decrease with refinement. The
    node bracket (largest stuck |x|, smallest slipping |x|) must contain the closed-form c
    to within one node spacing.
    """
    errs = []
    for lv in levels.values():
        aH, h = lv["a_hertz"], lv["h"]
        cat = lv["cattaneo"]
        assert len(cat) >= 10
        ratio, c_mom, c_in, c_out = cat.T
        c_exact = np.sqrt(1 - ratio) * aH
        err = np.abs(c_mom - c_exact).max() / aH
        errs.append(err)
        assert err <= 0.25 * h / aH, (lv["elements"], err)
        assert np.all(c_in - h * 1.0001 <= c_exact) and np.all(c_exact <= c_out + h * 1.0001)
    assert errs[0] > errs[1] > errs[2], errs


def test_dissipation_matches_halfspace(levels):
    """Steady dissipation per cycle, discrete solver on the reduced FE model vs the
    half-space slider bed under the same P(θ), Q(θ) (Q*/fP ≈ 0.78).

    Tolerance per level: |D_FE/D_hs − 1| ≤ 0.5 h/a_H (4.0 %, 2.0 %, 1.0 %). Observed
    D_FE/D_hs = 0.9793, 0.9987, 0.9979 (20, 40, 80 elements; D_hs = 0.1354, 0.1362,
    0.1364 J/m per cycle). The error is set by where
    the contact and slip-zone edges fall between nodes, so it is not monotone in h at
    every level (e.g. 1.011 at 24 and 0.9998 at 64 elements; docs/fe.md), but it stays
    below 0.5 h/a_H; the floor of ≈ 0.2 % is the finite size of the bodies.
    """
    errs = []
    for lv in levels.values():
        res, hs = lv["result"], lv["halfspace"]
        assert res.steady_state == "cyclic_slip" and hs.steady
        assert res.energy_balance_error < 1e-9
        assert abs(hs.slider_sum_dissipation / hs.dissipation_per_cycle - 1) < 1e-6
        P = lv["P_cycle"]
        assert np.ptp(P) < 1e-5 * P.mean()  # constant P (B ≈ 0)
        ratio = np.abs(lv["Q_cycle"]).max() / (F * P.mean())
        assert 0.7 < ratio < 0.85
        err = abs(res.dissipation_per_cycle / hs.dissipation_per_cycle - 1)
        errs.append(err)
        assert err <= 0.5 * lv["h"] / lv["a_hertz"], (lv["elements"], err)
    assert errs[1] < errs[0] and errs[2] < errs[0], errs
