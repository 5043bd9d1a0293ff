"""
A fibre-reinforced bending actuator
===================================

The shipped ``fiber_bending_3d`` scene (millimetres and kilopascals): a half-round silicone body with a half-round
chamber, a crossed pair of aramid threads wound around it (``[[fibers]]``, a crossed helix on its D section) that
keep it from ballooning, and a paper sheet on its flat bottom (``[[layers]]``) that keeps that face from stretching.
Pressurised, it lengthens everywhere but along the sheet, and bends towards it. Here in four increments; the scene's
own ramp has eight.
"""

import matplotlib.pyplot as plt
import numpy as np
from drawing import draw_surface

import taichi_pneuma as tp

scene = tp.load_scene("fiber_bending_3d").with_values({"schedule.increments": 4, "chambers[0].keyframes": [[4, 120.0]]})
result = tp.simulate(scene)
mesh = result.mesh
outer = mesh.surface[np.isin(mesh.surface[:, :3], mesh.boundary).all(axis=1)]  # the chamber's wall left out
pressure, angle = result.pressure[:, 0], result.history["tip_rotation"]
print(
    f"{len(mesh.vertices)} nodes, {len(mesh.elements)} tetrahedra; bending angle {angle[-1]:+.1f} deg at "
    f"{pressure[-1]:.0f} kPa"
)

fig = plt.figure(figsize=(10, 3.4), layout="constrained")
ax = fig.add_subplot(1, 2, 1, projection="3d")
draw_surface(ax, result.positions[-1], outer)
ax.view_init(elev=15, azim=-70)
ax.set_title(f"p = {pressure[-1]:.0f} kPa")
curve = fig.add_subplot(1, 2, 2)
curve.plot(pressure, -angle, "o-")
curve.set(xlabel="pressure p [kPa]", ylabel="bending angle [deg]", title="bending angle against pressure")
curve.grid(alpha=0.3)
plt.show()
