"""The ``discrete3d`` case: TOML reader, slipcycle.run, outputs (summary with units,
result.nc with node coordinates, ParaView fields), refusals and the model's checks."""

import json
from pathlib import Path

import meshio
import numpy as np
import pytest
import xarray as xr

import slipcycle
from slipcycle.discrete3d import Load3D
from slipcycle.discrete3d.model import FrictionalSystem3D, ModelError3D
from slipcycle.discrete3d.wellposed import critical_friction_3d, radial_matrix
from slipcycle.io import CaseError
from slipcycle.io.results import write_outputs

CASE = """
model = "discrete3d"
[discrete3d]
A = [[2.0, 0.0], [0.0, 2.0]]
B = [[0.0, 0.0]]
C = [[1.0]]
friction = 0.5
coordinates = [[0.1, 0.2, 0.0]]
area = 0.5
[loading]
p0 = [1.0]
q1 = [[1.0, 1.0]]
q1_phase = [[0.0, -1.5707963267948966]]
[run]
cycles = 10
steps_per_cycle = 40
step_tolerance = 1e-4
"""


def test_a_case_runs_through_slipcycle_run_and_writes_fields_for_paraview(tmp_path):
    """One node on a rotating load: slipcycle.run dispatches through the registry; the
    summary carries units and the class; result.nc has node coordinates and units on
    every variable; the XDMF and VTU series hold the steady cycle's fields."""
    res = slipcycle.run(CASE)
    assert res.model == "discrete3d"
    assert res.steady_state.value == "cyclic_slip"
    s = res.summary()
    assert s["steady_state_class"] == "cyclic_slip"
    assert s["units"]["dissipation_per_cycle"] == "J"
    # closed form of the rotating node (test_discrete3d_physics): 2π f P √(Q0² − f²P²)/k
    closed = 2 * np.pi * 0.5 * np.sqrt(1.0 - 0.25) / 2.0
    assert s["dissipation_per_cycle"] == pytest.approx(closed, rel=5e-3)
    assert s["dissipation_per_area"][0] == pytest.approx(s["dissipation_per_node"][0] / 0.5)
    write_outputs(tmp_path / "out", res.to_outputs(), CASE)
    out = tmp_path / "out"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["steady_state"] == "cyclic_slip"
    ds = xr.open_dataset(out / "result.nc")
    for name in list(ds.data_vars) + list(ds.coords):
        assert "units" in ds[name].attrs, name
    assert float(ds["x"][0]) == pytest.approx(0.1) and float(ds["y"][0]) == pytest.approx(0.2)
    ds.close()
    assert (out / "figures" / "interface_states.png").is_file()
    pvd = (out / "fields" / "interface.pvd").read_text()
    assert pvd.count("<DataSet") == 41
    mesh = meshio.read(out / "fields" / "interface_0010.vtu")
    assert np.allclose(mesh.points[0], [0.1, 0.2, 0.0])
    # on the cone: |tangential traction| = f p / area at a slipping instant
    tq = np.linalg.norm(mesh.point_data["tangential_traction"][0])
    assert tq == pytest.approx(0.5 * mesh.point_data["pressure"][0], rel=1e-9)
    with meshio.xdmf.TimeSeriesReader(out / "fields" / "interface.xdmf") as reader:
        points, _ = reader.read_points_cells()
        assert reader.num_steps == 41
        t, point_data, _ = reader.read_data(5)
        assert "dissipation_per_area" in point_data


def test_result_of_a_python_system_and_its_repr():
    system = FrictionalSystem3D(2 * np.eye(2), np.zeros((1, 2)), [[1.0]], 0.5)
    load = Load3D.harmonic([1.0], [0.0, 0.0], None, [0.2, 0.2])
    res = slipcycle.run((system, load, {"cycles": 5}))
    assert res.steady_state.value == "shakedown"
    assert "DiscreteResult3D discrete3d: shakedown" in repr(res)
    assert "<table>" in res._repr_html_()


@pytest.mark.parametrize("edit,key", [
    (("A = [[2.0, 0.0], [0.0, 2.0]]", "A = [[2.0, 0.0, 0.0], [0.0, 2.0, 0.0]]"),
     "discrete3d.A"),
    (("A = [[2.0, 0.0], [0.0, 2.0]]", "A = [[2.0, 3.0], [3.0, 2.0]]"), "discrete3d.A"),
    (("friction = 0.5", "friction = -0.1"), "discrete3d.friction"),
    (("q1 = [[1.0, 1.0]]", "q1 = [[1.0, 1.0, 1.0]]"), "loading.q1"),
    (("step_tolerance = 1e-4", "step_tolerence = 1e-4"),
     "run.step_tolerence"),
    (("step_tolerance = 1e-4", "step_tolerance = 1e-4\nreplay = 1"), "run.replay"),
])
def test_invalid_cases_are_refused_naming_the_key(edit, key):
    with pytest.raises(CaseError) as err:
        slipcycle.run(CASE.replace(*edit))
    assert err.value.key == key


def test_the_cli_runs_the_example_case(tmp_path, capsys):
    from slipcycle.cli.main import main

    example = Path(slipcycle.__file__).parent / "examples" / "discrete3d_three_node.toml"
    text = example.read_text().replace("cycles = 40", "cycles = 2").replace(
        "step_tolerance = 1e-7", "step_tolerance = 1e-3")
    case = tmp_path / "c.toml"
    case.write_text(text)
    assert main(["run", str(case), "--out", str(tmp_path / "o")]) == 0
    assert (tmp_path / "o" / "fields" / "interface.xdmf").is_file()


def test_sampled_critical_friction_finds_where_the_radial_matrix_loses_p_property():
    """Well-posedness: at the sampled f_crit the radial matrix of the reported subset and
    directions is singular (det changes sign); the certified bound lies below it; a
    system with f above f_crit is refused, naming friction."""
    rng = np.random.default_rng(4)
    n = 2
    M = rng.normal(size=(3 * n, 3 * n))
    K = M @ M.T + 3 * np.eye(3 * n)
    A, B, C = K[:2 * n, :2 * n], K[2 * n:, :2 * n], K[2 * n:, 2 * n:]
    fc = critical_friction_3d(A, B, C, np.ones(n))
    assert np.isfinite(fc.f_crit) and fc.lower_bound <= fc.f_crit
    M0, M1 = radial_matrix(A, B, np.ones(n), list(fc.nodes), list(fc.directions))
    assert np.linalg.det(M0 + 0.999 * fc.f_crit * M1) * np.linalg.det(
        M0 + 1.001 * fc.f_crit * M1) <= 0
    with pytest.raises(ModelError3D) as err:
        FrictionalSystem3D(A, B, C, 1.01 * fc.f_crit)
    assert err.value.key == "friction"
    FrictionalSystem3D(A, B, C, 1.01 * fc.f_crit, accept_ill_posed=True)


def test_run_replay_reaches_the_solver_and_the_same_steady_state():
    """``[run] replay = true`` freezes the step subdivision (the solver reports replayed
    cycles) and ends on the steady state of the default adaptive run, within the step
    control's error level."""
    from slipcycle.discrete3d.case import read_discrete3d_case, solve_model
    from slipcycle.io.case import parse_case_text

    adaptive = slipcycle.run(CASE)
    dc = read_discrete3d_case(parse_case_text(CASE.replace("step_tolerance = 1e-4",
                                                      "step_tolerance = 1e-4\nreplay = true")))
    assert dc.run["replay"] is True
    frozen = solve_model(dc)
    assert frozen.solution.replayed_cycles >= 1
    assert frozen.solution.steady_state == adaptive.solution.steady_state == "cyclic_slip"
    assert frozen.solution.dissipation_per_cycle == pytest.approx(
        adaptive.solution.dissipation_per_cycle, rel=1e-3)
