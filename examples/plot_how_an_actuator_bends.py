"""
How an actuator bends
=====================

An inflated chamber bends a body because it lengthens one side of it more than the other: the beam curls
away from the side that grows. Which side grows is decided by where the chamber sits and by how stiff the
material around it is, and it can change during one ramp. This page runs the reference beam with its chamber
at three heights, looks at what the two faces of the beam do, and adds a stiff layer to a PneuNet finger.
Every number printed and drawn here comes from the runs on this page.
"""

import matplotlib.pyplot as plt
import numpy as np

import taichi_pneuma as tp
from taichi_pneuma.render.drawing import draw_result, show

# %%
# Where the chamber sits
# ----------------------
# The reference beam (3.5 x 0.8, clamped on the left) with its chamber 0.15 above the neutral axis, on it and
# 0.15 below, each inflated to 3.5 times its rest area in 35 increments.
heights = (0.15, 0.0, -0.15)
runs = {cy: tp.simulate(tp.reference_scene(cy=cy)) for cy in heights}

fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
for cy, result in runs.items():
    ratio, tip = result.area_ratio[:, 0], result.history["tip_dy"]
    ax.plot(ratio, tip, marker=".", label=f"chamber at cy = {cy:+.2f}")
    top, low = int(np.argmax(tip)), int(np.argmin(tip))
    print(
        f"cy = {cy:+.2f}: tip highest {tip[top]:+.3f} (step {top}, area x{ratio[top]:.2f}), "
        f"lowest {tip[low]:+.3f} (step {low}, area x{ratio[low]:.2f}), final {tip[-1]:+.3f}"
    )
high = runs[0.15].history["tip_dy"]
peak = int(np.argmax(high))
ax.annotate(
    f"rises to {high[peak]:+.3f} first (step {peak})",
    (runs[0.15].area_ratio[peak, 0], high[peak]),
    xytext=(1.3, -0.2),
    arrowprops={"arrowstyle": "->"},
)
ax.axhline(0.0, color="0.7", lw=0.8)
ax.set(xlabel="chamber area / rest area", ylabel="tip deflection dy (the right edge's mean)")
ax.legend()

# %%
# The chamber above the axis does something the rule "it curls away from the chamber" does not predict: the
# tip first **rises**, and only past about 2.7 times the rest area is it below where it started.
#
# Why the high chamber first curls the other way
# -----------------------------------------------
# A beam curls away from its longer side: its tip rotation is about the difference of the lengths of its bottom and
# top faces over its depth. Measure each face's length end to end: the distance between its two corners, over
# the same at rest.


def face_length(result, face: str) -> np.ndarray:
    """Per step: the distance between the two end corners of the beam's top (or bottom) face, over its rest
    value."""
    rest = result.mesh.vertices
    y = rest[:, 1].max() if face == "top" else rest[:, 1].min()
    ids = np.flatnonzero(np.isclose(rest[:, 1], y))
    ends = result.positions[:, ids[np.argmax(rest[ids, 0])]] - result.positions[:, ids[np.argmin(rest[ids, 0])]]
    length = np.linalg.norm(ends, axis=1)
    return length / length[0]


result = runs[0.15]
top, bottom = face_length(result, "top"), face_length(result, "bottom")
shortest = int(np.argmin(top))
even = shortest + int(np.argmax(top[shortest:] >= bottom[shortest:]))  # the top face as long as the bottom again
fig, (left, right) = plt.subplots(1, 2, figsize=(10, 3.6), layout="constrained")
left.plot(top, marker=".", label="top face")
left.plot(bottom, marker=".", label="bottom face")
right.plot(high, marker=".", color="k")
for ax in (left, right):
    ax.axvline(shortest, color="0.6", ls="--", lw=0.8)
    ax.axvline(even, color="0.6", ls=":", lw=0.8)
left.set(xlabel="step", ylabel="face length end to end / at rest", title="chamber at cy = +0.15")
left.legend()
right.axhline(0.0, color="0.7", lw=0.8)
right.set(xlabel="step", ylabel="tip deflection", title="the tip")
print(
    f"top face shortest x{top[shortest]:.3f} at step {shortest} (the tip's highest at step {peak}); "
    f"top as long as the bottom again at step {even} (x{top[even]:.4f} against x{bottom[even]:.4f}; "
    f"the tip {high[even]:+.3f}); at the end top x{top[-1]:.3f}, bottom x{bottom[-1]:.4f}"
)

# %%
# The thin wall above the chamber bulges out first instead of stretching, and a bulge draws its ends together:
# the top face gets *shorter* end to end, while the thick rubber below the chamber is pushed along the beam and
# the bottom face gets a little longer. The bottom side is the longer one, so the beam curls up, most when the
# top face is shortest (dashed line). As the chamber grows, the bulged wall can no longer bend out of the way
# and stretches: its tension grows with the pressure, the top face lengthens again, and where it is as long as
# the bottom (dotted line) the tip is back at zero. From there the top is the longer side and the beam curls
# down. A chamber below the axis does the mirror image (down first, then up); one on the axis grows both faces
# alike and the beam stays straight.

fig, axes = plt.subplots(1, 2, figsize=(11, 2.6), layout="constrained")
for ax, step in zip(axes, (peak, -1)):
    draw_result(ax, result, step)
    ax.set_title(f"step {step % len(top)}: area x{result.area_ratio[step, 0]:.2f}, tip {high[step]:+.3f}")

# %%
# A stiffer layer
# ---------------
# A PneuNet finger (six chambers in a row near its top, all at one pressure) has a strain-limiting layer along
# its bottom, five times stiffer than the rest. The same finger with the layer as soft as the body, for
# comparison, each inflated to 900 in 10 increments:

finger = tp.load_scene("pneunet_finger")
ramp = {f"chambers[{c}].keyframes": [[0, 0.0], [10, 900.0]] for c in range(len(finger.controls))}
fig, (bend, extend) = plt.subplots(1, 2, figsize=(10, 3.6), layout="constrained")
for label, E in (("stiff layer (5 x E)", 5e4), ("no layer (uniform E)", 1e4)):
    run = tp.simulate(finger.with_values({**ramp, "schedule.increments": 10, "material.regions[0].E": E}))
    pressure = run.pressure[:, 0]
    bend.plot(pressure, run.history["tip_rotation"], marker=".", label=label)
    extend.plot(pressure, run.history["tip_dx"], marker=".", label=label)
    print(
        f"{label}: bending angle {run.history['tip_rotation'][1]:+.1f} deg at p = {pressure[1]:.0f}, "
        f"{run.history['tip_rotation'][-1]:+.1f} deg at p = {pressure[-1]:.0f}; "
        f"largest extension {run.history['tip_dx'].max():+.3f}"
    )
bend.set(xlabel="pressure", ylabel="bending angle (deg)")
extend.set(xlabel="pressure", ylabel="tip extension dx")
bend.legend()
show("plot_how_an_actuator_bends")

# %%
# The stiff layer holds the bottom back: the chambers' growth goes into bending instead of lengthening the
# finger. Without it the finger first gets longer (its tip moves out along x) and bends less at every pressure.
#
# Fibre-reinforced actuators bend for the same reason with a different means: the chamber runs the whole length,
# a helix of thread keeps it from ballooning out, so it can only grow along its axis, and a paper sheet on the
# flat bottom keeps that side from lengthening. Against a PneuNet of the same length, silicone, walls and sheet
# (the :doc:`actuators <../actuators>` page, measured by ``benchmarks/pneunet_vs_fiber.py``), the fibre-reinforced
# actuator bends twice as much per kPa at first and nearly in proportion to the pressure; the PneuNet's walls
# bulge more as they stretch, so it catches up at about 60 kPa and passes it.
