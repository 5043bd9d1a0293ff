"""
Steering: where the chamber sits decides the bend
=================================================

The same ramp with the chamber above the axis, on it and below it: the beam curls down, stays straight
and curls up (``pneuma-steer`` runs the three on the reference mesh).
"""

import matplotlib.pyplot as plt

import taichi_pneuma as tp
from taichi_pneuma.render.drawing import draw_result, show

fig, axes = plt.subplots(3, 1, figsize=(6, 8), layout="constrained")
for ax, cy in zip(axes, (0.15, 0.0, -0.15)):
    result = tp.simulate(tp.reference_scene(cy=cy, steps=8, max_area=0.005))
    draw_result(ax, result, vmin=1.0, vmax=1.8)
    ax.set_title(f"cy = {cy:+.2f}: tip deflection {result.tip_deflection:+.3f}")
show("plot_steering")
