"""The scale of the service cycle: what counts as slip in a steady cycle.

A steady cycle is ``shakedown`` when no node slips in it (Barber 2012, §3), and a node
"slips" when its slip length over the cycle exceeds a tolerance that separates slip from
the round-off and step-control noise of the evolution. That tolerance must be relative to
what the *periodic* load can do: the elastic displacement of its variation over the cycle,
r^w(θ) − r^w(0). Measured against the whole load instead (a bolt preload thousands of
times the service load, or the slip and initial gap left by the assembly), a real microslip
under a small service load falls below it and the run is called ``shakedown`` while it
dissipates energy every cycle.

References
----------
Barber, J. R. (2012). Frictional systems subjected to oscillating loads. Ann. Solid Struct.
Mech. 2, 45–55.
"""

from __future__ import annotations

import numpy as np

__all__ = ["service_force_scale", "service_displacement_scale", "cycle_slip_tolerance",
           "service_slip_tolerance", "slips_in_cycle"]


def service_force_scale(samples: np.ndarray, whole: float) -> float:
    """Force scale of the service cycle [N]: max_s |r^w(θ_s) − r^w(θ_0)|_∞, the variation
    of the load over the cycle, at most ``whole`` (the whole load's scale: a load that
    swings about zero varies by twice its amplitude), and ``whole`` for a constant load.

    The tolerances of the cycles follow it (the friction limits' and the step control's,
    and the steady-state residual, :class:`~slipcycle.coupled.cycles.ResidualScale`):
    relative to the whole load (a preload 1e7 times the service load) they would let a
    node slip a whole-load tolerance early at every reversal and pass the transient of
    the first cycles as steady; capped by it, they are never coarser than before.

    Parameters
    ----------
    samples : (S, M) array
        Load samples r^w(θ_s) of one cycle [N] (the first at θ = 0).
    whole : float
        Force scale of the whole load [N].

    Returns
    -------
    float
    """
    variation = _variation(samples)
    return min(variation, float(whole)) if variation > 0.0 else float(whole)


def _variation(samples: np.ndarray) -> float:
    """max_s |r^w(θ_s) − r^w(θ_0)|_∞ [N]."""
    samples = np.asarray(samples, float)
    return float(np.max(np.abs(samples - samples[0]), initial=0.0))


def service_displacement_scale(samples: np.ndarray, stiffness_scale: float) -> float:
    """Elastic displacement scale of the service cycle [m].

    Parameters
    ----------
    samples : (S, M) array
        Load samples r^w(θ_s) of one cycle [N] (the first at θ = 0).
    stiffness_scale : float
        max diag K of the system [N/m].

    Returns
    -------
    float
        max_s |r^w(θ_s) − r^w(θ_0)|_∞ / max diag K: the displacement the variation of the
        load over the cycle gives a node held only by its own stiffness; 0 for a constant
        load.
    """
    return _variation(samples) / float(stiffness_scale)


def cycle_slip_tolerance(tol: float, service_scale: float, disp_scale: float) -> float:
    """Slip length [m] at or below which a node counts as stuck over a steady cycle.

    max(100 tol, 1e-9) × u_s, u_s the service cycle's displacement scale
    (:func:`service_displacement_scale`), so that the threshold follows the service
    load, not the preload; at least 1e-12 × the displacement scale of the whole load
    (round-off of a cycle whose load hardly varies).

    Parameters
    ----------
    tol : float
        Steady-state tolerance [1].
    service_scale : float
        u_s [m].
    disp_scale : float
        Displacement scale of the whole load [m].

    Returns
    -------
    float
    """
    return max(max(100 * tol, 1e-9) * service_scale, 1e-12 * disp_scale)


def service_slip_tolerance(tol: float, samples: np.ndarray, stiffness_scale: float,
                           disp_scale: float) -> float:
    """The slip tolerance of a steady cycle under the load ``samples``: the one rule that
    classifies every steady-state run (``shakedown`` / ``cyclic_slip``).

    :func:`cycle_slip_tolerance` of :func:`service_displacement_scale`: a node whose slip
    length over the cycle exceeds it slips, so that the class follows the service load
    (and with it the dissipation, at most f p × the slip length per node), not the
    preload or the state the assembly left.

    Parameters
    ----------
    tol : float
        Steady-state tolerance [1].
    samples : (S, M) array
        Load samples r^w(θ_s) of one cycle [N].
    stiffness_scale : float
        max diag K [N/m].
    disp_scale : float
        Displacement scale of the whole load [m].

    Returns
    -------
    float
        Slip length [m].
    """
    return cycle_slip_tolerance(tol, service_displacement_scale(samples, stiffness_scale),
                                disp_scale)


#: a node slips in the cycle only if its slip length exceeds this multiple of its net
#: movement over the cycle: a node creeping monotonically towards a stuck limit has slip
#: length equal to its net movement (factor 1), one that slips back and forth has more
CREEP_FACTOR = 2.0


def slips_in_cycle(slip_length: np.ndarray, drift: np.ndarray, slip_tol: float,
                   ratcheting: bool = False) -> np.ndarray:
    """Which nodes slip in the last cycle run (the ``slipping_nodes`` of every run).

    A node slips when its slip length over the cycle exceeds ``slip_tol``
    (:func:`service_slip_tolerance`) and, unless the state ratchets, also
    :data:`CREEP_FACTOR` × its net movement over the cycle: a run stopped before its limit
    (or one whose convergence test is measured against a much larger preload) still has
    nodes creeping geometrically towards their stuck state, each cycle by the same small
    amount in the same direction; they are stuck in the limit, and their slip is the
    convergence error, not cyclic slip. A ratcheting node moves on every cycle by its
    drift and counts as slipping by its slip length alone.

    Parameters
    ----------
    slip_length : (N,) or (M, N) array
        Slip length of each node over the last cycle [m] (of M runs).
    drift : (N,) or (M, N) array
        Norm of each node's tangential start-of-cycle change over that cycle [m].
    slip_tol : float
        [m].
    ratcheting : bool or (M,) bool array
        The run's state ratchets (each run's).

    Returns
    -------
    (N,) or (M, N) bool array
    """
    slip_length = np.asarray(slip_length, float)
    beyond_creep = slip_length > CREEP_FACTOR * np.asarray(drift, float)
    # (1,) or (M, 1): one flag per run, broadcast over its nodes
    ratchets = np.expand_dims(np.asarray(ratcheting, bool), -1)
    return (slip_length > slip_tol) & (beyond_creep | ratchets)
