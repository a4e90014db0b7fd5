"""
Where the local dissipation peaks: three quarters across the slip annulus
=========================================================================

Barber 2012 (§4.5) states that for a Hertzian contact the local dissipation density W(r)
peaks "about half way between the edge of the contact area and the edge of the permanent
stick zone". The Mindlin–Deresiewicz solution says otherwise. With the Ciavarella–Jäger
superposition, W(r) = 4 λ f² p(r) h_c(r), h_c the gap outside a Hertz contact of the stick
radius c, and dW/dr = 0 puts the peak at the fraction ξ = (r* − c)/(a − c) of the slip
annulus with **3/4 ≤ ξ ≤ 0.816**: exactly 3/4 for a thin annulus (W ∝ (r − c)^{3/2}
(a − r)^{1/2}), rising to r* = √(2/3) a as Q* → fP (derivation: theory page
*Half-space microslip*, section "Where the local dissipation peaks").

First figure: W(r) of slipcycle's slider bed for a steel sphere, P = 100 N, f = 0.5,
Q = ±30 N (Q*/fP = 0.6; the result's own ``figures()["dissipation_density"]``), with the
stick radius c, the half-way point and the closed-form peak. Second: the peak position
from the solver for several Q*/fP against the closed form
(``tests/test_docs_dissipation_peak.py`` checks it over 0.02 … 0.98).
Run time: about 20 s (docs build on a busy 2-core machine).
"""

# %%
import numpy as np
from matplotlib.figure import Figure
from scipy.optimize import brentq

import slipcycle
from slipcycle.halfspace import ContactElasticity, HalfspaceModel, solve, sphere
from slipcycle.halfspace.tractions import abel_operators, dissipation_density


def closed_form_peak(load_ratio):
    """Peak radius r*/a of W(r): the root of the condition derived on the theory page."""
    g = (1 - load_ratio) ** (1 / 3)                       # c/a (Cattaneo)

    def condition(rho):
        s = np.sqrt(rho**2 - g**2)
        return (g * s * (3 * rho**2 - 2)
                + rho**2 * (3 * rho**2 - 2 - 2 * g**2) * np.arccos(g / rho))

    return g, brentq(condition, g * (1 + 1e-12), 1.0)


result = slipcycle.run(slipcycle.example_path("halfspace_sphere"))   # Q*/fP = 0.6
summary = result.summary()
a, c = summary["contact_size_max"], summary["permanent_stick_size"]
g, rho = closed_form_peak(0.6)
fig_density = result.figures()["dissipation_density"]()
ax = fig_density.axes[0]
ax.axvline((c + a) / 2 * 1e3, color="0.5", ls="--", label="half way between c and a")
ax.axvline(rho * a * 1e3, color="k", ls="-", lw=0.8,
           label=f"closed-form peak, ξ = {(rho - g) / (1 - g):.3f} of the annulus")
ax.axvline(a * 1e3, color="0.4", ls="-.", label="contact radius a")
ax.set_xlim(0.6 * a * 1e3, 1.02 * a * 1e3)
ax.legend(fontsize=7, loc="upper left")

# %%
# The peak position over the load ratio: slipcycle's W(r) on 3000 radii against the root
steel = ContactElasticity.from_materials((200e9, 200e9), (0.3, 0.3), plane=False)
ratios = np.array([0.05, 0.3, 0.6, 0.85, 0.97])
measured = []
for x in ratios:
    model = HalfspaceModel.harmonic(sphere(0.01, steel.contact_modulus), 0.5,
                                    steel.compliance_ratio, P0=100.0, Q1=x * 0.5 * 100.0,
                                    elasticity=steel, max_cycles=3, steps_per_cycle=64)
    bed, history = solve(model)
    ops = abel_operators(bed, n_radii=3000)
    W = dissipation_density(ops, history.last_t, history.last_z)
    r = ops.radius / float(model.profile.contact_size(100.0))
    g, _ = closed_form_peak(x)
    measured.append((r[np.argmax(W)] - g) / (1 - g))
xs = np.linspace(0.001, 0.999, 100)
closed = [(rho - g) / (1 - g) for g, rho in map(closed_form_peak, xs)]

fig_fraction = Figure(figsize=(6.0, 4.0))
ax = fig_fraction.subplots()
ax.plot(xs, closed, "k-", label="closed form (Mindlin–Deresiewicz)")
ax.plot(ratios, measured, "o", color="C3", label="slipcycle W(r), largest sample")
ax.axhline(0.5, color="0.5", ls="--", label="half way (Barber 2012, §4.5)")
ax.set_xlabel("Q* / fP")
ax.set_ylabel("peak position ξ = (r* − c)/(a − c)")
ax.set_ylim(0.4, 0.9)
ax.grid(alpha=0.3)
ax.legend(fontsize=8)
fig_fraction.tight_layout()
