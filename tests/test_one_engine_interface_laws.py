"""One engine per physics: each rods interface law is a type, found by name in one table.

:data:`slipcycle.rods.interfaces.INTERFACE_LAWS` maps ``TwoRods.interface`` to an
:class:`~slipcycle.rods.interfaces.InterfaceLaw`; ``make_bed``, the regularisation study and
the limits study take the bed, stiffness and capacity from it instead of comparing names.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np
import pytest

from slipcycle.rods import interfaces, limits, regularisation
from slipcycle.rods.interfaces import (
    INTERFACE_LAWS,
    Bed,
    Iwan,
    Jenkins,
    SegalmanIwan,
    coulomb_bed,
    distributed_bed,
    interface_law,
    iwan_bed,
    jenkins_bed,
    make_bed,
    welded_bed,
)
from slipcycle.rods.model import INTERFACES, Excitation, Rod, TwoRods

STEEL = dict(E=200e9, nu=0.3, density=7850.0)
N0 = 1.0e4
PARAMS = SegalmanIwan(20.0, 1.5e5, -0.4, 0.05)


def rods(interface):
    r = Rod(0.5, 0.01, **STEEL)
    return TwoRods(r, Rod(0.4, 0.012, **STEEL), 0.3, interface, 1e13, 0.01)


def same_bed(a: Bed, b: Bed) -> bool:
    return (a.kind == b.kind and a.rigid == b.rigid and np.array_equal(a.kappa, b.kappa)
            and np.array_equal(a.cap_unit, b.cap_unit))


def test_the_table_covers_every_interface_name():
    assert tuple(INTERFACE_LAWS) == INTERFACES
    for name, law in INTERFACE_LAWS.items():
        assert law.name == name and interface_law(name).name == name
    with pytest.raises(ValueError, match="interface"):
        interface_law("glued")


@pytest.mark.parametrize("name", INTERFACES)
def test_each_law_builds_the_bed_of_its_constructor(name):
    r = rods(name)
    ref = {"welded": welded_bed(r), "distributed": distributed_bed(r, 37),
           "coulomb": coulomb_bed(r), "jenkins": jenkins_bed(r),
           "iwan": iwan_bed(r, N0, None, PARAMS)[0]}[name]
    law = interface_law(name, rings=37, iwan=PARAMS)
    assert same_bed(law.bed(r, N0), ref)
    assert same_bed(make_bed(r, N0, 37, PARAMS), ref)
    assert law.bed(r, N0).is_frictional == law.is_frictional == (name != "welded")
    assert law.rigid == ref.rigid


@pytest.mark.parametrize("name", INTERFACES)
def test_law_properties_equal_the_rods_model(name):
    """Stiffness, capacity and slip inception as ``TwoRods`` reports them (which may now
    delegate to the law)."""
    r = rods(name)
    law = interface_law(name)
    assert law.stiffness(r) == r.interface_torsional_stiffness
    assert law.gross_slip_torque(r, N0) == r.gross_slip_torque(N0)
    assert law.slip_inception_torque(r, N0) == r.slip_inception_torque(N0)
    assert law.needs_interface_stiffness == (name in ("distributed", "jenkins", "iwan"))
    if name == "iwan":  # the fitted element's K_T, F_S are the rings' (test_rods_physics)
        return
    bed = law.bed(r, N0)
    if math.isfinite(law.stiffness(r)):
        assert bed.stiffness == pytest.approx(law.stiffness(r), rel=1e-12)
    assert bed.capacity(N0) == pytest.approx(law.gross_slip_torque(r, N0), rel=1e-12)


def test_iwan_fit_happens_once_and_is_kept():
    r = rods("iwan")
    law = Iwan().fitted(r, N0)
    assert law.params is not None and law.fitted(r, N0) is law
    assert same_bed(law.bed(r, N0), make_bed(r, N0))


def test_swapping_a_law_in_the_table_changes_every_user(monkeypatch):
    """make_bed, the regularisation study and the limits study dispatch through the table."""

    @dataclass(frozen=True)
    class Stiffer(Jenkins):
        name: ClassVar[str] = "jenkins"

        def bed(self, rods, N_ref):
            b = super().bed(rods, N_ref)
            return Bed(b.kind, 2.0 * b.kappa, b.cap_unit)

        def stiffness(self, rods):
            return 2.0 * super().stiffness(rods)

    r = rods("jenkins")
    k = make_bed(r, N0).stiffness
    theta_g = limits.gross_slip_amplitude(r, N0)
    monkeypatch.setitem(INTERFACE_LAWS, "jenkins", Stiffer)
    assert make_bed(r, N0).stiffness == 2.0 * k
    Tg = interfaces.gross_slip_torque(r.friction, N0, r.contact_radius)
    assert limits.gross_slip_amplitude(r, N0) == pytest.approx(
        theta_g - Tg / (2.0 * r.interface_stiffness * r.contact_J), rel=1e-14)
    study = regularisation.regularisation_study(r, Excitation(1e-3, 1.0, N0), rings=10,
                                                iwan=PARAMS, points=4, steps_per_cycle=64)
    assert study["_beds"]["jenkins"].stiffness == 2.0 * k


#: modules whose solvers no longer compare interface names
SOLVERS = ("interfaces.py", "modal.py", "limits.py", "quasistatic.py", "regularisation.py")


@pytest.mark.parametrize("module", SOLVERS)
def test_no_string_dispatch_on_interface_names(module):
    text = (Path(interfaces.__file__).parent / module).read_text(encoding="utf-8")
    names = "|".join(INTERFACES)
    assert not re.findall(rf"(==|!=|\bin)\s*\(?\s*\"({names})\"", text)
    assert not re.findall(r"\.(kind|interface)\s*(==|!=|in\b)", text)
