"""
A balloon driven three ways: the chamber kinds
==============================================

The shipped ``balloon_*`` scenes are one body: a thin V-shaped wall dented into its chamber, which pops
out past a pressure peak (a limit point). Driven by volume control (``control = "volume"``) or by a
syringe (``"syringe"``, air pushed through a tube) the wall follows the whole pressure-volume curve
through the drop; a pressure regulator (``"pressure"``) finds no equilibrium past the peak and stops
there, keeping the steps it did. Here each ramp takes 12 increments instead of the scenes' 36.
"""

import matplotlib.pyplot as plt

import taichi_pneuma as tp
from taichi_pneuma.render.drawing import show

fig, ax = plt.subplots(figsize=(6, 4), layout="constrained")
DRIVES = {"balloon_volume": 1.75, "balloon_syringe": 58.0, "balloon_pressure": 0.036}  # each scene's final command
for (name, final), style in zip(DRIVES.items(), ("-", "--", "o")):
    scene = tp.load_scene(name).with_values({"schedule.increments": 12, "chambers[0].keyframes": [[12, final]]})
    try:
        result = tp.simulate(scene, max_cuts=2)
    except tp.RampFailed as stopped:  # past the limit point under pressure control
        print(f"{name}: {stopped}")
        result = stopped.result
    ax.plot(result.area[:, 0], result.pressure[:, 0], style, label=f"{name} ({result.scene.controls[0].kind.name})")
    print(f"{name}: {len(result.steps)} steps, peak pressure {result.peak_pressure:.2f}")
ax.set(xlabel="chamber area (volume per unit depth, mm^2)", ylabel="pressure (kPa)", title="one wall, three drives")
ax.legend()
show("plot_balloon")
