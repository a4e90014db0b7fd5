"""Loads of a discrete frictional system: p^w(θ), q^w(θ) per contact node.

The reactions with every node held at v = w = 0 are

    q^w(θ) = q_0 + λ q̃(θ) + Σ_c q_c g_c(θ),    p^w(θ) = p_0 + λ p̃(θ) + Σ_c p_c g_c(θ)

where q̃, p̃ are harmonic series or tabulated periodic series per node
(:class:`~slipcycle.loading.HarmonicLoad`, :class:`~slipcycle.loading.TabulatedLoad`) and
each basic load case c of a finite-element model (reaction vectors p_c, q_c) is scaled by
a scalar time function g_c(θ) = mean_c + λ g̃_c(θ) (harmonic or tabulated).

One form for the 2-D model (:mod:`slipcycle.discrete`, one tangential component per node)
and the 3-D model (:mod:`slipcycle.discrete3d`, two per node, node-major: node 0 t1, node 0
t2, node 1 t1, …): q has t·N components, p has N. All values are in N; θ in rad. Load
vectors are stacked tangential first, ``r^w = [q^w, p^w]`` with shape (..., (t + 1) N).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from slipcycle.loading import HarmonicLoad, TabulatedLoad, cycle_angles

__all__ = ["LoadCase", "DiscreteLoad", "force_scale"]

TWO_PI = 2.0 * np.pi


@dataclass(frozen=True)
class LoadCase:
    """One basic load case scaled by a time function.

    Parameters
    ----------
    p : (N,) array
        Normal reactions of the load case at unit intensity [N].
    q : (t N,) array
        Tangential reactions [N] (t = 1 in 2-D, 2 in 3-D, node-major).
    time : HarmonicLoad or TabulatedLoad of size 1
        g(θ), dimensionless (its λ multiplies the periodic part).
    """

    p: np.ndarray
    q: np.ndarray
    time: HarmonicLoad | TabulatedLoad


@dataclass(frozen=True)
class DiscreteLoad:
    """Periodic loads p^w(θ), q^w(θ) of an N-node system (2-D or 3-D).

    Parameters
    ----------
    p : HarmonicLoad or TabulatedLoad of size N
        Per-node normal load functions (mean and periodic part).
    q : HarmonicLoad or TabulatedLoad of size t N
        Tangential load functions, t = 1 (2-D) or 2 (3-D, node-major).
    cases : list of LoadCase
        Basic load cases × time functions, added to p and q.
    """

    p: HarmonicLoad | TabulatedLoad
    q: HarmonicLoad | TabulatedLoad
    cases: tuple = field(default_factory=tuple)

    @property
    def n_nodes(self) -> int:
        return self.p.size

    @property
    def tangential_dims(self) -> int:
        """t: tangential components per node (1 in 2-D, 2 in 3-D)."""
        return self.q.size // self.p.size

    @classmethod
    def harmonic(cls, p0, q0, p1=None, q1=None, p1_phase=0.0, q1_phase=0.0, lam: float = 1.0
                 ) -> DiscreteLoad:
        """p^w = p0 + λ Σ_h p_h cos(hθ + α_h), likewise q^w.

        p0 is (N,), p1 (N,) or (H, N); q0 is (t N,) (or (N, t)), q1 (t N,) or (H, t N).
        """
        p0 = np.atleast_1d(np.asarray(p0, float))
        q0 = np.asarray(q0, float).reshape(-1)
        p1 = np.zeros_like(p0) if p1 is None else np.asarray(p1, float)
        q1 = np.zeros_like(q0) if q1 is None else np.asarray(q1, float)
        return cls(HarmonicLoad(p0, p1, p1_phase, lam), HarmonicLoad(q0, q1, q1_phase, lam))

    def with_lam(self, lam: float) -> DiscreteLoad:
        """The same load with load factor λ (periodic parts and load-case time functions)."""
        cases = tuple(LoadCase(c.p, c.q, c.time.with_lam(lam)) for c in self.cases)
        return DiscreteLoad(self.p.with_lam(lam), self.q.with_lam(lam), cases)

    def __call__(self, theta) -> np.ndarray:
        """r^w = [q^w, p^w] at angles θ (n,) → (n, (t + 1) N), N."""
        theta = np.atleast_1d(np.asarray(theta, float))
        q = self.q(theta)
        p = self.p(theta)
        for c in self.cases:
            g = c.time(theta)[:, 0]
            q = q + g[:, None] * c.q[None, :]
            p = p + g[:, None] * c.p[None, :]
        return np.hstack([q, p])

    def breakpoints(self) -> np.ndarray:
        """Angles in [0, 2π) where a tabulated part has a kink (must be load samples)."""
        pts = [f.theta for f in (self.p, self.q) if isinstance(f, TabulatedLoad)]
        pts += [c.time.theta for c in self.cases if isinstance(c.time, TabulatedLoad)]
        if not pts:
            return np.zeros(0)
        return np.unique(np.concatenate(pts))

    def piecewise_linear(self) -> bool:
        """True if the load is exactly piecewise linear between :meth:`breakpoints`."""
        funcs = [self.p, self.q] + [c.time for c in self.cases]
        return all(isinstance(f, TabulatedLoad) or not np.any(f.amplitudes) for f in funcs)

    def split_lam(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """r^w(θ; λ) = r0(θ) + λ r1(θ) at the angles θ: (r0, r1), each (n, (t + 1) N).

        r0 holds every part that λ does not scale (means, load-case means)."""
        r0 = self.with_lam(0.0)(theta)
        return r0, self.with_lam(1.0)(theta) - r0

    def cycle_samples(self, steps_per_cycle: int) -> tuple[np.ndarray, np.ndarray]:
        """Load samples of one cycle: angles (n+1,) from 0 to 2π and values (n+1, 2N).

        The angles are ``steps_per_cycle`` equal steps merged with the breakpoints of
        tabulated parts, so that the piecewise-linear path between samples is exact for a
        tabulated load. The last sample repeats the first value exactly (periodicity).
        """
        th = cycle_angles(steps_per_cycle)
        bp = self.breakpoints()
        if bp.size:
            th = np.unique(np.concatenate([th, bp]))
            th = th[np.concatenate([[True], np.diff(th) > 1e-14])]
        vals = self(th)
        vals[-1] = vals[0]
        return th, vals


def force_scale(values: np.ndarray) -> float:
    """The force scale of load samples: max |r^w| (N), or 1 when every sample is zero.

    Tolerances of the discrete models' steady-state and admissibility tests are relative
    to it.
    """
    s = float(np.max(np.abs(values), initial=0.0))
    return s if s > 0 else 1.0
