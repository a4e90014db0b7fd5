"""One engine per physics: the rods' gross-slip torque (2/3) f N a is written once.

:func:`slipcycle.rods.model.gross_slip_torque` (re-exported by ``rods.interfaces``) is its
only home; every caller in the rods solvers goes through it (identity of the imported
name, and a fake swapped in at each caller changes that caller's answer), and no other copy
of the formula is left in the modules that call it.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from slipcycle.rods import interfaces, limits, quasistatic, regularisation
from slipcycle.rods.interfaces import SegalmanIwan, gross_slip_torque
from slipcycle.rods.model import Excitation, Rod, TwoRods

STEEL = dict(E=200e9, nu=0.3, density=7850.0)
N0 = 1.0e4
RODS_SRC = Path(interfaces.__file__).parent


def rods(interface="distributed"):
    r = Rod(0.5, 0.01, **STEEL)
    return TwoRods(r, r, 0.3, interface, 1e13, 0.01)


def test_closed_form():
    """(2/3) π f p a³ with p = N/(π a²)."""
    f, N, a = 0.3, N0, 0.01
    p = N / (math.pi * a * a)
    assert gross_slip_torque(f, N, a) == pytest.approx(2 / 3 * math.pi * f * p * a**3,
                                                       rel=1e-15)


def test_every_caller_agrees_with_the_one_function():
    r = rods()
    Tg = gross_slip_torque(r.friction, N0, r.contact_radius)
    assert quasistatic.gross_slip_torque_qs(r, N0) == Tg
    assert interfaces.jenkins_bed(r).capacity(N0) == pytest.approx(Tg, rel=1e-15)
    assert interfaces.coulomb_bed(r).capacity(N0) == pytest.approx(Tg, rel=1e-15)
    assert interfaces.distributed_bed(r, 50).capacity(N0) == pytest.approx(Tg, rel=1e-12)
    assert limits.gross_slip_amplitude(r, N0) == Tg * (
        r.rods_compliance + 1.0 / (r.interface_stiffness * r.contact_J))


@pytest.mark.parametrize("module", [limits, quasistatic, regularisation])
def test_callers_import_the_one_function(module):
    assert module.gross_slip_torque is interfaces.gross_slip_torque


def _doubled(monkeypatch, module, factor=2.0):
    monkeypatch.setattr(module, "gross_slip_torque",
                        lambda f, N, a: factor * gross_slip_torque(f, N, a))


def test_swapping_the_function_changes_every_caller(monkeypatch):
    r = rods()
    before = {
        "jenkins": interfaces.jenkins_bed(r).capacity(N0),
        "coulomb": interfaces.coulomb_bed(r).capacity(N0),
        "qs": quasistatic.gross_slip_torque_qs(r, N0),
        "theta_g": limits.gross_slip_amplitude(r, N0),
    }
    for module in (interfaces, limits, quasistatic):
        _doubled(monkeypatch, module)
    after = {
        "jenkins": interfaces.jenkins_bed(r).capacity(N0),
        "coulomb": interfaces.coulomb_bed(r).capacity(N0),
        "qs": quasistatic.gross_slip_torque_qs(r, N0),
        "theta_g": limits.gross_slip_amplitude(r, N0),
    }
    for key, value in before.items():
        assert after[key] == pytest.approx(2.0 * value, rel=1e-15), key


def test_swapping_the_function_changes_the_iwan_fit_and_the_study(monkeypatch):
    r = rods("iwan")
    iw0, _ = interfaces.fit_iwan(r, N0, points=8)
    exc = Excitation(1e-3, 1.0, N0)
    params = SegalmanIwan(iw0.F_S, iw0.K_T, -0.5, 0.1)
    study0 = regularisation.regularisation_study(r, exc, rings=10, iwan=params, points=4,
                                                 steps_per_cycle=64)
    # 0.9: the fit samples the rings at 0.05…0.97 F_S, which must reach past their T_s = 0.75 T_g
    _doubled(monkeypatch, interfaces, 0.9)
    _doubled(monkeypatch, regularisation, 0.9)
    iw1, _ = interfaces.fit_iwan(r, N0, points=8)
    assert iw1.F_S == pytest.approx(0.9 * iw0.F_S, rel=1e-15)
    study1 = regularisation.regularisation_study(r, exc, rings=10, iwan=params, points=4,
                                                 steps_per_cycle=64)
    assert study1["gross_slip_torque"] == pytest.approx(0.9 * study0["gross_slip_torque"],
                                                        rel=1e-15)
    assert study1["theta_gross"] == pytest.approx(0.9 * study0["theta_gross"], rel=1e-15)
    assert np.allclose(study1["amplitude"], 0.9 * study0["amplitude"], rtol=1e-15, atol=0)


#: copies outside the one function (none left; the list may only shrink)
KNOWN_ELSEWHERE: set[str] = set()


def test_no_other_copy_of_the_formula_in_the_rods_package():
    """The product 2/3 × … occurs once in the package, in the one function."""
    pattern = re.compile(r"2(\.0)?\s*/\s*3(\.0)?\s*\*")
    hits = {path.name: len(pattern.findall(path.read_text(encoding="utf-8")))
            for path in RODS_SRC.glob("*.py")}
    assert hits.pop("model.py") == 1     # the function, re-exported by interfaces
    assert {name for name, n in hits.items() if n} <= KNOWN_ELSEWHERE
