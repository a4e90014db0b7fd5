"""The slider bed equivalent to an uncoupled half-space contact (SPEC §4).

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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["SliderBed", "make_bed"]


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


def make_bed(profile, *, friction: float, compliance_ratio: float, P_max: float,
             n_sliders: int = 1000, P_lo: float | None = None) -> SliderBed:
    """Discretise ``profile`` into a slider bed covering loads up to ``P_max``.

    Parameters
    ----------
    profile : Profile
        Normal law of the contact.
    friction, compliance_ratio : float
        f and λ_c.
    P_max : float
        Largest normal load of the history (N or N/m); the bed is exact up to it.
    n_sliders : int
        Number of distributed sliders (profiles with an exact finite slider set ignore it).
    P_lo : float, optional
        Loads below this are lumped into one slider. Defaults to 1e-6·P_max.
    """
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
    # Fine table of S(P) to place edges at equal stiffness increments.
    P_tab = P_lo + (P_max - P_lo) * np.linspace(0.0, 1.0, 8 * n_sliders + 1) ** 2
    with np.errstate(divide="ignore"):
        S_tab = 1.0 / profile.compliance(P_tab)
    S_tab = np.maximum.accumulate(np.nan_to_num(S_tab, posinf=0.0))
    S_targets = np.linspace(S_tab[0], S_tab[-1], n_sliders + 1)
    P_edges = np.interp(S_targets, S_tab, P_tab)
    P_edges[0], P_edges[-1] = P_lo, P_max
    U_edges = profile.approach(P_edges)
    with np.errstate(divide="ignore"):
        S_edges = np.nan_to_num(1.0 / profile.compliance(P_edges), posinf=0.0)
    dS = np.diff(S_edges)
    keep = dS > 0
    # stiffness-weighted centroid of the levels in each cell: ∫ s k ds / ∫ k ds
    centroid = (np.diff(U_edges * S_edges) - np.diff(P_edges))[keep] / dS[keep]
    level, k = centroid, dS[keep]
    edges = np.concatenate([[P_edges[0]], P_edges[1:][keep]])
    if S_edges[0] > 0:  # lumped slider for everything below P_lo
        level = np.concatenate([[U_edges[0] - P_edges[0] / S_edges[0]], level])
        k = np.concatenate([[S_edges[0]], k])
        edges = np.concatenate([[0.0], edges])
    size = profile.contact_size(edges)
    return SliderBed(level, k, compliance_ratio, friction, edges,
                     None if size is None else np.asarray(size, float))
