"""Load functions read from case tables (shared by the case readers of the discrete models).
"""

from __future__ import annotations

import numpy as np

from slipcycle.io.case import Section
from slipcycle.loading import HarmonicLoad, TabulatedLoad

__all__ = ["time_function"]


def time_function(sec: Section, lam: float) -> HarmonicLoad | TabulatedLoad:
    """Scalar time function g(θ) = mean + λ g̃(θ) of a basic load case, from its table.

    Parameters
    ----------
    sec : Section
        The ``[[loading.case]]`` table: ``mean``, and either ``amplitude``/``phase`` (one
        per harmonic, rad) or tabulated ``theta`` (rad, strictly increasing in [0, 2π)) and
        ``values``.
    lam : float
        Load factor λ of the periodic part.

    Returns
    -------
    HarmonicLoad or TabulatedLoad
        Of size 1, dimensionless.
    """
    mean = sec.float("mean", 0.0)
    if sec.has("theta"):
        theta = sec.array("theta", shape=(None,), ge=0.0, lt=2 * np.pi)
        if theta.size < 2 or np.any(np.diff(theta) <= 0):
            raise sec.error("theta", "must have at least 2 strictly increasing angles in "
                                     "[0, 2π)")
        vals = sec.array("values", shape=(theta.size,))
        return TabulatedLoad(theta, vals[:, None], [mean], lam)
    amp = np.atleast_1d(sec.array("amplitude", 0.0))
    if amp.ndim != 1:
        raise sec.error("amplitude", "must be a number or a list (one per harmonic)")
    phase = np.atleast_1d(sec.array("phase", 0.0))
    if phase.size == 1:
        phase = np.full(amp.shape, float(phase[0]))
    elif phase.shape != amp.shape:
        raise sec.error("phase", f"must be a number or a list of {amp.size} phases")
    return HarmonicLoad([mean], amp[:, None], phase[:, None], lam)
