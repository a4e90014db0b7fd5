"""A tangential amplitude far below fP microslips in a thin rim, and the slider bed must
resolve it: the sphere and the rough law against their closed forms down to Q/fP = 1e-7.

Sphere (Mindlin & Deresiewicz 1953; Johnson 1985, eq. 7.60 for two bodies), constant P,
Q = ±Q*, x = Q*/(fP):

    W = 2 · 9 f² P² (2 − ν) / (10 a G) · B(x),
    B(x) = 1 − (1 − x)^{5/3} − (5x/6)(1 + (1 − x)^{2/3}) = 5x³/162 + O(x⁴),

summed here as its power series (the closed form cancels to round-off below x ≈ 1e-4).
Rough law U = γσ ln P: Ŵ = −4q ln(1 − q) − 8[(1 − q) ln(1 − q) + q] = Σ_{k≥3}
(4/(k − 1) − 8/(k(k − 1))) q^k (the Masing construction of test_halfspace_closed_forms).

Before the bed gave its slip zone cells of their own, x = 1e-3 came out 70 % high and
x = 1e-4 as shakedown (D = 0) with 2000 sliders; before the cell centroids were computed
without cancellation, x = 1e-6 was 30 % low and the rough law at q = 1e-7 38 % low.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from slipcycle.halfspace import ContactElasticity, make_bed, sphere
from slipcycle.halfspace.case import parse_case
from slipcycle.halfspace.model import solve
from slipcycle.halfspace.wmap import w_hat_point
from slipcycle.io import parse_case_text

E, NU, R, P, F = 200e9, 0.3, 0.01, 100.0, 0.5

SPHERE_CASE = """
model = "halfspace"
[halfspace]
profile = "sphere"
radius = {R}
E = [{E}, {E}]
nu = [{NU}, {NU}]
friction = {F}
[loading]
P0 = {P}
Q1 = {Q!r}
[run]
cycles = 4
steps_per_cycle = 200
sliders = 2000
"""


def _binomials(alpha: float, n: int) -> list[float]:
    c = [1.0]
    for k in range(1, n):
        c.append(c[-1] * (alpha - k + 1) / k)
    return c


def mindlin_bracket(x: float) -> float:
    """B(x) as its power series (the terms up to x² cancel exactly)."""
    c53, c23 = _binomials(5 / 3, 80), _binomials(2 / 3, 80)
    return sum((-c53[k] * (-1) ** k - 5 / 6 * c23[k - 1] * (-1) ** (k - 1)) * x**k
               for k in range(3, 80))


def mindlin_loss(x: float) -> float:
    """W [J] of the sphere case at x = Q*/(fP)."""
    contact_modulus = E / (2 * (1 - NU**2))
    a = (3 * P * R / (4 * contact_modulus)) ** (1 / 3)
    G = E / (2 * (1 + NU))
    return 2 * 9 * F**2 * P**2 * (2 - NU) / (10 * a * G) * mindlin_bracket(x)


def masing_w_hat(q: float) -> float:
    """Ŵ of the rough law at q = Q1/(fP), as its power series."""
    return sum((4 / (k - 1) - 8 / (k * (k - 1))) * q**k for k in range(3, 80))


def test_the_series_are_the_closed_forms_where_those_do_not_cancel():
    x = 0.3
    closed = 1 - (1 - x) ** (5 / 3) - 5 * x / 6 * (1 + (1 - x) ** (2 / 3))
    assert mindlin_bracket(x) == pytest.approx(closed, rel=1e-12)
    assert mindlin_bracket(1e-3) == pytest.approx(5 / 162 * 1e-9, rel=1e-2)
    q = 0.3
    assert masing_w_hat(q) == pytest.approx(
        -4 * q * math.log(1 - q) - 8 * ((1 - q) * math.log(1 - q) + q), rel=1e-12)


@pytest.mark.parametrize("x", [1e-1, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7])
def test_sphere_microslip_loss_at_tiny_amplitudes_is_mindlins(x):
    model = parse_case(parse_case_text(SPHERE_CASE.format(R=R, E=E, NU=NU, F=F, P=P,
                                                          Q=x * F * P)))
    bed, res = solve(model, record_last_cycle=False)
    assert res.steady
    # the polygon of 200 samples per cycle costs 1.6e-4 (measured at every x)
    assert res.dissipation_per_cycle == pytest.approx(mindlin_loss(x), rel=2e-3)
    # the rim slips, as in the continuum: not shakedown
    assert np.any(res.slider_dissipation[-1] > 0)


def test_sphere_at_a_tiny_amplitude_from_the_command_line(tmp_path, run_cli):
    x = 2e-4   # the probe's case: shakedown with D = -1.3e-27 J before
    case = tmp_path / "tiny.toml"
    case.write_text(SPHERE_CASE.format(R=R, E=E, NU=NU, F=F, P=P, Q=x * F * P))
    code, _, err = run_cli("run", case, "--out", tmp_path / "out")
    assert code == 0, err
    s = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert s["steady_state_class"] == "cyclic_slip"
    assert s["dissipation_per_cycle"] == pytest.approx(mindlin_loss(x), rel=2e-3)


@pytest.mark.parametrize("q", [1e-4, 1e-6, 1e-7])
def test_rough_law_loss_at_tiny_amplitudes_is_the_masing_series(q):
    W = w_hat_point(0.0, q, 0.0, n_sliders=400, steps_per_cycle=400)
    assert W == pytest.approx(masing_w_hat(q), rel=1e-3)


def test_every_slider_of_a_thin_slip_zone_lies_inside_its_cell():
    el = ContactElasticity.from_materials((E, E), (NU, NU), plane=False)
    prof = sphere(R, el.contact_modulus)
    bed = make_bed(prof, friction=F, compliance_ratio=el.compliance_ratio, P_max=P,
                   n_sliders=2000, P_slip=P * (1 - 1e-8))
    U = prof.approach(bed.edge_load)
    assert bed.size > 2000   # the slip zone got cells of its own
    inside = (bed.level[1:] >= U[1:-1]) & (bed.level[1:] <= U[2:])
    assert inside.all()
