"""Shakedown limit λ2 of the 3-D system: a second-order cone program.

With every node in contact, a slip state v (the residual tangential reaction field is
A v, the residual normal field B v) is *safe* for the whole cycle iff at every instant
every node lies in its cone,

    | q0_j(θ) + λ q1_j(θ) + (A v)_j |  ≤  f_j ( p0_j(θ) + λ p1_j(θ) + (B v)_j ),

the loads split as r^w(θ; λ) = r0(θ) + λ r1(θ) (:meth:`~slipcycle.discrete3d.loads.Load3D.
split_lam`). The set of safe v is the *safe region* S(λ) (Klarbring, Ciavarella & Barber
2007; Ahn, Bertocchi & Barber 2008 for the 2-D polyhedron); on the cone it is convex but
not polyhedral. λ2 = sup{λ : S(λ) ≠ ∅} is the second-order cone program

    maximise λ over (v, λ)  subject to  (f_j p_j(θ_k), q_j(θ_k)) ∈ 𝒦³ for all j, k,

solved with Clarabel (Goulart & Chen 2024, an interior-point solver for conic programs).
Over the load samples θ_k the program is exact for the piecewise-linear load path the
simulation follows: for fixed v the constraint is a second-order cone in (q^w, p^w), so it
holds along a chord when it holds at its ends. For an uncoupled system (B = 0) the
frictional Melan theorem (Klarbring et al. 2007) makes λ2 the shakedown limit: below it
the system shakes down from every start, above it it cannot.

References
----------
A. Klarbring, M. Ciavarella, J. R. Barber, "Shakedown in elastic contact problems with
Coulomb friction", Int. J. Solids Struct. 44 (2007) 8355–8365. Y. J. Ahn, E. Bertocchi,
J. R. Barber, J. Mech. Phys. Solids 56 (2008) 3433–3440. P. J. Goulart, Y. Chen,
"Clarabel: an interior-point solver for conic programs with quadratic objectives",
arXiv:2405.12762 (2024).
"""

from __future__ import annotations

from dataclasses import dataclass

import clarabel
import numpy as np
import scipy.sparse as sp

from slipcycle.discrete3d.loads import Load3D
from slipcycle.discrete3d.model import FrictionalSystem3D
from slipcycle.errors import SolverError

__all__ = ["SafeRegion3D", "lambda2_socp", "is_safe"]


@dataclass(frozen=True)
class SafeRegion3D:
    """Result of :func:`lambda2_socp`.

    Attributes
    ----------
    lambda2 : float
        Largest load factor with a non-empty safe region (``lam_max`` if the program hit
        that cap, 0 if even λ = 0 has no safe state, then ``feasible`` is False).
    safe_slip : (N, 2) array
        A safe slip state at λ2 [m] (residual tangential reactions A v).
    feasible : bool
        Whether some λ ≥ 0 has a safe state.
    status : str
        Clarabel's status.
    samples : int
        Load samples of the program.
    """

    lambda2: float
    safe_slip: np.ndarray
    feasible: bool
    status: str
    samples: int


def _cone_rows(system: FrictionalSystem3D, r0: np.ndarray, r1: np.ndarray):
    """Clarabel rows s = b − G y ∈ 𝒦³ per (sample, node), y = [v (2N), λ]."""
    n = system.n_nodes
    f = system.friction
    A, B = system.A, system.B
    ns = r0.shape[0]
    # per node j: rows (t, u1, u2) = (f p, q1, q2) as affine functions of y
    Gv = np.empty((n, 3, 2 * n))
    Gv[:, 0] = f[:, None] * B
    Gv[:, 1] = A[0::2]
    Gv[:, 2] = A[1::2]
    q0 = r0[:, :2 * n].reshape(ns, n, 2)
    q1 = r1[:, :2 * n].reshape(ns, n, 2)
    p0, p1 = r0[:, 2 * n:], r1[:, 2 * n:]
    b = np.concatenate([(f * p0)[:, :, None], q0], axis=2)          # (ns, n, 3)
    g_lam = np.concatenate([(f * p1)[:, :, None], q1], axis=2)      # (ns, n, 3)
    G = np.concatenate([np.broadcast_to(Gv, (ns, n, 3, 2 * n)), g_lam[..., None]], axis=3)
    return -G.reshape(ns * n * 3, 2 * n + 1), b.reshape(-1)


def lambda2_socp(system: FrictionalSystem3D, load: Load3D, steps_per_cycle: int = 100,
                 *, lam_max: float = 1e6, tol: float = 1e-9) -> SafeRegion3D:
    """λ2 by the second-order cone program of the module docstring.

    Parameters
    ----------
    system : FrictionalSystem3D
    load : Load3D
        Its λ is ignored (the program scales the periodic part).
    steps_per_cycle : int
        Load samples (the cycle samples of the simulation, breakpoints included).
    lam_max : float
        Cap on λ (a load whose periodic part never leaves the cones has no finite λ2).
    tol : float
        Clarabel's gap and feasibility tolerances.

    Returns
    -------
    SafeRegion3D

    Raises
    ------
    SolverError
        If Clarabel stops without a solution or a certificate.
    """
    n = system.n_nodes
    theta, _ = load.cycle_samples(steps_per_cycle)
    theta = theta[:-1]
    r0, r1 = load.split_lam(theta)
    G, b = _cone_rows(system, r0, r1)
    nv = 2 * n + 1
    # λ ≥ 0 and λ ≤ lam_max as two non-negative rows, then the cones
    Gb = np.zeros((2, nv))
    Gb[0, -1] = -1.0
    Gb[1, -1] = 1.0
    Aall = sp.csc_matrix(np.vstack([Gb, G]))
    ball = np.concatenate([[0.0, lam_max], b])
    cones = [clarabel.NonnegativeConeT(2)] + [clarabel.SecondOrderConeT(3)] * (len(b) // 3)
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.tol_gap_abs = settings.tol_gap_rel = tol
    settings.tol_feas = tol
    c = np.zeros(nv)
    c[-1] = -1.0
    # a tiny regularisation of v picks the safe state of least norm at λ2
    P = sp.csc_matrix(sp.diags(np.concatenate([np.full(2 * n, 1e-12), [0.0]])))
    solver = clarabel.DefaultSolver(P, c, Aall, ball, cones, settings)
    sol = solver.solve()
    status = str(sol.status)
    if "Infeasible" in status and "Dual" not in status:
        return SafeRegion3D(0.0, np.zeros((n, 2)), False, status, theta.size)
    if "Solved" not in status:
        raise SolverError(f"the shakedown cone program stopped with status {status}")
    y = np.asarray(sol.x)
    return SafeRegion3D(float(y[-1]), y[:2 * n].reshape(n, 2), True, status, theta.size)


def is_safe(system: FrictionalSystem3D, load: Load3D, v: np.ndarray,
            steps_per_cycle: int = 100, rtol: float = 1e-9) -> bool:
    """Whether the slip state v ((N, 2) or (2N,)) lies in the safe region of ``load``
    (every node inside its cone at every sample, to ``rtol`` × the load scale)."""
    n = system.n_nodes
    theta, vals = load.cycle_samples(steps_per_cycle)
    x = np.concatenate([np.asarray(v, float).reshape(2 * n), np.zeros(n)])
    r = vals + system.K @ x
    q = r[:, :2 * n].reshape(len(theta), n, 2)
    p = r[:, 2 * n:]
    scale = max(float(np.max(np.abs(vals))), 1e-300)
    return bool(np.all(system.friction * p - np.linalg.norm(q, axis=2) >= -rtol * scale))
