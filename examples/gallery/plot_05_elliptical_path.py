"""
Periodic elliptical load path, P_S and P_D (Barber 2012, Fig. 6)
================================================================

Reproduces **Fig. 6** of Barber 2012 (§4.3): under P = P0 + P1 cos θ,
Q = Q0 + Q1 cos(θ − φ) with a phase lag the load path is an ellipse, reached from the
unloaded state along an assembly segment OA. Where the normal load increases and
:math:`|dQ/dP| < f` the contact sticks everywhere; past the points C and E where
:math:`|dQ/dP| = f` a
microslip annulus grows from the edge (the stick zone is the contact area at the
fictitious load P_S of the Ciavarella–Jäger construction). The region that never slips
is the contact area at P_D; its tractions remember the assembly, but the dissipation does
not depend on it.

Steel sphere, P = 100 + 40 cos θ N, Q = 5 + 25 cos(θ − π/2) N, f = 0.5 (the shipped
``halfspace_sphere_out_of_phase`` case). Figures: the result's own ``figures()``; the
points where :math:`|dQ/dP| = f` along the ellipse, the stick load P_S of every state
(from the result's Dataset) and P_D (from the summary) are marked on the load path.
Run time: about 4 s (docs build on a busy 2-core machine).
"""

# %%
import numpy as np

import slipcycle

result = slipcycle.run(slipcycle.example_path("halfspace_sphere_out_of_phase"))
summary = result.summary()
print(result)
P_D = summary["permanent_stick_load"]
print(f"P_D = {P_D:.4g} N, permanent stick radius = {summary['permanent_stick_size']:.4g} m")

# %%
# The load path with the points where :math:`|dQ/dP| = f` and the load P_D
figures = result.figures()
fig_path = figures["load_path"]()
ax = fig_path.axes[0]
ds = result.to_dataset()
last = ds.cycle.values == ds.cycle.values.max()
P, Q = ds.P.values[last], ds.Q.values[last]
f = 0.5
excess = np.abs(np.gradient(Q)) - f * np.abs(np.gradient(P))   # > 0 where |dQ/dP| > f
for k in np.flatnonzero(np.diff(np.sign(excess)) != 0):
    ax.plot(P[k], Q[k], "ko", ms=4)
# at each state (P, Q) the stick zone is the contact area at P_S (dashed, same Q): P_S = P
# where the whole contact sticks, and its smallest value over the cycle is P_D
ax.plot(ds.stick_load.values[last], Q, color="C1", ls="--", lw=1,
        label="P_S at each state (stick zone = contact area at P_S)")
ax.axvline(P_D, color="C3", ls=":", label=f"P_D = {P_D:.3g} N (permanent stick)")
ax.plot([], [], "ko", ms=4, label="|dQ/dP| = f")
ax.legend(loc="lower left", fontsize=7)
ax.set_title("Elliptical periodic load path (Barber 2012, Fig. 6)", fontsize=10)
fig_path.tight_layout()

# %%
# The stick zone over the cycle: its minimum is the contact radius at P_D
fig_stick = figures["stick_zone"]()
fig_stick.axes[0].axhline(summary["permanent_stick_size"] * 1e3, color="C3", ls=":",
                          label="permanent stick radius a(P_D)")
fig_stick.axes[0].legend(fontsize=8)
fig_stick.tight_layout()

# %%
# Where the energy is dissipated: W(r) over the steady cycle
fig_density = figures["dissipation_density"]()
