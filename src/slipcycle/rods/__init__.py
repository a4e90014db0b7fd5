"""Two coaxial elastic rods with a frictional interface under torsion (Python API).

Build the system and its excitation, choose an interface law, then solve::

    from slipcycle.rods import Rod, TwoRods, Excitation, make_bed, modal_basis, steady_state
    rod = Rod(length=0.5, radius=0.01, E=210e9, nu=0.3, density=7850.0)
    rods = TwoRods(rod, rod, friction=0.3, interface="distributed",
                   interface_stiffness=1e13, damping_ratio=0.01)
    exc = Excitation(rotation_amplitude=1e-3, frequency=0.5 * omega1(rods), axial_force=1e3)
    dyn = steady_state(rods, exc, make_bed(rods, exc.axial_force), modal_basis(rods, 50))

- :mod:`~slipcycle.rods.model`       :class:`Rod`, :class:`TwoRods`, :class:`Excitation`
- :mod:`~slipcycle.rods.interfaces`  interface laws as beds of Jenkins elements (Iwan 1966;
  Segalman 2005)
- :mod:`~slipcycle.rods.welded`      transfer matrices, natural frequencies
- :mod:`~slipcycle.rods.modal`       modal basis and the periodic steady state
- :mod:`~slipcycle.rods.quasistatic` the quasi-static loop
- :mod:`~slipcycle.rods.limits`      the limit frequency of the quasi-static approximation
- :mod:`~slipcycle.rods.case`        :class:`RodsCase` and :func:`analyse` (every quantity
  that ``slipcycle run`` reports)

Names are imported on first use (the solvers compile with Numba).
"""

from __future__ import annotations

import importlib

from slipcycle.rods.model import INTERFACES, Excitation, Rod, TwoRods

_LAZY = {
    "RodsCase": "case", "analyse": "case", "interface_bed": "case",
    "Bed": "interfaces", "SegalmanIwan": "interfaces", "make_bed": "interfaces",
    "fit_iwan": "interfaces", "InterfaceLaw": "interfaces", "interface_law": "interfaces",
    "INTERFACE_LAWS": "interfaces", "gross_slip_torque": "model",
    "omega1": "welded", "natural_frequencies": "welded", "interface_torque_frf": "welded",
    "ModalBasis": "modal", "DynamicResult": "modal", "modal_basis": "modal",
    "steady_state": "modal",
    "quasi_static_loop": "quasistatic",
    "regularisation_study": "regularisation",
    "Study": "limits", "Point": "limits", "limit_frequency": "limits",
    "regime_map": "limits", "position_map": "limits", "make_study": "limits",
}

__all__ = ["INTERFACES", "Excitation", "Rod", "TwoRods", *_LAZY]


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(f"slipcycle.rods.{_LAZY[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'slipcycle.rods' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
