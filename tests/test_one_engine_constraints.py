"""One engine per physics: the 2N all-contact friction constraints are built in one place.

:func:`slipcycle.discrete.shakedown.friction_constraints` gives the rows s A_j + f_j B_j
and the right-hand sides s q^w_j + f_j p^w_j; the safe region (λ1, λ2), the admissible
region of initial states (basin maps, random starts) and the sampled reference
``extreme_constraints`` (the "≥" form, opposite sign) all take them from there. The sign
convention is checked against the physics: a slip state in the safe region keeps
|q_j| ≤ f_j p_j over the whole cycle, one outside breaks it somewhere.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog

from slipcycle.discrete import basins, shakedown
from slipcycle.discrete.loads import DiscreteLoad
from slipcycle.discrete.model import FrictionalSystem
from slipcycle.discrete.shakedown import (
    admissible_region_at,
    extreme_constraints,
    friction_constraints,
    lambda2,
    safe_region,
)


def system_and_load(n=2, seed=3):
    rng = np.random.default_rng(seed)
    M = rng.standard_normal((2 * n, 2 * n))
    K = M @ M.T + 2 * n * np.eye(2 * n)
    A, B, C = K[:n, :n], K[n:, :n], K[n:, n:]
    system = FrictionalSystem(0.5 * (A + A.T), 0.2 * B, C, rng.uniform(0.2, 0.4, n),
                              accept_ill_posed=True)
    load = DiscreteLoad.harmonic(rng.uniform(2.0, 3.0, n), 0.1 * rng.standard_normal(n),
                                 rng.uniform(0.1, 0.4, n), rng.uniform(0.2, 0.6, n),
                                 rng.uniform(0, 3, n), rng.uniform(0, 3, n))
    return system, load


def physical_margins(system, load, v, theta):
    """s q_j + f_j p_j (θ, 2N) with q = q^w + A v, p = p^w + B v (all nodes in contact)."""
    n = system.n_nodes
    r = load(theta)
    q = r[:, :n] + v @ system.A.T
    p = r[:, n:] + v @ system.B.T
    f = np.asarray(system.friction, float)
    out = np.empty((theta.size, 2 * n))
    out[:, 0::2] = q + f * p
    out[:, 1::2] = -q + f * p
    return out


@pytest.mark.parametrize("n", [1, 2, 4])
def test_rows_and_rhs_are_the_coulomb_inequalities(n):
    system, load = system_and_load(n)
    fc = friction_constraints(system)
    rng = np.random.default_rng(0)
    th = np.linspace(0, 2 * np.pi, 9)
    for v in rng.standard_normal((5, n)) * 1e-2:
        r = load(th)
        margin = v @ fc.rows.T + fc.rhs(r[:, :n], r[:, n:])
        assert np.allclose(margin, physical_margins(system, load, v, th), rtol=1e-12,
                           atol=1e-12)
        assert np.allclose(fc.load_matrix() @ r.T, fc.rhs(r[:, :n], r[:, n:]).T,
                           rtol=1e-14, atol=0)


def test_the_safe_region_lp_uses_the_le_form_and_the_sampled_copy_the_ge_form():
    system, load = system_and_load()
    fc = friction_constraints(system)
    reg = safe_region(system, load)
    G_ext, h_ext = extreme_constraints(system, load, steps=20000)
    G_adm, b_adm = admissible_region_at(system, load, 0.0)
    assert np.array_equal(reg.G, -fc.rows)        # G v ≤ h
    assert np.array_equal(G_adm, -fc.rows)        # G v ≤ b
    assert np.array_equal(G_ext, fc.rows)         # the opposite sign: G v ≥ h
    # the same half-spaces: h_ext = −h(λ) of the safe region (sampled maximum)
    lam = load.p.lam
    assert np.allclose(h_ext, -reg.h(lam), rtol=0, atol=1e-6 * reg.scale)
    r0 = load(np.array([0.0]))[0]
    assert np.array_equal(b_adm, fc.rhs(r0[:2], r0[2:]))


def test_a_state_in_the_safe_region_never_slips_and_one_outside_does():
    """The convention that would catch a flipped copy: S(λ) is where Coulomb holds."""
    system, load = system_and_load()
    reg = safe_region(system, load)
    lam2, _ = lambda2(reg)
    lam = 0.5 * lam2
    n = system.n_nodes
    th = np.linspace(0, 2 * np.pi, 4001)
    # the Chebyshev-like centre: maximise the smallest slack of G v ≤ h(λ)
    c = np.zeros(n + 1)
    c[-1] = -1.0
    norms = np.linalg.norm(reg.G, axis=1)
    res = linprog(c, A_ub=np.hstack([reg.G, norms[:, None]]), b_ub=reg.h(lam),
                  bounds=[(None, None)] * n + [(0, None)], method="highs")
    v_in = res.x[:n]
    assert reg.contains(v_in, lam)
    ld = load.with_lam(lam)
    assert physical_margins(system, ld, v_in, th).min() > 0.0
    # push it out through its tightest constraint
    k = int(np.argmax(reg.G @ v_in - reg.h(lam)))
    v_out = v_in + 3.0 * res.x[-1] * reg.G[k] / norms[k]
    assert not reg.contains(v_out, lam)
    assert physical_margins(system, ld, v_out, th).min() < 0.0


def test_every_builder_takes_the_rows_from_the_one_function(monkeypatch):
    """Swap in a recording wrapper: each caller asks it, and each answer follows it."""
    system, load = system_and_load()
    calls = []
    true = shakedown.friction_constraints

    def recording(sys_):
        calls.append(sys_)
        fc = true(sys_)
        return type(fc)(2.0 * fc.rows, fc.node, fc.sign, fc.friction)

    ref = {"safe": safe_region(system, load).G, "adm": admissible_region_at(system, load)[0],
           "ext": extreme_constraints(system, load, steps=64)[0]}
    monkeypatch.setattr(shakedown, "friction_constraints", recording)
    assert np.array_equal(safe_region(system, load).G, 2.0 * ref["safe"])
    assert np.array_equal(admissible_region_at(system, load)[0], 2.0 * ref["adm"])
    assert np.array_equal(extreme_constraints(system, load, steps=64)[0], 2.0 * ref["ext"])
    before = len(calls)
    basins.admissible_box(system, load)
    shakedown.sample_initial_slips(system, load, 3)
    assert len(calls) == before + 2
    assert all(c is system for c in calls)
