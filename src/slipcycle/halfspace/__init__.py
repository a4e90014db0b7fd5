"""Uncoupled half-space contacts: Cattaneo–Mindlin / Ciavarella–Jäger microslip.

Data flow: a :class:`~slipcycle.halfspace.profiles.Profile` (the normal law P(U)) becomes a
:class:`~slipcycle.halfspace.bed.SliderBed` (independent Coulomb sliders indexed by the
approach at which they touch); :func:`~slipcycle.halfspace.history.run_history` drives the
bed along a load path; :mod:`~slipcycle.halfspace.tractions` turns slider line loads into
traction and dissipation distributions for axisymmetric profiles; :mod:`~.wmap` computes
the dimensionless rough-surface dissipation Ŵ(P̂1, Q̂1, φ); :mod:`~.topography` turns
measured topography into P(U) by a boundary-element solver (the studies that use them,
the Ŵ map and the roughness study, are in :mod:`slipcycle.studies`).
"""

import importlib

from slipcycle.halfspace.bed import SliderBed, make_bed
from slipcycle.halfspace.elastic import ContactElasticity
from slipcycle.halfspace.history import HistoryResult, run_history
from slipcycle.halfspace.loads import contact_loads
from slipcycle.halfspace.model import HalfspaceModel, solve
from slipcycle.halfspace.profiles import (
    Cylinder2D,
    FlatPunch,
    PowerLaw,
    Profile,
    RoughExponential,
    Tabulated,
    sphere,
)

# the topography bridge needs xarray and (optionally) SurfaceTopography: loaded on first use
_LAZY = {name: "topography" for name in (
    "BEMLaw", "ExponentialFit", "SurfaceMap", "TopographySource", "bem_normal_law",
    "fit_exponential", "read_surface")}

__all__ = [
    "ContactElasticity", "Cylinder2D", "FlatPunch", "HalfspaceModel", "HistoryResult",
    "PowerLaw", "Profile", "RoughExponential", "SliderBed", "Tabulated", "contact_loads",
    "make_bed", "run_history", "solve", "sphere",
    "BEMLaw", "ExponentialFit", "SurfaceMap", "TopographySource", "bem_normal_law",
    "fit_exponential", "read_surface",
]


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(f"slipcycle.halfspace.{_LAZY[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'slipcycle.halfspace' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
