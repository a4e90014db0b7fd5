"""``slipcycle run`` of finite-element cases: every result states whether its dissipation
is mesh-converged.

Two contacts, each solved on ``elements`` multiplied by ``[fe.convergence] refinements``:

- a sharp-edged complete contact (the block of ``fe_block_nu03.toml`` pressed on a rigid
  flat and slid back and forth): the edge tractions of the stuck solution are singular,
  only the edge node slips, and the dissipation falls under refinement faster than the
  node spacing: reported NOT mesh-converged;
- an incomplete contact (the cylinder of ``fe_cylinder.toml`` on a block, Hertz with
  Cattaneo–Mindlin slip zones): the dissipation converges with a positive order, and its
  extrapolation agrees with the closed form derived below.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import xarray as xr
from scipy.integrate import quad

import slipcycle
from slipcycle.cli.main import main
from slipcycle.examples import example_text
from slipcycle.io.metadata import cf_problems
from slipcycle.io.results import to_jsonable

# the block pressed by a constant 2 µm approach of its top face and slid ±3 µm: cyclic
# slip at the edge (the example's quarter-cycle lag and 1.5 µm shake down on every mesh)
BLOCK = (example_text("fe_block_nu03")
         .replace("normal = 0.5e-6           # m", "normal = 0.0")
         .replace("tangential = 1.5e-6       # m", "tangential = 3.0e-6")
         .replace("tangential = 1.5707963", "tangential = 0.0")
         .replace("cycles = 40", "cycles = 12")
         .replace("steps_per_cycle = 400", "steps_per_cycle = 200")
         .replace("refinements = [1, 2, 4]", "refinements = [1, 2, 4, 8]"))

# cylinder R = 10 mm on a block, both steel (β = 0), thickness 10 mm: top pressed 90 µm
# (P ≈ 48 kN, a ≈ 0.73 mm of the 1 mm candidate half-width), slid δ_t* sin θ with
# δ_t* = 28 µm (Q*/fP ≈ 0.54, slip zones 0.27 a wide at each edge), f = 0.3
CYLINDER_LOADS = """
[fe.discrete]
friction = 0.3
cycles = 6
steps_per_cycle = 200
[fe.discrete.mean]
normal = 90e-6
[fe.discrete.amplitude]
tangential = 28e-6
[fe.discrete.phase]
tangential = -1.5707963
"""
CYLINDER = example_text("fe_cylinder") + CYLINDER_LOADS
E, NU, F, THICKNESS = 210e9, 0.3, 0.3, 0.01


@pytest.fixture(scope="module")
def block():
    return slipcycle.run(BLOCK)


@pytest.fixture(scope="module")
def cylinder():
    return slipcycle.run(CYLINDER)


def test_block_on_flat_dissipation_is_not_mesh_converged(block):
    """Sharp-edged complete contact: the dissipation falls with the node spacing.

    Observed (4, 8, 16, 32 elements; 9, 17, 33, 65 contact nodes; h = 5, 2.5, 1.25,
    0.625 mm): 63.4, 17.7, 5.88, 1.72 µJ per cycle, only the two edge nodes slipping on
    every mesh: each halving of h divides the dissipation by 3.0 to 3.6. The last three
    meshes give the observed order 1.50 and extrapolate to −0.54 µJ: the dissipation
    vanishes under refinement (relative error of the finest value: infinite).
    """
    s = block.summary()
    values = s["dissipation_mesh_values"]
    h = s["dissipation_mesh_spacing"]
    assert s["mesh_elements"] == [4, 8, 16, 32] and s["mesh_n_nodes"] == [9, 17, 33, 65]
    assert s["dissipation_mesh_converged"] is False
    assert values[-1] == s["dissipation_per_cycle"] == block.dissipation_per_cycle
    # the trend measured on the run: every refinement cuts D at least in proportion to h
    ratios = [values[i + 1] / values[i] for i in range(len(values) - 1)]
    assert all(0 < r < h[i + 1] / h[i] for i, r in enumerate(ratios)), ratios
    assert s["dissipation_relative_error"] > 1.0
    assert s["dissipation_observed_order"] > 1.0
    assert s["dissipation_extrapolated"] < 0.5 * values[-1]
    # the slip stays at the edges: only the outermost nodes slip on the finest mesh
    n = s["n_nodes"]
    assert set(s["slipping_nodes"]) <= {0, n - 1} and s["slipping_nodes"]
    assert "WARNING" in block.message and "NOT mesh-converged" in block.message
    assert "NOT mesh-converged" in s["dissipation_mesh_message"]


def cattaneo_mindlin_dissipation(P: float, Q: float, f: float, e_star: float) -> float:
    """Dissipation per cycle [J/m] of a 2-D Hertz contact, constant P, Q between ±Q*.

    Derivation (plane strain, similar materials, β = 0; Johnson 1985, Contact Mechanics,
    §7.2, with the unloading argument of Mindlin & Deresiewicz 1953, J. Appl. Mech. 20,
    327): p = p₀ (1 − x²/a²)^{1/2}, p₀ = 2P/(πa). Loaded from Q = 0 to Q*, the
    Cattaneo tractions q = f p₀[(1 − x²/a²)^{1/2} − (c/a)(1 − x²/c²)^{1/2}] leave the
    stick zone |x| < c, (c/a)² = 1 − Q*/(fP). The relative surface displacement of two
    half-planes obeys ds/dx = −(2/(πE*)) PV∫ q(ξ)/(x − ξ) dξ (Johnson eq. 2.25b), with
    1/E* = (1 − ν₁²)/E₁ + (1 − ν₂²)/E₂; as PV∫(b² − ξ²)^{1/2}/(x − ξ) dξ = π(x −
    sgn x (x² − b²)^{1/2}) for |x| > b, the slip in c < |x| < a is

        S(x; c) = (f p₀/(a E*)) [ |x| (x² − c²)^{1/2} − c² arccosh(|x|/c) ].

    Unloading from Q* to −Q* adds −2 × the loading solution with 2f, so every point of
    c < |x| < a slips 2 S(x; c) in one direction against the traction f p; the loop
    dissipates twice that:

        W = 2 ∫ f p · 2 S dx = (32 f² P²/(π² E*)) I(k),
        I(k) = ∫_k^1 (1 − s²)^{1/2} [s (s² − k²)^{1/2} − k² arccosh(s/k)] ds, k = c/a,

    independent of R; W ∝ Q*³ for small Q* (the Mindlin law, checked below).
    """
    k = math.sqrt(1.0 - Q / (f * P))

    def integrand(s):
        return math.sqrt(1 - s * s) * (s * math.sqrt(s * s - k * k)
                                       - k * k * math.acosh(s / k))

    integral = quad(integrand, k, 1.0, epsabs=0.0, epsrel=1e-12, limit=200)[0]
    return 32.0 * f**2 * P**2 * integral / (math.pi**2 * e_star)


def test_shipped_block_example_shakes_down_on_every_mesh():
    """``fe_block_nu03.toml`` as shipped (pressed first, tangential motion lagging by a
    quarter cycle) shakes down on 9, 17 and 33 nodes: D = 0 on every mesh, converged."""
    r = slipcycle.run(example_text("fe_block_nu03"))
    s = r.summary()
    assert s["mesh_n_nodes"] == [9, 17, 33]
    assert s["dissipation_mesh_values"] == [0.0, 0.0, 0.0]
    assert r.steady_state == "shakedown" and s["dissipation_mesh_converged"] is True


def test_closed_form_matches_the_halfspace_slider_bed():
    """The closed form above against the half-space model's slider bed (Ciavarella–Jäger
    superposition, :mod:`slipcycle.halfspace`), force controlled, Q*/fP = 0.54, 200
    steps per cycle: observed ratio 1 + 1.6e-4 with 4000 sliders (tolerance 1e-3)."""
    from slipcycle.halfspace import ContactElasticity, Cylinder2D, make_bed, run_history

    el = ContactElasticity.from_materials((E, E), (NU, NU), plane=True)
    P, Q = 4.83e6, 0.54 * F * 4.83e6
    theta = np.linspace(0, 2 * np.pi, 201)[1:]
    bed = make_bed(Cylinder2D(0.01, el.contact_modulus), friction=F,
                   compliance_ratio=el.compliance_ratio, P_max=1.001 * P, n_sliders=4000)
    an = np.concatenate([np.linspace(0, P, 51)[1:], np.full(50, P)])
    at = np.concatenate([np.zeros(50), np.linspace(0, Q * np.sin(theta[-1]), 51)[1:]])
    hs = run_history(bed, an, at, np.full_like(theta, P), Q * np.sin(theta), max_cycles=4)
    W = cattaneo_mindlin_dissipation(P, Q, F, el.contact_modulus)
    assert W / hs.dissipation_per_cycle == pytest.approx(1.0, abs=1e-3)
    # small amplitudes: W ∝ Q*³, doubling Q* multiplies W by 8 (1 + O(Q*/fP)); observed
    # 8.04 from Q*/fP = 0.01 (smaller amplitudes reach the round-off of the integrand)
    w1, w2 = (cattaneo_mindlin_dissipation(P, q, F, el.contact_modulus)
              for q in (0.01 * F * P, 0.02 * F * P))
    assert 8.0 < w2 / w1 < 8.1


def test_cylinder_on_block_dissipation_converges_to_cattaneo_mindlin(cylinder):
    """Incomplete contact: positive observed order, converged, and the extrapolation
    agrees with :func:`cattaneo_mindlin_dissipation` under the P, Q* of the finest run.

    Observed (20, 40, 80 elements; 41, 81, 161 nodes; h = 50, 25, 12.5 µm):
    D = 8.545, 8.456, 8.439 mJ, observed order 2.43, extrapolated 8.435 mJ (estimated
    error of the finest value 4.5e-4); closed form 8.490 mJ: ratio 0.9935. Tolerance
    2 %: the closed form is for half-planes, the bodies here are 10 mm high with
    a ≈ 0.73 mm (a/height = 0.073; the finite-size error is of order (a/height)² ≈ 0.5 %).
    """
    s = cylinder.summary()
    assert s["mesh_n_nodes"] == [41, 81, 161]
    assert s["dissipation_mesh_converged"] is True
    assert s["dissipation_observed_order"] > 0.5
    assert s["dissipation_relative_error"] <= 0.05
    assert "WARNING" not in cylinder.message
    last = cylinder.finest.to_dataset().isel(cycle=-1)
    P = float(last["normal_reaction"].sum("node").mean())
    Q = float(np.abs(last["tangential_reaction"].sum("node")).max())
    assert np.ptp(last["normal_reaction"].sum("node").values) < 1e-6 * P  # constant P
    a = math.sqrt(4 * (P / THICKNESS) * 0.01 / (math.pi * E / (2 * (1 - NU**2))))
    assert 0.6e-3 < a < 1e-3  # incomplete: inside the candidate zone |x| < 1 mm
    # per unit length in the closed form: P, Q* [N/m], W [J/m]
    W = THICKNESS * cattaneo_mindlin_dissipation(P / THICKNESS, Q / THICKNESS, F,
                                                 E / (2 * (1 - NU**2)))
    assert s["dissipation_extrapolated"] / W == pytest.approx(1.0, abs=0.02)


def test_cylinder_on_too_coarse_a_base_mesh_is_flagged_not_monotone():
    """With 10, 20, 40 elements (h = 100, 50, 25 µm; a ≈ 7 node spacings on the coarsest)
    the contact and slip-zone edges jump between nodes: D = 8.301, 8.545, 8.456 mJ is not
    monotone, so no order is claimed and the run warns (not in the asymptotic range)."""
    r = slipcycle.run(CYLINDER.replace("elements = 20", "elements = 10"))
    s = r.summary()
    v = s["dissipation_mesh_values"]
    assert s["mesh_n_nodes"] == [21, 41, 81]
    assert (v[1] - v[0]) * (v[2] - v[1]) < 0
    assert s["dissipation_mesh_converged"] is False
    assert s["dissipation_observed_order"] is None and s["dissipation_extrapolated"] is None
    assert "not monotone" in r.message and "WARNING" in r.message


def test_cli_and_python_give_identical_summaries_and_standard_outputs(block, tmp_path,
                                                                      monkeypatch, capsys):
    """``slipcycle run`` writes what ``slipcycle.run`` returns (wall times and provenance
    aside), prints the warning, and its files follow the output standards."""
    jsonschema = pytest.importorskip("jsonschema")
    from slipcycle.io.schema import load_schema

    (tmp_path / "block.toml").write_text(BLOCK)
    monkeypatch.chdir(tmp_path)
    assert main(["run", "block.toml", "--out", "out", "--no-progress"]) == 0
    err = capsys.readouterr().err
    assert "NOT mesh-converged" in err
    written = json.loads((tmp_path / "out" / "summary.json").read_text())
    jsonschema.validate(written, load_schema("summary"))
    python = to_jsonable(block.summary())
    for d in (written, python):
        d.pop("metadata", None)
        d.pop("wall_time_s")
    assert written == python
    with xr.open_dataset(tmp_path / "out" / "result.nc") as ds:
        assert cf_problems(ds) == []
        np.testing.assert_allclose(ds["mesh_dissipation"].values,
                                   python["dissipation_mesh_values"], rtol=1e-12)
    assert (tmp_path / "out" / "figures" / "mesh_convergence.png").stat().st_size > 0


def test_one_mesh_says_convergence_is_not_assessed():
    r = slipcycle.run(BLOCK.replace("refinements = [1, 2, 4, 8]", "refinements = [1]"))
    s = r.summary()
    assert s["mesh_elements"] == [4]
    assert s["dissipation_mesh_converged"] is None
    assert s["dissipation_extrapolated"] is None
    assert "not assessed" in r.message


@pytest.mark.parametrize("table, key", [
    ("refinements = [2, 4]", "fe.convergence.refinements"),
    ("refinements = [1, 1]", "fe.convergence.refinements"),
    ("refinements = [1, 2.5]", "fe.convergence.refinements"),
    ('refinements = "oops"', "fe.convergence.refinements"),
    ("refinements = [1, 8000]", "fe.convergence.refinements"),
    ("refinements = [1, 2]\nrtol = 0", "fe.convergence.rtol"),
    ("refinemnts = [1, 2]", "fe.convergence.refinemnts"),
])
def test_bad_convergence_keys_are_one_line_errors(table, key, tmp_path, monkeypatch,
                                                  capsys):
    text = BLOCK.replace("rtol = 0.05", "").replace("refinements = [1, 2, 4, 8]", table)
    (tmp_path / "case.toml").write_text(text)
    monkeypatch.chdir(tmp_path)
    code = main(["run", "case.toml", "--out", "out"])
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert code == 2 and len(err) == 1, err
    assert err[0].startswith(f"error: {key}"), err
    assert not (tmp_path / "out").exists()


def test_fe_case_without_loads_names_the_table_and_reduce(tmp_path, monkeypatch, capsys):
    (tmp_path / "case.toml").write_text(example_text("fe_cylinder"))
    monkeypatch.chdir(tmp_path)
    code = main(["run", "case.toml", "--out", "out"])
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert code == 2 and len(err) == 1
    assert err[0].startswith("error: fe.discrete:") and "slipcycle reduce" in err[0]
