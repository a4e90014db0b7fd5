"""Periodic load functions of the cycle angle θ = Ωt.

A load has ``m`` components (nodes, or P and Q of a contact). Two forms:

- :class:`HarmonicLoad`:  X(θ) = X0 + λ Σ_h X_h cos(hθ + α_h)
- :class:`TabulatedLoad`: X(θ) = X0 + λ X̃(θ), X̃ piecewise linear and periodic in θ.

Solvers sample a cycle at ``steps_per_cycle`` equal angles (:func:`cycle_angles`) and take
the load path between samples to be linear; assembly protocols are polylines through given
load states (:func:`piecewise_linear_path`).

Phase convention (the one place it is stated; other modules refer here)
-----------------------------------------------------------------------
:class:`HarmonicLoad` stores *leads* α_h: X = X0 + λ Σ X_h cos(hθ + α_h). Two families of
case files use two words, each with the meaning of its literature:

- coupled discrete systems (``p1_phase``, ``q1_phase``) give leads α_h directly:
  p = p0 + λ p1 cos(θ + p1_phase);
- half-space contacts give *lags* of the load behind the normal-load reference,
  P = P0 + λ P1 cos(θ − P1_phase), Q = Q0 + λ Q1 cos(θ − phase), the convention of the
  rough-contact dissipation map Ŵ(P̂1, Q̂1, φ) (Putignano, Ciavarella & Barber 2011): a
  positive ``phase`` φ means Q reaches its maximum φ/(2π) of a cycle after P. For
  harmonic h the lag is in the harmonic's own angle, cos(hθ − φ_h).

Build lag-specified loads with :meth:`HarmonicLoad.lagging` (α_h = −φ_h), and half-space
loads with :func:`slipcycle.halfspace.contact_loads`, which is what the case parser calls.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

TWO_PI = 2.0 * np.pi

__all__ = ["PeriodicLoad", "HarmonicLoad", "TabulatedLoad", "cycle_angles",
           "piecewise_linear_path"]


class PeriodicLoad(Protocol):
    """Anything that maps cycle angles (n,) to load values (n, m)."""

    def __call__(self, theta: np.ndarray) -> np.ndarray: ...

    @property
    def size(self) -> int: ...


@dataclass(frozen=True)
class HarmonicLoad:
    """X(θ) = X0 + λ Σ_h X_h cos(hθ + α_h): α_h are leads (module docstring: phases).

    Parameters
    ----------
    mean : (m,) array
        X0.
    amplitudes : (H, m) array
        X_h for harmonics h = 1..H.
    phases : (H, m) array
        α_h in radians.
    lam : float
        Load factor λ multiplying the periodic part.
    """

    mean: np.ndarray
    amplitudes: np.ndarray
    phases: np.ndarray
    lam: float = 1.0

    def __post_init__(self):
        mean = np.atleast_1d(np.asarray(self.mean, float))
        amp = np.asarray(self.amplitudes, float).reshape(-1, mean.size)
        ph = np.broadcast_to(np.asarray(self.phases, float), amp.shape).copy()
        object.__setattr__(self, "mean", mean)
        object.__setattr__(self, "amplitudes", amp)
        object.__setattr__(self, "phases", ph)

    @property
    def size(self) -> int:
        return self.mean.size

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        theta = np.asarray(theta, float)
        h = np.arange(1, self.amplitudes.shape[0] + 1)
        # (n, H, m) -> sum over harmonics
        arg = h[None, :, None] * theta[:, None, None] + self.phases[None]
        return self.mean[None, :] + self.lam * np.sum(self.amplitudes[None] * np.cos(arg), axis=1)

    def with_lam(self, lam: float) -> HarmonicLoad:
        return HarmonicLoad(self.mean, self.amplitudes, self.phases, lam)

    @classmethod
    def lagging(cls, mean, amplitudes, lags, lam: float = 1.0) -> HarmonicLoad:
        """X(θ) = X0 + λ Σ_h X_h cos(hθ − φ_h): harmonics given by their lags φ_h (rad).

        Same shapes as the constructor; see the module docstring for the convention.
        """
        return cls(mean, amplitudes, -np.asarray(lags, float), lam)


@dataclass(frozen=True)
class TabulatedLoad:
    """X(θ) = X0 + λ X̃(θ) with X̃ tabulated at angles in [0, 2π), periodic, linear between.

    Parameters
    ----------
    theta : (K,) array
        Strictly increasing angles in [0, 2π).
    values : (K, m) array
        X̃ at those angles.
    mean : (m,) array, optional
        X0 (default zero).
    lam : float
        Load factor λ.
    """

    theta: np.ndarray
    values: np.ndarray
    mean: np.ndarray | None = None
    lam: float = 1.0

    def __post_init__(self):
        th = np.asarray(self.theta, float)
        vals = np.asarray(self.values, float)
        if vals.ndim == 1:
            vals = vals[:, None]
        if th.ndim != 1 or th.size < 2 or vals.shape[0] != th.size:
            raise ValueError("theta must be (K,) with K >= 2 and values (K, m)")
        if np.any(np.diff(th) <= 0) or th[0] < 0 or th[-1] >= TWO_PI:
            raise ValueError("theta must increase strictly within [0, 2π)")
        mean = np.zeros(vals.shape[1]) if self.mean is None else np.atleast_1d(
            np.asarray(self.mean, float))
        object.__setattr__(self, "theta", th)
        object.__setattr__(self, "values", vals)
        object.__setattr__(self, "mean", mean)

    @property
    def size(self) -> int:
        return self.values.shape[1]

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        t = np.mod(np.asarray(theta, float), TWO_PI)
        # Close the period so interpolation wraps from the last sample to the first.
        th = np.concatenate([self.theta, [self.theta[0] + TWO_PI]])
        vals = np.vstack([self.values, self.values[:1]])
        t = np.where(t < th[0], t + TWO_PI, t)
        out = np.column_stack([np.interp(t, th, vals[:, j]) for j in range(self.size)])
        return self.mean[None, :] + self.lam * out

    def with_lam(self, lam: float) -> TabulatedLoad:
        return TabulatedLoad(self.theta, self.values, self.mean, lam)


def cycle_angles(steps_per_cycle: int, cycles: int = 1) -> np.ndarray:
    """Sample angles θ_k = 2πk/steps for k = 0..cycles·steps (both ends included)."""
    return np.linspace(0.0, TWO_PI * cycles, steps_per_cycle * cycles + 1)


def piecewise_linear_path(states: np.ndarray, steps_per_segment: int | np.ndarray
                          ) -> np.ndarray:
    """Sample a polyline through load states.

    Parameters
    ----------
    states : (S, m) array
        Load states visited in order (the first is the starting state).
    steps_per_segment : int or (S-1,) int array
        Number of linear sub-steps on each segment (>= 1).

    Returns
    -------
    (n, m) array
        The states along the path, starting with ``states[0]`` and ending with
        ``states[-1]``; every given state is one of the samples.
    """
    states = np.atleast_2d(np.asarray(states, float))
    nseg = states.shape[0] - 1
    if nseg < 1:
        return states.copy()
    steps = np.broadcast_to(np.asarray(steps_per_segment, int), (nseg,))
    pieces = [states[:1]]
    for k in range(nseg):
        s = np.linspace(0.0, 1.0, steps[k] + 1)[1:, None]
        pieces.append(states[k] + s * (states[k + 1] - states[k]))
    return np.vstack(pieces)
