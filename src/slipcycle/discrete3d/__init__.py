"""Three-dimensional coupled discrete frictional systems with the isotropic Coulomb cone
(J. R. Barber, J. Phys.: Conf. Ser. 382 (2012) 012002, §3, in 3-D; Klarbring, Ciavarella &
Barber 2007 for shakedown; Alart & Curnier 1991 for the incremental solver).

- :mod:`~slipcycle.discrete3d.model`      :class:`FrictionalSystem3D` (A, B, C, f, frames)
- :mod:`~slipcycle.discrete3d.loads`      q^w(θ) (two per node), p^w(θ): :class:`Load3D`
- :mod:`~slipcycle.discrete3d.wellposed`  sampled critical friction, certified bound
- :mod:`~slipcycle.discrete3d.cone`       the local return map on the cone
- :mod:`~slipcycle.discrete3d.evolution`  load steps: semismooth Newton, step doubling
- :mod:`~slipcycle.discrete3d.steady`     cycling to the steady state, classes
- :mod:`~slipcycle.discrete3d.shakedown`  λ2 by a second-order cone program (Clarabel)
- :mod:`~slipcycle.discrete3d.basins`     steady states from many starts / protocols
- :mod:`~slipcycle.discrete3d.fields`     XDMF / VTU fields for ParaView
- :mod:`~slipcycle.discrete3d.case`       ``model = "discrete3d"`` cases and results
"""

from slipcycle.discrete3d.basins import Basins3D, basins3d, random_starts
from slipcycle.discrete3d.case import Discrete3DCase, DiscreteResult3D, solve_model
from slipcycle.discrete3d.loads import Load3D, LoadCase3D
from slipcycle.discrete3d.model import FrictionalSystem3D, ModelError3D, embed_2d
from slipcycle.discrete3d.shakedown import SafeRegion3D, lambda2_socp
from slipcycle.discrete3d.steady import SteadyResult3D, simulate3d
from slipcycle.discrete3d.wellposed import CriticalFriction3D, critical_friction_3d

__all__ = ["Basins3D", "basins3d", "random_starts", "Discrete3DCase", "DiscreteResult3D",
           "FrictionalSystem3D", "Load3D", "LoadCase3D", "ModelError3D", "SafeRegion3D",
           "SteadyResult3D",
           "CriticalFriction3D", "critical_friction_3d", "embed_2d", "lambda2_socp",
           "simulate3d", "solve_model"]
