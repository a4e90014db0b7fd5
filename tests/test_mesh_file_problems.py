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


def test_a_missing_clamped_set_is_reported_under_fe_mesh_clamped(tmp_path, run_cli):
    """The tag named in ``clamped`` is not in the file: the key that names it is blamed
    (it was ``fe.mesh.nosuch``, the tag itself)."""
    _write(tmp_path / "box.msh", box())
    case = tmp_path / "model.toml"
    case.write_text('model = "fe"\n[fe]\ngeometry = "mesh"\n[fe.mesh]\nfile = "box.msh"\n'
                    'contact = "base"\nclamped = ["nosuch"]\nE = 2.1e11\nnu = 0.3\n'
                    '[[fe.load_case]]\nname = "push"\nboundary = "top"\n'
                    'displacement = [1e-6, 0.0, 0.0]\n')
    code, _, err = run_cli("reduce", case, "--out", tmp_path / "r.npz")
    assert code == 2 and err.startswith("error: fe.mesh.clamped: "), err
    assert "'nosuch'" in err and not (tmp_path / "r.npz").exists()
