"""Periodic loads and assembly protocols."""

from slipcycle.loading.periodic import (
    HarmonicLoad,
    PeriodicLoad,
    TabulatedLoad,
    cycle_angles,
    piecewise_linear_path,
)

__all__ = ["HarmonicLoad", "PeriodicLoad", "TabulatedLoad", "cycle_angles",
           "piecewise_linear_path"]
