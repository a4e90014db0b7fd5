"""Half-space microslip against closed forms (Cattaneo, Mindlin–Deresiewicz, Ŵ laws)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipcycle.halfspace import ContactElasticity, Cylinder2D, make_bed, run_history, sphere
from slipcycle.halfspace.wmap import w_hat_point


def _cattaneo_run(profile, lam, f, P, Q, n=4000, steps=400):
    bed = make_bed(profile, friction=f, compliance_ratio=lam, P_max=P, n_sliders=n)
    an = np.concatenate([np.linspace(0, P, 51)[1:], np.full(steps, P)])
    at = np.concatenate([np.zeros(50), np.linspace(0, Q, steps + 1)[1:]])
    res = run_history(bed, an, at, np.full(4, P), np.full(4, Q), max_cycles=1)
    first = res.first_slip[an.size - 1]
    return bed, bed.stick_extent(np.array([first]))[1][0]


@pytest.mark.parametrize("ratio", [0.1, 0.3, 0.5, 0.7, 0.9])
def test_cattaneo_stick_radius_sphere(ratio):
    el = ContactElasticity.from_materials((200e9, 200e9), (0.3, 0.3), plane=False)
    prof = sphere(0.01, el.contact_modulus)
    P, f = 100.0, 0.5
    _, c = _cattaneo_run(prof, el.compliance_ratio, f, P, ratio * f * P)
    a = float(prof.contact_size(P))
    assert c / a == pytest.approx((1 - ratio) ** (1 / 3), rel=5e-3)


@pytest.mark.parametrize("ratio", [0.1, 0.5, 0.9])
def test_cattaneo_stick_halfwidth_cylinder(ratio):
    el = ContactElasticity.from_materials((200e9, 200e9), (0.3, 0.3), plane=True)
    assert el.compliance_ratio == 1.0
    prof = Cylinder2D(0.02, el.contact_modulus)
    P, f = 1e5, 0.4   # N/m
    _, c = _cattaneo_run(prof, 1.0, f, P, ratio * f * P)
    a = float(prof.contact_size(P))
    assert c / a == pytest.approx((1 - ratio) ** 0.5, rel=5e-3)


def mindlin_energy(P, Qa, f, lam, approach):
    """Closed-form loss per cycle for constant P and Q = ±Qa (Masing + Cattaneo).

    The monotonic curve is V(Q) = λ f [U(P) − U(P − Q/f)] (Ciavarella–Jäger: dV/dQ equals
    λ times the normal compliance at P_S = P − Q/f); for a loop between ±Qa,
    W = 4 Qa V(Qa) − 8 ∫_0^Qa V(u) du. With U ∝ P^{2/3} (Hertz) the integral is elementary,
    giving Johnson's eq. (7.60) (Contact Mechanics, §7.6) for two bodies.
    """
    PS = P - Qa / f
    U = approach
    Vm = lam * f * (U(P) - U(PS))
    k = U(1.0)  # U = k P^{2/3}
    integral = lam * f * (Qa * U(P) - f * k * 0.6 * (P ** (5 / 3) - PS ** (5 / 3)))
    return 4 * Qa * Vm - 8 * integral


@pytest.mark.parametrize("materials", [((200e9, 200e9), (0.3, 0.3)), ((70e9, 70e9), (0.33, 0.33))])
@pytest.mark.parametrize("ratio", [0.05, 0.2, 0.5, 0.8, 0.95])
def test_mindlin_deresiewicz_energy_loss(materials, ratio):
    el = ContactElasticity.from_materials(*materials, plane=False)
    prof = sphere(0.005, el.contact_modulus)
    P, f = 50.0, 0.4
    Qa = ratio * f * P
    bed = make_bed(prof, friction=f, compliance_ratio=el.compliance_ratio, P_max=P,
                   n_sliders=2000)
    S = 800
    th = 2 * np.pi * np.arange(1, S + 1) / S
    an = np.concatenate([np.linspace(0, P, 51)[1:], np.full(100, P)])
    at = np.concatenate([np.zeros(50), np.linspace(0, Qa, 101)[1:]])
    res = run_history(bed, an, at, np.full(S, P), Qa * np.cos(th), max_cycles=4)
    W_exact = mindlin_energy(P, Qa, f, el.compliance_ratio,
                             lambda p: float(prof.approach(np.array([p]))[0]))
    # Johnson (7.60) written out, as a check on the derivation above
    nu, E = materials[1][0], materials[0][0]
    G = E / (2 * (1 + nu))
    a = float(prof.contact_size(P))
    x = Qa / (f * P)
    johnson = 2 * 9 * f**2 * P**2 / (10 * a) * (2 - nu) / G * (
        1 - (1 - x) ** (5 / 3) - 5 * x / 6 * (1 + (1 - x) ** (2 / 3)))
    assert W_exact == pytest.approx(johnson, rel=1e-9)
    assert res.steady
    assert res.dissipation_per_cycle == pytest.approx(W_exact, rel=5e-3)
    assert res.slider_sum_dissipation == pytest.approx(res.dissipation_per_cycle, rel=1e-6)


def test_in_phase_loading_below_fP1_dissipates_nothing():
    el = ContactElasticity.from_materials((200e9, 200e9), (0.3, 0.3), plane=False)
    prof = sphere(0.01, el.contact_modulus)
    f, P0, P1, Q1 = 0.5, 100.0, 40.0, 15.0      # Q1 < f P1
    bed = make_bed(prof, friction=f, compliance_ratio=el.compliance_ratio, P_max=P0 + P1,
                   n_sliders=1000)
    S = 400
    th = 2 * np.pi * np.arange(1, S + 1) / S
    an = np.linspace(0, P0 + P1, 101)[1:]
    at = np.linspace(0, Q1, 101)[1:]
    res = run_history(bed, an, at, P0 + P1 * np.cos(th), Q1 * np.cos(th), max_cycles=5)
    reference = mindlin_energy(P0, Q1, f, el.compliance_ratio,
                               lambda p: float(prof.approach(np.array([p]))[0]))
    assert res.steady
    assert abs(res.dissipation_per_cycle) < 1e-9 * reference
    # ... while the same Q with constant P does dissipate
    assert reference > 0


def _w_exact(q):
    """Ŵ for P̂1 = 0 from the same Masing construction with U = γσ ln P."""
    return -4 * q * math.log(1 - q) - 8 * ((1 - q) * math.log(1 - q) + q)


@pytest.mark.parametrize("q", [0.005, 0.01])  # the law is leading order: error ≈ q
def test_w_hat_small_amplitude_cubic_law(q):
    W = w_hat_point(0.0, q, 0.0, n_sliders=400, steps_per_cycle=400)
    assert W == pytest.approx(2 / 3 * q**3, rel=0.02)
    assert W == pytest.approx(_w_exact(q), rel=2e-3)


def test_general_compliance_small_amplitude_law_sphere():
    """W ≈ (2/3)(λ/f)|dC/dP| Q1³ for any profile (here Hertz), constant P, small Q1."""
    el = ContactElasticity.from_materials((200e9, 200e9), (0.3, 0.3), plane=False)
    prof = sphere(0.01, el.contact_modulus)
    f, P, Q1 = 0.5, 100.0, 0.5
    bed = make_bed(prof, friction=f, compliance_ratio=el.compliance_ratio, P_max=P,
                   n_sliders=20000)
    S = 400
    th = 2 * np.pi * np.arange(1, S + 1) / S
    an = np.linspace(0, P, 101)[1:]
    res = run_history(bed, an, np.zeros(100), np.full(S, P), Q1 * np.sin(th), max_cycles=4)
    h = 1e-3 * P
    C = lambda p: float(prof.compliance(np.array([p]))[0])  # noqa: E731
    dCdP = (C(P + h) - C(P - h)) / (2 * h)
    law = 2 / 3 * el.compliance_ratio / f * abs(dCdP) * Q1**3
    assert res.dissipation_per_cycle == pytest.approx(law, rel=0.02)


@pytest.mark.parametrize("P1,Q1,phi", [(0.4, 0.3, 1.0), (0.2, 0.5, -2.0), (0.6, 0.2, 0.4)])
def test_w_hat_mirror_symmetry_and_asymmetry(P1, Q1, phi):
    W = w_hat_point(P1, Q1, phi)
    assert w_hat_point(P1, Q1, phi + np.pi) == pytest.approx(W, rel=1e-9)
    if P1 >= 0.4:  # reversing the way round the ellipse changes which arcs stick
        assert abs(w_hat_point(P1, Q1, -phi) - W) > 0.05 * W


def test_w_hat_second_cycle_is_steady():
    assert w_hat_point(0.4, 0.5, 1.0, cycles=2) == pytest.approx(
        w_hat_point(0.4, 0.5, 1.0, cycles=3), rel=1e-9)
