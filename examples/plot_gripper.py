"""
A gripper closing on a cylinder
===============================

The shipped ``gripper_2d`` scene (millimetres and kilopascals): two fingers hang from a clamped palm, each with four
chambers along its outer side and a paper sheet bonded to its inner face. Pressurised together, the chambers
lengthen the outer sides while the sheets hold the inner ones, so the fingers curl inwards and close on a rigid
cylinder (an ``[[obstacles]]`` table; frictionless contact with the same no-penetration guarantee as the ground).
Its history reports the cylinder's contact force at every step: the grip force against pressure.
"""

import matplotlib.pyplot as plt

import taichi_pneuma as tp
from taichi_pneuma.render.drawing import draw_obstacles, draw_result, show

result = tp.simulate(tp.load_scene("gripper_2d"))
pressure = result.pressure[:, 0]
grip = result.history["object.magnitude"] / 2  # the sum over both fingers' contacts: each presses with half
touch = int((grip > 0).argmax())
print(
    f"the fingertips touch the cylinder at {pressure[touch]:.0f} kPa; at {pressure[-1]:.0f} kPa each presses with "
    f"{grip[-1]:.1f} N/m (per metre of depth: a force per unit depth in plane strain)"
)

fig, (body, curve) = plt.subplots(1, 2, figsize=(10, 4), layout="constrained", width_ratios=(1.3, 1))
draw_result(body, result)
draw_obstacles(body, result)
body.set_title(f"p = {pressure[-1]:.0f} kPa")
curve.plot(pressure, grip, "o-")
curve.set(xlabel="pressure p [kPa]", ylabel="grip force per finger [kPa mm = N/m]", title="grip force")
curve.grid(alpha=0.3)
show("plot_gripper")
