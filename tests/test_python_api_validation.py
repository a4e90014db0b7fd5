"""The Python API refuses invalid models at construction, naming the field (InputError)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from slipcycle.discrete import FrictionalSystem, critical_friction
from slipcycle.errors import InputError
from slipcycle.halfspace import HalfspaceModel, solve, sphere
from slipcycle.rods import Excitation, Rod, TwoRods

ROD = dict(length=0.5, radius=0.01, E=210e9, nu=0.3, density=7850.0)
BAD = st.one_of(st.floats(max_value=0.0), st.just(math.nan), st.just(math.inf))


def _key(exc_info) -> str:
    return exc_info.value.key


# -- discrete -------------------------------------------------------------------------------
COUPLED = dict(A=[[2.0, -1.0], [-1.0, 2.0]], B=[[0.0, 0.8], [-0.8, 0.0]], C=np.eye(2))


@pytest.mark.parametrize(("field", "value"), [
    ("A", [[1.0, 2.0, 3.0]]), ("A", [[1.0, 0.5], [0.0, 1.0]]), ("A", [[-1.0, 0], [0, 1.0]]),
    ("C", [[1.0, 2.0], [0.0, 1.0]]), ("C", np.eye(3)), ("B", [[np.nan, 0], [0, 0]]),
    ("B", 10 * np.eye(2)), ("friction", -0.1), ("friction", [0.1, 0.2, 0.3]),
    ("friction", math.inf)])
def test_discrete_refuses_bad_matrices(field, value):
    args = dict(A=np.eye(2), B=np.zeros((2, 2)), C=np.eye(2), friction=0.3)
    args[field] = value
    with pytest.raises(InputError) as err:
        FrictionalSystem(**args)
    assert _key(err) == field


def test_discrete_refuses_friction_above_f_crit_unless_accepted():
    fc = critical_friction(np.asarray(COUPLED["A"]), np.asarray(COUPLED["B"])).f_crit
    FrictionalSystem(**COUPLED, friction=0.9 * fc, accept_ill_posed=False)
    with pytest.raises(InputError) as err:
        FrictionalSystem(**COUPLED, friction=1.1 * fc, accept_ill_posed=False)
    assert _key(err) == "friction" and "f_crit" in str(err.value)
    FrictionalSystem(**COUPLED, friction=1.1 * fc, accept_ill_posed=True)


@settings(max_examples=30, deadline=None)
@given(f=st.floats(max_value=0.0, exclude_max=True) | st.just(math.nan))
def test_discrete_refuses_negative_friction(f):
    with pytest.raises(InputError) as err:
        FrictionalSystem(np.eye(1), np.zeros((1, 1)), np.eye(1), f)
    assert _key(err) == "friction"


# -- halfspace ------------------------------------------------------------------------------
PROFILE = sphere(0.01, 1.1e11)


@settings(max_examples=30, deadline=None)
@given(field=st.sampled_from(["friction", "compliance_ratio"]), value=BAD)
def test_halfspace_refuses_non_positive_parameters(field, value):
    args = dict(friction=0.5, compliance_ratio=1.2)
    args[field] = value
    with pytest.raises(InputError) as err:
        HalfspaceModel.harmonic(PROFILE, P0=100.0, Q1=20.0, **args)
    assert _key(err) == field


@pytest.mark.parametrize(("field", "value"), [
    ("normal_control", "torque"), ("tangential_control", "force-ish"),
    ("protocol", np.zeros((2, 3))), ("steps_per_cycle", 4), ("n_sliders", 0),
    ("max_cycles", 0), ("snapshots", [7.0]), ("steady_tol", 2.0), ("profile", "sphere")])
def test_halfspace_refuses_bad_settings(field, value):
    kw = {field: value}
    profile = kw.pop("profile", PROFILE)
    with pytest.raises(InputError) as err:
        HalfspaceModel.harmonic(profile, 0.5, 1.2, P0=100.0, Q1=20.0, **kw)
    assert _key(err) == field


@settings(max_examples=20, deadline=None)
@given(P1=st.floats(100.5, 1e4))
def test_halfspace_refuses_tensile_normal_load(P1):
    model = HalfspaceModel.harmonic(PROFILE, 0.5, 1.2, P0=100.0, P1=P1, Q1=20.0)
    with pytest.raises(InputError) as err:
        solve(model)
    assert _key(err) == "normal" and "tensile" in err.value.problem


def test_halfspace_refuses_tensile_protocol_state():
    model = HalfspaceModel.harmonic(PROFILE, 0.5, 1.2, P0=100.0, Q1=20.0,
                                    protocol=np.array([[-5.0, 0.0]]))
    with pytest.raises(InputError) as err:
        solve(model)
    assert _key(err) == "protocol[0]"


# -- rods -----------------------------------------------------------------------------------
@settings(max_examples=40, deadline=None)
@given(field=st.sampled_from(["length", "radius", "E", "density"]), value=BAD)
def test_rod_refuses_non_positive_properties(field, value):
    with pytest.raises(InputError) as err:
        Rod(**{**ROD, field: value})
    assert _key(err) == field


@settings(max_examples=40, deadline=None)
@given(nu=st.floats(allow_nan=True).filter(lambda x: not -1.0 < x <= 0.5))
def test_rod_refuses_poisson_ratio_out_of_range(nu):
    with pytest.raises(InputError) as err:
        Rod(**{**ROD, "nu": nu})
    assert _key(err) == "nu"


@pytest.mark.parametrize(("field", "value"), [
    ("friction", -0.1), ("interface", "glue"), ("damping_ratio", 1.5),
    ("interface_stiffness", -1.0), ("interface_stiffness", math.inf), ("rod1", "steel")])
def test_two_rods_refuses_bad_fields(field, value):
    args = dict(rod1=Rod(**ROD), rod2=Rod(**ROD), friction=0.3, interface="distributed",
                interface_stiffness=1e13)
    args[field] = value
    with pytest.raises(InputError) as err:
        TwoRods(**args)
    assert _key(err) == field


@settings(max_examples=30, deadline=None)
@given(field=st.sampled_from(["axial_force", "rotation_amplitude", "axial_amplitude"]),
       value=st.floats(max_value=0.0, exclude_max=True) | st.just(math.nan))
def test_excitation_refuses_tensile_or_negative_loads(field, value):
    args = dict(rotation_amplitude=1e-3, frequency=100.0, axial_force=1e3)
    args[field] = value
    with pytest.raises(InputError) as err:
        Excitation(**args)
    assert _key(err) == field


def test_excitation_refuses_non_positive_frequency():
    with pytest.raises(InputError) as err:
        Excitation(rotation_amplitude=1e-3, frequency=0.0, axial_force=1e3)
    assert _key(err) == "frequency"
