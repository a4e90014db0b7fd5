"""Loads of the 3-D discrete system: q^w(θ) (2 per node, node-major), p^w(θ) per node.

    q^w(θ) = q_0 + λ q̃(θ) + Σ_c q_c g_c(θ),    p^w(θ) = p_0 + λ p̃(θ) + Σ_c p_c g_c(θ)

with q̃, p̃ harmonic or tabulated periodic series (:class:`~slipcycle.loading.HarmonicLoad`,
:class:`~slipcycle.loading.TabulatedLoad`, the phase convention of
:mod:`slipcycle.loading.periodic`) and basic load cases (q_c, p_c) scaled by scalar time
functions g_c(θ) = mean_c + λ g̃_c(θ). The same form as the loads of the 2-D model, with
two tangential components per node. Values in N, θ in rad; stacked ``r^w = [q^w, p^w]``,
shape (..., 3N).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from slipcycle.loading import HarmonicLoad, TabulatedLoad, cycle_angles

__all__ = ["LoadCase3D", "Load3D"]


@dataclass(frozen=True)
class LoadCase3D:
    """One basic load case scaled by a time function.

    Parameters
    ----------
    q : (2N,) array
        Tangential reactions of the load case at unit intensity [N], node-major.
    p : (N,) array
        Normal reactions [N].
    time : HarmonicLoad or TabulatedLoad of size 1
        g(θ), dimensionless (its λ multiplies the periodic part).
    """

    q: np.ndarray
    p: np.ndarray
    time: HarmonicLoad | TabulatedLoad


@dataclass(frozen=True)
class Load3D:
    """Periodic loads q^w(θ) (2N components) and p^w(θ) (N) of an N-node 3-D system.

    Parameters
    ----------
    q : HarmonicLoad or TabulatedLoad of size 2N
    p : HarmonicLoad or TabulatedLoad of size N
    cases : tuple of LoadCase3D
    """

    q: HarmonicLoad | TabulatedLoad
    p: HarmonicLoad | TabulatedLoad
    cases: tuple = field(default_factory=tuple)

    @property
    def n_nodes(self) -> int:
        return self.p.size

    @classmethod
    def harmonic(cls, p0, q0, p1=None, q1=None, p1_phase=0.0, q1_phase=0.0,
                 lam: float = 1.0) -> Load3D:
        """p^w = p0 + λ Σ_h p_h cos(hθ + α_h), likewise q^w.

        Parameters
        ----------
        p0 : (N,) array
        q0 : (N, 2) or (2N,) array
        p1 : (N,) or (H, N) array, optional
        q1 : (N, 2), (2N,) or (H, 2N) array, optional
        p1_phase, q1_phase : float or arrays of the amplitudes' shape
        lam : float
        """
        p0 = np.atleast_1d(np.asarray(p0, float))
        q0 = np.asarray(q0, float).reshape(-1)
        p1 = np.zeros_like(p0) if p1 is None else np.asarray(p1, float)
        q1 = np.zeros_like(q0) if q1 is None else np.asarray(q1, float).reshape(-1, q0.size)
        qph = np.asarray(q1_phase, float)
        if qph.ndim:
            qph = qph.reshape(-1, q0.size)
        return cls(HarmonicLoad(q0, q1, qph, lam), HarmonicLoad(p0, p1, p1_phase, lam))

    def with_lam(self, lam: float) -> Load3D:
        """The same load with load factor λ."""
        cases = tuple(LoadCase3D(c.q, c.p, c.time.with_lam(lam)) for c in self.cases)
        return Load3D(self.q.with_lam(lam), self.p.with_lam(lam), cases)

    def __call__(self, theta) -> np.ndarray:
        """r^w = [q^w, p^w] at angles θ (n,) → (n, 3N) [N]."""
        theta = np.atleast_1d(np.asarray(theta, float))
        q = self.q(theta)
        p = self.p(theta)
        for c in self.cases:
            g = c.time(theta)[:, 0]
            q = q + g[:, None] * c.q[None, :]
            p = p + g[:, None] * c.p[None, :]
        return np.hstack([q, p])

    def breakpoints(self) -> np.ndarray:
        """Angles in [0, 2π) where a tabulated part has a kink."""
        pts = [f.theta for f in (self.p, self.q) if isinstance(f, TabulatedLoad)]
        pts += [c.time.theta for c in self.cases if isinstance(c.time, TabulatedLoad)]
        return np.unique(np.concatenate(pts)) if pts else np.zeros(0)

    def cycle_samples(self, steps_per_cycle: int) -> tuple[np.ndarray, np.ndarray]:
        """Angles (n+1,) from 0 to 2π (with the tabulated breakpoints) and loads (n+1, 3N);
        the last sample repeats the first (periodicity). The path is linear between."""
        th = cycle_angles(steps_per_cycle)
        bp = self.breakpoints()
        if bp.size:
            th = np.unique(np.concatenate([th, bp]))
            th = th[np.concatenate([[True], np.diff(th) > 1e-14])]
        vals = self(th)
        vals[-1] = vals[0]
        return th, vals

    def split_lam(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """r^w(θ; λ) = r0(θ) + λ r1(θ) at the angles θ: (r0, r1), each (n, 3N).

        r0 holds every part that λ does not scale (means, load-case means)."""
        r0 = self.with_lam(0.0)(theta)
        return r0, self.with_lam(1.0)(theta) - r0
