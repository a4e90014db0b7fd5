"""
Basins of attraction (beyond the source papers)
===============================================

Between λ1 and λ2 the steady state of a coupled system depends on the initial condition
(Barber 2012, §3; Ahn, Bertocchi & Barber 2008) — physically on the assembly protocol,
e.g. the order in which bolts are tightened. slipcycle maps it: a grid of initial slip
states (v₀, v₁) at θ = 0, each run to its steady state
(:func:`slipcycle.studies.basins.basins_study`, the engine of ``slipcycle basins``).
Left: the steady state reached from each start (grey: starts that violate a friction
limit at θ = 0); right: the steady dissipation per cycle; outlined: the safe region S(λ).
Starts inside S(λ) shake down, others end in cyclic slip of node 1 with a dissipation
that depends on the start. The box-counting dimension of the class boundary is reported:
the boundary here is a smooth curve (dimension 1), which a coarse grid overestimates; a
fractal boundary, as Andersson, Barber & Ahn (2013) describe near unstable orbits, would
keep a value above 1 as the grid is refined.

The triangle example at λ = 1, a 41 × 41 grid.
Run time: about 8 s (docs build on a busy 2-core machine).
"""

# %%
import tempfile

import slipcycle
from slipcycle.io import read_case
from slipcycle.studies.basins import basins_study

with tempfile.TemporaryDirectory() as work:              # the store of the runs
    basins = basins_study(read_case(slipcycle.example_path("shakedown_triangle")), work,
                          grid=41, workers=1, progress=False).result
print(basins)
print("box-counting dimension of the class boundary:",
      round(basins.summary()["boundary_box_counting_dimension"], 2))
fig = basins.figures()["basin_map"]()
