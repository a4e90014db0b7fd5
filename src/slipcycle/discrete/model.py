"""The coupled discrete frictional system (J. R. Barber, "Frictional systems under periodic
loads — history-dependence, non-uniqueness and energy dissipation", J. Phys.: Conf. Ser. 382
(2012) 012002, §3).

N contact nodes of a 2-D elastic body, reduced to the contact degrees of freedom:

    q = q^w(θ) + A v + Bᵀ w      tangential reactions
    p = p^w(θ) + B v + C w       normal reactions (compressive positive)

with v the tangential slip and w ≥ 0 the normal separation of each node. The reduced
stiffness K = [[A, Bᵀ], [B, C]] must be symmetric positive definite.

Vectors of the state and of the reactions are stored with the tangential part first:
``x = [v, w]`` (2N,) and ``r = [q, p]`` (2N,), so that ``r = r^w + K x``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from slipcycle.coupled.system import CoupledSystem, coupled_stiffness, friction_per_node
from slipcycle.errors import ModelError

__all__ = ["FrictionalSystem", "ModelError", "STICK", "SLIP_POS", "SLIP_NEG", "SEPARATED",
           "STATE_NAMES"]

#: Node states (modes). ``SLIP_POS``: v̇ > 0 with q = −f p; ``SLIP_NEG``: v̇ < 0 with q = +f p.
STICK, SLIP_POS, SLIP_NEG, SEPARATED = 0, 1, 2, 3
STATE_NAMES = ("stick", "slip_positive", "slip_negative", "separated")

#: largest ``f_crit_exact_max_nodes``: the exact enumeration visits (3^N − 1)/2 pairs
_EXACT_MAX_NODES = 14


def _square(name: str, M, n: int | None) -> np.ndarray:
    try:
        M = np.asarray(M, dtype=float)
    except (TypeError, ValueError):
        raise ModelError(name, "must be a square matrix of numbers") from None
    if M.ndim != 2 or M.shape[0] != M.shape[1]:
        raise ModelError(name, f"must be a square matrix, got shape {M.shape}")
    if n is not None and M.shape[0] != n:
        raise ModelError(name, f"must be {n}×{n} like A, got {M.shape[0]}×{M.shape[1]}")
    if not np.all(np.isfinite(M)):
        raise ModelError(name, "must contain only finite numbers (found nan or inf)")
    return M


def _check_spd(name: str, M: np.ndarray, rtol: float = 1e-10) -> None:
    scale = max(np.max(np.abs(M)), np.finfo(float).tiny)
    asym = np.max(np.abs(M - M.T))
    if asym > rtol * scale:
        i, j = np.unravel_index(np.argmax(np.abs(M - M.T)), M.shape)
        raise ModelError(name, f"must be symmetric: entries [{i}][{j}] = {M[i, j]:.6g} and "
                               f"[{j}][{i}] = {M[j, i]:.6g} differ")
    eig = np.linalg.eigvalsh(0.5 * (M + M.T))
    if eig[0] <= rtol * max(eig[-1], 0.0) or eig[0] <= 0.0:
        raise ModelError(name, f"must be positive definite: smallest eigenvalue {eig[0]:.6g} "
                               f"(largest {eig[-1]:.6g})")


@dataclass(frozen=True)
class FrictionalSystem(CoupledSystem):
    """A validated coupled discrete frictional system.

    Parameters
    ----------
    A : (N, N) array_like
        Tangential stiffness [N/m], symmetric positive definite.
    B : (N, N) array_like
        Normal–tangential coupling [N/m]: ``B[j, i]`` is the normal reaction at node j per
        unit slip of node i. Unrestricted; ``B = 0`` is the uncoupled case.
    C : (N, N) array_like
        Normal stiffness [N/m], symmetric positive definite.
    friction : float or (N,) array_like
        Coulomb coefficient f ≥ 0 of each node.
    accept_ill_posed : bool, optional
        ``False`` (default): refuse f ≥ f_crit, the critical friction coefficient below
        which the rate problem has a unique solution (A. Klarbring, "Examples of
        non-uniqueness and non-existence of solutions to quasistatic contact problems with
        friction", Ing.-Arch. 60 (1990) 529–541; P-matrix condition, see
        :func:`~slipcycle.discrete.wellposed.critical_friction`). ``True``: accept it
        (the solvers may then stop with :class:`~slipcycle.errors.SolverError`); the
        case-file key ``discrete.accept_ill_posed = true`` passes it.
    f_crit_exact_max_nodes : int, optional
        Largest N for which f_crit is computed exactly (else a bound is used), 0 to 14
        (the exact enumeration visits (3^N − 1)/2 subset/sign pairs). Default 10.

    Raises
    ------
    ModelError
        Naming the matrix and the failed property (shape, finiteness, symmetry, positive
        definiteness of A, C or of the whole K = [[A, Bᵀ], [B, C]], f < 0, and unless
        ``accept_ill_posed=True`` f ≥ f_crit, keyed ``friction``), or the value of
        ``accept_ill_posed`` or ``f_crit_exact_max_nodes``.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    friction: np.ndarray
    K: np.ndarray = field(init=False, repr=False, compare=False)
    accept_ill_posed: bool = field(default=False, compare=False)
    f_crit_exact_max_nodes: int = field(default=10, compare=False, repr=False)

    ILL_POSED = "the rate problem is ill posed (Klarbring P-matrix condition)"

    def __post_init__(self):
        A = _square("A", self.A, None)
        n = A.shape[0]
        if n < 1:
            raise ModelError("A", "must have at least one node")
        B = _square("B", self.B, n)
        C = _square("C", self.C, n)
        _check_spd("A", A)
        _check_spd("C", C)
        A = 0.5 * (A + A.T)
        C = 0.5 * (C + C.T)
        K = coupled_stiffness(A, B, C)
        f = friction_per_node(self.friction, n)
        self._store(A=A, B=B, C=C, friction=f, K=K)
        exact = self.f_crit_exact_max_nodes
        if isinstance(exact, (bool, np.bool_)) or not isinstance(exact, (int, np.integer)):
            raise ModelError("f_crit_exact_max_nodes", f"must be an integer, got {exact!r}")
        for bad, bound in ((exact < 0, ">= 0"), (exact > _EXACT_MAX_NODES,
                                                  f"<= {_EXACT_MAX_NODES}")):
            if bad:
                raise ModelError("f_crit_exact_max_nodes", f"must be {bound}, got {exact}")
        if not self.accept_ill_posed:
            self._check_well_posed()

    @cached_property
    def critical_friction(self):
        """Klarbring's critical friction coefficient of this system, with the friction
        ratios of its nodes (a :class:`~slipcycle.discrete.wellposed.CriticalFriction`;
        exact up to ``f_crit_exact_max_nodes`` nodes)."""
        from slipcycle.discrete.wellposed import critical_friction

        return critical_friction(self.A, self.B, self.friction,
                                 exact_max_nodes=self.f_crit_exact_max_nodes)

    def _ill_posed_nodes(self, fc) -> str:
        """The critical nodes and their slip signs (the 2-D rate problem has both)."""
        return f"nodes {list(fc.nodes)}, slip signs {list(fc.signs)}"
