"""
The reference beam in 3D, from a mesh file
==========================================

The shipped ``beam_3d`` scene reads its body from ``beam_3d.msh`` (written by gmsh through
``examples/beam_3d_mesh.py``; reading needs only meshio): a 3.5 x 0.8 x 0.8 beam of linear tetrahedra with
an ellipsoidal cavity above its axis, the cavity's surface a physical group that the scene names as its
chamber. Volume control doubles the cavity's volume in 10 increments and the beam curls down, like the 2D
reference (``pneuma-inflate --scene beam_3d``).
"""

import matplotlib.pyplot as plt
import numpy as np

import taichi_pneuma as tp
from taichi_pneuma.render.drawing import draw_surface, show

scene = tp.load_scene("beam_3d").with_values({"schedule.increments": 5, "chambers[0].keyframes": [[5, 2.0]]})
result = tp.simulate(scene)
mesh = result.mesh
outer = mesh.surface[np.isin(mesh.surface[:, :3], mesh.boundary).all(axis=1)]  # the cavity's wall left out
print(f"{len(mesh.vertices)} nodes, {len(mesh.elements)} tetrahedra; tip deflection {result.tip_deflection:+.4f}")

fig = plt.figure(figsize=(9, 2.8), layout="constrained")
for i, step in enumerate((0, -1)):
    ax = fig.add_subplot(1, 2, i + 1, projection="3d")
    draw_surface(ax, result.positions[step], outer)
    ax.view_init(elev=20, azim=-60)
    ax.set_title("rest" if step == 0 else f"volume x{result.area_ratio[-1, 0]:.2f}: tip {result.tip_deflection:+.3f}")
show("plot_beam_3d")
