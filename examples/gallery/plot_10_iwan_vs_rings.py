"""
What lumping the interface costs: rings, Iwan, Jenkins, Coulomb (beyond the papers)
====================================================================================

The rods study asks what regularising a frictional interface into one point costs
(§1.1 there). slipcycle answers it for the two-rod interface: the quasi-static
dissipation per cycle against the amplitude for the distributed interface (rings with
uniform pressure: slip starts at the rim at T_s = (3/4) T_g) and for lumped laws with the
same stiffness and capacity — a Jenkins element, a Coulomb slider and Segalman's
four-parameter Iwan element fitted to the rings (Iwan 1966; Segalman 2005). The rings
dissipate nothing below T_s and ∝ (T* − T_s)² above it; the Iwan element dissipates at
every amplitude (∝ T*^{3+χ}), Jenkins and Coulomb only in gross slip; beyond gross slip
every law gives D ≈ 4 T_g Θa (slope 1).

The shipped ``rods_spec`` case (equal steel rods); its run includes this study
(``[run] regularisation``). Run time: about 5 s (docs build on a busy 2-core machine).
"""

# %%
import slipcycle

result = slipcycle.run(slipcycle.example_path("rods_spec"))
regularisation = result.summary()["regularisation"]
for law in ("distributed", "iwan", "jenkins", "coulomb"):
    print(f"{law:12s} microslip slope {regularisation[law]['slope_microslip']}, "
          f"macroslip slope {regularisation[law]['slope_macroslip']}")
print("fitted Iwan chi:", round(regularisation["iwan_fit"]["chi"], 3))
fig = result.figures()["regularisation"]()
