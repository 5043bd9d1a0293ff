"""2D shapes of bodies and chambers, each yielding a closed counter-clockwise polygon (polygon()).

Bodies are rectangles, polygons or unions of axis-aligned rectangles; chambers are ellipses, rectangles with rounded
corners or polygons. An ellipse and a rounded rectangle's corners are curves, which their polygon samples; they also
give project(points): points near the outline moved onto the exact curve (planar.py puts a quadratic or refined
mesh's boundary nodes there).

Checking a geometry takes time and memory quadratic in its outline points, so a geometry has at most MAX_SHAPES
chambers (a union at most MAX_SHAPES rectangles) and MAX_WALL_POINTS outline points in all (2000 points: 0.7 s and
190 MB for the self-crossing test of one polygon).

Each is a part of the scene file declared as every named part is (io/registry.py): its fields are the keys of its
[body] or [[chambers]] table (key(): doc and unit), its class attribute name the table's `shape = "..."`, and it is
registered in PLANAR_BODIES or PLANAR_CHAMBERS (a polygon in both), which scene/shape_keys.py reads.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import require, require_finite, shape_of
from ..io.registry import Registry, key
from ..io.units import LENGTH
from .polygons import polygon_self_intersects, signed_area

MAX_WALL_POINTS = 2000
MAX_SHAPES = 64
PAIR = "[x, y]"
PLANAR_BODIES: Registry = Registry("2D body shape")  # shape = "..." of a 2D [body], in the order registered
PLANAR_CHAMBERS: Registry = Registry("2D chamber shape")  # shape = "..." of a 2D [[chambers]]


def _pair(name: str, value, positive: bool = False) -> tuple[float, float]:
    require(shape_of(value) == (2,), f"{name} = {value!r} must be a pair of numbers")
    pair = (require_finite(f"{name}", value[0]), require_finite(f"{name}", value[1]))
    if positive:
        require(min(pair) > 0, f"{name} = {value!r} must be > 0")
    return pair


@PLANAR_BODIES.register
@dataclass(frozen=True)
class Rectangle:
    """An axis-aligned rectangle; its polygon starts at the bottom-left corner."""

    center: tuple[float, float] = key(doc=PAIR, unit=LENGTH, omitted=(0.0, 0.0))
    size: tuple[float, float] = key(doc="[width, height]", unit=LENGTH)
    name = "rectangle"

    def __post_init__(self):
        _pair("center", self.center)
        _pair("size", self.size, positive=True)

    def polygon(self) -> np.ndarray:
        (cx, cy), (w, h) = self.center, self.size
        return np.array(
            [[cx - w / 2, cy - h / 2], [cx + w / 2, cy - h / 2], [cx + w / 2, cy + h / 2], [cx - w / 2, cy + h / 2]],
            dtype=np.float64,
        )


@PLANAR_CHAMBERS.register
@dataclass(frozen=True)
class Ellipse:
    """Ellipse with semi-axes (a, b) about center, sampled at `points` angles from 0 (128; a scene file's 64)."""

    center: tuple[float, float] = key(doc=PAIR, unit=LENGTH)
    semi_axes: tuple[float, float] = key(doc="[a, b]", unit=LENGTH)
    points: int = key(128, "wall points, 8 or more (2D)", omitted=64)
    name = "ellipse"

    def __post_init__(self):
        _pair("center", self.center)
        _pair("semi_axes", self.semi_axes, positive=True)
        require(
            isinstance(self.points, (int, np.integer)) and 8 <= self.points <= MAX_WALL_POINTS,
            f"points = {self.points!r} must be an integer in [8, {MAX_WALL_POINTS}]",
        )

    def polygon(self) -> np.ndarray:
        t = np.linspace(0.0, 2.0 * np.pi, self.points, endpoint=False)
        (cx, cy), (a, b) = self.center, self.semi_axes
        return np.column_stack([cx + a * np.cos(t), cy + b * np.sin(t)])

    def project(self, points: np.ndarray) -> np.ndarray:
        """Points (k, 2) near the ellipse moved onto it at their parameter angle t = atan2((y - cy) / b,
        (x - cx) / a): (cx + a cos t, cy + b sin t), radially on a circle; the polygon's vertices stay."""
        (cx, cy), (a, b) = self.center, self.semi_axes
        t = np.arctan2((points[:, 1] - cy) / b, (points[:, 0] - cx) / a)
        return np.column_stack([cx + a * np.cos(t), cy + b * np.sin(t)])


@PLANAR_CHAMBERS.register
@dataclass(frozen=True)
class RoundedRectangle:
    """Axis-aligned rectangle whose corners are quarter circles of `radius` (< half the shorter side)."""

    center: tuple[float, float] = key(doc=PAIR, unit=LENGTH)
    size: tuple[float, float] = key(doc="[w, h]", unit=LENGTH)
    radius: float = key(doc="corner radius, below half the shorter side", unit=LENGTH)
    corner_points: int = key(6, "points per corner (2D)")
    name = "rounded_rectangle"

    def __post_init__(self):
        _pair("center", self.center)
        w, h = _pair("size", self.size, positive=True)
        r = require_finite("radius", self.radius)
        require(
            0 < r < min(w, h) / 2,
            f"radius = {self.radius!r} must lie in (0, {min(w, h) / 2:g}) (half the shorter side)",
        )
        require(
            isinstance(self.corner_points, (int, np.integer)) and 2 <= self.corner_points <= MAX_WALL_POINTS // 4,
            f"corner_points = {self.corner_points!r} must be an integer in [2, {MAX_WALL_POINTS // 4}]",
        )

    def polygon(self) -> np.ndarray:
        (cx, cy), (w, h), r = self.center, self.size, self.radius
        corners = [
            (cx + w / 2 - r, cy - h / 2 + r),
            (cx + w / 2 - r, cy + h / 2 - r),
            (cx - w / 2 + r, cy + h / 2 - r),
            (cx - w / 2 + r, cy - h / 2 + r),
        ]
        points = []
        for k, (ox, oy) in enumerate(corners):
            t = np.linspace(-np.pi / 2 + k * np.pi / 2, k * np.pi / 2, self.corner_points)
            points.append(np.column_stack([ox + r * np.cos(t), oy + r * np.sin(t)]))
        return np.vstack(points)

    def project(self, points: np.ndarray) -> np.ndarray:
        """Points (k, 2) near the outline moved to its nearest point. The shape is the box of the corner circles'
        centres grown by radius, so that is o + r (p - o) / |p - o| with o the box's point nearest p: onto its
        corner circle in a corner, unmoved on a straight side."""
        (cx, cy), (w, h), r = self.center, self.size, self.radius
        half = np.array([w / 2 - r, h / 2 - r])
        o = np.clip(points - (cx, cy), -half, half) + (cx, cy)
        d = points - o
        return o + r * d / np.linalg.norm(d, axis=1, keepdims=True)


@PLANAR_BODIES.register
@PLANAR_CHAMBERS.register
@dataclass(frozen=True)
class Polygon:
    """A simple polygon given by its vertices (either orientation; stored counter-clockwise)."""

    points: tuple = key(doc="[[x, y], ...], at least 3", unit=LENGTH)
    name = "polygon"

    def __post_init__(self):
        pts = np.asarray(self.points, dtype=object)
        require(len(pts) <= MAX_WALL_POINTS, f"points: {len(pts)} given, at most {MAX_WALL_POINTS} are allowed")
        require(
            pts.ndim == 2 and pts.shape[1] == 2 and len(pts) >= 3,
            f"points = {self.points!r} must be a list of at least 3 [x, y] pairs",
        )
        for p in self.points:
            _pair("points", p)
        poly = np.asarray(self.points, dtype=np.float64)
        require(abs(signed_area(poly)) > 0, f"points = {self.points!r} enclose no area")
        require(not polygon_self_intersects(poly), f"points = {self.points!r} cross each other (not a simple polygon)")

    def polygon(self) -> np.ndarray:
        poly = np.asarray(self.points, dtype=np.float64)
        return poly if signed_area(poly) > 0 else poly[::-1].copy()


@PLANAR_BODIES.register
@dataclass(frozen=True)
class RectangleUnion:
    """The union of axis-aligned rectangles; it must form one region without holes."""

    rectangles: tuple[Rectangle, ...]
    name = "union"

    def __post_init__(self):
        require(1 <= len(self.rectangles) <= MAX_SHAPES, f"rectangles must list 1 to {MAX_SHAPES} rectangles")
        loops = union_boundary([r.polygon() for r in self.rectangles])
        require(
            len(loops) == 1,
            f"rectangles: their union has {len(loops)} boundary loops; it must be one connected region without holes",
        )

    def polygon(self) -> np.ndarray:
        return union_boundary([r.polygon() for r in self.rectangles])[0]


def union_boundary(polygons: list[np.ndarray]) -> list[np.ndarray]:
    """Counter-clockwise boundary loops of a union of axis-aligned rectangles (each given as its 4 corners).

    The rectangles' edge coordinates cut the plane into grid cells, each wholly inside or outside
    the union; the boundary is the set of cell sides between an inside and an outside cell, directed
    with the inside on the left, chained into loops with collinear vertices dropped.
    """
    boxes = np.array([[p[:, 0].min(), p[:, 1].min(), p[:, 0].max(), p[:, 1].max()] for p in polygons])
    xs, ys = np.unique(boxes[:, [0, 2]]), np.unique(boxes[:, [1, 3]])
    mx, my = (xs[:-1] + xs[1:]) / 2, (ys[:-1] + ys[1:]) / 2
    inside = np.zeros((len(mx) + 2, len(my) + 2), dtype=bool)  # padded by one outside cell each side
    for x0, y0, x1, y1 in boxes:
        inside[1:-1, 1:-1] |= ((mx >= x0) & (mx <= x1))[:, None] & ((my >= y0) & (my <= y1))[None, :]
    successor: dict[tuple[int, int], tuple[int, int]] = {}
    for i, j in zip(*np.nonzero(inside)):
        # cell (i, j) spans grid corners (i - 1 .. i, j - 1 .. j); sides with outside neighbours, CCW
        for (di, dj), a, b in (
            ((0, -1), (i - 1, j - 1), (i, j - 1)),
            ((1, 0), (i, j - 1), (i, j)),
            ((0, 1), (i, j), (i - 1, j)),
            ((-1, 0), (i - 1, j), (i - 1, j - 1)),
        ):
            if not inside[i + di, j + dj]:
                require(a not in successor, "rectangles: their union touches itself at a corner")
                successor[a] = b
    loops = []
    while successor:
        start = next(iter(successor))
        loop = [start]
        while (nxt := successor.pop(loop[-1])) != start:
            loop.append(nxt)
        pts = np.array([[xs[i], ys[j]] for i, j in loop])
        prev, nxt_ = np.roll(pts, 1, axis=0), np.roll(pts, -1, axis=0)
        turn = (pts[:, 0] - prev[:, 0]) * (nxt_[:, 1] - pts[:, 1]) - (pts[:, 1] - prev[:, 1]) * (nxt_[:, 0] - pts[:, 0])
        loops.append(pts[turn != 0])
    return loops
