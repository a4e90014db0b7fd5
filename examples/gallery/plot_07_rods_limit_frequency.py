"""
Rods: torque ratio and the limit of the quasi-static analysis
=============================================================

Reproduces the central result of the rods study (two coaxial rods end to end with a
frictional interface, rod 1 clamped, rod 2 twisted and pressed): the ratio of the maximum
interfacial torque of the dynamic solution to that of the quasi-static one,
T_Dmax/T_QSmax, against the frequency ratio Ω/ω1, and the **limit frequency** below which
the quasi-static answer is within 5 %; then the **regime map** over frequency and drive
amplitude Θa/Θg (stiffness-dominated below the ±5 % contour, inertia-dominated above;
dashed lines: resonances of the stuck system). The dissipation ratio D_dyn/D_qs is far
more sensitive to inertia than the peak torque.

Equal steel rods, distributed (microslip) interface, the shipped ``rods_limits_equal``
case on a coarse grid (20 frequencies, 6 amplitudes, 20 modes per rod instead of 50).
With the case's own settings ``slipcycle limits`` gives the limit frequency ratios 0.338
(torque) and 0.070 (dissipation). Run time: about 11 s (docs build on a busy 2-core machine).
"""

# %%
import slipcycle
from slipcycle.io import parse_case_text
from slipcycle.studies.limits import limits_study, parse_limits

text = slipcycle.example_path("rods_limits_equal").read_text()
coarse = (text
          .replace("num = 40}", "num = 20}")
          .replace("amplitude_ratio = {start = 0.3, stop = 3.0, num = 20}",
                   "amplitude_ratio = {start = 0.4, stop = 2.0, num = 6}\n"
                   "position = [0.3, 0.5, 0.7]\nposition_frequencies = 6")
          .replace("modes = 50", "modes = 20"))
study = limits_study(parse_limits(parse_case_text(coarse), tolerance=0.05))
print(study)

figures = study.figures()
fig_ratio = figures["limit_frequency"]()

# %%
fig_regimes = figures["regime_map"]()

# %%
# The same ratios over the position of the interface along the rods
fig_position = figures["position_map"]()
