"""
Attraction to a unique periodic orbit (Barber 2012, Fig. 3)
===========================================================

Reproduces **Fig. 3** of Barber 2012: when every node slips at some time during the cycle
but not all at the same time, the memory stored in the stuck nodes is exchanged between
them every cycle and degrades, so trajectories from distinct starts A and B are
attracted to one rectangular periodic orbit (Barber 2012, §3.1). For the coupled
two-node system shipped as ``discrete_two_node`` (out-of-phase loads) both nodes slip in
every cycle at λ = 1.4: two admissible starts converge, over six cycles, to the same
orbit with the same dissipation per cycle (to round-off).

Panel by :func:`slipcycle.plot.shakedown.safe_region_panels` (constraints at their
extreme positions; above λ2 there is no safe region).
Run time: about 7 s (docs build on a busy 2-core machine).
"""

# %%
import numpy as np

import slipcycle
from slipcycle.discrete import simulate
from slipcycle.discrete.shakedown import lambda1, lambda2, safe_region, sample_initial_slips
from slipcycle.plot.shakedown import safe_region_panels

case = slipcycle.run(slipcycle.example_path("discrete_two_node")).case
region = safe_region(case.system, case.load)
l2 = lambda2(region)[0]
l1 = lambda1(region, l2)["lambda1"]

lam = 1.4
load = case.load.with_lam(lam)
starts = sample_initial_slips(case.system, load, 2, seed=3)     # A and B
trajectories, dissipation = [], []
for v0 in starts:
    run = simulate(case.system, load, initial_slip=v0, cycles=60, steps_per_cycle=200)
    trajectories.append((np.vstack([v0[None], run.x[:, :, :2].reshape(-1, 2)]),
                         run.steady_state))
    dissipation.append(run.dissipation_per_cycle)
    print(f"start {np.round(v0, 3)}: {run.steady_state} after {run.cycles_run} cycles, "
          f"slipping nodes {run.slipping_nodes}, D = {run.dissipation_per_cycle:.6g} J")
print("relative difference of the two steady dissipations:",
      abs(dissipation[0] - dissipation[1]) / dissipation[0])

fig = safe_region_panels(region, [{"lam": lam, "trajectories": trajectories}], l1, l2)
