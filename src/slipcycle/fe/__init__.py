"""Static reduction of finite-element models to contact nodes (Python API).

2-D plane-strain models (below) and 3-D tetrahedral bodies on a rigid flat
(:func:`block_on_rigid_3d`, :func:`reduce_on_rigid_flat`, or a mesh file:
:func:`read_mesh_solid` and :func:`reduce_mesh_solid`; returning a
:class:`slipcycle.io.matrices.ReducedStiffness` with two tangential directions per node).

Build a :class:`Problem` with a geometry builder, condense it with :func:`reduce_problem`
and use the :class:`ReducedModel` (A, B, C and the load vectors p^w, q^w per basic load
case) as a coupled discrete frictional system::

    from slipcycle.fe import block_on_rigid, reduce_problem
    red = reduce_problem(block_on_rigid(width=0.02, height=0.01, E=200e9, nu=0.3))
    system = FrictionalSystem(red.A, red.B, red.C, 0.3)   # slipcycle.discrete

The reduction is the static condensation (Guyan 1965) of the contact degrees of freedom
as used for frictional systems by J. R. Barber, "Frictional systems under periodic loads —
history-dependence, non-uniqueness and energy dissipation", J. Phys.: Conf. Ser. 382
(2012) 012002. Names are imported on first use (the assembly needs scikit-fem).
"""

from __future__ import annotations

import importlib

_LAZY = {
    "block_on_rigid": "builders", "two_blocks": "builders", "cylinder_on_block": "builders",
    "from_mesh": "builders",
    "Body": "geometry",
    "read_mesh_body": "meshfile",
    "LoadCase": "reduction", "Problem": "reduction", "ReducedModel": "reduction",
    "reduce_problem": "reduction",
    "combined_loads": "loads",
    "coupling_ratio": "checks", "dundurs_beta": "checks",
    "Block3D": "solid3d", "block_on_rigid_3d": "solid3d", "reduce_on_rigid_flat": "solid3d",
    "MeshSolid": "meshfile3d", "read_mesh_solid": "meshfile3d",
    "reduce_mesh_solid": "meshfile3d",
}

__all__ = list(_LAZY)


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(f"slipcycle.fe.{_LAZY[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'slipcycle.fe' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
