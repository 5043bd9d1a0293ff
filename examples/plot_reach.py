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
from drawing import draw_body

import taichi_pneuma as tp
from taichi_pneuma.control.inverse import Reacher

tp.init("cpu")
scene = tp.load_scene("bidirectional")
built = scene.build()
reacher = Reacher(built)  # each chamber's commands bounded by its [[chambers]] bounds
reached = reacher.follow(list(scene.targets))

fig, ax = plt.subplots(figsize=(8, 4), layout="constrained")
for result in reached:
    draw_body(ax, built.mesh.vertices + result.pose.u, built.mesh)
    commands = ", ".join(f"{name} {value:.3f}" for name, value in zip(reacher.names, result.pose.commands))
    print(f"target {result.target.tip}: {commands}; {result.summary_line()}")
ax.plot(*zip(*(r.target.tip for r in reached)), "r+", ms=14, mew=2, label="targets")
ax.plot(*zip(*(r.pose.tip for r in reached)), "o", mfc="none", color="tab:orange", label="tip reached")
ax.legend(loc="upper left")
ax.set_title("three targets, two chambers")
plt.show()
