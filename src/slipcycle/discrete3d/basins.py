"""Basins of attraction of the 3-D system: steady states reached from many starts.

A coupled system (B ≠ 0) may reach different steady cycles from different initial slip
states or assembly protocols (Andersson, Barber & Ahn 2013; Barber 2012, §3.1): every
start is run to its steady state with :func:`~slipcycle.discrete3d.steady.simulate3d`, and
the class, dissipation and start-of-cycle state are recorded. Random starts are initial
slips admissible at θ = 0 (inside every cone), drawn uniformly in a box and kept by
rejection. For an uncoupled system (B = 0) every start must reach the same dissipation
(frictional Melan theorem).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from slipcycle.discrete3d.loads import Load3D
from slipcycle.discrete3d.model import FrictionalSystem3D
from slipcycle.discrete3d.steady import (
    InadmissibleInitialState3D,
    initial_state_3d,
    simulate3d,
)

__all__ = ["Basins3D", "random_starts", "basins3d", "distinct_values"]


@dataclass(frozen=True)
class Basins3D:
    """Steady states reached from each start.

    Attributes
    ----------
    labels : tuple of str
        ``"start k"`` / ``"protocol k"``.
    steady_state : tuple of str
        The class reached from each start.
    dissipation_per_cycle : (S,) array
        Dissipation of the last cycle [J].
    final_states : (S, 3N) array
        Start-of-cycle state [v, w] of the last cycle [m].
    cycles_run : (S,) int array
    """

    labels: tuple
    steady_state: tuple
    dissipation_per_cycle: np.ndarray
    final_states: np.ndarray
    cycles_run: np.ndarray

    def attractors(self, rtol: float = 1e-6) -> list[float]:
        """Distinct steady dissipations (within ``rtol`` of the largest) [J]."""
        return distinct_values(self.dissipation_per_cycle, rtol)


def distinct_values(values, rtol: float = 1e-6) -> list[float]:
    """The distinct values of ``values``, sorted, two being one when they differ by at
    most ``rtol`` times the largest magnitude (the attractors of a basin study)."""
    d = np.sort(np.asarray(values, float))
    scale = max(float(np.max(np.abs(d), initial=0.0)), 1e-300)
    out: list[float] = []
    for x in d:
        if not out or abs(x - out[-1]) > rtol * scale:
            out.append(float(x))
    return out


def random_starts(system: FrictionalSystem3D, load: Load3D, count: int, scale: float, *,
                  seed: int = 0, max_tries: int = 10_000) -> np.ndarray:
    """``count`` initial slips (count, N, 2) [m] admissible at θ = 0, uniform in
    [−scale, scale] per component, by rejection.

    Parameters
    ----------
    system : FrictionalSystem3D
    load : Load3D
        The loads; the starts must satisfy the cone at θ = 0.
    count : int
        Number of starts wanted.
    scale : float
        Half-width of the uniform draw of each slip component, m.
    seed : int
        Seed of the random generator (the same seed gives the same starts).
    max_tries : int
        Draws allowed before giving up.

    Returns
    -------
    numpy.ndarray, shape (count, N, 2)
        Admissible initial slips, m.

    Raises
    ------
    ValueError
        If fewer than ``count`` admissible starts were found in ``max_tries`` draws.
    """
    rng = np.random.default_rng(seed)
    n = system.n_nodes
    r0 = load(np.array([0.0]))[0]
    tol = 1e-10 * max(float(np.max(np.abs(r0))), 1e-300)
    found = []
    for _ in range(max_tries):
        v = rng.uniform(-scale, scale, (n, 2))
        try:
            initial_state_3d(system, r0, v, tol)
        except InadmissibleInitialState3D:
            continue
        found.append(v)
        if len(found) == count:
            return np.array(found)
    raise ValueError(f"only {len(found)} of {count} random starts were admissible at θ = 0; "
                     "reduce the scale")


def basins3d(system: FrictionalSystem3D, load: Load3D, *, starts=None, protocols=None,
             **run) -> Basins3D:
    """Run every start (initial slips (S, N, 2) and/or protocols, each (M, 3N)) to its
    steady state.

    Parameters
    ----------
    system : FrictionalSystem3D
    load : Load3D
    starts : (S, N, 2) array, optional
    protocols : sequence of (M, 3N) arrays, optional
    **run
        Settings of :func:`simulate3d` (``cycles``, ``steps_per_cycle``, ``tol``, ...).

    Returns
    -------
    Basins3D
    """
    labels, states, diss, finals, cycles = [], [], [], [], []
    jobs = [("start", {"initial_slip": v}) for v in ([] if starts is None else starts)]
    jobs += [("protocol", {"protocol": p}) for p in ([] if protocols is None else protocols)]
    counts = {"start": 0, "protocol": 0}
    for kind, kw in jobs:
        res = simulate3d(system, load, record=False, **kw, **run)
        labels.append(f"{kind} {counts[kind]}")
        counts[kind] += 1
        states.append(res.steady_state)
        diss.append(res.dissipation_per_cycle)
        finals.append(res.cycle_start_states[-1])
        cycles.append(res.cycles_run)
    n3 = 3 * system.n_nodes
    return Basins3D(tuple(labels), tuple(states), np.array(diss),
                    np.array(finals).reshape(-1, n3), np.array(cycles, int))
