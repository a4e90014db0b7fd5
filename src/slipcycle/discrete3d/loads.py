"""Loads of the 3-D discrete system: q^w(θ) (2 per node, node-major), p^w(θ) per node.

The one load type of the discrete models, :class:`slipcycle.loading.nodal.DiscreteLoad`,
with two tangential components per node: ``Load3D(p=..., q=..., cases=...)`` with q of
size 2N; ``r^w = [q^w, p^w]`` has shape (..., 3N).
"""

from slipcycle.loading.nodal import DiscreteLoad as Load3D
from slipcycle.loading.nodal import LoadCase as LoadCase3D

__all__ = ["LoadCase3D", "Load3D"]
