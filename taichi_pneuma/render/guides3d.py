"""What a 3D frame draws besides the body, to be read: the x-y-z axes, a scale bar, the rest shape's ghost, and
rigid obstacles (their Shape.surface: a box, a plane as a square, a sphere, cylinder or capsule as a surface of
revolution).

- axes: a triad in the view's bottom-left corner (top-left where fewer of the body's nodes lie: quiet_corners),
  each world axis e drawn as the segment (e . r, -(e . u)) AXIS_PX long from one point (r, u the camera's right
  and up: its direction as the camera sees it, shortened by how much it points at the eye);
- the scale bar: the round length scalebar.scale_bar picks for the view's width at the depth of the camera's target
  (the centre of the body's bounding box), F / distance pixels per world unit (render.camera), in the bottom-right
  (or top-right, as the axes);
- the ghost: the pixels the rest body (cut as the frames are) covers (rasterised once), tinted GHOST_FILL where
  the frame shows the background, and its outline (covered pixels with an uncovered 4-neighbour) GHOST_EDGE;
- obstacles (obstacle_geometry: each shape's Shape.surface, the triangles ParaView's files hold too: a box, a plane
  as a square, a sphere, cylinder or capsule as a surface of revolution): opaque shaded faces in the 3D scene (so
  the body hides them and they hide it where they should) and their edges (a box's, a square's sides) as thin quads
  facing the eye (segment_triangles), nudged towards it so they win over their faces.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .camera import Camera
from .scalebar import scale_bar
from .surface import rasterise
from .text import MARGIN_PX, Label, label_box

if TYPE_CHECKING:
    from ..terms.obstacle_shapes import Shape

AXIS_PX = 26
AXIS_COLORS = ((0.8, 0.15, 0.1), (0.1, 0.55, 0.15), (0.1, 0.3, 0.85))
GHOST_FILL, GHOST_EDGE = (0.93, 0.93, 0.93), (0.55, 0.55, 0.55)
INK = (0.15, 0.15, 0.15)


def obstacle_triangles(shape: Shape, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """A 3D obstacle's shape where it is placed as triangles (t, 3, 3) and edges (e, 2, 3) (Shape.surface: a box
    its faces and edges; a plane the square of half-side reach about its point and its sides; a sphere, cylinder or
    capsule a surface of revolution, no edges)."""
    surface = shape.surface(reach, shape.parameters()[:3])
    return surface.points[surface.triangles], surface.points[surface.edges]


def obstacle_geometry(result) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
    """Each obstacle of a 3D run as triangles (steps, t, 3, 3) and edges (steps, e, 2, 3) at each step
    (obstacle_triangles, a plane's square as wide as the body is long, moved by the obstacle's offset)."""
    reach = float(np.ptp(result.mesh.vertices, axis=0).max())
    drawn = []
    for o in result.scene.obstacles:
        triangles, edges = obstacle_triangles(o.shape, reach)
        offsets = np.array([o.offset(s.step) for s in result.steps])[:, None, None]
        drawn.append((triangles + offsets, edges + offsets))
    return tuple(drawn)


def segment_triangles(ends: np.ndarray, camera: Camera, width_px: float, height: int) -> np.ndarray:
    """Segments (k, 2, 3) as quads (2k, 3, 3) width_px pixels wide facing the eye, moved 0.3 % of the way to it."""
    eye = camera.eye
    ends = ends + 0.003 * (eye - ends)
    middle = ends.mean(axis=1)
    depth = np.linalg.norm(middle - eye, axis=1)
    across = np.cross(ends[:, 1] - ends[:, 0], eye - middle)
    across *= (width_px / 2 * depth / camera.focal(height) / np.maximum(np.linalg.norm(across, axis=1), 1e-300))[
        :, None
    ]
    a, b, c, d = ends[:, 0] - across, ends[:, 1] - across, ends[:, 1] + across, ends[:, 0] + across
    return np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])


def ghost_mask(corners: np.ndarray, camera: Camera, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """(covered, outline) (height, width) booleans of the world triangles corners (f, 3, 3) seen by camera."""
    pixels, depth = camera.project(corners, width, height)
    covered = rasterise(pixels, depth, np.zeros((len(corners), 3)), width, height)[..., 0] < 0.5
    inner = covered.copy()
    inner[1:] &= covered[:-1]
    inner[:-1] &= covered[1:]
    inner[:, 1:] &= covered[:, :-1]
    inner[:, :-1] &= covered[:, 1:]
    return covered, covered & ~inner


def draw_ghost(view: np.ndarray, covered: np.ndarray, outline: np.ndarray, background) -> None:
    """Tint the background pixels of view (h, w, 3) uint8 the ghost covers, in place."""
    free = np.all(view == _rgb8(background), axis=2)
    view[free & covered] = _rgb8(GHOST_FILL)
    view[free & outline] = _rgb8(GHOST_EDGE)


def draw_axes(
    view: np.ndarray, camera: Camera, top: bool = False
) -> tuple[list[Label], tuple[float, float, float, float]]:
    """Draw the triad into view (h, w, 3) uint8 in place, in its bottom-left corner (top: top-left); its axis
    labels and the box (left, top, right, bottom) it covers."""
    from PIL import Image, ImageDraw

    h, inset = view.shape[0], MARGIN_PX + AXIS_PX + 6
    origin = np.array([inset, inset if top else h - inset], float)
    basis = camera.basis()
    picture = Image.fromarray(view)
    draw = ImageDraw.Draw(picture)
    labels = []
    for k in range(3):
        step = np.array([basis[0][k], -basis[1][k]]) * AXIS_PX
        draw.line([*origin, *(origin + step)], fill=tuple(_rgb8(AXIS_COLORS[k]).tolist()), width=2)
        tip = origin + step * (1 + 9 / max(float(np.linalg.norm(step)), 1e-9))
        labels.append(Label("xyz"[k], float(tip[0]), float(tip[1]), "mm", AXIS_COLORS[k]))
    view[:] = np.asarray(picture)
    side = AXIS_PX + 16
    return labels, (origin[0] - side, origin[1] - side, origin[0] + side, origin[1] + side)


def draw_scale_bar(
    view: np.ndarray, camera: Camera, unit: str, top: bool = False
) -> tuple[list[Label], tuple[float, float, float, float], float]:
    """Draw the scale bar into view (h, w, 3) uint8 in place, in its bottom-right corner (top: top-right); its
    label, the box it covers and its length in world units."""
    h, w = view.shape[:2]
    per_unit = camera.focal(h) / camera.distance  # pixels per world unit at the target's depth
    length, text = scale_bar(w / per_unit, unit)
    right, row = w - MARGIN_PX - 4, MARGIN_PX + 24 if top else h - MARGIN_PX - 4
    left = right - length * per_unit
    ink = _rgb8(INK)
    x0, x1 = int(round(left)), int(round(right))
    view[row - 1 : row + 2, x0 : x1 + 1] = ink
    view[row - 5 : row + 2, x0 : x0 + 2] = ink
    view[row - 5 : row + 2, x1 - 1 : x1 + 1] = ink
    label = Label(text, (left + right) / 2, row - 7, "md")
    return [label], (left - 1, row - 24, right + 1, row + 2), length


def quiet_corners(points: np.ndarray, camera: Camera, width: int, height: int, unit: str) -> tuple[bool, bool]:
    """Whether the axes and the scale bar go top (True) or bottom: where their box holds fewer of the points
    (every step's nodes) seen by camera in a (width, height) view (bottom on a tie)."""
    pixels, _ = camera.project(points.reshape(-1, 3), width, height)
    scratch = np.zeros((height, width, 3), np.uint8)

    def crowd(box) -> int:
        left, upper, right, lower = box
        x, y = pixels[:, 0], pixels[:, 1]
        return int(np.count_nonzero((x >= left) & (x <= right) & (y >= upper) & (y <= lower)))

    return (
        crowd(draw_axes(scratch, camera, True)[1]) < crowd(draw_axes(scratch, camera)[1]),
        crowd(draw_scale_bar(scratch, camera, unit, True)[1]) < crowd(draw_scale_bar(scratch, camera, unit)[1]),
    )


def _rgb8(color) -> np.ndarray:
    return (np.asarray(color) * 255 + 0.5).astype(np.uint8)


def place_key(key: list[tuple[str, tuple]], limit: float) -> list[tuple[Label, float, int]]:
    """The key's pieces side by side, a piece that does not fit on the line going to the next, and one longer than
    a line wrapped at words, so that none passes pixel column limit: (label, its x, its line)."""

    def width(text: str) -> float:
        box = label_box(Label(text, 0.0, 0.0))
        return box[2] - box[0]

    placed, x, row = [], float(MARGIN_PX), 0
    for text, color in key:
        words = text.split(" ")
        while words:
            if x > MARGIN_PX and x + width(" ".join(words)) > limit:  # the rest of the piece to the next line
                x, row = float(MARGIN_PX), row + 1
            take = len(words)
            while take > 1 and x + width(" ".join(words[:take])) > limit:
                take -= 1
            chunk, words = " ".join(words[:take]), words[take:]
            placed.append((Label(chunk, x, 0.0, "la", color), x, row))
            x += width(chunk) + 16
            if words:
                x, row = float(MARGIN_PX), row + 1
    return placed
