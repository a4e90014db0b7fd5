"""From a finite-element code's export to a ready ``discrete3d`` case (``slipcycle reduce``).

A model file (``model = "fe_import"``, :mod:`slipcycle.fe_import.model`) names each
body's stiffness export (CalculiX ``.sti``, Abaqus/CalculiX ``.mtx``, Matrix Market,
Harwell–Boeing, MATLAB, Nastran DMIG: the readers of :mod:`slipcycle.io.fe_formats`), its
mesh (the deck or any meshio mesh: :mod:`slipcycle.fe_import.mesh`), the contact surface
and the load cases; :func:`import_joint` condenses the bodies onto the contact with the
engine of slipcycle's own 3-D reductions and :func:`write_import` writes the case. See
docs/from_fe_code.md.
"""

from slipcycle.fe_import.files import OUTPUT_FILES, is_import_model, reduce_import, write_import
from slipcycle.fe_import.joint import ImportedBody, ImportedJoint, import_joint, read_body
from slipcycle.fe_import.mesh import ImportedMesh, read_mesh
from slipcycle.fe_import.model import BodySpec, ImportModel, LoadSpec, read_import_model

__all__ = ["BodySpec", "ImportModel", "ImportedBody", "ImportedJoint", "ImportedMesh",
           "LoadSpec", "OUTPUT_FILES", "import_joint", "is_import_model", "read_body",
           "read_import_model", "read_mesh", "reduce_import", "write_import"]
