"""
The Cattaneo–Mindlin problem: load path and tractions (Barber 2012, Figs. 4–5)
==============================================================================

Reproduces **Figs. 4 and 5** of Barber 2012 (§4.1): a Hertzian sphere is pressed by a
normal force P, which is then held constant while a tangential force Q is applied
(Cattaneo 1938; Mindlin 1949). The load path runs inside the cone :math:`|Q| < fP` beyond which
gross slip would occur, and the fictitious load P_S = P − Q/f is found by the
construction of Fig. 5: the line of slope f through the current state meets the P axis at
P_S. The shear traction is then q = f p − f p_S (eq. 5): the contact sticks inside the
contact area of P_S and slips in the annulus outside it. The tangential load then
oscillates between ±Q* (Mindlin & Deresiewicz 1953), which gives the hysteresis loop.

Steel sphere R = 10 mm, P = 100 N, f = 0.5, Q* = 30 N (the shipped ``halfspace_sphere``
case, assembled along the Cattaneo path: P first, then Q). Figures: the result's own
``figures()``; the P_S construction is drawn on the load path.
Run time: about 3 s (docs build on a busy 2-core machine).
"""

# %%
import numpy as np

import slipcycle
from slipcycle.halfspace import ContactElasticity, HalfspaceModel, sphere

steel = ContactElasticity.from_materials((200e9, 200e9), (0.3, 0.3), plane=False)
P, f, Q_star = 100.0, 0.5, 30.0
model = HalfspaceModel.harmonic(
    sphere(0.01, steel.contact_modulus), f, steel.compliance_ratio, P0=P, Q1=Q_star,
    elasticity=steel, protocol=np.array([[P, 0.0]]),      # P first, then Q (Cattaneo)
    max_cycles=3, steps_per_cycle=400)
result = slipcycle.run(model)                 # a model object runs like a case file
print(result)
summary = result.summary()
print("stick radius at Q = Q*:", summary["permanent_stick_size"], "m;",
      "contact radius:", summary["contact_size_max"], "m")

# %%
# Load path (Fig. 5) with the construction of P_S = P − Q*/f
figures = result.figures()
fig_path = figures["load_path"]()
ax = fig_path.axes[0]
P_S = P - Q_star / f
ax.plot([P_S, P], [0.0, Q_star], "k--", lw=1, label=f"slope f: P_S = P − Q/f = {P_S:g} N")
ax.plot([P_S], [0.0], "ko", ms=4)
ax.legend(loc="upper left", fontsize=8)
ax.set_title("Cattaneo–Mindlin load path (Barber 2012, Fig. 5)", fontsize=10)
fig_path.tight_layout()

# %%
# Tractions: at θ = 0 (Q = +Q*) the shear traction is f p − f p_S (eq. 5)
fig_tractions = figures["tractions"]()

# %%
# The steady hysteresis loop between ±Q*
fig_loop = figures["hysteresis"]()
