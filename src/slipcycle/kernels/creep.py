"""How far a geometrically converging cycle sequence still is from its limit.

Plain cycling of a frictional system converges to its periodic state at the rate of the
cycle map's spectral radius ρ; FE-reduced models creep at ρ close to 1, where the last
increment says little: the rest of the creep is ρ/(1 − ρ) times it (Aitken's Δ² estimate;
Brezinski & Redivo Zaglia, *Extrapolation Methods*, 1991, §2.1). The steady-state tests
of the discrete models require that distance, not the last increment alone, to be below
their tolerance.
"""

from __future__ import annotations

import numpy as np

__all__ = ["creep_distance"]


def creep_distance(starts, residual: float, xscale: float) -> float:
    """The distance of the last start-of-cycle state to the sequence's limit, relative to
    ``xscale``.

    Parameters
    ----------
    starts : sequence of (n,) arrays
        Successive start-of-cycle states of plain cycles (no step between them) [m].
    residual : float
        max |x_c − x_{c−1}| / ``xscale`` of the last two.
    xscale : float
        Displacement scale [m].

    Returns
    -------
    float
        ρ/(1 − ρ) · ``residual`` with ρ = |x_c − x_{c−1}| / |x_{c−1} − x_{c−2}| (max
        norms) where the increments shrink, by a ratio above one half; else ``residual``
        (a faster contraction has at most that much left; increments that do not shrink,
        fewer than three starts, or increments within a thousand round-offs of the state
        give no ratio).
    """
    if len(starts) < 3:
        return residual
    last = residual * xscale
    before = float(np.max(np.abs(starts[-2] - starts[-3])))
    if last <= 1e3 * np.finfo(float).eps * xscale or not 0.0 < last < before:
        return residual
    rho = last / before
    return max(residual, residual * rho / (1.0 - rho))
