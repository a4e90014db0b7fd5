"""
Constraints moving in slip space (Barber 2012, Fig. 1)
======================================================

Reproduces **Fig. 1** of J. R. Barber, *Frictional systems under periodic loads*,
J. Phys.: Conf. Ser. 382 (2012) 012002: with both nodes of a two-node system in contact,
each Coulomb inequality excludes the half-plane on one side of a line in (v₀, v₁), and
the lines translate, at fixed slopes, as the loads vary. A constraint that reaches the
state P pushes it along one axis only: IV (node 1, q = −fp) pushes P up (v̇₁ > 0), III
down, II right and I left (Barber's eqs. 3–4; nodes numbered from 0).

The system is the coupled two-node system of Ahn, Bertocchi & Barber (2008) shipped as
``discrete_triangle_protocol``, started from the slip state (−0.518, 0.528): node 1 then
slips every cycle while node 0 stays stuck. Each panel draws the four constraints at one
instant of the steady cycle (shaded: the states admissible at that instant), zoomed on
the steady orbit, with the state P at that instant (◆): the state moves vertically only,
pushed up by IV and down by III. Run time: about 4 s (docs build on a busy 2-core machine).
"""

# %%
# Run the example from the given initial slip (the Python API, no case file edits)
import numpy as np

import slipcycle
from slipcycle.discrete import simulate
from slipcycle.discrete.shakedown import admissible_region_at, safe_vertices
from slipcycle.plot.discrete import v_space

case = slipcycle.run(slipcycle.example_path("discrete_triangle_protocol")).case
system, load = case.system, case.load
run = simulate(system, load, initial_slip=np.array([-0.518, 0.528]), cycles=60,
               steps_per_cycle=200)
print(run.steady_state, "slipping nodes:", run.slipping_nodes,
      "permanently stuck:", run.permanently_stuck_nodes)

# %%
# The constraints at an instant where node 1 slips forward (IV active) ...
modes = run.modes[-1]                       # 0 stick, 1 slip +, 2 slip −, 3 separated
k_up = int(np.flatnonzero(modes[:, 1] == 1)[len(np.flatnonzero(modes[:, 1] == 1)) // 2])
k_down = int(np.flatnonzero(modes[:, 1] == 2)[len(np.flatnonzero(modes[:, 1] == 2)) // 2])


def constraints_at(theta):
    """The four constraint lines at one instant, in the {v : G v ≥ h} form of v_space."""
    G, b = admissible_region_at(system, load, theta)
    return -G, -b, safe_vertices(-G, -b)


def instant(k, title):
    """v_space at sample k of the last cycle, zoomed on the steady orbit, with P marked."""
    fig = v_space(run, *constraints_at(run.theta[k]))
    ax = fig.axes[0]
    for text in ax.get_legend().get_texts():    # these are positions now, not extremes
        text.set_text(text.get_text().replace(", extreme", ", now")
                      .replace("safe shakedown region", "admissible at this instant"))
    orbit = run.x[-1, :, :2]
    centre, half = orbit.mean(axis=0), 2.5 * np.ptp(orbit, axis=0).max()
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.plot(*orbit[k], "D", color="C4", ms=7, zorder=5)
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return fig


fig_iv = instant(k_up, f"θ = {run.theta[k_up]:.2f} rad: IV advances and pushes P (◆) up")

# %%
# ... and half a cycle later, where III pushes it back down
fig_iii = instant(k_down, f"θ = {run.theta[k_down]:.2f} rad: III advances and pushes P (◆) "
                  "down")
