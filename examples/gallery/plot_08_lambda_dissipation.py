"""
λ1 … λ4 on the dissipation curve (beyond the source papers)
===========================================================

Barber 2012 (§3.2) describes four load factors in words: below λ1 every initial condition
shakes down; between λ1 and λ2 the outcome depends on it; above λ2 shakedown is
impossible but the steady dissipation still depends on the initial condition while some
node stays stuck; above λ3 every node slips in every cycle and the steady state is unique;
above λ4 the memory is erased at one instant of every cycle. slipcycle **computes** them:
λ1 and λ2 by linear programs on the safe region S(λ), λ3 and λ4 as brackets from
simulations over λ and random initial conditions, refined by bisection
(:func:`slipcycle.studies.shakedown.shakedown_study`, the engine of
``slipcycle shakedown``).

The triangle example (``shakedown_triangle``): λ1 = 0.946, λ2 = 1.104. The first figure
shows the steady dissipation per cycle from every start against λ, coloured by the steady
state; the second the safe region and trajectories below λ1, between λ1 and λ2 and above
λ2 (Barber's Figs. 1–3 in one row). 15 values of λ × 4 starts.
Run time: about 17 s (docs build on a busy 2-core machine).
"""

# %%
import tempfile

import slipcycle
from slipcycle.io import read_case
from slipcycle.studies.shakedown import shakedown_study

with tempfile.TemporaryDirectory() as work:              # scan store and checkpoint
    study = shakedown_study(read_case(slipcycle.example_path("shakedown_triangle")), work,
                            lam_points=15, starts=3, lam_tol=2e-2, workers=1,
                            progress=False).result
print(study)
print("lambda1 =", round(study.lambda1, 4), " lambda2 =", round(study.lambda2, 4))
print("lambda3 in", study.lambda3_bracket, " lambda4 in", study.lambda4_bracket)

figures = study.figures()
fig_lambda = figures["dissipation_vs_lambda"]()

# %%
fig_panels = figures["safe_region_panels"]()
