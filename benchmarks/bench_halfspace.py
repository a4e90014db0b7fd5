"""Half-space benchmarks: slider updates per second, the Ŵ map, optional Tamaas comparison.

Targets (issue 2, this 2-core machine): ≥ 2·10⁷ slider-updates/s per core at 10⁵ sliders in
tangential force control; the 50 × 50 × 36 Ŵ map in under 60 s.
"""

from __future__ import annotations

import time

import numpy as np

from slipcycle.halfspace import ContactElasticity, make_bed, run_history, sphere
from slipcycle.halfspace.kernels import drive
from slipcycle.halfspace.wmap import w_hat_map


def _updates_per_second(n: int, steps: int = 200) -> tuple[float, float]:
    el = ContactElasticity.from_materials((200e9, 200e9), (0.3, 0.3), plane=False)
    bed = make_bed(sphere(0.01, el.contact_modulus), friction=0.5,
                   compliance_ratio=el.compliance_ratio, P_max=140.0, n_sliders=n)
    th = 2 * np.pi * np.arange(1, steps + 1) / steps
    U = bed.approach(100 + 40 * np.cos(th))
    Q = 30 * np.sin(th)
    t, z, d = np.zeros(bed.size), np.zeros(bed.size), np.zeros(bed.size)
    args = (bed.level, bed.normal_stiffness, bed.tangential_stiffness, 0.5)
    idx, rec = np.empty(0, np.int64), np.empty((0, bed.size))
    out = np.empty(steps), np.empty(steps), np.empty(steps, np.int64)
    drive(t, z, d, *args, U, Q, True, 0.0, idx, rec, rec, *out)   # compile + warm cycle
    reps = max(1, int(2e7 // (n * steps)))
    t0 = time.perf_counter()
    passes = 0
    for _ in range(reps):
        _, p = drive(t, z, d, *args, U, Q, True, 0.0, idx, rec, rec, *out)
        passes += p
    dt = time.perf_counter() - t0
    return bed.size * steps * reps / dt, passes / (steps * reps)


def _tamaas_row():
    """First monotonic Cattaneo load: slipcycle vs Tamaas' PolonskyKeerTan (256² grid).

    Tamaas solves the boundary-element problem for one load state and keeps no load
    history, so only this first loading compares. Skipped when Tamaas is not installed.
    """
    try:
        import tamaas as tm
    except ImportError:
        return [{"name": "Tamaas PolonskyKeerTan 256² Cattaneo (not installed: skipped)",
                 "value": float("nan"), "unit": "s"}]
    tm.set_log_level(tm.LogLevel.warning)  # keep its iteration log out of the table
    N, L, R, E, nu, f, ratio = 256, 1.0, 2.0, 1.0, 0.3, 0.5, 0.5
    pbar = 2e-4                                    # mean pressure over the periodic cell
    model = tm.ModelFactory.createModel(tm.model_type.surface_2d, [L, L], [N, N])
    model.E, model.nu = E, nu
    x = np.linspace(0, L, N, endpoint=False) - L / 2
    X, Y = np.meshgrid(x, x, indexing="ij")
    solver = tm.PolonskyKeerTan(model, -(X**2 + Y**2) / (2 * R), 1e-8, f)
    t0 = time.perf_counter()
    solver.solve([ratio * f * pbar, 0.0, pbar])
    t_tm = time.perf_counter() - t0
    tr = model.traction
    p, q = tr[..., 2], np.hypot(tr[..., 0], tr[..., 1])
    contact = p > 0
    stuck = contact & (q < f * p * (1 - 1e-3))
    area = (L / N) ** 2
    c_tm = np.sqrt(stuck.sum() * area / np.pi)
    a_tm = np.sqrt(contact.sum() * area / np.pi)
    # slipcycle: same sphere, same loads (E* of Tamaas' single deformable body)
    e_star = E / (1 - nu**2)
    el = ContactElasticity(e_star, (2 - nu) / (2 * (1 - nu)))
    P = pbar * L * L
    t0 = time.perf_counter()
    bed = make_bed(sphere(R, e_star), friction=f, compliance_ratio=el.compliance_ratio,
                   P_max=P, n_sliders=4000)
    res = run_history(bed, np.concatenate([np.linspace(0, P, 51)[1:], np.full(200, P)]),
                      np.concatenate([np.zeros(50), np.linspace(0, ratio * f * P, 201)[1:]]),
                      np.full(2, P), np.full(2, ratio * f * P), max_cycles=1)
    c_sc = float(bed.stick_extent(np.array([res.first_slip[249]]))[1][0])
    t_sc = time.perf_counter() - t0
    a = float(sphere(R, e_star).contact_size(P))
    exact = (1 - ratio) ** (1 / 3)
    return [
        {"name": f"Cattaneo c/a, Q/fP = {ratio}: closed form", "value": exact, "unit": "1"},
        {"name": "Cattaneo c/a: slipcycle (4000 sliders)", "value": c_sc / a, "unit": "1"},
        {"name": "Cattaneo c/a: Tamaas PolonskyKeerTan 256²", "value": c_tm / a_tm, "unit": "1"},
        {"name": "Cattaneo first load: slipcycle time", "value": t_sc, "unit": "s"},
        {"name": "Cattaneo first load: Tamaas time", "value": t_tm, "unit": "s"},
    ]


def benchmarks() -> list[dict]:
    rows = []
    for n in (1_000, 10_000, 100_000, 1_000_000):
        rate, passes = _updates_per_second(n)
        row = {"name": f"slider updates/s, force control, n = {n:,} ({passes:.1f} sweeps/step)",
               "value": rate, "unit": "updates/s"}
        if n == 100_000:
            row.update(target=">= 2e7", ok=rate >= 2e7)
        rows.append(row)
    # single Mindlin run end-to-end (bed + history), 2000 sliders, 400 steps x cycles
    el = ContactElasticity.from_materials((200e9, 200e9), (0.3, 0.3), plane=False)
    prof = sphere(0.01, el.contact_modulus)
    t0 = time.perf_counter()
    bed = make_bed(prof, friction=0.5, compliance_ratio=el.compliance_ratio, P_max=100.0,
                   n_sliders=2000)
    th = 2 * np.pi * np.arange(1, 401) / 400
    run_history(bed, np.linspace(0, 100, 101)[1:], np.zeros(100), np.full(400, 100.0),
                30 * np.sin(th), max_cycles=5)
    rows.append({"name": "Mindlin sphere run (2000 sliders, 400 steps/cycle)",
                 "value": (time.perf_counter() - t0) * 1e3, "unit": "ms"})
    w_hat_map([0.4], [0.5], [1.0])  # compile
    t0 = time.perf_counter()
    W = w_hat_map(np.linspace(0, 0.9, 50), np.linspace(0.01, 0.99, 50),
                  np.linspace(-np.pi, np.pi, 36))
    dt = time.perf_counter() - t0
    rows.append({"name": f"W_hat map 50x50x36 ({np.isnan(W).mean():.0%} gross slip)",
                 "value": dt, "unit": "s", "target": "< 60", "ok": dt < 60})
    rows += _tamaas_row()
    return rows
