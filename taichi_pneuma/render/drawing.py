"""Matplotlib pictures of a Result, for notebooks, scripts and the gallery: a 2D body coloured per element
(draw_body, draw_result), a 2D scene's rigid obstacles (draw_obstacles), a 3D body's surface shaded by its
normals (draw_surface). Each draws onto the matplotlib axes it is given, so it composes with other plots. show()
ends a script: a window where there is a display, PNG files in the current folder where there is none.

The apps draw the same states with the project's own renderer (videos and PNGs, frames.py and frames3d.py);
these few functions keep a script that plots a run to its subject. They read a Result's attributes
(positions, mesh, fields, scene, steps) and import nothing above this layer.
"""

import sys
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

LIGHT = np.array([-0.4, -0.6, 0.7]) / np.linalg.norm([-0.4, -0.6, 0.7])  # towards the light: above, in front


def draw_body(ax, positions, mesh, values=None, label="largest principal stretch", **style):
    """The triangles of `mesh` at `positions` (n, 2), coloured per element by `values` (the rest mesh's
    outline in grey beneath); returns the collection, for a colour bar."""
    corners = mesh.triangles[:, :3]
    ax.triplot(mesh.vertices[:, 0], mesh.vertices[:, 1], corners, color="0.85", lw=0.3)
    if values is None:
        shown = ax.triplot(positions[:, 0], positions[:, 1], corners, color="0.3", lw=0.4)[0]
    else:
        shown = ax.tripcolor(positions[:, 0], positions[:, 1], corners, facecolors=values, **style)
        plt.colorbar(shown, ax=ax, label=label, shrink=0.8)
    ax.set_aspect("equal")
    return shown


def draw_result(ax, result, step=-1, **style):
    """A Result's body at `step` (default the last), coloured by its largest principal stretch."""
    return draw_body(ax, result.positions[step], result.mesh, result.fields(step)["max_stretch"], **style)


def draw_obstacles(ax, result, step=-1, reach=1e3):
    """A 2D Result's rigid obstacles at `step`, filled grey (a plane's line across `reach`)."""
    for obstacle in result.scene.obstacles:
        points, closed = obstacle.shape.outline(reach)
        points = points + obstacle.offset(result.steps[step].step)[:2]
        if closed:
            ax.fill(*points.T, color="0.8", ec="0.35", lw=1.0)
        else:
            ax.plot(*points.T, color="0.35", lw=1.5)


def draw_surface(ax, positions, faces, color=(0.55, 0.7, 0.9)):
    """The surface triangles `faces` of a 3D body at `positions` (n, 3), lit from above; the scene's y axis
    drawn upwards."""
    positions = positions[:, [0, 2, 1]]  # matplotlib's z is up
    triangles = positions[faces[:, :3]]
    normals = -np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])  # (y, z swapped)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    shade = 0.35 + 0.65 * np.clip(normals @ LIGHT, 0.0, 1.0)  # ambient plus Lambert
    ax.add_collection3d(Poly3DCollection(triangles, facecolors=np.outer(shade, color).clip(0, 1), linewidths=0))
    lo, hi = positions.min(axis=0), positions.max(axis=0)
    ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]), xlabel="x", ylabel="z", zlabel="y")
    ax.set_box_aspect(hi - lo)
    ax.set_axis_off()


OFF_SCREEN = {"agg", "cairo", "pdf", "pgf", "ps", "svg", "template"}  # matplotlib's backends that draw no window


def show(name: str) -> list[Path]:
    """plt.show() where matplotlib draws in a window (or a notebook); where it draws off screen (a non-interactive
    backend, as MPLBACKEND=Agg or no display gives), save every open figure in the current folder as name.png
    (name_2.png, ... after the first), say so, and return their paths. Inside a docs build (sphinx-gallery, which
    collects the figures itself) it only calls plt.show()."""
    if "sphinx_gallery" in sys.modules or matplotlib.get_backend().lower() not in OFF_SCREEN:
        plt.show()
        return []
    paths = [Path(f"{name}.png" if k == 0 else f"{name}_{k + 1}.png") for k in range(len(plt.get_fignums()))]
    for number, path in zip(plt.get_fignums(), paths):
        plt.figure(number).savefig(path)
    print("wrote " + ", ".join(str(path) for path in paths))
    return paths
