"""
A design study: tip deflection over chamber height and stiffness
================================================================

A :class:`~taichi_pneuma.study.sweep.Sweep` runs a scene once per point of a grid over any of its
keys (here the chamber height ``cy`` and Young's modulus ``E``) on a pool of worker processes, appends a
row per run to a CSV as it finishes (a study run again resumes), and plots the result: for two keys a
heatmap of the tip deflection. ``pneuma-sweep --vary cy=-0.15:0.15:4 --vary E=5e3:2e4:3`` is the same
study from the command line. Under area control the modulus hardly changes the bend: the commanded area
fixes the deformation, and E only scales the pressure.
"""

import tempfile

import matplotlib.pyplot as plt

import taichi_pneuma as tp
from taichi_pneuma.render.drawing import show
from taichi_pneuma.study import LocalPool, Sweep, parse_vary

if __name__ == "__main__":  # the workers are spawned processes, which import this file without running it
    base = tp.reference_scene(steps=5, max_area=0.01)
    axes = [parse_vary("cy=-0.15:0.15:4"), parse_vary("E=5e3:2e4:3")]
    with tempfile.TemporaryDirectory() as out, LocalPool(workers=2) as pool:  # the folder removed at the end
        sweep = Sweep(base, axes, out=out, name="cy_E")
        report = sweep.run(pool)
        image = plt.imread(sweep.png)  # the study's plot, written beside its CSV and JSON
    print(f"{report.ran} runs in {report.seconds:.1f} s, {report.failed} failed")
    fig, ax = plt.subplots(figsize=(6, 4.5), layout="constrained")
    ax.imshow(image)
    ax.set_axis_off()
    show("plot_sweep_heatmap")
