"""Where the local dissipation of a Mindlin–Deresiewicz contact peaks.

Constant normal load P on a Hertzian sphere, tangential load Q oscillating between ±Q*
(Mindlin & Deresiewicz 1953). By the Ciavarella–Jäger superposition (Ciavarella 1998,
Jäger 1998) the slip at radius r in the annulus c ≤ r ≤ a after a monotonic tangential
load is λ f h_c(r), where h_c is the gap outside a Hertz contact of radius c,

    h_c(r) = [c √(r² − c²) + (r² − 2c²) arccos(c/r)] / (π R),

and in the steady cycle every point of the annulus slips back and forth by 2 λ f h_c(r) at
the traction ±f p(r) (Masing: the unloading is the loading with 2f), so

    W(r) = 4 λ f² p(r) h_c(r),   p(r) = p0 √(1 − r²/a²),   (c/a)³ = 1 − Q*/(fP).

dW/dr = 0 gives, with ρ = r/a and γ = c/a, the peak radius as the root of

    γ √(ρ² − γ²) (3ρ² − 2) + ρ² (3ρ² − 2 − 2γ²) arccos(γ/ρ) = 0.

The fraction ξ = (ρ − γ)/(1 − γ) of the annulus width at which W peaks is 3/4 in the limit
of a thin annulus (W ∝ (r − c)^{3/2} (a − r)^{1/2}) and rises to √(2/3) = 0.816 as
Q* → fP (c → 0): about three quarters of the way from the stick edge to the contact edge,
not half way as quoted in Barber 2012, §4.5. The tests compare slipcycle's W(r)
(``slipcycle.halfspace`` solver and :mod:`slipcycle.halfspace.tractions`) with this.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq, minimize_scalar

from slipcycle.halfspace import ContactElasticity, HalfspaceModel, solve, sphere
from slipcycle.halfspace.tractions import abel_operators, dissipation_density

P, F, R = 100.0, 0.5, 0.01      # N, friction, sphere radius (m)
ELASTICITY = ContactElasticity.from_materials((200e9, 200e9), (0.3, 0.3), plane=False)


def stick_ratio(load_ratio: float) -> float:
    """γ = c/a = (1 − Q*/fP)^{1/3} (Cattaneo 1938, Mindlin 1949)."""
    return (1.0 - load_ratio) ** (1.0 / 3.0)


def peak_condition(rho: float, gamma: float) -> float:
    """The left side of dW/dr = 0 (module docstring); zero at the peak radius ρ = r/a."""
    s = np.sqrt(max(rho**2 - gamma**2, 0.0))
    return (gamma * s * (3 * rho**2 - 2)
            + rho**2 * (3 * rho**2 - 2 - 2 * gamma**2) * np.arccos(min(gamma / rho, 1.0)))


def peak_radius(gamma: float) -> float:
    """Closed-form peak radius ρ* = r*/a of W(r) for stick ratio γ."""
    if gamma == 0.0:
        return float(np.sqrt(2.0 / 3.0))
    lo = gamma * (1.0 + 1e-12)
    return float(brentq(peak_condition, lo, 1.0, args=(gamma,), xtol=1e-14))


def peak_fraction(load_ratio: float) -> float:
    """ξ = (r* − c)/(a − c): the peak's position across the slip annulus."""
    g = stick_ratio(load_ratio)
    return (peak_radius(g) - g) / (1.0 - g)


def density_closed_form(r, a, c):
    """W(r) = 4 λ f² p(r) h_c(r) [J/m²] (module docstring) at radii r [m]."""
    r = np.asarray(r, float)
    p = 3 * P / (2 * np.pi * a**2) * np.sqrt(np.clip(1 - (r / a) ** 2, 0.0, None))
    rr = np.maximum(r, c)
    gap = (c * np.sqrt(rr**2 - c**2) + (rr**2 - 2 * c**2) * np.arccos(c / rr)) / (np.pi * R)
    return 4 * ELASTICITY.compliance_ratio * F**2 * p * gap


def solver_density(load_ratio: float, n_radii: int = 4000):
    """W(r) of slipcycle's slider bed over the steady cycle: (r/a, W [J/m²], a [m])."""
    model = HalfspaceModel.harmonic(
        sphere(R, ELASTICITY.contact_modulus), F, ELASTICITY.compliance_ratio, P0=P,
        Q1=load_ratio * F * P, elasticity=ELASTICITY, max_cycles=3, steps_per_cycle=64,
        n_sliders=2000)
    bed, res = solve(model)
    assert res.steady
    ops = abel_operators(bed, n_radii=n_radii)
    W = dissipation_density(ops, res.last_t, res.last_z)
    a = float(model.profile.contact_size(P))
    return ops.radius / a, W, a


def measured_peak_radius(rho, W) -> float:
    """Peak of the sampled W by a parabola through the largest sample and its neighbours."""
    k = int(np.argmax(W))
    y0, y1, y2 = W[k - 1:k + 2]
    return float(rho[k] + 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2) * (rho[1] - rho[0]))


@pytest.mark.parametrize("load_ratio", [0.01, 0.3, 0.6, 0.9, 0.999])
def test_closed_form_peak_is_the_maximum_of_the_closed_form_density(load_ratio):
    """The root of the derived condition is the maximum of W(r) found by brute force."""
    g = stick_ratio(load_ratio)
    best = minimize_scalar(lambda x: -density_closed_form(x, 1.0, g) * 1e3,
                           bounds=(g, 1.0), method="bounded", options={"xatol": 1e-12})
    assert peak_radius(g) == pytest.approx(best.x, abs=1e-6 * (1 - g) + 1e-9)


def test_peak_fraction_limits_three_quarters_and_root_two_thirds():
    """ξ → 3/4 for a thin annulus, ξ → √(2/3) as Q* → fP; never the half-way point."""
    # (the two leading terms of the condition cancel for a thin annulus: 1e-4 keeps
    # the root well conditioned in double precision)
    assert peak_fraction(1e-4) == pytest.approx(0.75, abs=1e-4)
    assert peak_fraction(1.0) == pytest.approx(np.sqrt(2 / 3), abs=1e-12)
    xi = [peak_fraction(x) for x in np.linspace(1e-4, 1.0, 200)]
    assert np.all(np.diff(xi) > -1e-9)               # monotonic in Q*/fP
    assert 0.75 - 1e-4 < min(xi) and max(xi) < 0.8166


@pytest.mark.parametrize("load_ratio", [0.1, 0.6, 0.95])
def test_solver_density_matches_the_mindlin_deresiewicz_density(load_ratio):
    """The whole W(r) profile of the solver, not only its peak, is the closed form."""
    rho, W, a = solver_density(load_ratio)
    Wc = density_closed_form(rho * a, a, stick_ratio(load_ratio) * a)
    assert W.max() == pytest.approx(Wc.max(), rel=5e-3)
    assert np.abs(W - Wc).max() < 0.04 * Wc.max()


@settings(max_examples=8, deadline=None, derandomize=True)
@given(load_ratio=st.floats(0.02, 0.98))
def test_solver_dissipation_peaks_three_quarters_across_the_slip_annulus(load_ratio):
    """slipcycle's W(r) peaks where the closed form says, far from the half-way point."""
    rho, W, _ = solver_density(load_ratio)
    g = stick_ratio(load_ratio)
    xi_solver = (measured_peak_radius(rho, W) - g) / (1 - g)
    xi_closed = peak_fraction(load_ratio)
    assert xi_solver == pytest.approx(xi_closed, abs=0.02)
    assert abs(xi_solver - 0.5) > 0.2


def test_peak_table_of_the_theory_page_is_the_closed_form():
    """The table of docs/theory/ciavarella_jaeger.md, to its 4 printed decimals."""
    from pathlib import Path

    page = Path(__file__).resolve().parents[1] / "docs" / "theory" / "ciavarella_jaeger.md"
    rows = {}
    for line in page.read_text(encoding="utf-8").splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if cells[0] in ("$Q^*/fP$", "$r^*/a$", "$\\xi$"):
            rows[cells[0]] = [float(c) for c in cells[1:]]
    assert len(rows) == 3
    for x, r, xi in zip(rows["$Q^*/fP$"], rows["$r^*/a$"], rows["$\\xi$"], strict=True):
        assert r == pytest.approx(peak_radius(stick_ratio(x)), abs=5.1e-5)
        assert xi == pytest.approx(peak_fraction(x), abs=5.1e-5)
