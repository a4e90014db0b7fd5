"""
The assembly decides the damping: a lap joint's showcase (beyond the source papers)
===================================================================================

Barber (2012, §1, §3): in a coupled frictional system the assembly protocol — the order
in which the bolts are tightened, or the loading path before the steady cycle — can
decide how much a joint dissipates and whether it shakes down. One ``lap_joint`` case
runs the argument (``slipcycle run lap_joint_assembly.toml``, a small shipped joint): two
bolts of steel (elastic: tightening one unloads the other), tightened in turn or
together, tightened while the upper grip is held 900 N out of line and then released
(fit-up), or overloaded to 3 kN before service; each protocol cycled to its steady state,
again with B = 0 (the frictional Melan converse: one answer for every protocol), and the
shakedown window of the protocols (λ2 with separation and the service amplitude up to
which each one shakes down).

Here that case's joint on its coarser mesh (75 contact nodes) with its window grid of
three amplitudes. Left of the figure: the steady dissipation of every protocol,
coupled and with B = 0; right: the class of each protocol over the service amplitude.
The fit-up dissipates about half as much again as plain tightening, while with B = 0 the
protocols agree to 0.1 %. The numbers on both meshes are in docs/lap_joint.md
("Showcase"), checked by tests/test_lap_joint_showcase.py.
Run time: about 15 s of CPU, a minute of wall time on a busy 2-core machine.
"""

# %%
import matplotlib.pyplot as plt
import numpy as np

from slipcycle.examples import example_path
from slipcycle.io import read_case
from slipcycle.joints.lap_joint_case import coarser_joint, joint_contact, read_lap_joint_case
from slipcycle.joints.lap_joint_showcase import lap_joint_showcase

# the shipped showcase case (its joint, protocols and run settings)
lc = read_lap_joint_case(read_case(example_path("lap_joint_assembly.toml")))
contact = joint_contact(coarser_joint(lc.joint, lc.coarsening[0]))
show = lap_joint_showcase(contact, lc.protocols, lc.settings, melan_check=True,
                          window=lc.window, fields=())
names = [p.name for p in lc.protocols]
d, d0 = 1e6 * show.dissipation, 1e6 * show.decoupled.dissipation
print(f"{contact.n_nodes} contact nodes")
for name, a, b, f in zip(names, d, d0, show.bolt_force, strict=True):
    print(f"{name:>12}: D = {a:7.2f} µJ (B = 0: {b:7.2f} µJ), bolt forces after "
          f"assembly {f.round(1)} N")
print("class window between the protocols [N]:", show.protocol_class_window()[0])

fig, ax = plt.subplots(figsize=(6.4, 3.6))
x = np.arange(len(names))
ax.bar(x - 0.2, d, 0.4, label="coupled")
ax.bar(x + 0.2, d0, 0.4, label="B = 0")
ax.set_xticks(x, names)
ax.set_ylabel("steady dissipation per cycle [µJ]")
ax.legend()
fig.tight_layout()

# %%
# Which protocol shakes down where: the class of each protocol (and of a safe start)
# over the service amplitude, with λ2 and each protocol's limit bracket.
fig2 = show.windows[0].figures()["shakedown_map"]()
