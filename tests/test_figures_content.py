"""What each figure must show, tested on the matplotlib Figure objects (artists, legend
texts, axis limits, the data drawn), not on pixels: complete legends, no empty panel
titled with a wrong number, differences drawn where the result is a difference, outlines
on interface maps, closed periodic loops; and the half-space traction kink explained
against the closed forms of Cattaneo and Mindlin & Deresiewicz."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import ONE_NODE_3D

import slipcycle
from slipcycle.examples import example_text

#: the sphere of the ``halfspace_sphere`` example: P (N), Q amplitude (N), f, R (m), E* (Pa)
P, Q1, F, R = 100.0, 30.0, 0.5, 0.01
E_STAR = 1.0 / (2 * (1 - 0.3**2) / 200e9)


def _sphere(protocol: str = "", steps: int = 40):
    text = example_text("halfspace_sphere").replace("steps_per_cycle = 400",
                                                    f"steps_per_cycle = {steps}")
    return slipcycle.run(text + protocol)


@pytest.fixture(scope="module")
def proportional():
    """The example as shipped: its assembly loads P and Q proportionally from zero."""
    return _sphere()


@pytest.fixture(scope="module")
def normal_first():
    """The same cycle, reached by pressing first and then shearing (Mindlin's path)."""
    return _sphere("[[loading.protocol]]\nP = 100.0\nQ = 0.0\n")


def _hertz():
    a = (3 * P * R / (4 * E_STAR)) ** (1 / 3)
    return a, 3 * P / (2 * np.pi * a**2)


def _cattaneo(r, x, a, p0):
    """p0 (x/a) √(1 − r²/x²) inside r < x, 0 outside: the stick-zone correction."""
    return np.where(r < x, p0 * (x / a) * np.sqrt(np.clip(1 - (r / x) ** 2, 0, None)), 0.0)


def _closed_form_q_top(r, path: str):
    """q(r) at θ = 0 (Q = +Q1) of the steady cycle, and the radii b and c.

    Steady annulus (Mindlin & Deresiewicz): (c/a)³ = 1 − 2Q1/(2fP). Proportional path
    (q = (Q1/P) p after the assembly, no slip): the first reversal by 2Q1 slips b < r < a
    with (b/a)³ = 1 − 2Q1/((f + Q1/P) P); superposing the Cattaneo corrections gives
    q = f p + (f + Q1/P) p_b − 2f p_c. Normal-first path: q = f (p − p_c).
    """
    a, p0 = _hertz()
    p = p0 * np.sqrt(np.clip(1 - (r / a) ** 2, 0, None))
    c = a * (1 - Q1 / (F * P)) ** (1 / 3)
    b = a * (1 - 2 * Q1 / ((F + Q1 / P) * P)) ** (1 / 3)
    if path == "proportional":
        q = F * p + (F + Q1 / P) * _cattaneo(r, b, a, p0) - 2 * F * _cattaneo(r, c, a, p0)
    else:
        q = F * (p - _cattaneo(r, c, a, p0))
    return q, a, b, c


def _closed_form_q_cycle(r, path: str) -> np.ndarray:
    """(4, m): q(r) at θ = 0, π/2, π, 3π/2 of the steady cycle (Q = Q1 cos θ).

    From either extreme a change of Q by ΔQ adds ∓2f (p − p_c(ΔQ)) with
    (c(ΔQ)/a)³ = 1 − ΔQ/(2fP) (Mindlin & Deresiewicz): those annuli never reach the
    locked-in edge b < c of the proportional path."""
    q_top, a, _, _ = _closed_form_q_top(r, path)
    _, p0 = _hertz()
    p = p0 * np.sqrt(np.clip(1 - (r / a) ** 2, 0, None))

    def change(dQ):
        return 2 * F * (p - _cattaneo(r, a * (1 - dQ / (2 * F * P)) ** (1 / 3), a, p0))

    q_bottom = q_top - change(2 * Q1)
    return np.array([q_top, q_top - change(Q1), q_bottom, q_bottom + change(Q1)])


@pytest.mark.parametrize("path", ["proportional", "normal_first"])
def test_sphere_shear_traction_over_the_cycle_is_the_closed_form_of_its_load_path(
        request, path):
    ds = request.getfixturevalue(path).to_dataset()
    np.testing.assert_allclose(ds.snapshot_theta.values, np.pi / 2 * np.arange(4),
                               atol=1e-12)
    r = ds.radius.values
    _, a, b, c = _closed_form_q_top(r, path)
    q_ref = _closed_form_q_cycle(r, path)
    _, p0 = _hertz()
    inside = r < 0.95 * a     # away from the edge singularity of the slider cells
    err = np.max(np.abs(ds.shear_traction.values[:, inside] - q_ref[:, inside])) / (F * p0)
    assert err < 0.01, err   # 2001 sliders: 0.3 % (proportional), 0.03 % (normal first)
    # the stick radius of the run is the closed form's c
    assert float(ds.permanent_stick_size) == pytest.approx(c, rel=0.01)


def test_sphere_traction_kink_inside_the_stick_zone_is_the_first_reversals_slip_edge(
        proportional, normal_first):
    """The kink the demo's ``tractions.png`` shows at r = 0.12 mm inside the stick radius
    0.14 mm is physics of the load path: the edge b = 0.63 a of the annulus slipped once,
    at the first reversal after a proportional assembly, locked in ever after. Pressing
    first (Mindlin's path) leaves q(r) increasing over the stick zone: no kink."""
    _, a, b, c = _closed_form_q_top(np.zeros(1), "proportional")
    assert b / a == pytest.approx(0.63, abs=0.005)
    assert c / a == pytest.approx(0.737, abs=0.005)
    assert b * 1e3 == pytest.approx(0.12, abs=0.005)
    assert c * 1e3 == pytest.approx(0.14, abs=0.005)
    for result, kink in ((proportional, True), (normal_first, False)):
        ds = result.to_dataset()
        r, q = ds.radius.values, ds.shear_traction.values[0]
        stick = r < float(ds.permanent_stick_size)
        k = int(np.argmin(q[stick]))
        if kink:   # the minimum over the stick zone, with q rising on both sides of it
            assert r[k] == pytest.approx(b, abs=2 * (r[1] - r[0]))
            assert q[k - 5] > q[k] < q[k + 5]
        else:
            assert k == 0
            assert np.all(np.diff(q[stick]) > -1e-3 * F * _hertz()[1])


def _legend_texts(ax) -> list[str]:
    legend = ax.get_legend()
    return [t.get_text() for t in legend.get_texts()] if legend is not None else []


def _labelled_lines(ax) -> list[str]:
    return [ln.get_label() for ln in ax.get_lines() if not ln.get_label().startswith("_")]


def test_sphere_tractions_figure_has_every_curve_in_its_legend(proportional):
    from slipcycle.plot.halfspace import tractions

    ds = proportional.to_dataset()
    ax = tractions(ds).axes[0]
    texts = _legend_texts(ax)
    drawn = [ln for ln in ax.get_lines() if len(ln.get_xdata()) > 2]
    assert all(not ln.get_label().startswith("_") for ln in drawn)   # none left unnamed
    assert sorted(texts) == sorted(_labelled_lines(ax))
    assert sum(t.startswith("q, θ") for t in texts) == ds.sizes["snapshot"]
    assert any(t.startswith("p") for t in texts)          # the pressure is named
    assert any("permanent stick radius" in t for t in texts)


def test_sphere_dissipation_density_curve_ends_at_zero_on_the_contact_edge(proportional):
    from slipcycle.plot.halfspace import dissipation_density

    ds = proportional.to_dataset()
    ax = dissipation_density(ds).axes[0]
    (curve,) = [ln for ln in ax.get_lines() if len(ln.get_xdata()) > 2]
    r, W = np.asarray(curve.get_xdata()) / 1e3, np.asarray(curve.get_ydata())
    a, _ = _hertz()
    assert W[-1] == 0.0
    assert r[-1] == pytest.approx(a, rel=0.01)
    np.testing.assert_array_equal(W[:-1], ds.dissipation_density.values)
    # the curve drawn carries the dissipation: ∫ W 2πr dr = ∮ Q dV (energy balance)
    D = float(ds.dissipation.values[-1])
    assert np.trapezoid(W * 2 * np.pi * r, r) == pytest.approx(D, rel=0.01)


# -- discrete two-node example ----------------------------------------------------------------


@pytest.fixture(scope="module")
def two_node():
    """The demo's two-node case: it shakes down, both nodes stuck in the last cycle, whose
    dissipation is the last creep of the approach (4.35e-9 J in the demo)."""
    return slipcycle.run(example_text("discrete_two_node"))


def test_two_node_hysteresis_titles_carry_each_nodes_dissipation_and_add_up_to_the_summary(
        two_node):
    import re

    from slipcycle.plot.discrete import hysteresis, scaled_unit

    ds = two_node.to_dataset()
    summary = two_node.summary()
    assert summary["permanently_stuck_nodes"] == [0, 1]
    D = np.asarray(ds["dissipation_per_node"])
    assert D.sum() == pytest.approx(summary["dissipation_per_cycle"], rel=1e-12)
    fig = hysteresis(ds)
    factor, unit = scaled_unit(D, "J")
    for j, ax in enumerate(fig.axes[:2]):
        value = re.search(r"D = ([-0-9.e+]+) (\S+)$", ax.get_title())
        assert value is not None and "≈" not in ax.get_title(), ax.get_title()
        assert value[2] == unit
        assert float(value[1]) * factor == pytest.approx(D[j], rel=5e-3)
        # stuck: no frame, no empty axes, the reason written instead of a loop
        assert not ax.axison and ax.get_lines() == []
        assert any("stuck" in t.get_text() and "tolerance" in t.get_text() for t in ax.texts)
    total = re.search(r"D = ([-0-9.e+]+) (\S+) in all", fig._suptitle.get_text())
    assert float(total[1]) * factor == pytest.approx(summary["dissipation_per_cycle"],
                                                     rel=5e-3)


def test_two_node_v_space_legend_names_only_constraint_lines_inside_a_panel(two_node):
    import re

    fig = two_node.to_outputs().figures["v_space"]()
    main = fig.axes[0]
    legend_texts = _legend_texts(main)
    named = [t for t in legend_texts if t.endswith(", extreme")]
    assert named, legend_texts
    for name in named:
        (line,) = [ln for ln in main.get_lines() if ln.get_label() == name]
        x, y = (np.asarray(d, float) for d in line.get_data())
        # the drawn line (a segment over the x range, or vertical) meets a panel's box
        seen = False
        for ax in fig.axes:
            (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
            xs = np.linspace(max(x.min(), x0), min(x.max(), x1), 200)
            if xs.size and x.max() > x.min():
                ys = np.interp(xs, x, y)
                seen |= bool(np.any((ys >= y0) & (ys <= y1)))
            else:
                seen |= bool(x0 <= x[0] <= x1)
        assert seen, f"{name} is in the legend but in neither panel"
    outside = {"I", "II", "III", "IV"} - {t.split()[0] for t in named}
    title = main.get_legend().get_title().get_text()
    for roman in outside:   # every constraint not drawn is still named, as out of view
        assert re.search(rf"(: |; ){roman} \(node", title), title


# -- bolted lap joint (the demo's size: coarse mesh, two protocols, one mesh) -----------------


@pytest.fixture(scope="module")
def lap_joint():
    import tomllib

    from slipcycle.api import apply_overrides, toml_text
    from slipcycle.demo import LAP_JOINT_DEMO

    text = toml_text(apply_overrides(tomllib.loads(example_text("bolted_lap_joint")),
                                     LAP_JOINT_DEMO))
    result = slipcycle.run(text)
    return result, result.to_outputs()


def _draw(fig):
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return canvas.get_renderer()


def test_lap_joint_protocol_figure_plots_the_differences_behind_orders_differ(lap_joint):
    result, out = lap_joint
    ds, s = out.dataset, out.summary
    fig = out.figures["dissipation_by_protocol"]()
    ax, axd = fig.axes[:2]
    d = np.asarray(ds["dissipation"], float)
    # the values, on an axis zoomed to them (bars from 0 would hide a 0.1 % spread)
    lo, hi = ax.get_ylim()
    assert lo > 0.9 * d.min() * 1e6 and hi < 1.1 * d.max() * 1e6
    # the differences from the reference protocol, in per mille, and the tolerance band
    (bars,) = axd.containers
    heights = np.array([b.get_height() for b in bars])
    np.testing.assert_allclose(heights, (d - d[0]) / d[0] * 1e3, rtol=1e-12, atol=1e-12)
    tol = s["difference_tol"]
    (band,) = [p for p in axd.patches if "difference_tol" in p.get_label()]
    assert band.get_y() == pytest.approx(-tol * 1e3)
    assert band.get_height() == pytest.approx(2 * tol * 1e3)
    texts = [t.get_text() for t in fig.legends[0].get_texts()]
    assert any(f"{tol:g}" in t for t in texts)
    # a spread beyond the band is what orders_differ says
    assert s["orders_differ"] == (np.ptp(d) / d.max() > tol)
    assert f"{s['dissipation_spread']:.3g}" in axd.get_title()
    # one mesh: no "finest mesh" legend
    assert ds.sizes["mesh"] == 1
    assert not any("finest" in t for t in texts)
    assert any("one mesh" in t for t in texts)


@pytest.mark.parametrize("name", ["slip_maps", "dissipation_maps"])
def test_lap_joint_interface_maps_outline_plates_holes_and_washers_and_fill_the_panel(
        lap_joint, name):
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Circle, Rectangle

    result, out = lap_joint
    ds = out.dataset
    desc = result.contact.description
    fig = out.figures[name]()
    c, w = desc["overlap_m"] * 1e3, desc["plate_width_m"] * 1e3
    centres = np.asarray(desc["bolt_centres_m"]) * 1e3
    maps = [ax for ax in fig.axes if ax.get_title().split(":")[0] in
            [str(p) for p in ds["protocol_name"].values]]
    assert len(maps) == ds.sizes["protocol"]
    for ax in maps:
        (rect,) = [p for p in ax.patches if isinstance(p, Rectangle)]
        assert rect.get_xy() == pytest.approx((-c / 2, -w / 2))
        assert (rect.get_width(), rect.get_height()) == pytest.approx((c, w))
        circles = [(p.center, p.radius) for p in ax.patches if isinstance(p, Circle)]
        for r in (desc["bolt_diameter_m"] / 2 * 1e3, desc["washer_diameter_m"] / 2 * 1e3):
            found = sorted(tuple(np.round(ctr, 9)) for ctr, rad in circles
                           if rad == pytest.approx(r))
            assert found == sorted(tuple(np.round(x, 9)) for x in centres), (r, found)
        # every node drawn as a disc of its area (not a fixed tiny marker) ...
        (nodes,) = [col for col in ax.collections if isinstance(col, PatchCollection)]
        assert len(nodes.get_paths()) == ds.sizes["node"]
        radii = np.array([np.ptp(path.vertices[:, 0]) / 2 for path in nodes.get_paths()])
        np.testing.assert_allclose(radii, 0.42 * np.sqrt(ds["node_area"].values) * 1e3,
                                   rtol=1e-6)
        # ... and the view is the joint, with no empty gap around it
        x0, x1 = ax.get_xlim()
        y0, y1 = ax.get_ylim()
        assert x0 >= -c / 2 * 1.1 and x1 <= c / 2 * 1.1
        assert y0 >= -w / 2 * 1.1 and y1 <= w / 2 * 1.1
    # the panel takes most of the figure width given to it (no large empty gap)
    renderer = _draw(fig)
    width = fig.get_window_extent(renderer).width
    used = sum(ax.get_window_extent(renderer).width for ax in fig.axes)
    assert used > 0.6 * width, used / width


def test_lap_joint_bolt_figure_keeps_its_legend_clear_of_the_bars(lap_joint):
    _, out = lap_joint
    fig = out.figures["dissipation_by_bolt"]()
    renderer = _draw(fig)
    legends = fig.legends + [ax.get_legend() for ax in fig.axes if ax.get_legend()]
    (legend,) = legends
    box = legend.get_window_extent(renderer)
    for bar in fig.axes[0].patches:
        assert not box.overlaps(bar.get_window_extent(renderer))


# -- two rods -----------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def rods():
    return slipcycle.run(example_text("rods_microslip"))


def test_rods_regularisation_left_panel_has_partial_slip_only_and_explains_each_entry(rods):
    import re

    reg = rods.analysis["reg"]
    fig = rods.to_outputs().figures["regularisation"]()
    ax1, ax2 = fig.axes
    series = [ln for ln in ax1.get_lines() if len(ln.get_xdata()) > 2]
    assert series
    for ln in series:
        x = np.asarray(ln.get_xdata(), float)
        assert x.max() < 1.0                 # no gross-slip point stacked at T* = T_g
        assert np.ptp(np.log(x)) > 0.01      # a curve, not a vertical smear
    texts = _legend_texts(ax1)
    assert sorted(texts) == sorted(_labelled_lines(ax1))
    assert all(":" in t for t in texts), texts           # every entry says what it is
    iwan = [t for t in texts if t.startswith("iwan")]
    slope = float(re.search(r"slope ([0-9.]+)", iwan[0])[1])
    assert slope == pytest.approx(reg["iwan"]["slope_microslip"], abs=0.005)
    # the models without microslip are named, not drawn as empty series
    note = " ".join(t.get_text() for t in ax1.texts)
    for m in ("jenkins", "coulomb"):
        assert m in note and not any(t.startswith(m) for t in texts)
    assert sorted(_legend_texts(ax2)) == sorted(_labelled_lines(ax2))


def test_rods_time_history_gives_a_constant_normal_force_no_panel_of_its_own(rods):
    ds = rods.to_dataset()
    assert np.ptp(ds.N.values) == 0.0
    fig = rods.to_outputs().figures["time_history"]()
    (ax,) = fig.axes
    assert "N = 10000 N (constant)" in ax.get_title()


def test_rods_time_history_draws_a_varying_normal_force():
    text = example_text("rods_microslip").replace("frequency_ratio = 0.3",
                                                  "frequency_ratio = 0.3\naxial_amplitude = 2e3")
    result = slipcycle.run(text)
    fig = result.to_outputs().figures["time_history"]()
    assert len(fig.axes) == 2
    (line,) = fig.axes[1].get_lines()
    np.testing.assert_array_equal(line.get_ydata(), result.to_dataset().N.values)


# -- sphere with out-of-phase loads: the steady loop is closed --------------------------------


@pytest.fixture(scope="module")
def out_of_phase():
    return slipcycle.run(example_text("halfspace_sphere_out_of_phase"))


def test_out_of_phase_sphere_tractions_name_each_distinct_pressure_once(out_of_phase):
    """P = P0 + P1 cos θ is equal at θ = π/2 and 3π/2: one dashed curve names both."""
    from slipcycle.plot.halfspace import tractions

    ds = out_of_phase.to_dataset()
    ax = tractions(ds).axes[0]
    texts = _legend_texts(ax)
    assert sorted(texts) == sorted(_labelled_lines(ax))
    pressures = [t for t in texts if t.startswith("p, ")]
    assert pressures == ["p, θ = 0.00 rad", "p, θ = 1.57, 4.71 rad", "p, θ = 3.14 rad"]
    dashed = [ln for ln in ax.get_lines() if ln.get_label().startswith("p, ")]
    for ln, k in zip(dashed, (0, 1, 2), strict=True):
        np.testing.assert_array_equal(ln.get_ydata(), ds.pressure.values[k] / 1e6)


def test_out_of_phase_sphere_hysteresis_loop_is_closed_and_encloses_the_dissipation(
        out_of_phase):
    result = out_of_phase
    ds = result.to_dataset()
    outputs = result.to_outputs()
    for name in ("hysteresis", "load_path"):
        ax = outputs.figures[name]().axes[0]
        (loop,) = [ln for ln in ax.get_lines() if ln.get_label() in ("last cycle",
                                                                     "periodic cycle")]
        x, y = (np.asarray(v, float) for v in loop.get_data())
        # drawn from the state at θ = 0 (the step before the cycle's first sample) to θ = 2π
        n = int(np.sum(ds.cycle.values == ds.sizes["cycle_run"] - 1))
        assert x.size == n + 1
        scale = np.ptp(x)
        assert abs(x[-1] - x[0]) <= 1e-6 * scale and abs(y[-1] - y[0]) <= 1e-6 * np.ptp(y)
    # the closed loop drawn encloses the cycle's dissipation ∮ Q dV
    x, y = (np.asarray(v, float) for v in [ln for ln in outputs.figures["hysteresis"]()
                                           .axes[0].get_lines()
                                           if ln.get_label() == "last cycle"][0].get_data())
    area = np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(x)) * 1e-6     # V drawn in µm
    assert area == pytest.approx(float(ds.dissipation.values[-1]), rel=1e-9)


@pytest.mark.parametrize("run", ["proportional", "out_of_phase", "two_node", "rods",
                                 "lap_joint"])
def test_every_figure_of_these_runs_lies_inside_its_canvas(request, run):
    """Legends placed outside the axes (tractions, the lap joint's maps and bars) are
    inside the figure, not cut off at its edge."""
    result = request.getfixturevalue(run)
    outputs = result[1] if isinstance(result, tuple) else result.to_outputs()
    for name, make in outputs.figures.items():
        fig = make()
        renderer = _draw(fig)
        box = fig.get_tightbbox(renderer)          # inches, the drawn artists
        width, height = fig.get_size_inches()
        assert box.x0 >= -0.01 and box.y0 >= -0.01, name
        assert box.x1 <= width + 0.01 and box.y1 <= height + 0.01, name



def test_one_node_3d_figures_draw_silently_with_quiet(tmp_path, run_cli):
    """A single node at the origin: its slip-direction arrows were scaled by the data
    extent (zero), and matplotlib printed a RuntimeWarning under -q."""
    import warnings

    case = tmp_path / "one.toml"
    case.write_text(ONE_NODE_3D.format(f=0.4))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        code, out, err = run_cli("-q", "run", case, "--out", tmp_path / "out")
    assert code == 0 and out == "" and err == ""
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)]
    assert (tmp_path / "out" / "figures" / "slip_directions.png").is_file()
