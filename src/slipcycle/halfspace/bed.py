"""The slider bed equivalent to an uncoupled half-space contact.

By the Ciavarella–Jäger theorem a contact of similar half-spaces behaves, in its global
force–displacement response, like a bed of independent sliders indexed by the approach
level s at which they touch: P(U) = ∫ k(s) (U − s)₊ ds with k = d²P/dU². Slider i has
normal stiffness k_i, tangential stiffness k_i/λ_c and Coulomb limit f k_i (U − s_i)₊.

Discretisation. The load range [P_lo, P_max] is cut into cells of equal increments of
normal stiffness S = dP/dU (for the sphere this is equal increments of contact radius, as
in the method of dimensionality reduction). Cell j between loads P_j, P_{j+1} becomes one
slider of stiffness S_{j+1} − S_j placed at the stiffness-weighted centroid of the cell's
levels, so the discrete P(U) equals the exact law at every cell edge. Everything below
P_lo is lumped into one slider chosen to reproduce P and S at P_lo; it lies deeper than
every slider that slips while the loads stay above P_lo.

Which loads a history reaches. A slider can slip only where the stick load P_S of some
step lies below its level. For constant P and Q between ±Q*, P_S ≥ P − Q*/f (Mindlin &
Deresiewicz 1953); :func:`lumping_load` takes the conservative P_min − (Q_max − Q_min)/f
over the history (the range of Q includes the unloaded Q = 0), and callers check after the
run that slip never reached the lumped slider or the cell above it
(:func:`lumped_slider_slipped`), rerunning on an unlumped bed otherwise, so the result never
rests on the bound alone. The rough law
dP/dU = P/(γσ) has no first touch, so its bed always lumps below some P_lo > 0; its
construction (:func:`rough_unit_bed`) is compiled so that the Ŵ-map kernel and
:func:`make_bed` share it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from slipcycle.halfspace.profiles import RoughExponential

__all__ = ["SliderBed", "lumped_slider_slipped", "lumping_load", "make_bed",
           "rough_unit_bed", "UNLUMPED_FRACTION"]

#: where no bound applies, loads below this fraction of P_max are lumped (rough law only:
#: it needs some P_lo > 0); the lumped slider is exact in P(U) above it
UNLUMPED_FRACTION = 1e-9


@njit(cache=True)
def lumping_load(P_min, P_max, Q_min, Q_max, friction):
    """Load below which no slider slips over a history, or 0 if there is no such bound.

    Parameters
    ----------
    P_min, P_max : float
        Extreme normal loads of the history after the unloaded start (N or N/m).
    Q_min, Q_max : float
        Extreme tangential loads of the history (the unloaded Q = 0 is included).
    friction : float

    Returns
    -------
    float
        P_min − (Q_max − Q_min)/f when positive (with a margin of 1 % of the slip range,
        so the lumped cell never touches a stick front), else 0.
    """
    dq = (max(Q_max, 0.0) - min(Q_min, 0.0)) / friction
    bound = P_min - dq
    bound -= 0.01 * (P_max - bound)
    return bound if bound > 0.0 else 0.0


def lumped_slider_slipped(first_slip: np.ndarray) -> bool:
    """Whether slip reached the lumped slider (index 0) or the cell just above it.

    Slider 1 slipping means the stick front came within one cell of the lumped loads, so
    the history must be rerun on a bed that lumps less.
    """
    return bool(np.asarray(first_slip).size and np.min(first_slip) <= 1)


@njit(cache=True)
def rough_unit_bed(P_lo, P_max, n):
    """Slider bed of the rough law P = exp(U) (γσ = 1, reference load 1).

    Exact at n+1 equally spaced loads in [P_lo, P_max] (equal increments of S = dP/dU = P),
    one slider per cell at the stiffness-weighted centroid of its levels, plus one slider
    lumping everything below P_lo (reproducing P and S there).

    Returns
    -------
    level, kn : (n+1,) arrays
        Levels (units of γσ) and normal stiffnesses (units of 1/γσ).
    edge_load : (n+2,) array
        Loads at the cell edges, 0 first (the lumped slider's cell).
    """
    level = np.empty(n + 1)
    kn = np.empty(n + 1)
    edges = np.empty(n + 2)
    level[0] = np.log(P_lo) - 1.0          # reproduces P and dP/dU at P_lo
    kn[0] = P_lo
    edges[0] = 0.0
    edges[1] = P_lo
    dP = (P_max - P_lo) / n
    for j in range(n):
        Pa = P_lo + j * dP
        Pb = P_lo + (j + 1) * dP
        kn[j + 1] = dP                      # ΔS with S = dP/dU = P
        # centroid (Pb ln Pb − Pa ln Pa − ΔP)/ΔP = ln Pa + (1 + r) ln(1 + r)/r − 1 with
        # r = ΔP/Pa: the offset from ln Pa without the difference of two large
        # products, which cancels to round-off in the thin cells of a tiny amplitude
        r = (Pb - Pa) / Pa
        if r < 1e-4:
            offset = r * (0.5 - r * (1.0 / 6.0 - r * (1.0 / 12.0 - r / 20.0)))
        else:
            offset = (1.0 + r) * np.log1p(r) / r - 1.0
        level[j + 1] = np.log(Pa) + offset
        edges[j + 2] = Pb
    edges[n + 1] = P_max
    return level, kn, edges


@dataclass(frozen=True)
class SliderBed:
    """Independent Coulomb sliders with moving limits.

    Attributes
    ----------
    level : (n,) array
        Approach s_i (m) at which slider i touches; ascending.
    normal_stiffness : (n,) array
        k_i in N/m (N/m² per unit length for plane problems).
    compliance_ratio : float
        λ_c; tangential stiffness is k_i/λ_c.
    friction : float
        Coulomb coefficient f.
    edge_load : (n+1,) array
        Normal load P at the cell edges: slider i represents contact that forms between
        P = edge_load[i] and edge_load[i+1] (used for stick-zone extents).
    edge_size : (n+1,) array or None
        Contact size a(P) at the cell edges (m), when the profile defines one.
    """

    level: np.ndarray
    normal_stiffness: np.ndarray
    compliance_ratio: float
    friction: float
    edge_load: np.ndarray
    edge_size: np.ndarray | None = None

    @property
    def size(self) -> int:
        return self.level.size

    @property
    def tangential_stiffness(self) -> np.ndarray:
        return self.normal_stiffness / self.compliance_ratio

    def _cumulative(self):
        K = np.cumsum(self.normal_stiffness)
        M = np.cumsum(self.normal_stiffness * self.level)
        # load when U reaches each level: sum over sliders below of k (s_j - s_i)
        P_at_level = np.concatenate([[0.0], K[:-1] * self.level[1:] - M[:-1]])
        return K, M, P_at_level

    def load(self, U: np.ndarray) -> np.ndarray:
        """Normal load P(U) of the discrete bed (exact, piecewise linear)."""
        U = np.asarray(U, float)
        K, M, _ = self._cumulative()
        j = np.searchsorted(self.level, U, side="right") - 1
        jj = np.clip(j, 0, None)
        return np.where(j >= 0, K[jj] * U - M[jj], 0.0)

    def approach(self, P: np.ndarray) -> np.ndarray:
        """Approach U(P) of the discrete bed (exact inverse of :meth:`load`; P ≥ 0)."""
        P = np.asarray(P, float)
        K, M, P_at_level = self._cumulative()
        j = np.clip(np.searchsorted(P_at_level, P, side="right") - 1, 0, None)
        return np.where(P > 0, (P + M[j]) / K[j], self.level[0])

    def stick_extent(self, first_slipping: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """Stick load P_S and stick size for the index of the lowest slipping slider.

        Returns the load at the edge between the last stuck cell and the first slipping
        one, and the contact size there (None if the profile has no contact size).
        """
        idx = np.asarray(first_slipping, int)
        P_S = self.edge_load[idx]
        size = None if self.edge_size is None else self.edge_size[idx]
        return P_S, size


#: fewest cells, as a fraction of ``n_sliders``, between the lowest load at which a slider
#: can slip and the largest load (:func:`make_bed`, ``P_slip``)
SLIP_CELLS = 0.1


def _equal_stiffness_edges(profile, P_lo: float, P_max: float, n: int) -> np.ndarray:
    """Loads (n + 1,) from ``P_lo`` to ``P_max`` at equal increments of S = dP/dU."""
    # a fine table of S(P) to interpolate the loads of the stiffness targets
    P_tab = P_lo + (P_max - P_lo) * np.linspace(0.0, 1.0, 8 * n + 1) ** 2
    with np.errstate(divide="ignore"):
        S_tab = 1.0 / profile.compliance(P_tab)
    S_tab = np.maximum.accumulate(np.nan_to_num(S_tab, posinf=0.0))
    P_edges = np.interp(np.linspace(S_tab[0], S_tab[-1], n + 1), S_tab, P_tab)
    P_edges[0], P_edges[-1] = P_lo, P_max
    return P_edges


def _centroids(U_edges: np.ndarray, S_edges: np.ndarray, P_edges: np.ndarray) -> np.ndarray:
    """Stiffness-weighted centroid ∫ s k ds / ∫ k ds of the levels of each cell (n,) [m]:
    (Δ(U S) − ΔP)/ΔS, exact for any law. In a cell thin against its level (the cells of a
    slip zone a millionth of the load wide) that difference cancels to round-off and may
    land outside the cell; there the midpoint is taken, whose error, about ΔU ΔS/(12 S),
    is then far below the cell's width."""
    dS = np.diff(S_edges)
    with np.errstate(divide="ignore", invalid="ignore"):
        exact = (np.diff(U_edges * S_edges) - np.diff(P_edges)) / dS
        # round-off of the difference, relative to the cell's width
        noise = 4 * np.finfo(float).eps * (np.abs(U_edges * S_edges)[1:]
                                          + np.abs(P_edges[1:])) / dS
    lo, hi = U_edges[:-1], U_edges[1:]
    mid = 0.5 * (lo + hi)
    return np.where(noise < 1e-3 * (hi - lo), np.clip(exact, lo, hi), mid)


def make_bed(profile, *, friction: float, compliance_ratio: float, P_max: float,
             n_sliders: int = 1000, P_lo: float | None = None,
             P_slip: float | None = None) -> SliderBed:
    """Discretise ``profile`` into a slider bed covering loads up to ``P_max``.

    The bed is the Ciavarella–Jäger equivalent of the contact: independent Coulomb
    sliders indexed by the approach s at which they touch, with density k(s) = d²P/dU²
    (module docstring). Cells have equal increments of the normal stiffness S = dP/dU
    (for the sphere, equal increments of contact radius, as in the method of
    dimensionality reduction); each cell is one slider of stiffness ΔS at the
    stiffness-weighted centroid of its levels, so the discrete P(U) equals the exact law
    at every cell edge. Loads below ``P_lo`` are lumped into one slider that reproduces P
    and S at ``P_lo``. Profiles with an exact finite slider set
    (:meth:`Profile.concentrated`: flat punch, tabulated) use it as it is.

    Parameters
    ----------
    profile : Profile
        Normal law P(U) of the contact (:mod:`slipcycle.halfspace.profiles`).
    friction : float
        Coulomb coefficient f (dimensionless); slider i carries at most
        f k_i (U − s_i)₊.
    compliance_ratio : float
        λ_c = (dV/dQ)/(dU/dP) (dimensionless): slider i has tangential stiffness k_i/λ_c
        (:class:`~slipcycle.halfspace.elastic.ContactElasticity`).
    P_max : float
        Largest normal load of the history (N, or N/m for plane profiles); the bed is
        exact up to it and its last cell edge is ``P_max``.
    n_sliders : int
        Number of distributed sliders (cells) between ``P_lo`` and ``P_max``; profiles
        with an exact finite slider set ignore it.
    P_lo : float, optional
        Load (N or N/m) below which the law is lumped into one slider. Defaults to
        1e-6·P_max, and for the rough law (also when ≤ 0) to
        ``UNLUMPED_FRACTION``·P_max; a history's own value comes from
        :func:`lumping_load`. Ignored by profiles with an exact finite slider set.
    P_slip : float, optional
        Load (N or N/m) below which no slider slips in the history (:func:`lumping_load`).
        Profiles with a first touch keep their cells from ``P_lo`` (their tractions cover
        the whole contact); when fewer than :data:`SLIP_CELLS` × ``n_sliders`` of them lie
        above ``P_slip`` (a slip zone thinner than a few cells, which the bed could not
        resolve: a small tangential amplitude), ``n_sliders`` more cells are placed
        between ``P_slip`` and ``P_max``.

    Returns
    -------
    SliderBed
        n sliders in ascending level: ``level`` (n,) m, ``normal_stiffness`` (n,) N/m
        (N/m² for plane profiles), the given ``compliance_ratio`` and ``friction``,
        ``edge_load`` (n + 1,) N or N/m (0 first when a lumped slider or first touch
        starts the bed) and ``edge_size`` (n + 1,) m, the contact radius or half-width at
        the edges (None for the rough law and profiles without a contact size). n is at
        most ``n_sliders`` + 1 (cells of zero stiffness increment are dropped; one more
        for the lumped slider), 2 ``n_sliders`` + 1 with the cells added above ``P_slip``.

    References
    ----------
    Ciavarella, M. (1998). The generalized Cattaneo partial slip plane contact problem.
    I—Theory. Int. J. Solids Struct. 35, 2349–2362. Jäger, J. (1998). A new principle in
    contact mechanics. J. Tribol. 120, 677–684. Popov, V. L. & Heß, M. (2015). Method of
    Dimensionality Reduction in Contact Mechanics and Friction, Springer (equal increments
    of contact radius).
    """
    if isinstance(profile, RoughExponential):
        lo = P_lo if P_lo is not None and P_lo > 0 else UNLUMPED_FRACTION * P_max
        level, k, edges = rough_unit_bed(lo / profile.reference_load,
                                         P_max / profile.reference_load, int(n_sliders))
        g = profile.gamma_sigma
        return SliderBed(g * level, k * profile.reference_load / g, compliance_ratio,
                         friction, edges * profile.reference_load, None)
    conc = profile.concentrated()
    if conc is not None:
        level, k = (np.asarray(a, float) for a in conc)
        K = np.cumsum(k)
        edges = np.concatenate([[0.0], K[:-1] * level[1:] - np.cumsum(k * level)[:-1],
                                [max(P_max, 0.0)]])
        edges = np.maximum.accumulate(edges)
        size = profile.contact_size(edges)
        return SliderBed(level, k, compliance_ratio, friction, edges, size)

    P_lo = 1e-6 * P_max if P_lo is None else P_lo
    P_edges = _equal_stiffness_edges(profile, P_lo, P_max, n_sliders)
    if P_slip is not None and P_lo < P_slip < P_max \
            and np.count_nonzero(P_edges > P_slip) < SLIP_CELLS * n_sliders:
        # the loads at which sliders can slip span few cells (a small tangential
        # amplitude: the slip annulus is thinner than a cell, and the bed would stick
        # where the contact microslips): as many cells again, between P_slip and P_max
        P_edges = np.union1d(P_edges, _equal_stiffness_edges(profile, P_slip, P_max,
                                                             n_sliders))
    U_edges = profile.approach(P_edges)
    with np.errstate(divide="ignore"):
        S_edges = np.nan_to_num(1.0 / profile.compliance(P_edges), posinf=0.0)
    dS = np.diff(S_edges)
    keep = dS > 0
    level, k = _centroids(U_edges, S_edges, P_edges)[keep], dS[keep]
    edges = np.concatenate([[P_edges[0]], P_edges[1:][keep]])
    if S_edges[0] > 0:  # lumped slider for everything below P_lo
        level = np.concatenate([[U_edges[0] - P_edges[0] / S_edges[0]], level])
        k = np.concatenate([[S_edges[0]], k])
        edges = np.concatenate([[0.0], edges])
    size = profile.contact_size(edges)
    return SliderBed(level, k, compliance_ratio, friction, edges,
                     None if size is None else np.asarray(size, float))
