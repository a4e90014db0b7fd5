"""
Triangular safe region and a cyclic-slip orbit (Barber 2012, Fig. 2)
=====================================================================

Reproduces **Fig. 2** of Barber 2012: the four constraints at their *extreme* positions
I^E … IV^E (the positions that exclude most of the slip space; they are
not reached at the same instant) bound the safe shakedown region, here a **triangle**
because one constraint is inactive (Ahn, Bertocchi & Barber 2008). Started inside the
triangle the system shakes down; started elsewhere it can oscillate along a segment
P₁P₂ for ever, node 1 slipping every cycle, because the constraint that would push it
into the triangle never advances far enough.

Two runs of the same system and loads (``discrete_triangle_protocol``, λ = 1 between
λ1 = 0.946 and λ2 = 1.104): the shipped assembly protocol (clamp node 1 while node 0 is
sheared, then clamp node 0) shakes down; the initial slip (−0.518, 0.528) ends in cyclic
slip of node 1. Figures: the result's own ``figures()["v_space"]``.
Run time: about 4 s (docs build on a busy 2-core machine).
"""

# %%
import numpy as np

import slipcycle
from slipcycle.discrete import simulate
from slipcycle.discrete.shakedown import extreme_constraints, safe_vertices
from slipcycle.plot.discrete import v_space

assembled = slipcycle.run(slipcycle.example_path("discrete_triangle_protocol"))
print(assembled)
fig_shakedown = assembled.figures()["v_space"]()

# %%
# The same system from another initial condition: cyclic slip along P1P2
system, load = assembled.case.system, assembled.case.load
cyclic = simulate(system, load, initial_slip=np.array([-0.518, 0.528]), cycles=60,
                  steps_per_cycle=200)
G, h = extreme_constraints(system, load)
fig_cyclic = v_space(cyclic, G, h, safe_vertices(G, h))
print(cyclic.steady_state, "dissipation per cycle:", cyclic.dissipation_per_cycle, "J")
