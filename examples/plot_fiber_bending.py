"""
Fibre-reinforced actuators: bending, blocked force, twist
=========================================================

The shipped ``fiber_bending_3d`` scene (millimetres and kilopascals): a half-round silicone body with a half-round
chamber, a crossed pair of aramid threads wound around it (``[[fibers]]``, a crossed helix on its D section) that
keep it from ballooning, and a paper sheet on its flat bottom (``[[layers]]``) that keeps that face from stretching.
Pressurised, it lengthens everywhere but along the sheet, and bends towards it. ``blocked_force_3d`` holds the same
actuator against a plate under its tip (``[[obstacles]]``): the force it presses with is its blocked force.
``fiber_twist_3d`` winds a tube with a single helix, and it twists. Here on coarse linear meshes, for speed, which
lock in this nearly incompressible rubber: the actuator on linear tetrahedra of 8 mm (4 mm near the chamber) bends
91 degrees at 120 kPa where its converged bend is 154 (the scene ships quadratic tetrahedra: 154.5) and presses
with 731 mN where the converged blocked force is 874 mN (benchmarks/results/actuators.md), the twisting tube on
linear tetrahedra 1.5 times the shipped size twists about a third too little (its scene ships quadratic ones).
"""

import matplotlib.pyplot as plt
import numpy as np

import taichi_pneuma as tp
from taichi_pneuma.render.drawing import draw_surface, show

COARSE = {"mesh.order": 1, "mesh.size": 8.0, "mesh.near_chambers": 4.0, "mesh.distance": 4.0}  # linear, coarse
bending = tp.simulate(tp.load_scene("fiber_bending_3d").with_values(COARSE))
blocked = tp.simulate(tp.load_scene("blocked_force_3d").with_values(COARSE))
LINEAR = {"mesh.order": 1, "mesh.size": 4.5, "mesh.near_chambers": 3.0, "mesh.distance": 3.0}  # 1.5 times
twist = tp.simulate(tp.load_scene("fiber_twist_3d").with_values(LINEAR))
mesh = bending.mesh
outer = mesh.surface[np.isin(mesh.surface[:, :3], mesh.boundary).all(axis=1)]  # the chamber's wall left out
p = bending.pressure[:, 0]
force_at_end = blocked.steps[-1].blocked_force
print(
    f"at {p[-1]:.0f} kPa: bending angle {bending.tip_rotation:+.1f} deg, blocked force {force_at_end:.0f} mN; "
    f"twist {twist.steps[-1].tip_twist:+.1f} deg at {twist.pressure[-1, 0]:.0f} kPa"
)

fig = plt.figure(figsize=(11, 3.4), layout="constrained")
ax = fig.add_subplot(1, 3, 1, projection="3d")
draw_surface(ax, bending.positions[-1], outer)
ax.view_init(elev=15, azim=-70)
ax.set_title(f"fiber_bending_3d at {p[-1]:.0f} kPa")
angle = fig.add_subplot(1, 3, 2)
angle.plot(p, -bending.history["tip_rotation"], "o-", label="bending angle (fiber_bending_3d)")
angle.plot(twist.pressure[:, 0], -twist.history["tip_twist"], "s-", label="twist (fiber_twist_3d)")
angle.set(xlabel="pressure p [kPa]", ylabel="angle [deg]")
angle.legend(fontsize="small")
force = fig.add_subplot(1, 3, 3)
force.plot(blocked.pressure[:, 0], blocked.history["blocked_force"], "o-")
force.set(xlabel="pressure p [kPa]", ylabel="blocked force [mN]", title="blocked_force_3d")
for ax in (angle, force):
    ax.grid(alpha=0.3)
show("plot_fiber_bending")
