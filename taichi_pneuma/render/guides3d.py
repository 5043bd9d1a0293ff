"""What a 3D frame draws besides the body, to be read: the x-y-z axes, a scale bar, the rest shape's ghost, and
rigid obstacles (a box, a plane as a square, a sphere, cylinder or capsule as a surface of revolution).

- axes: a triad in the view's bottom-left corner (top-left where fewer of the body's nodes lie: quiet_corners),
  each world axis e drawn as the segment (e . r, -(e . u)) AXIS_PX long from one point (r, u the camera's right
  and up: its direction as the camera sees it, shortened by how much it points at the eye);
- the scale bar: the round length scalebar.scale_bar picks for the view's width at the depth of the camera's target
  (the centre of the body's bounding box), F / distance pixels per world unit (render.camera), in the bottom-right
  (or top-right, as the axes);
- the ghost: the pixels the rest body (cut as the frames are) covers (rasterised once), tinted GHOST_FILL where
  the frame shows the background, and its outline (covered pixels with an uncovered 4-neighbour) GHOST_EDGE;
- obstacles (obstacle_geometry: a box as its box, a plane as a square, a sphere, cylinder or capsule as its profile
  revolved about its axis, revolved()): opaque shaded faces in the 3D scene (so the body hides them and they hide it
  where they should) and the edges of boxes and squares as thin quads facing the eye (segment_triangles), nudged
  towards it so they win over their faces.
"""

from __future__ import annotations

import numpy as np

from .camera import Camera
from .scalebar import scale_bar
from .surface import rasterise
from .text import MARGIN_PX, Label, label_box

AXIS_PX = 26
AXIS_COLORS = ((0.8, 0.15, 0.1), (0.1, 0.55, 0.15), (0.1, 0.3, 0.85))
GHOST_FILL, GHOST_EDGE = (0.93, 0.93, 0.93), (0.55, 0.55, 0.55)
INK = (0.15, 0.15, 0.15)
BOX_TRIANGLES = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1)]  # outward
BOX_TRIANGLES += [(2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]
BOX_EDGES = ((0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7), (0, 4), (1, 5), (2, 6), (3, 7))


def box(lo, hi) -> tuple[np.ndarray, np.ndarray]:
    """The box lo..hi as triangles (12, 3, 3) and edges (12, 2, 3); corner k has bits (x, y, z) = k's (4, 2, 1)."""
    corners = np.array([[(lo, hi)[k >> 2 & 1][0], (lo, hi)[k >> 1 & 1][1], (lo, hi)[k & 1][2]] for k in range(8)])
    return corners[np.array(BOX_TRIANGLES)], corners[np.array(BOX_EDGES)]


def square(point, normal, half: float) -> tuple[np.ndarray, np.ndarray]:
    """The square of half-side `half` about point in the plane of normal: triangles (2, 3, 3) and edges (4, 2, 3)."""
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    u = np.cross(n, np.eye(3)[int(np.argmin(np.abs(n)))])
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    c = np.asarray(point, float) + half * np.array([-u - v, u - v, u + v, -u + v])
    return c[np.array([[0, 1, 2], [0, 2, 3]])], c[np.array([[0, 1], [1, 2], [2, 3], [3, 0]])]


SEGMENTS = 32  # around a surface of revolution
NO_EDGES = np.zeros((0, 2, 3))


def revolved(center, axis, profile: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The surface swept by profile (k, 2): points (a, r) at a along the unit axis and r from it, from one pole
    (r = 0) to the other, turned SEGMENTS times about the axis through center: triangles (f, 3, 3), no edges."""
    a = np.asarray(axis, float)
    u = np.cross(a, np.eye(3)[int(np.argmin(np.abs(a)))])
    u /= np.linalg.norm(u)
    v = np.cross(a, u)
    turn = np.linspace(0.0, 2 * np.pi, SEGMENTS + 1)
    rings = (
        np.asarray(center, float)
        + profile[:, None, :1] * a
        + profile[:, None, 1:] * (np.cos(turn)[None, :, None] * u + np.sin(turn)[None, :, None] * v)
    )  # (k, SEGMENTS + 1, 3)
    p, q = rings[:-1, :-1], rings[:-1, 1:]  # each quad between two rings and two turns: two triangles
    r, s = rings[1:, 1:], rings[1:, :-1]
    triangles = np.concatenate([np.stack([p, q, r], axis=2), np.stack([p, r, s], axis=2)]).reshape(-1, 3, 3)
    area = 0.5 * np.linalg.norm(np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]), axis=1)
    return triangles[area > 0], NO_EDGES  # (the poles' quads have a side of length 0)


def profile(shape) -> np.ndarray:
    """A sphere's, cylinder's or capsule's (a, r) profile from pole to pole (obstacle_shapes' shapes): a half circle;
    the flat caps and the side; a quarter circle, the side and a quarter circle."""
    from ..terms.obstacle_shapes import Capsule, Sphere

    radius, half = shape.radius, 0.0 if isinstance(shape, Sphere) else 0.5 * shape.length
    quarter = np.linspace(0.0, np.pi / 2, SEGMENTS // 4 + 1)
    if isinstance(shape, Sphere | Capsule):
        cap = np.stack([-half - radius * np.cos(quarter), radius * np.sin(quarter)], axis=1)
        return np.concatenate([cap, cap[::-1] * (-1, 1)])
    return np.array([[-half, 0.0], [-half, radius], [half, radius], [half, 0.0]])


def obstacle_triangles(obstacle, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """A 3D obstacle where it is placed as triangles (t, 3, 3) and edges (e, 2, 3): a box its faces and edges; a
    plane the square about its point of half-side reach; a sphere, cylinder or capsule revolved(), no edges."""
    from ..terms.obstacle_shapes import Box, Cylinder, Plane, Sphere, axis_vector

    shape = obstacle.shape
    if isinstance(shape, Box):
        p = shape.parameters()
        return box(p[:3] - p[3:6], p[:3] + p[3:6])
    if isinstance(shape, Plane):
        return square(shape.point, shape.normal, reach)
    if isinstance(shape, Sphere):
        return revolved(shape.center, (1.0, 0.0, 0.0), profile(shape))
    assert isinstance(shape, Cylinder), shape  # (and a Capsule: a Cylinder's subclass)
    return revolved(shape.center, axis_vector(shape.axis), profile(shape))


def obstacle_geometry(result) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
    """Each obstacle of a 3D run as triangles (steps, t, 3, 3) and edges (steps, e, 2, 3) at each step
    (obstacle_triangles, a plane's square as wide as the body is long, moved by the obstacle's offset)."""
    reach = float(np.ptp(result.mesh.vertices, axis=0).max())
    drawn = []
    for o in result.scene.obstacles:
        triangles, edges = obstacle_triangles(o, reach)
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
