"""A coupled two-node frictional system from Python (J. R. Barber, "Frictional systems
under periodic loads — history-dependence, non-uniqueness and energy dissipation",
J. Phys.: Conf. Ser. 382 (2012) 012002).

Run as a script or cell by cell (``# %%``). Figures go to ``$SLIPCYCLE_EXAMPLES_OUT``
(default: a new temporary directory).
"""

# %% Build the system (reduced stiffness A, B, C in N/m) and its periodic loads (N)
import os
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from slipcycle.discrete import (  # noqa: E402
    DiscreteLoad,
    FrictionalSystem,
    critical_friction,
    simulate,  # noqa: E402
)

out = os.environ.get("SLIPCYCLE_EXAMPLES_OUT") or tempfile.mkdtemp(prefix="slipcycle-")
os.makedirs(out, exist_ok=True)

A = [[1.0, -0.3], [-0.3, 0.8]]
B = [[0.4, 0.1], [-0.2, 0.3]]
C = [[1.0, -0.2], [-0.2, 1.0]]
# accept_ill_posed=False: refuse f >= f_crit (Klarbring 1990) at construction
system = FrictionalSystem(A, B, C, 0.5, accept_ill_posed=False)
# p^w = p0 + p1 cos(θ + p1_phase), q^w likewise, per node
load = DiscreteLoad.harmonic(p0=[1.0, 1.0], q0=[0.0, 0.0], p1=[0.3, 0.2], q1=[0.4, 0.5],
                             p1_phase=[0.0, 1.0], q1_phase=[0.5, 2.0])

# %% Run to the steady state
res = simulate(system, load, cycles=40, steps_per_cycle=400)
fc = critical_friction(system.A, system.B, system.friction)
print(f"f_crit = {fc.f_crit:.10g}")
print(f"steady_state = {res.steady_state}")
print(f"cycles_run = {res.cycles_run}")
print(f"dissipation_per_cycle = {res.dissipation_per_cycle:.10g} J")

# %% Plot slip and tangential reaction of each node over the last cycle
n = system.n_nodes
fig, axes = plt.subplots(1, 2, figsize=(9, 3.5))
for j in range(n):
    axes[0].plot(res.theta, res.x[-1, :, j], label=f"node {j}")
    axes[1].plot(res.x[-1, :, j], res.r[-1, :, j], label=f"node {j}")
axes[0].set_xlabel("θ (rad)")
axes[0].set_ylabel("slip v (m)")
axes[1].set_xlabel("slip v (m)")
axes[1].set_ylabel("tangential reaction q (N)")
axes[0].legend()
fig.suptitle(f"{res.steady_state}: D = {res.dissipation_per_cycle:.3g} J per cycle")
fig.tight_layout()
fig.savefig(os.path.join(out, "discrete_last_cycle.png"), dpi=100)
plt.close(fig)
print(f"figures in {out}")
