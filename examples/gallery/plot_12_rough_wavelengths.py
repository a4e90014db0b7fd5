"""
Which wavelengths of a rough surface matter for microslip dissipation
=====================================================================

Barber 2012 (§4.6) argues that every engineering contact is incomplete because of
roughness, that the incremental normal stiffness of a rough interface is roughly
proportional to the load, and that only the long-wavelength terms of the surface profile
spectrum matter for the dissipation. This example puts the claim to a quantitative test
with slipcycle's roughness study (the engine of ``slipcycle roughness``) on the shipped
self-affine surface ``rough_surface.nc`` (1 mm², rms 1 µm), at a coarser BEM grid than the
shipped case so that the page builds in seconds:

1. the normal law P(U) of the nominally flat contact by the boundary-element solver of
   ContactMechanics, with the local γσ = dU/d ln P and the load range over which the
   exponential law holds;
2. the dissipation per cycle and the incremental stiffness after removing wavelengths
   below a cut-off λ_s (and, separately, above λ_l);
3. the dissipation against the phase of the tangential load;
4. the local fretting map of a flat circular punch of the same nominal area: each ring is
   a small rough contact under its own load cycle; the smooth punch sticks completely and
   dissipates nothing.

Needs the ``topo`` extra. Run time: about 20–40 s (first run; the BEM laws are cached).
"""

# %%
import slipcycle
from slipcycle.io import read_case
from slipcycle.studies.roughness import parse_roughness_case, roughness_study

case = read_case(slipcycle.example_path("halfspace_topography"), models=["halfspace"])
# a coarser study than the shipped case: BEM grid 64, two grids and slider counts
case.data["halfspace"]["bem_grid"] = 64
case.data["run"]["sliders"] = 200
case.data["roughness"].update(
    {"grids": [32, 64], "sliders": [100, 200],
     "phases": {"start": -3.141592653589793, "stop": 3.141592653589793, "num": 5},
     "rings": 8})
model, source, settings = parse_roughness_case(case)
study = roughness_study(model, source, settings)
print(study)

figures = study.figures()
fig_law = figures["normal_law"]()

# %%
fig_cutoff = figures["cutoff_study"]()

# %%
fig_phase = figures["dissipation_vs_phase"]()

# %%
fig_map = figures["fretting_map"]()
