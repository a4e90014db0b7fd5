"""Half-space microslip from Python: a steel sphere on a steel flat under an oscillating
tangential load (Cattaneo–Mindlin; Ciavarella 1998 and Jäger 1998 for general histories).

Run as a script (``python examples/python_halfspace.py``) or cell by cell (``# %%``).
Figures go to ``$SLIPCYCLE_EXAMPLES_OUT`` (default: a new temporary directory).
"""

# %% Build the model: profile, elasticity, loads — no case file
import os
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from slipcycle.halfspace import ContactElasticity, HalfspaceModel, solve, sphere  # noqa: E402

out = os.environ.get("SLIPCYCLE_EXAMPLES_OUT") or tempfile.mkdtemp(prefix="slipcycle-")
os.makedirs(out, exist_ok=True)

elasticity = ContactElasticity.from_materials((200e9, 200e9), (0.3, 0.3), plane=False)
model = HalfspaceModel.harmonic(
    sphere(0.01, elasticity.contact_modulus),      # radius 10 mm
    0.5, elasticity.compliance_ratio,              # friction f, compliance ratio λ_c
    P0=100.0, Q1=30.0,                             # P = 100 N, Q = 30 cos θ N
    elasticity=elasticity, max_cycles=3, steps_per_cycle=400)

# %% Solve: assembly, then cycles to the steady state
bed, result = solve(model)
W = float(result.dissipation_per_cycle)
print(f"contact_modulus = {elasticity.contact_modulus:.6g} Pa")
print(f"dissipation_per_cycle = {W:.10g} J")
print(f"steady = {bool(result.steady)}")

# %% Plot the tangential hysteresis loop of the last cycle
last = result.cycle == result.cycle.max()
fig, ax = plt.subplots(figsize=(5, 4))
ax.plot(result.V[last] * 1e6, result.Q[last], lw=1.5)
ax.set_xlabel("tangential displacement V (µm)")
ax.set_ylabel("tangential load Q (N)")
ax.set_title(f"sphere, f = 0.5: W = {W:.3g} J per cycle")
fig.tight_layout()
fig.savefig(os.path.join(out, "halfspace_hysteresis.png"), dpi=100)
plt.close(fig)
print(f"figures in {out}")
