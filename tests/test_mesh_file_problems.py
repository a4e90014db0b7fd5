"""3-D mesh files that cannot be a body (issue 34): a NaN node coordinate and a truncated
Gmsh file are named as what they are, under the mesh file's key, instead of blaming the
load case or reporting meshio's "list index out of range"."""

from __future__ import annotations

import numpy as np
import pytest
from test_fe3d_meshfile import H, box, faces_on, write_msh

from slipcycle.io import CaseError

pytest.importorskip("meshio")
pytest.importorskip("skfem")

from slipcycle.fe.meshfile3d import read_mesh_solid  # noqa: E402

TAGS = {"contact": "base", "top": "top"}


def _write(path, mesh):
    write_msh(path, mesh, {"base": faces_on(mesh, lambda c: np.abs(c[2]) < 1e-12),
                           "top": faces_on(mesh, lambda c: np.abs(c[2] - H) < 1e-12)})


def test_a_nan_node_coordinate_is_named_under_the_mesh_key(tmp_path):
    _write(tmp_path / "box.msh", box())
    text = (tmp_path / "box.msh").read_text().splitlines()
    i = text.index("$Nodes") + 2                     # the first node: "1 x y z"
    number = text[i].split()[0]
    text[i] = f"{number} nan 0 0"
    (tmp_path / "nan.msh").write_text("\n".join(text) + "\n")
    with pytest.raises(CaseError) as info:
        read_mesh_solid(tmp_path / "nan.msh", TAGS)
    msg = str(info.value)
    assert msg.startswith("fe.mesh.file: ") and "non-finite coordinate" in msg


def test_a_truncated_mesh_file_is_named_as_truncated(tmp_path):
    _write(tmp_path / "box.msh", box())
    data = (tmp_path / "box.msh").read_text()
    (tmp_path / "cut.msh").write_text(data[: int(len(data) * 0.6)])
    with pytest.raises(CaseError) as info:
        read_mesh_solid(tmp_path / "cut.msh", TAGS)
    msg = str(info.value)
    assert msg.startswith("fe.mesh.file: cannot read mesh file") and "\n" not in msg
    assert "truncated" in msg or "end" in msg.lower(), msg
