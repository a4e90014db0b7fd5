"""Contact sets of the elastic solution at a fixed slip, and the reactions of the closed
nodes with the open ones condensed out (3-D shakedown with separation).

In a shakedown state no node slips: a closed node j keeps its slip v_j, an open node
carries no force (q_j = 0, p_j = 0) and moves freely with the elastic body. At a load
sample with open set O and closed set C the open degrees of freedom follow from the
closed ones, ``x_O = −K_OO⁻¹ (r^w_O + K_Ot v_C)``, and the reactions of the closed nodes
are affine in (v_C, r^w):

    r_C = (r^w_C − K_CO K_OO⁻¹ r^w_O) + (K_Ct − K_CO K_OO⁻¹ K_Ot) v_C,

the Schur complement of the open block (static condensation). The contact set itself is
that of the elastic solution with the closed nodes stuck at their slip: every closed node
compressive (p_j ≥ 0), every open node with a non-negative gap (w_j ≥ 0). It is found by
an active-set iteration: block pivoting while no set repeats, then the least-index rule
(K. G. Murty, "Linear Complementarity, Linear and Nonlinear Programming", Heldermann 1988,
ch. 2); a set that does not settle is an error, never a guess.

References
----------
A. Klarbring, M. Ciavarella, J. R. Barber, "Shakedown in elastic contact problems with
Coulomb friction", Int. J. Solids Struct. 44 (2007) 8355–8365 (the safe state with
separation: an open node's residual force vanishes).
"""

from __future__ import annotations

import numpy as np

from slipcycle.discrete3d.model import FrictionalSystem3D
from slipcycle.errors import SolverError

__all__ = ["elastic_open_set", "elastic_reactions", "open_sets", "closed_rows"]


def _dofs(n: int, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Tangential (2k,) and normal (k,) degrees of freedom of ``nodes`` (k,)."""
    t = np.stack([2 * nodes, 2 * nodes + 1], axis=1).reshape(-1)
    return t, 2 * n + nodes


def elastic_reactions(system: FrictionalSystem3D, r: np.ndarray, slip: np.ndarray,
                      is_open: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Elastic solution at the load r^w (3N,) with the nodes ``is_open`` (N,) free and the
    others stuck at ``slip`` ((2N,) [m]) with zero gap: reactions r (3N,) [N] and state
    x = [v, w] (3N,) [m]."""
    n = is_open.size
    K = system.K
    o = np.flatnonzero(is_open)
    ct, _ = _dofs(n, np.flatnonzero(~is_open))
    x = np.zeros(3 * n)
    x[ct] = slip.reshape(-1)[ct]
    if o.size:
        ot, on = _dofs(n, o)
        od = np.concatenate([ot, on])
        x[od] = -np.linalg.solve(K[np.ix_(od, od)], r[od] + K[np.ix_(od, ct)] @ x[ct])
    return r + K @ x, x


def elastic_open_set(system: FrictionalSystem3D, r: np.ndarray, slip: np.ndarray,
                     start: np.ndarray | None = None, rtol: float = 1e-10) -> np.ndarray:
    """Open set of the elastic solution at the load r^w with the closed nodes stuck.

    Parameters
    ----------
    system : FrictionalSystem3D
    r : (3N,) array
        Load [q^w, p^w] [N].
    slip : (N, 2) or (2N,) array
        Slip of the nodes that are closed [m] (an open node's entry is not used).
    start : (N,) bool array, optional
        First guess of the open set (default: the nodes with p^w + B v < 0).
    rtol : float
        A reaction or gap within ``rtol`` × its scale of zero keeps the node's guess.

    Returns
    -------
    (N,) bool array
        True where the node is open.

    Raises
    ------
    SolverError
        If the active-set iteration cycles (meets a set twice under the least-index
        rule) or does not settle within 4 N + 10 changes.
    """
    n = system.n_nodes
    K = system.K
    slip = np.asarray(slip, float).reshape(2 * n)
    p_scale = rtol * max(float(np.max(np.abs(r))), 1e-300)
    w_scale = p_scale / max(float(np.max(np.diag(K))), 1e-300)
    if start is None:
        start = r[2 * n:] + system.B @ slip < 0
    is_open = np.asarray(start, bool).copy()
    seen, pivoted = set(), set()
    for it in range(4 * n + 10):
        reac, x = elastic_reactions(system, r, slip, is_open)
        p, w = reac[2 * n:], x[2 * n:]
        wrong = (is_open & (w < -w_scale)) | (~is_open & (p < -p_scale))
        if not wrong.any():
            return is_open
        key = is_open.tobytes()
        if key not in seen and it < n:
            # block pivoting: change every violator while no set repeats (fast) ...
            seen.add(key)
            is_open = is_open ^ wrong
        else:
            # ... then the least-index rule, one node per step. Each step depends on the
            # set alone, so a set met twice means a cycle that never settles: a node
            # stuck at its slip would pull (p < 0) and, free, would penetrate (w < 0)
            if key in pivoted:
                break
            pivoted.add(key)
            j = int(np.flatnonzero(wrong)[0])
            is_open[j] = not is_open[j]
    raise SolverError("the contact set of the elastic solution did not settle")


def open_sets(system: FrictionalSystem3D, vals: np.ndarray, slip: np.ndarray,
              previous: np.ndarray | None = None) -> np.ndarray:
    """Open sets (S, N) of the elastic solutions at the load samples ``vals`` (S, 3N)
    with the slip ``slip`` (:func:`elastic_open_set`), each started from ``previous``."""
    out = np.empty((vals.shape[0], system.n_nodes), bool)
    for k, r in enumerate(vals):
        out[k] = elastic_open_set(system, r, slip,
                                  None if previous is None else previous[k])
    return out


def closed_rows(system: FrictionalSystem3D, is_open: np.ndarray):
    """Reactions of the closed nodes and gaps of the open ones as linear maps.

    Parameters
    ----------
    system : FrictionalSystem3D
    is_open : (N,) bool array

    Returns
    -------
    c : (k,) int array
        The closed nodes.
    R_load : (3k, 3N) array
        Reactions [q (2k, node-major), p (k)] of the closed nodes per unit load r^w.
    R_slip : (3k, 2N) array
        The same per unit slip v [N/m] (zero columns for the open nodes).
    W_load, W_slip : (m, 3N), (m, 2N) arrays
        Gaps w of the m open nodes per unit load [m/N] and per unit slip [1].
    """
    n = system.n_nodes
    K = system.K
    o = np.flatnonzero(is_open)
    c = np.flatnonzero(~is_open)
    ct, cn = _dofs(n, c)
    cd = np.concatenate([ct, cn])
    # x_O = −K_OO⁻¹ (r_O + K_Ot v_C): as maps of the load (E_load) and of the slip (E_slip)
    E_load = np.zeros((3 * n, 3 * n))
    E_slip = np.zeros((3 * n, 2 * n))
    E_slip[ct, ct] = 1.0
    if o.size:
        ot, on = _dofs(n, o)
        od = np.concatenate([ot, on])
        Kinv = np.linalg.inv(K[np.ix_(od, od)])
        E_load[np.ix_(od, od)] = -Kinv
        E_slip[np.ix_(od, ct)] = -Kinv @ K[np.ix_(od, ct)]
    R_load = np.eye(3 * n)[cd] + K[cd] @ E_load
    R_slip = K[cd] @ E_slip
    nodes = 2 * n + o
    return c, R_load, R_slip, E_load[nodes], E_slip[nodes]
