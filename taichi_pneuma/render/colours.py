"""The colours of a 2D frame (RGB in [0, 1]) and the colour map a field is drawn in (render.frames; the 3D
frames share BACKGROUND and the colour map)."""

from __future__ import annotations

from functools import cache

import numpy as np

BACKGROUND = (1.0, 1.0, 1.0)
FACE = (0.72, 0.89, 0.66)  # the body's faces, light green, when it is not coloured by a field
EDGE = (0.18, 0.49, 0.20)  # the element edges over FACE
GHOST = (0.78, 0.78, 0.78)  # the rest shape's outline under the body, light grey
OUTLINE = (0.2, 0.2, 0.2)  # the body's outline when it is coloured by a field (no inner edges)
CHAMBER_ALPHA = 0.35
# the chamber's fill: translucent blue blended onto BACKGROUND (the chamber is a hole in the mesh: only
# background lies under it), so it can be drawn opaque
CHAMBER_FILL = tuple(CHAMBER_ALPHA * c + (1 - CHAMBER_ALPHA) * b for c, b in zip((0.1, 0.3, 1.0), BACKGROUND))
CHAMBER_WALL = (0.05, 0.2, 0.95)  # the chamber's wall loop, strong blue
PIN = (0.15, 0.15, 0.15)  # the pinned vertices' square markers
GROUND = (0.45, 0.3, 0.15)  # the ground line
OBSTACLE = (0.45, 0.3, 0.15)  # a rigid obstacle's outline (the ground's colour: both are rigid)
OBSTACLE_FILL = (0.86, 0.82, 0.76)  # ... and its inside
AXES = (0.35, 0.35, 0.35)  # axes and tick marks
TEXT = (0.1, 0.1, 0.1)
AREA_CURVE = (0.05, 0.2, 0.95)  # one chamber's area ratio in the trace panel (several: matplotlib's tab10)
PRESSURE_CURVE = (0.85, 0.15, 0.1)  # one chamber's pressure in the trace panel
CURSOR = (0.2, 0.2, 0.2)  # the trace panel's cursor at the current step
TARGET = (0.9, 0.1, 0.1)  # inverse control: the target's cross
TIP_PATH = (0.95, 0.55, 0.0)  # inverse control: where the tip reached earlier targets, and the descent's iterates
COLORMAP = "viridis"  # a colour field's map: one scale for all tracks and steps
COLORBAR_PX = 96  # width of the colour bar strip beside the panels


@cache  # a memo of the one colour map, its array read-only: shared by every call
def _colormap_table() -> np.ndarray:
    """The colour map's table of RGB colours (matplotlib's, N entries), read-only."""
    import matplotlib

    cmap = matplotlib.colormaps[COLORMAP]
    table = cmap(np.arange(cmap.N))[:, :3]
    table.flags.writeable = False
    return table


def colormap(values: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """RGB (k, 3) of values on the colour map, lo..hi mapped to its ends: the table entry matplotlib's
    colormap call picks (floor of t N, the top end in the last entry), looked up without the call."""
    table = _colormap_table()
    t = np.clip((values - lo) / (hi - lo if hi > lo else 1.0), 0.0, 1.0)
    return table[np.minimum((t * len(table)).astype(int), len(table) - 1)]
