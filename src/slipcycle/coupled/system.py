"""System methods shared by the 2-D and 3-D coupled discrete frictional systems.

Both store the reduced stiffness ``K = [[A, Bᵀ], [B, C]]`` with C the N×N normal block, and
states and reactions tangential part first, ``x = [v, w]``, ``r = [q, p] = r^w + K x``
(J. R. Barber, J. Phys.: Conf. Ser. 382 (2012) 012002, §3).
"""

from __future__ import annotations

import numpy as np

from slipcycle.errors import ModelError
from slipcycle.io.case import friction_range_problem

__all__ = ["CoupledSystem", "coupled_stiffness", "friction_per_node"]


class CoupledSystem:
    """Mix-in of the coupled discrete systems: what does not depend on the dimension.

    A subclass is a frozen dataclass with the arrays ``A``, ``B``, ``C``, ``K`` and
    ``friction``, a ``critical_friction`` property (``f_crit``, ``method``, ``nodes``),
    and sets :attr:`ERROR` (the :class:`~slipcycle.errors.ModelError` it raises) and
    :attr:`ILL_POSED` (why f ≥ f_crit is refused, in words).
    """

    #: the error class of the model
    ERROR: type[ModelError] = ModelError
    #: what f ≥ f_crit makes ill posed, and by which condition
    ILL_POSED: str = ""

    @property
    def n_nodes(self) -> int:
        """Number of contact nodes N."""
        return self.C.shape[0]

    @property
    def uncoupled(self) -> bool:
        """True if B = 0 (the frictional Melan theorem applies)."""
        return not np.any(self.B)

    def reactions(self, x: np.ndarray, r_w: np.ndarray) -> np.ndarray:
        """Reactions ``r = [q, p] = r^w + K x`` [N] for states ``x = [v, w]`` [m], of shape
        (M,) or (..., M) with M the number of degrees of freedom."""
        return r_w + x @ self.K.T

    def stiffness_scale(self) -> float:
        """A typical stiffness (largest diagonal entry of K) [N/m]."""
        return float(np.max(np.diag(self.K)))

    def _store(self, **arrays) -> None:
        """Set the validated arrays as read-only float fields of the frozen system, and
        check the ``accept_ill_posed`` flag."""
        for name, val in arrays.items():
            val = np.array(val, dtype=float)
            val.setflags(write=False)
            object.__setattr__(self, name, val)
        if not isinstance(self.accept_ill_posed, (bool, np.bool_)):
            raise self.ERROR("accept_ill_posed", "must be True or False, got "
                                                 f"{self.accept_ill_posed!r}")

    def _ill_posed_nodes(self, fc) -> str:
        """The nodes (and what else the model reports) of the critical combination."""
        nodes = [int(j) for j in fc.nodes]
        if len(nodes) > 8:      # one line: the first nodes and how many there are
            return f"nodes {nodes[:8]} … ({len(nodes)} in all)"
        return f"nodes {nodes}"

    def _check_well_posed(self) -> None:
        """Refuse f ≥ f_crit (Klarbring's P-matrix condition), keyed ``friction``, with the
        remedy ``accept_ill_posed = true``."""
        fc = self.critical_friction
        fmax = float(np.max(self.friction))
        if fmax >= fc.f_crit:
            raise self.ERROR("friction",
                             f"f = {fmax:g} is not below the critical friction coefficient "
                             f"f_crit = {fc.f_crit:.6g} ({fc.method}; "
                             f"{self._ill_posed_nodes(fc)}): {self.ILL_POSED}",
                             remedy=("accept_ill_posed", True, "run anyway"))


def likely_cause(system) -> str:
    """Why the incremental or rate problem of a coupled system may have no solution: f
    above its critical value for the current slipping and separated nodes (a system run
    with ``accept_ill_posed``), or, f checked below it, loads of sizes too far apart for
    double precision (a preload 1e16 times a service load, a displacement amplitude of
    1e10 m on a µm preload)."""
    if getattr(system, "accept_ill_posed", True):
        return ("the friction coefficient is probably above the critical value for the "
                "current set of slipping and separated nodes")
    return ("f is below the sampled critical value, so the likely cause is loads of "
            "sizes too far apart for double precision (the round-off of the largest "
            "above the smallest), or a critical value the sampling missed")


def coupled_stiffness(A: np.ndarray, B: np.ndarray, C: np.ndarray,
                      error: type[ModelError] = ModelError) -> np.ndarray:
    """The reduced stiffness K = [[A, Bᵀ], [B, C]] [N/m], refused (keyed ``B``) unless it is
    positive definite (Cholesky; the eigenvalue only for the message)."""
    K = np.block([[A, B.T], [B, C]])
    try:
        np.linalg.cholesky(K)
    except np.linalg.LinAlgError:
        eig = np.linalg.eigvalsh(K)[0]
        raise error("B", "K = [[A, Bᵀ], [B, C]] is not positive definite "
                         f"(smallest eigenvalue {eig:.6g}): the coupling B is too "
                         "large for A and C") from None
    return K


def friction_per_node(friction, n: int, error: type[ModelError] = ModelError) -> np.ndarray:
    """The friction coefficient of each of the n nodes, (n,) [1]: a number for all or one
    per node, finite and ≥ 0 (keyed ``friction``)."""
    try:
        f = np.asarray(friction, dtype=float)
    except (TypeError, ValueError):
        raise error("friction", "must be a number or a list of numbers") from None
    if f.ndim == 0:
        f = np.full(n, float(f))
    if f.shape != (n,):
        raise error("friction", f"must be a number or a list of {n} numbers, got shape "
                                f"{f.shape}")
    if not np.all(np.isfinite(f)):
        raise error("friction", "must be finite")
    if np.any(f < 0):
        raise error("friction", f"must be >= 0, got {f[f < 0][0]:g}")
    problem = friction_range_problem(f)
    if problem:
        raise error("friction", problem)
    return f
