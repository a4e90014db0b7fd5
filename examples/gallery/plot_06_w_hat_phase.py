"""
Rough-contact dissipation against the phase (Barber 2012, Fig. 7)
=================================================================

Reproduces **Fig. 7** of Barber 2012 (§4.6; Putignano, Ciavarella & Barber 2011): the
dimensionless dissipation per cycle Ŵ = W/(λ γσ f² P0) of a nominally flat rough contact
(dP/dU = P/γσ, Akarapu et al. 2011) against the phase φ of the tangential load, for
P̂1 = P1/P0 = 0.4 and several Q̂1 = Q1/(f P0). For in-phase loading there is no
dissipation while Q̂1 < P̂1; otherwise the loss is largest near φ = ±π/2, and
Ŵ(φ) = Ŵ(φ + π) (Q0 = 0). Gaps are phases at which the load path reaches gross slip.
The second figure checks the small-amplitude law Ŵ ≈ (2/3) Q̂1³.

Computed with :func:`slipcycle.studies.w_hat_map.w_hat_map_study` (the engine of
``slipcycle map``) on a small grid: 4 × 37 points, 100 sliders.
Run time: about 3 s (docs build on a busy 2-core machine).
"""

# %%
import numpy as np

from slipcycle.studies.w_hat_map import w_hat_map_study

Q1_hat = np.array([0.2, 0.4, 0.6, 0.8])
phase = np.linspace(-np.pi, np.pi, 37)
study = w_hat_map_study(np.array([0.4]), Q1_hat, phase, 0.4, Q1_hat,
                        {"steps_per_cycle": 200, "n_sliders": 100})
print(study)
print(f"small-amplitude slope of log Ŵ against log Q̂1: {study.cubic_law_slope:.3f} (law: 3)")

figures = study.figures()
fig_phase = figures["w_hat_vs_phase"]()

# %%
fig_cubic = figures["w_hat_cubic_law"]()
