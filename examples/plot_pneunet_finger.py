"""
A multi-chamber finger
======================

The shipped ``pneunet_finger`` scene: six chambers in a row near the top of a long finger with a stiffer
bottom layer, all under pressure control, ramped to 900, held, and released. The pressurised chambers
balloon, push each other apart along the top, and the finger curls towards its stiff layer.
"""

import matplotlib.pyplot as plt
import numpy as np

import taichi_pneuma as tp
from taichi_pneuma.render.drawing import draw_result, show

scene = tp.load_scene("pneunet_finger")  # a scene shipped with the package, by name
result = tp.simulate(scene)
peak = result.peak_step()
print(
    f"{len(result.chamber_names)} chambers; at step {peak}: pressure {result.pressure[peak].max():.0f}, "
    f"tip rotation {result.history['tip_rotation'][peak]:+.1f} deg"
)

fig, ax = plt.subplots(figsize=(8, 4), layout="constrained")
draw_result(ax, result, step=peak)
ax.set_title(f"step {peak}: every chamber at p = {result.pressure[peak].max():.0f}")

# %%
# The tip's rotation over the schedule: it curls while the pressure rises and comes back when released.
fig, ax = plt.subplots(figsize=(6, 3), layout="constrained")
ax.plot(np.arange(len(result.steps)), result.history["tip_rotation"], "o-")
ax.set(xlabel="step", ylabel="tip rotation (deg)")
show("plot_pneunet_finger")
