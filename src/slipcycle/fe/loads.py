"""Periodic contact-node loads from combinations of a reduced model's basic load cases.

A reduced finite-element model (:class:`~slipcycle.fe.reduction.ReducedModel`) carries the
reactions (q_c, p_c) of each basic load case c at the contact nodes held fixed. A periodic
loading that scales case c by mean_c + λ amplitude_c cos(θ + phase_c) gives

    p^w(θ) = Σ_c mean_c p_c + λ Re[Σ_c amplitude_c e^{i phase_c} p_c e^{iθ}],

and likewise q^w: per node a mean and one harmonic with amplitude |Σ …| and lead
arg(Σ …). :func:`combined_loads` is the one place this combination is made; the discrete
case file written by ``slipcycle reduce --case`` is its text form.

Reference: J. R. Barber, "Frictional systems under periodic loads — history-dependence,
non-uniqueness and energy dissipation", J. Phys.: Conf. Ser. 382 (2012) 012002 (loads of
the reduced system as superposed reactions of the fixed contact nodes).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from slipcycle.fe.reduction import ReducedModel
from slipcycle.loading import HarmonicLoad

__all__ = ["combined_loads"]


def combined_loads(reduced: ReducedModel, mean: Mapping[str, float] | None = None,
                   amplitude: Mapping[str, float] | None = None,
                   phase: Mapping[str, float] | None = None, lam: float = 1.0
                   ) -> tuple[HarmonicLoad, HarmonicLoad]:
    """Normal and tangential periodic loads of the contact nodes (module docstring).

    Parameters
    ----------
    reduced : ReducedModel
        Basic load cases ``reduced.load_cases`` with reactions ``p_w``, ``q_w``
        (cases, N) [N per unit case intensity].
    mean : mapping, optional
        Load case name → multiplier of the mean load (dimensionless); the ``gap`` case
        enters with 1 unless given, every other case with 0.
    amplitude : mapping, optional
        Load case name → multiplier of the first harmonic (dimensionless), default 0.
    phase : mapping, optional
        Load case name → lead of its harmonic (rad), default 0.
    lam : float
        Load factor λ of the periodic part.

    Returns
    -------
    p, q : HarmonicLoad
        p^w(θ) and q^w(θ), each of size N [N]: ``DiscreteLoad(p, q)`` of
        :mod:`slipcycle.discrete` is the discrete system's load.

    Raises
    ------
    ValueError
        A name that is not a load case of ``reduced``.
    """
    mean, amplitude, phase = dict(mean or {}), dict(amplitude or {}), dict(phase or {})
    names = reduced.load_cases
    for part, table in (("mean", mean), ("amplitude", amplitude), ("phase", phase)):
        for k in table:
            if k not in names:
                raise ValueError(f"{part}.{k}: unknown load case; the model has "
                                 f"{', '.join(names)}")
    q0, p0 = reduced.combine(**{n: mean.get(n, 1.0 if n == "gap" else 0.0) for n in names})
    cq = np.zeros(reduced.n, complex)
    cp = np.zeros(reduced.n, complex)
    for i, n in enumerate(names):
        a = amplitude.get(n, 0.0) * np.exp(1j * phase.get(n, 0.0))
        cq += a * reduced.q_w[i]
        cp += a * reduced.p_w[i]
    return (HarmonicLoad(p0, np.abs(cp), np.angle(cp), lam),
            HarmonicLoad(q0, np.abs(cq), np.angle(cq), lam))
