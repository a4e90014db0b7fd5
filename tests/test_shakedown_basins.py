"""Outcomes below λ1, between λ1 and λ2, above λ2; fast kernel vs general solver; basin
maps, box counting and the shakedown/basins commands (issue 4)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from slipcycle.discrete import DiscreteLoad, FrictionalSystem, simulate
from slipcycle.discrete.basins import (
    admissible_box,
    basin_row,
    box_counting_dimension,
    run_records,
)
from slipcycle.discrete.case import read_discrete_case
from slipcycle.discrete.fastcycle import steady_state_fast, steady_states_batch
from slipcycle.discrete.shakedown import (
    lambda1,
    lambda2,
    safe_region,
    sample_initial_slips,
)
from slipcycle.io import read_case

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "slipcycle" / "examples"
RUN = {"cycles": 80, "steps_per_cycle": 60, "tol": 1e-8}


@pytest.fixture(scope="module")
def tri():
    dc = read_discrete_case(read_case(EXAMPLES / "shakedown_triangle.toml"))
    region = safe_region(dc.system, dc.load)
    l2 = lambda2(region)[0]
    l1 = lambda1(region, l2)["lambda1"]
    return dc.system, dc.load, region, l1, l2


def test_fast_kernel_agrees_with_general_solver(tri):
    system, load, *_ = tri
    V = sample_initial_slips(system, load, 6, seed=5)
    for v0 in V:
        a = steady_state_fast(system, load, v0, **RUN)
        b = simulate(system, load, initial_slip=v0, record=False, **RUN)
        assert a["steady_state"] == b.steady_state
        assert a["cycles_run"] == b.cycles_run
        assert a["dissipation_per_cycle"] == pytest.approx(b.dissipation_per_cycle, abs=1e-12)
        np.testing.assert_allclose(a["final_slip"], b.cycle_start_states[-1][:2], atol=1e-12)


def test_fast_kernel_falls_back_on_separation():
    """A node that separates is handed to the general solver; the record still agrees."""
    A = np.array([[1.0, 0.2], [0.2, 1.0]])
    B = np.array([[0.3, 0.1], [-0.2, 0.2]])
    system = FrictionalSystem(A, B, np.eye(2), 0.3)
    load = DiscreteLoad.harmonic([0.3, 1.0], [0.0, 0.0], [0.5, 0.1], [0.1, 0.2],
                                 [0.0, 0.0], [1.0, 2.0])
    v0 = np.zeros(2)
    assert steady_state_fast(system, load, v0, **RUN)["code"] == -1
    rec = run_records(system, load, v0[None], **RUN)
    res = simulate(system, load, initial_slip=v0, record=False, **RUN)
    assert rec["dissipation_per_cycle"][0] == pytest.approx(res.dissipation_per_cycle,
                                                            abs=1e-12)


def _outcomes(system, load, lam, count=40):
    ld = load.with_lam(lam)
    V = sample_initial_slips(system, ld, count, seed=11)
    assert len(V) == count
    return run_records(system, ld, V, **RUN)["steady_state"]


def test_below_lambda1_every_start_shakes_down(tri):
    system, load, region, l1, l2 = tri
    for lam in (0.5 * l1, 0.97 * l1):
        assert np.all(_outcomes(system, load, lam) == 0), lam


def test_above_lambda2_no_start_shakes_down(tri):
    system, load, region, l1, l2 = tri
    for lam in (1.03 * l2, 1.5 * l2):
        cls = _outcomes(system, load, lam)
        assert not np.any(cls == 0)
        assert np.all(np.isin(cls, (1, 2)))


def test_between_lambda1_and_lambda2_basin_map_shows_both(tri):
    system, load, region, l1, l2 = tri
    lam = 0.5 * (l1 + l2)
    ld = load.with_lam(lam)
    box = admissible_box(system, ld)
    v1 = np.linspace(*box[0], 31)
    v2 = np.linspace(*box[1], 31)
    rows = [basin_row(system, ld, v1, y, **RUN) for y in v2]
    cls = np.array([r["steady_state"] for r in rows])
    assert (cls == 0).any() and (cls == 1).any()
    # every start inside the safe region S(λ) is already safe: shakedown, no dissipation
    V1, V2 = np.meshgrid(v1, v2)
    inside = region.contains(np.stack([V1, V2], -1), lam, tol=-1e-9)
    assert inside.any() and np.all(cls[inside] == 0)
    D = np.array([r["dissipation_per_cycle"] for r in rows])
    assert np.all(D[cls == 1] > 0)
    assert np.max(D[cls == 0]) < 1e-5 * np.min(D[cls == 1])   # asymptotic approach only


def test_box_counting_smooth_and_rough():
    n = 256
    x, y = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n))
    disc = (x ** 2 + y ** 2 < 0.5).astype(int)
    assert box_counting_dimension(disc)["dimension"] == pytest.approx(1.0, abs=0.1)
    noise = np.random.default_rng(0).integers(0, 2, (n, n))
    assert box_counting_dimension(noise)["dimension"] == pytest.approx(2.0, abs=0.05)
    assert np.isnan(box_counting_dimension(np.zeros((64, 64), int))["dimension"])
    # the edge of the admissible region is not a basin boundary
    assert np.isnan(box_counting_dimension(disc, valid=disc == 1)["dimension"])


def _cantor_labels(n: int) -> np.ndarray:
    """Two classes alternating with the level at which x first falls in a removed middle
    third: their boundary is (middle-thirds Cantor set) × [0, 1]."""
    y = (np.arange(n) + 0.5) / n
    lab = np.zeros(n, int)
    found = np.zeros(n, bool)
    for level in range(40):
        digit = np.floor(3 * y)
        hit = (digit == 1) & ~found
        lab[hit] = level % 2
        found |= hit
        y = 3 * y - digit
    return np.repeat(lab[:, None], n, axis=1)


def test_box_counting_recovers_a_known_fractal_dimension():
    # Cantor × interval: dimension 1 + log 2 / log 3 = 1.6309
    exact = 1 + np.log(2) / np.log(3)
    for n in (243, 729):
        dim = box_counting_dimension(_cantor_labels(n))["dimension"]
        assert dim == pytest.approx(exact, abs=0.03)


@pytest.fixture(scope="module")
def unstable():
    return read_discrete_case(read_case(EXAMPLES / "unstable_two_node.toml"))


def test_unstable_steady_states_amplify_perturbations(unstable):
    """Seed 001 §3.1: with strong coupling a periodic state can be unstable, so that small
    perturbations grow with successive cycles. Two starts 1e-9 m apart separate by more
    than 1e4× within 40 cycles, whatever the load step (so not a discretisation effect),
    and the general event-driven solver follows the compiled kernel while they are close.
    """
    system, load = unstable.system, unstable.load
    v0 = np.asarray(unstable.initial_slip, float)
    pair = np.array([v0, v0 + [1e-9, 0.0]])
    for steps in (64, 256):
        far = steady_states_batch(system, load, pair, cycles=40, steps_per_cycle=steps,
                                  tol=0.0, min_cycles=40)
        gap = np.abs(far["final_slip"][0] - far["final_slip"][1]).max()
        assert gap > 1e4 * 1e-9
        assert np.all(far["steady_state"] == "not_converged")
    near = steady_states_batch(system, load, v0[None], cycles=8, steps_per_cycle=256,
                               tol=0.0, min_cycles=8)
    ref = simulate(system, load, initial_slip=v0, cycles=8, steps_per_cycle=256, tol=0.0,
                   min_cycles=8)
    assert np.allclose(near["final_slip"][0], ref.x[-1, -1, :2], atol=1e-7)
    # aperiodic: the dissipation per cycle keeps changing (between ~1.0 and ~2.6 J)
    hist = np.asarray(ref.dissipation_history)
    assert np.ptp(hist[-4:]) > 0.05 * np.mean(hist[-4:])


def test_well_posed_despite_expanding_slope_product(unstable):
    """The expansion comes from a negative slope product k1+ k2- < -1 of the two slip
    lines, which the P-matrix condition allows (only positive products must stay < 1)."""
    from slipcycle.discrete.wellposed import critical_friction

    A, B = unstable.system.A, unstable.system.B
    f = float(unstable.system.friction[0])
    assert critical_friction(A, B, f).f_crit > f
    k1 = {s: (A[0, 1] + s * f * B[0, 1]) / (A[0, 0] + s * f * B[0, 0]) for s in (1, -1)}
    k2 = {s: (A[1, 0] + s * f * B[1, 0]) / (A[1, 1] + s * f * B[1, 1]) for s in (1, -1)}
    products = [k1[a] * k2[b] for a in (1, -1) for b in (1, -1)]
    assert max(products) < 1.0                      # P-matrix (well-posed corners)
    assert min(products) < -2.0                     # expanding pair


def test_shakedown_command(run_cli, tmp_path, tri):
    system, load, region, l1, l2 = tri
    out = tmp_path / "sd"
    code, stdout, err = run_cli("shakedown", EXAMPLES / "shakedown_triangle.toml", "--out",
                                out, "--lam-points", "6", "--starts", "2", "--workers", "1",
                                "--no-progress")
    assert code == 0, err
    s = json.loads((out / "summary.json").read_text())
    assert s["lambda1"] == pytest.approx(l1, rel=1e-8)
    assert s["lambda2"] == pytest.approx(l2, rel=1e-12)
    for key in ("lambda3_bracket", "lambda4_bracket", "dissipation_per_cycle",
                "lambda3_evidence", "safe_region_vertices"):
        assert key in s
    assert s["regime"] == "between_lambda1_and_lambda2"
    lo, hi = s["lambda3_bracket"]
    assert hi is None or lo < hi
    assert hi is None or hi > l2          # every node slipping needs λ above λ2 here
    assert {p.name for p in (out / "figures").iterdir()} == {
        "dissipation_vs_lambda.png", "safe_region_panels.png"}


def test_basins_command_and_errors(run_cli, tmp_path, write_case):
    out = tmp_path / "b"
    code, stdout, err = run_cli("basins", EXAMPLES / "shakedown_triangle.toml", "--out", out,
                                "--grid", "21", "--no-progress")
    assert code == 0, err
    s = json.loads((out / "summary.json").read_text())
    assert s["both_outcomes"] is True
    assert s["starts"] == 21 * 21
    assert 0.5 < s["boundary_box_counting_dimension"] < 2.0
    assert (out / "figures" / "basin_map.png").exists()
    text = (EXAMPLES / "shakedown_triangle.toml").read_text()
    code, _, err = run_cli("basins", EXAMPLES / "shakedown_triangle.toml", "--out",
                           tmp_path / "c", "--grid", "1")
    assert code == 2 and "--grid" in err
    code, _, err = run_cli("basins", EXAMPLES / "shakedown_triangle.toml", "--out",
                           tmp_path / "d", "--lam", "-1")
    assert code == 2 and "--lam" in err
    bad = write_case(text.replace("friction = 0.5", "friction = -0.5"), "bad.toml")
    code, _, err = run_cli("shakedown", bad, "--out", tmp_path / "e")
    assert code == 2 and "discrete.friction" in err
    assert not (tmp_path / "e" / "summary.json").exists()


def test_basins_random_and_protocols_any_n(run_cli, tmp_path, write_case):
    text = (EXAMPLES / "shakedown_triangle.toml").read_text()
    out = tmp_path / "r"
    code, _, err = run_cli("basins", EXAMPLES / "shakedown_triangle.toml", "--out", out,
                           "--random", "12", "--workers", "1", "--no-progress")
    assert code == 0, err
    s = json.loads((out / "summary.json").read_text())
    assert s["starts"] == 12 and s["mode"] == "random"
    protos = write_case("""
[[protocol]]
p_w = [[0.1, 1.0], [1.0, 1.0]]
q_w = [[0.3, 0.0], [0.0, 0.0]]
[[protocol]]
p_w = [[1.0, 1.0]]
""", "protocols.toml")
    del text
    out = tmp_path / "p"
    code, _, err = run_cli("basins", EXAMPLES / "shakedown_triangle.toml", "--out", out,
                           "--protocols", protos, "--workers", "1", "--no-progress")
    assert code == 0, err
    s = json.loads((out / "summary.json").read_text())
    assert s["starts"] == 2
    # the example's comment: this protocol shakes down
    assert s["class_counts"].get("shakedown", 0) >= 1
