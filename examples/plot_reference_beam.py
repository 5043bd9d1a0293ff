"""
The reference beam
==================

A clamped 3.5 x 0.8 beam with an elliptical chamber 0.15 above its neutral axis, inflated to 3.5 times
its rest area: the chamber's wall stretches the rubber above the axis more than below, and the beam curls
down. ``pneuma-inflate --cy 0.15`` runs the same scene on the reference mesh (tip -0.2790); here a coarser
mesh and 8 increments keep the example short.
"""

import tempfile

import matplotlib.pyplot as plt

import taichi_pneuma as tp
from taichi_pneuma.render.drawing import draw_result, show

scene = tp.reference_scene(cy=0.15, steps=9, max_area=0.005)
result = tp.simulate(scene)
print(
    f"tip deflection {result.tip_deflection:+.4f}, rotation {result.tip_rotation:+.1f} deg, "
    f"peak pressure {result.peak_pressure:.1f}"
)

fig, ax = plt.subplots(figsize=(8, 3), layout="constrained")
draw_result(ax, result)
ax.set_title(f"area x{result.area_ratio[-1, 0]:.2f}: tip {result.tip_deflection:+.3f}")

# %%
# ``result.save`` writes the history (CSV), states (npz), summary, scene file, ParaView files and the plot of
# the history: pressure against area ratio, and the tip, area and pressure against the command (here into a
# temporary folder, removed after the plot is read back).
with tempfile.TemporaryDirectory() as out:
    written = result.save(out)
    plot = plt.imread(next(path for path in written if path.name.endswith("_plot.png")))
fig, ax = plt.subplots(figsize=(10, 7), layout="constrained")
ax.imshow(plot)
ax.set_axis_off()
show("plot_reference_beam")
