"""Harmonic loads of a half-space contact, with the meaning of the case file.

    P(θ) = P0 + λ Σ_h P1_h cos(hθ − P1_phase_h)
    Q(θ) = Q0 + λ Σ_h Q1_h cos(hθ − phase_h)

``phase`` and ``P1_phase`` are lags (rad) behind the reference cos θ; the sign convention is
stated once in :mod:`slipcycle.loading.periodic`. ``[loading]`` of a ``model = "halfspace"``
case is parsed by this function, so a case file and a Python call with the same numbers
describe the same loads.
"""

from __future__ import annotations

import numpy as np

from slipcycle.loading import HarmonicLoad

__all__ = ["contact_loads"]


def contact_loads(P0: float, P1=0.0, Q0: float = 0.0, Q1=0.0, phase=0.0, P1_phase=0.0,
                  lam: float = 1.0) -> tuple[HarmonicLoad, HarmonicLoad]:
    """Normal and tangential loads P(θ), Q(θ) of a half-space contact.

    Parameters
    ----------
    P0, Q0 : float
        Mean normal and tangential loads (N, or N/m for plane contacts). Under approach or
        displacement control the same arguments carry U0 (m) and V0 (m).
    P1, Q1 : float or (H,) array
        Amplitudes of harmonics h = 1..H (same units).
    phase : float or (H,) array
        Lag φ_h of Q behind the reference (rad): Q = Q0 + λ Q1 cos(θ − φ). This is the φ
        of the rough-contact map Ŵ(P̂1, Q̂1, φ).
    P1_phase : float or (H,) array
        Lag of P (rad), same sign rule: P = P0 + λ P1 cos(θ − P1_phase).
    lam : float
        Load factor λ on the periodic parts.

    Returns
    -------
    normal, tangential : HarmonicLoad
        One-component loads; ``normal(theta)`` is (n, 1).
    """
    return (_one(P0, P1, P1_phase, lam, "P1_phase"), _one(Q0, Q1, phase, lam, "phase"))


def _one(mean, amp, lag, lam, name) -> HarmonicLoad:
    amp = np.atleast_1d(np.asarray(amp, float))
    lag = np.atleast_1d(np.asarray(lag, float))
    if amp.ndim != 1 or lag.ndim != 1 or lag.size not in (1, amp.size):
        raise ValueError(f"{name} needs 1 or {amp.size} values (one per harmonic)")
    lag = np.broadcast_to(lag, amp.shape)
    return HarmonicLoad.lagging(np.array([float(mean)]), amp[:, None], lag[:, None], lam)
