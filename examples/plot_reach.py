"""
Inverse control: commands that put the tip where you want it
============================================================

Given a target for the tip, :class:`~taichi_pneuma.control.inverse.Reacher` finds the chamber commands
that put it there: a bounded Gauss-Newton descent on exact sensitivities (the derivative of the
equilibrium with respect to each command), each step settled by a forward solve. The shipped
``bidirectional`` scene has two chambers, above and below the axis, and three targets (tip down, level,
up); the reacher follows them in order, each from the pose the last one reached
(``pneuma-reach --scene bidirectional`` does the same from the command line).
"""

import matplotlib.pyplot as plt

import taichi_pneuma as tp
from taichi_pneuma.control.inverse import Reacher
from taichi_pneuma.render.drawing import draw_body, show

tp.init("cpu")
scene = tp.load_scene("bidirectional")
built = scene.build()
reacher = Reacher(built)  # each chamber's commands bounded by its [[chambers]] bounds
reached = reacher.follow(list(scene.targets))

fig, axes = plt.subplots(3, 1, figsize=(7, 7.5), layout="constrained")
for ax, result in zip(axes, reached):
    draw_body(ax, built.mesh.vertices + result.pose.u, built.mesh)
    commands = ", ".join(f"{name} {value:.3f}" for name, value in zip(reacher.names, result.pose.commands))
    print(f"target {result.target.tip}: {commands}; {result.summary_line()}")
    ax.plot(*result.target.tip, "r+", ms=16, mew=2, label="target")
    ax.plot(*result.pose.tip, "o", ms=9, mfc="none", color="tab:orange", label="tip reached")
    ax.set_title(f"area ratios: {commands}; tip error {result.error:.1e}")
axes[0].legend(loc="upper left")
show("plot_reach")
