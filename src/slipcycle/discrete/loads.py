"""Loads of a discrete system: the periodic nodal loads of :mod:`slipcycle.loading.nodal`.

The 2-D and 3-D models share one load type (one tangential component per node here).
"""

from slipcycle.loading.nodal import DiscreteLoad, LoadCase

__all__ = ["LoadCase", "DiscreteLoad"]
