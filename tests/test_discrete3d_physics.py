"""Physics of the 3-D discrete model (isotropic Coulomb cone): reduction to the exact 2-D
solver, closed forms for one node under a rotating load, the order of convergence in the
step size, and the frictional Melan theorem against the cone program for λ2."""

import numpy as np
import pytest
from random_systems import along_t1

from slipcycle.discrete import DiscreteLoad, FrictionalSystem, simulate
from slipcycle.discrete3d.basins import basins3d, random_starts
from slipcycle.discrete3d.loads import Load3D
from slipcycle.discrete3d.model import FrictionalSystem3D, embed_2d
from slipcycle.discrete3d.shakedown import is_safe, lambda2_socp
from slipcycle.discrete3d.steady import simulate3d
from slipcycle.loading import HarmonicLoad, TabulatedLoad

A2 = np.array([[1.0, -0.3], [-0.3, 0.8]])
B2 = np.array([[0.4, 0.1], [-0.2, 0.3]])
C2 = np.array([[1.0, -0.2], [-0.2, 1.0]])


@pytest.mark.parametrize("p0", [[1.0, 1.0], [0.5, 0.45]], ids=["contact", "separation"])
def test_loads_along_one_direction_reproduce_the_exact_2d_solver(p0):
    """(a) With loads along t1 only, the cone reduces to |q| ≤ f p of the 2-D model, whose
    event-driven solver is exact for the piecewise-linear path: dissipation per cycle
    and the final state agree to 1e-6 (relative), also with a node that separates."""
    f = 0.5
    q0, p1, q1 = [0.1, -0.1], [0.6, 0.5], [0.9, 0.7]
    p1ph, q1ph = [0.0, 1.0], [0.5, 2.0]
    r2 = simulate(FrictionalSystem(A2, B2, C2, f),
                  DiscreteLoad.harmonic(p0, q0, p1, q1, p1ph, q1ph),
                  cycles=40, steps_per_cycle=100, tol=1e-10)
    load3 = Load3D.harmonic(p0, along_t1(q0), p1, along_t1(q1), p1ph,
                            np.repeat(q1ph, 2))
    r3 = simulate3d(embed_2d(A2, B2, C2, f), load3, cycles=40, steps_per_cycle=100,
                    tol=1e-10, step_tol=1e-8)
    assert r3.steady_state == r2.steady_state == "cyclic_slip"
    assert r3.dissipation_per_cycle == pytest.approx(r2.dissipation_per_cycle, rel=1e-6)
    x2, x3 = r2.cycle_start_states[-1], r3.cycle_start_states[-1]
    scale = r3.disp_scale
    assert np.max(np.abs(x3[0:4:2] - x2[:2])) <= 1e-6 * scale       # slips along t1
    assert np.max(np.abs(x3[1:4:2])) <= 1e-12 * scale               # nothing along t2
    assert np.max(np.abs(x3[4:] - x2[2:])) <= 1e-6 * scale          # separations
    assert r3.separating_nodes == r2.separating_nodes


def _single_node(f=0.5, P=1.0, k=1.0, kn=1.0):
    return FrictionalSystem3D(k * np.eye(2), np.zeros((1, 2)), [[kn]], f)


def _circle(P, Q0, offset=(0.0, 0.0)):
    """q^w = offset + Q0 (cos θ, sin θ), p^w = P."""
    return Load3D.harmonic([P], list(offset), None, [Q0, Q0], q1_phase=[0.0, -np.pi / 2])


@pytest.mark.parametrize("offset", [(0.0, 0.0), (0.4, -0.3)])
def test_single_node_on_a_rotating_load_slides_on_the_closed_form_circle(offset):
    """(b) One uncoupled node (A = k I, B = 0, C = k_n), constant P, q^w = c + Q0 e(θ) with
    Q0 > f P. Closed form of the steady orbit: q stays on the circle |q| = f P, rotating
    with the load at a constant lead ψ, cos ψ = f P / Q0 (the angle ψ between q^w and q
    obeys ψ' = 1 − (Q0 / f P) cos ψ, whose stable fixed point this is); the slip
    v = (q − q^w)/k is then a circle of radius √(Q0² − f²P²)/k centred at −c/k, traversed
    at the rate |v'| = √(Q0² − f²P²)/k, so D = ∮ f P |v'| dθ = 2π f P √(Q0² − f²P²)/k.
    The loading path is the 400-gon of the samples (D differs from the circle's by
    O(400⁻²) ≈ 5e-5); checked to 0.5 %."""
    f, P, k, Q0 = 0.5, 1.0, 1.0, 1.0
    res = simulate3d(_single_node(f, P, k), _circle(P, Q0, offset), cycles=20,
                     steps_per_cycle=400, tol=1e-9, step_tol=1e-6)
    assert res.steady_state == "cyclic_slip"
    closed = 2 * np.pi * f * P * np.sqrt(Q0**2 - (f * P) ** 2) / k
    assert res.dissipation_per_cycle == pytest.approx(closed, rel=5e-3)
    v = res.x[-1, :, :2]
    radius = np.linalg.norm(v + np.asarray(offset) / k, axis=1)
    assert np.allclose(radius, np.sqrt(Q0**2 - (f * P) ** 2) / k, rtol=5e-3)
    q = res.r[-1, :, :2]
    assert np.allclose(np.linalg.norm(q, axis=1), f * P, rtol=1e-9)


def test_single_node_inside_the_cone_shakes_down_with_zero_dissipation():
    """(b) Q0 < f P: after the first loading (the offset pushes the node to slip once)
    the load circle fits in the friction disk moved by the residual reaction, so the
    node shakes down: no dissipation in the steady cycle (Melan, one node)."""
    res = simulate3d(_single_node(), _circle(1.0, 0.4, (0.7, 0.2)), cycles=10,
                     steps_per_cycle=100, tol=1e-9)
    assert res.steady_state == "shakedown"
    assert res.dissipation_per_cycle == pytest.approx(0.0, abs=1e-12)


def test_fixed_steps_converge_at_first_order_and_step_doubling_at_second():
    """(d) Observed order of convergence in the step size h on the rotating-load node
    (the 16-gon load path, dissipation of the steady cycle), from successive differences
    |D(h) − D(h/2)| (no reference needed): backward Euler with fixed sub-steps is first
    order (measured 1.08, 1.04, 1.02, 1.01 for 2…64 sub-steps); step doubling with
    Richardson extrapolation of smooth steps (every interval accepted at the first level)
    approaches second order (measured 1.75, 1.85 for 32…256 samples per cycle)."""
    sys1 = _single_node()
    th = np.linspace(0, 2 * np.pi, 17)[:-1]
    polygon = Load3D(q=TabulatedLoad(th, np.column_stack([np.cos(th), np.sin(th)])),
                     p=HarmonicLoad([1.0], [0.0], 0.0))

    def order(values):
        diffs = np.abs(np.diff(values))
        return -np.polyfit(np.arange(diffs.size), np.log2(diffs), 1)[0]

    fixed = [simulate3d(sys1, polygon, cycles=6, steps_per_cycle=16, tol=1e-12,
                        adaptive=False, substeps=m).dissipation_per_cycle
             for m in (4, 8, 16, 32)]
    assert order(fixed) == pytest.approx(1.0, abs=0.15)
    doubled = [simulate3d(sys1, polygon, cycles=6, steps_per_cycle=spc, tol=1e-12,
                          step_tol=1.0).dissipation_per_cycle
               for spc in (32, 64, 128, 256)]
    assert 1.6 <= order(doubled) <= 2.2


def _uncoupled(seed):
    rng = np.random.default_rng(seed)
    n = 3
    M = rng.normal(size=(2 * n, 2 * n))
    A = M @ M.T + 2 * n * np.eye(2 * n)
    C = 3 * np.eye(n) + 0.5
    system = FrictionalSystem3D(A, np.zeros((n, 2 * n)), C, 0.4)
    load = Load3D.harmonic(np.full(n, 2.0), rng.normal(size=2 * n) * 0.2,
                           rng.normal(size=n) * 0.3, rng.normal(size=2 * n),
                           q1_phase=rng.uniform(0, 6, 2 * n), p1_phase=rng.uniform(0, 6, n))
    return system, load, rng


@pytest.mark.parametrize("seed", [1, pytest.param(2, marks=pytest.mark.slow)])
def test_uncoupled_systems_shake_down_below_lambda2_from_any_start_and_not_above(seed):
    """(f) Frictional Melan theorem (B = 0; Klarbring, Ciavarella & Barber 2007): below
    λ2 of the cone program the system shakes down from every assembly protocol, above it
    it slips cyclically. The program's safe slip state is safe at every sample."""
    system, load, rng = _uncoupled(seed)
    sr = lambda2_socp(system, load, 100)
    assert sr.feasible and 0 < sr.lambda2 < 1e5
    assert is_safe(system, load.with_lam(sr.lambda2), sr.safe_slip, 100, rtol=1e-6)
    n = system.n_nodes
    for trial in range(3):
        proto = np.concatenate([rng.normal(size=2 * n) * 1.5, np.full(n, 2.0)])[None]
        below = simulate3d(system, load.with_lam(0.8 * sr.lambda2), cycles=60,
                           steps_per_cycle=100, tol=1e-9, protocol=None if trial == 0
                           else proto)
        assert below.steady_state == "shakedown"
    above = simulate3d(system, load.with_lam(1.2 * sr.lambda2), cycles=60,
                       steps_per_cycle=100, tol=1e-9)
    assert above.steady_state == "cyclic_slip"
    assert above.dissipation_per_cycle > 0


def test_lambda2_of_a_rotating_load_is_the_friction_radius():
    """A single node with q^w = Q0 λ e(θ): the load polygon fits in a disk of radius f P
    iff its circumradius λ Q0 ≤ f P (centred by the residual reaction), so λ2 = f P / Q0."""
    sr = lambda2_socp(_single_node(f=0.5), _circle(1.0, 1.0, (0.3, 0.0)), 100)
    assert sr.lambda2 == pytest.approx(0.5, rel=1e-7)
    assert np.allclose(sr.safe_slip[0], [-0.3, 0.0], atol=1e-6)


@pytest.mark.slow
def test_uncoupled_basins_have_one_attractor_dissipation():
    """Basins (B = 0): from random admissible starts and an assembly protocol above λ2 the
    steady dissipation is the same (frictional Melan theorem: one attractor in D)."""
    system, load, rng = _uncoupled(1)
    lam = 1.2 * lambda2_socp(system, load, 60).lambda2
    load = load.with_lam(lam)
    n = system.n_nodes
    starts = random_starts(system, load, 3, 0.05, seed=2)
    proto = [np.concatenate([rng.normal(size=2 * n), np.full(n, 2.0)])[None]]
    b = basins3d(system, load, starts=starts, protocols=proto, cycles=60,
                 steps_per_cycle=60, tol=1e-9, step_tol=1e-6)
    assert set(b.steady_state) == {"cyclic_slip"}
    assert len(b.attractors(rtol=1e-4)) == 1
