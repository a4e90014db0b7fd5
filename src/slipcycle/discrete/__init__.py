"""Coupled discrete frictional systems under periodic loading (J. R. Barber, J. Phys.:
Conf. Ser. 382 (2012) 012002, §3; A. Klarbring, Ing.-Arch. 60 (1990) 529–541 for f_crit).

- :mod:`~slipcycle.discrete.model`      :class:`FrictionalSystem` (A, B, C, f), validation
- :mod:`~slipcycle.discrete.loads`      p^w(θ), q^w(θ): harmonic, tabulated, load cases
- :mod:`~slipcycle.discrete.wellposed`  critical friction coefficient f_crit (P-matrix)
- :mod:`~slipcycle.discrete.lcp`        Lemke's method
- :mod:`~slipcycle.discrete.rate`       the rate problem (active set + pivoting)
- :mod:`~slipcycle.discrete.evolution`  event-driven exact evolution
- :mod:`~slipcycle.discrete.steady`     cycling, steady state, classification
- :mod:`~slipcycle.discrete.case`       case file → results (``model = "discrete"``)
"""

from slipcycle.discrete.loads import DiscreteLoad, LoadCase
from slipcycle.discrete.model import FrictionalSystem, ModelError
from slipcycle.discrete.steady import SteadyResult, simulate
from slipcycle.discrete.wellposed import critical_friction

__all__ = ["DiscreteLoad", "FrictionalSystem", "LoadCase", "ModelError", "SteadyResult",
           "critical_friction", "simulate"]
