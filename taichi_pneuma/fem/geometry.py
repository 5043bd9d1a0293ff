"""Shapes -> Triangle meshes: a body polygon with chamber polygons punched out (or notched in at symmetry
lines), and its named vertex sets: the clamp, the tip, the rollers.

Bodies are rectangles, polygons or unions of axis-aligned rectangles; chambers are ellipses,
rectangles with rounded corners or polygons. Each shape yields a closed counter-clockwise
polygon. The body is meshed by Shewchuk's Triangle (through triangulation.py's binding) with the flags
``p q a<max_area>``: a planar straight-line graph (the body loop, then each chamber loop),
quality (20 degree minimum angle) refinement and a maximum triangle area; one hole point
strictly inside each chamber removes its inside. Each chamber wall is recovered from the output
segments as a closed vertex loop oriented counter-clockwise, so its signed shoelace area

    A(x) = 1/2 sum_i (x_i y_{i+1} - x_{i+1} y_i)

is positive at rest. Chambers must lie inside the body and apart from each other by at least
MARGIN; otherwise a PneumaInputError names the chamber.

Curved boundaries: an ellipse and a rounded rectangle's corners are curves, which their polygon samples. For
quadratic triangles, and for meshes refined uniformly, every node on a boundary segment of such a shape (the
points Triangle adds on its chords, the refinements' new nodes, the midside nodes) is moved onto the exact
curve (the shape's project), so the isoparametric elements have curved sides and converge at their full order
(P2: about h^3 in displacement, h^4 in a chamber's area) where straight-sided ones stay at h^2, limited by the
polygon. Interior midside nodes stay at their edges' middles, straight sides (rectangles, polygons, a rounded
rectangle's sides, the symmetry lines) stay straight, and a midside node whose move would fold its triangle
(a mesh too coarse for the curve) stays at its edge's middle. The ends of a wall cut by a symmetry line stay
where the polygon crosses the line: on the curve when a polygon vertex lies on it (an ellipse centred on a
line along an axis, its points a multiple of 4), else on the chord, off by the chord's sag. Linear triangles unrefined are Triangle's mesh of
the polygons as they are (the reference scene's).

Half and quarter models: a roller line along an edge of the body is a symmetry line, and a chamber may
cross it. Such a chamber is clipped to the body's side of its lines and notched into the body's outline
(no hole point); its wall is recovered as an open chain from line to line, and its area is closed by
the flat cap along the lines: with the origin o on them (their crossing, for two), the cap adds nothing,

    A(x) = 1/2 sum_i (x_i - o) x (x_{i+1} - o)      over the open chain,

oriented positive at rest. A chamber between two parallel lines (a channel) is refused. No two points of one outline may lie closer
than MIN_SPACING times its size (Triangle crashes on coincident points), and a geometry Triangle cannot
mesh (it runs out of floating-point precision) is a PneumaInputError too.

Checking that takes time and memory quadratic in the outline points, so a geometry has at most
MAX_SHAPES chambers (a union at most MAX_SHAPES rectangles) and MAX_WALL_POINTS outline points in all
(2000 points: 0.7 s and 190 MB for the self-crossing test of one polygon). Chamber names are distinct
and head CSV columns, so none starts like a spreadsheet formula (output.check_heading).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import limits
from ..errors import PneumaInputError, require, require_distinct, require_finite, shape_of
from ..io.output import check_heading
from ..io.units import PLANE_AREA, si_default
from . import triangulation
from .elements import TRIANGLE_P2

OUTER_MARKER = 1
MARGIN = 1e-3
MAX_WALL_POINTS = 2000
MAX_SHAPES = 64
MIN_SPACING = 1e-9
CUT_TOLERANCE = 1e-9  # points this close to a symmetry line, relative to the body's size, lie on it
SIDES = ("left", "right", "bottom", "top", "back", "front")  # pairs along x, y, z
ORDERS = (1, 2)
MAX_REFINEMENTS = 4


def _pair(name: str, value, positive: bool = False) -> tuple[float, float]:
    require(shape_of(value) == (2,), f"{name} = {value!r} must be a pair of numbers")
    pair = tuple(require_finite(f"{name}", v) for v in value)
    if positive:
        require(min(pair) > 0, f"{name} = {value!r} must be > 0")
    return pair


@dataclass(frozen=True)
class Rectangle:
    """An axis-aligned rectangle; its polygon starts at the bottom-left corner."""

    center: tuple[float, float]
    size: tuple[float, float]

    def __post_init__(self):
        _pair("center", self.center)
        _pair("size", self.size, positive=True)

    def polygon(self) -> np.ndarray:
        (cx, cy), (w, h) = self.center, self.size
        return np.array([[cx - w / 2, cy - h / 2], [cx + w / 2, cy - h / 2],
                         [cx + w / 2, cy + h / 2], [cx - w / 2, cy + h / 2]], dtype=np.float64)


@dataclass(frozen=True)
class Ellipse:
    """Ellipse with semi-axes (a, b) about center, sampled at `points` angles from 0."""

    center: tuple[float, float]
    semi_axes: tuple[float, float]
    points: int = 128

    def __post_init__(self):
        _pair("center", self.center)
        _pair("semi_axes", self.semi_axes, positive=True)
        require(isinstance(self.points, (int, np.integer)) and 8 <= self.points <= MAX_WALL_POINTS,
                f"points = {self.points!r} must be an integer in [8, {MAX_WALL_POINTS}]")

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


@dataclass(frozen=True)
class RoundedRectangle:
    """Axis-aligned rectangle whose corners are quarter circles of `radius` (< half the shorter side)."""

    center: tuple[float, float]
    size: tuple[float, float]
    radius: float
    corner_points: int = 6

    def __post_init__(self):
        _pair("center", self.center)
        w, h = _pair("size", self.size, positive=True)
        r = require_finite("radius", self.radius)
        require(0 < r < min(w, h) / 2, f"radius = {self.radius!r} must lie in (0, {min(w, h) / 2:g}) (half the shorter side)")
        require(isinstance(self.corner_points, (int, np.integer)) and 2 <= self.corner_points <= MAX_WALL_POINTS // 4,
                f"corner_points = {self.corner_points!r} must be an integer in [2, {MAX_WALL_POINTS // 4}]")

    def polygon(self) -> np.ndarray:
        (cx, cy), (w, h), r = self.center, self.size, self.radius
        corners = [(cx + w / 2 - r, cy - h / 2 + r), (cx + w / 2 - r, cy + h / 2 - r),
                   (cx - w / 2 + r, cy + h / 2 - r), (cx - w / 2 + r, cy - h / 2 + r)]
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


@dataclass(frozen=True)
class Polygon:
    """A simple polygon given by its vertices (either orientation; stored counter-clockwise)."""

    points: tuple

    def __post_init__(self):
        pts = np.asarray(self.points, dtype=object)
        require(len(pts) <= MAX_WALL_POINTS, f"points: {len(pts)} given, at most {MAX_WALL_POINTS} are allowed")
        require(pts.ndim == 2 and pts.shape[1] == 2 and len(pts) >= 3,
                f"points = {self.points!r} must be a list of at least 3 [x, y] pairs")
        for p in self.points:
            _pair("points", p)
        poly = np.asarray(self.points, dtype=np.float64)
        require(abs(signed_area(poly)) > 0, f"points = {self.points!r} enclose no area")
        require(not polygon_self_intersects(poly), f"points = {self.points!r} cross each other (not a simple polygon)")

    def polygon(self) -> np.ndarray:
        poly = np.asarray(self.points, dtype=np.float64)
        return poly if signed_area(poly) > 0 else poly[::-1].copy()


@dataclass(frozen=True)
class RectangleUnion:
    """The union of axis-aligned rectangles; it must form one region without holes."""

    rectangles: tuple[Rectangle, ...]

    def __post_init__(self):
        require(1 <= len(self.rectangles) <= MAX_SHAPES, f"rectangles must list 1 to {MAX_SHAPES} rectangles")
        loops = union_boundary([r.polygon() for r in self.rectangles])
        require(len(loops) == 1, f"rectangles: their union has {len(loops)} boundary loops; it must be one "
                                 f"connected region without holes")

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
        for (di, dj), a, b in (((0, -1), (i - 1, j - 1), (i, j - 1)), ((1, 0), (i, j - 1), (i, j)),
                               ((0, 1), (i, j), (i - 1, j)), ((-1, 0), (i - 1, j), (i - 1, j - 1))):
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


def signed_area(polygon: np.ndarray) -> float:
    """Shoelace area of a closed polygon (k, 2); positive when counter-clockwise."""
    x, y = polygon[:, 0], polygon[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def _cross(o, p, q):
    return (p[..., 0] - o[..., 0]) * (q[..., 1] - o[..., 1]) - (p[..., 1] - o[..., 1]) * (q[..., 0] - o[..., 0])


def segments_cross(a0, a1, b0, b1) -> np.ndarray:
    """Pairwise proper crossings between segments a (k, 2) and b (m, 2): a (k, m) boolean array."""
    A0, A1, B0, B1 = a0[:, None], a1[:, None], b0[None, :], b1[None, :]
    return (_cross(A0, A1, B0) * _cross(A0, A1, B1) < 0) & (_cross(B0, B1, A0) * _cross(B0, B1, A1) < 0)


def polygon_self_intersects(points: np.ndarray) -> bool:
    """Whether a closed polygon's non-adjacent edges cross (a proper segment intersection)."""
    a, b = points, np.roll(points, -1, axis=0)
    n = len(points)
    i, j = np.indices((n, n))
    adjacent = (np.abs(i - j) <= 1) | (np.abs(i - j) == n - 1)
    return bool(np.any(segments_cross(a, b, a, b) & ~adjacent))


def points_in_polygon(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Even-odd rule: which of points (k, 2) lie inside the closed polygon (m, 2)."""
    a, b = polygon, np.roll(polygon, -1, axis=0)
    px, py = points[:, 0:1], points[:, 1:2]
    straddles = (a[None, :, 1] > py) != (b[None, :, 1] > py)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_at = a[None, :, 0] + (py - a[None, :, 1]) * (b[None, :, 0] - a[None, :, 0]) / (b[None, :, 1] - a[None, :, 1])
    return np.count_nonzero(straddles & (px < x_at), axis=1) % 2 == 1


def distance_to_polygon(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Distance from each of points (k, 2) to the boundary of a closed polygon (m, 2)."""
    a, b = polygon[None, :], np.roll(polygon, -1, axis=0)[None, :]
    p = points[:, None]
    e = b - a
    t = np.clip(np.sum((p - a) * e, axis=2) / np.sum(e * e, axis=2), 0.0, 1.0)
    return np.min(np.linalg.norm(p - (a + t[..., None] * e), axis=2), axis=1)


def interior_point(polygon: np.ndarray) -> np.ndarray:
    """A point strictly inside a simple polygon: the centroid of the largest triangle of its triangulation."""
    k = len(polygon)
    tri = triangulate({"vertices": polygon, "segments": np.column_stack([np.arange(k), (np.arange(k) + 1) % k])}, "p")
    corners = tri["vertices"][tri["triangles"]]
    e1, e2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    return corners[np.argmax(np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]))].mean(axis=0)


def enclosed_area(points: np.ndarray, origin: np.ndarray | None = None) -> float:
    """The signed area a chamber wall encloses: the shoelace area of a closed loop (origin None), or for an
    open wall from symmetry line to symmetry line 1/2 sum_i (x_i - o) x (x_{i+1} - o), with the origin o on
    the lines (their intersection for two): the flat cap along the lines adds nothing."""
    if origin is None:
        return signed_area(points)
    r = points - origin
    return 0.5 * float(np.sum(r[:-1, 0] * r[1:, 1] - r[:-1, 1] * r[1:, 0]))


def symmetry_lines(body: np.ndarray, rollers, tol: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """The roller lines that run along an edge of the body (the body on one side, two of its vertices on the
    line, within tol), each as (unit normal pointing into the body, a point of the line)."""
    lines = []
    for roller in rollers:
        if roller.point is None:
            continue
        n, p = roller.unit_normal, np.asarray(roller.point, dtype=np.float64)
        s = (body - p) @ n
        if s.max() <= tol:
            n, s = -n, -s
        if s.min() >= -tol and np.count_nonzero(np.abs(s) <= tol) >= 2:
            lines.append((n, p))
    return lines


def clip(polygon: np.ndarray, n: np.ndarray, p: np.ndarray, tol: float) -> np.ndarray:
    """Sutherland-Hodgman: the part of a closed polygon on the side n . (x - p) >= 0. A vertex within tol of the
    line is moved onto it and kept; an edge crossing the line adds its crossing point."""
    s = (polygon - p) @ n
    out = []
    for i in range(len(polygon)):
        j = (i + 1) % len(polygon)
        if s[i] >= -tol:
            out.append(polygon[i] - s[i] * n if s[i] <= tol else polygon[i])
        if (s[i] > tol and s[j] < -tol) or (s[i] < -tol and s[j] > tol):
            out.append(polygon[i] + s[i] / (s[i] - s[j]) * (polygon[j] - polygon[i]))
    return np.array(out).reshape(-1, 2)


def cut_by_lines(polygon: np.ndarray, lines, tol: float, what: str) -> tuple[np.ndarray, np.ndarray | None]:
    """A chamber polygon (counter-clockwise) cut by the symmetry lines it crosses, as (wall, origin).

    Uncut: the polygon itself and None. Cut: the part on the body's side of the lines; its points on the lines
    (the cap) must be one run, on one line or on two crossing ones; the wall is the rest, an open chain from
    line to line that keeps the chamber on its left, and the origin of its enclosed area is the middle of the
    cap (one line) or the lines' crossing (two). A chamber cut into more than one wall (e.g. by two parallel
    lines) is refused: its cap would not be flat."""
    cutting = [(n, p) for n, p in lines if ((polygon - p) @ n).min() < -tol]
    if not cutting:
        return polygon, None
    for n, p in cutting:
        polygon = clip(polygon, n, p, tol)
        require(len(polygon) >= 3, f"{what} lies beyond a symmetry line")
    on = np.column_stack([np.abs((polygon - p) @ n) <= tol for n, p in cutting])
    cap = on.any(axis=1)
    starts, ends = np.flatnonzero(cap & ~np.roll(cap, 1)), np.flatnonzero(cap & ~np.roll(cap, -1))
    single = f"{what}: the symmetry lines must cut it into one wall from line to line (not between two parallel " \
             f"lines, nor crossing a line more than twice)"
    require(len(starts) == 1, single)
    k, m, count = starts[0], ends[0], len(polygon)
    wall = polygon[(m + np.arange((k - m) % count + 1)) % count]
    require(len(wall) >= 3, single)
    holding = on[(k + np.arange((m - k) % count + 1)) % count]
    if holding.all(axis=0).any():
        return wall, 0.5 * (wall[0] + wall[-1])
    used = np.flatnonzero(holding.any(axis=0))
    normals = np.array([cutting[i][0] for i in used])
    require(len(used) == 2 and abs(np.linalg.det(normals)) > 1e-12,
            f"{what}: its cap runs along {len(used)} symmetry lines; a cap on one line or two crossing ones is supported")
    origin = np.linalg.solve(normals, [normals[i] @ cutting[line][1] for i, line in enumerate(used)])
    return wall, origin


def notch(outline: np.ndarray, markers: np.ndarray, wall: np.ndarray, origin: np.ndarray, marker: int, tol: float,
          what: str):
    """The outline (counter-clockwise, with per-segment markers) with the cap between an open wall's ends cut
    out and the wall put in its place, reversed (the material on the left); the wall's segments get `marker`.

    Each end must lie on a body segment (marker OUTER_MARKER); the part of the outline left out must be the
    cap: the outline's area must drop by the wall's enclosed area (origin: see cut_by_lines)."""
    a, b = outline, np.roll(outline, -1, axis=0)
    e = b - a
    count = len(outline)

    def locate(point):
        t = np.clip(np.sum((point - a) * e, axis=1) / np.sum(e * e, axis=1), 0.0, 1.0)
        d = np.linalg.norm(point - (a + t[:, None] * e), axis=1)
        d[markers != OUTER_MARKER] = np.inf
        i = int(np.argmin(d))
        require(d[i] <= tol, f"{what} ends at {point.tolist()} on a symmetry line, off the body's edge (outside the body, or in another chamber)")
        return i, t[i]

    (ia, ta), (ib, tb) = locate(wall[0]), locate(wall[-1])
    steps = count if ia == ib and tb < ta else (ib - ia) % count
    walk = (ia + 1 + np.arange(steps)) % count
    cut = np.vstack([wall[:1], outline[walk], wall[-1:], wall[-2:0:-1]])
    expected = signed_area(outline) - enclosed_area(wall, origin)
    require(steps > 0 and abs(signed_area(cut) - expected) <= 1e-9 * abs(signed_area(outline)),
            f"{what}: the symmetry lines cut it off the body's edge (its cap is not a part of that edge)")
    return cut, np.concatenate([[markers[ia]], markers[walk], np.full(len(wall) - 1, marker)])


@dataclass(frozen=True)
class PointSet:
    """Named mesh nodes (the clamp, the tip): a side of the body's bounding box (within 1e-6; back and front
    are the sides normal to z, in 3D) or those in a closed box [x0, y0, x1, y1] ([x0, y0, z0, x1, y1, z1] in 3D)."""

    side: str | None = None
    box: tuple | None = None

    def __post_init__(self):
        require((self.side is None) != (self.box is None), "give exactly one of 'side' and 'box'")
        if self.side is not None:
            require(self.side in SIDES, f"side = {self.side!r} is not one of {', '.join(SIDES)}")
        else:
            require_box("box", self.box)

    def select(self, vertices: np.ndarray, what: str) -> np.ndarray:
        """The indices of the chosen vertices; choosing none is a PneumaInputError naming `what` (e.g. 'tip')."""
        if self.side is not None:
            axis = SIDES.index(self.side) // 2
            require(axis < vertices.shape[1], f"{what}.side = {self.side!r} needs a 3D body")
            x = vertices[:, axis]
            chosen = x <= x.min() + 1e-6 if SIDES.index(self.side) % 2 == 0 else x >= x.max() - 1e-6
        else:
            chosen = in_box(vertices, self.box, what)
        nodes = np.flatnonzero(chosen)
        require(len(nodes) > 0, f"{what}.box = {self.box!r} selects no mesh vertex")
        return nodes


def clamped(clamp: PointSet | None, vertices: np.ndarray) -> np.ndarray:
    """The clamped vertices: those clamp selects, none when there is no clamp (None: a body held otherwise,
    e.g. by rollers on its symmetry planes)."""
    return np.zeros(0, dtype=np.int64) if clamp is None else clamp.select(vertices, "clamp")


@dataclass(frozen=True)
class Roller:
    """A roller support: nodes whose displacement along `normal` is held, their tangential motion free.

    The nodes are those within `tolerance` of the line (the plane, in 3D) n . (X - point) = 0, or those in
    the closed box [x0, y0, x1, y1] ([x0, y0, z0, x1, y1, z1]). A roller line along an edge of the body is a
    symmetry line: a chamber may be cut by it (see Geometry), which is how half and quarter models of symmetric
    actuators are built; in 3D a roller plane holding a chamber's open rim closes that chamber (tetmesh.py)."""

    normal: tuple
    point: tuple | None = None
    box: tuple | None = None
    tolerance: float = 1e-6

    def __post_init__(self):
        normal = vector("normal", self.normal)
        require(any(normal), f"normal = {list(self.normal)!r} must not be zero")
        require((self.point is None) != (self.box is None),
                "give exactly one of 'point' (the roller line through it) and 'box'")
        if self.point is not None:
            require(len(vector("point", self.point)) == len(normal),
                    f"point = {list(self.point)!r} must have as many components as normal = {list(self.normal)!r}")
        else:
            require_box("box", self.box)
        require(require_finite("tolerance", self.tolerance) > 0, f"tolerance = {self.tolerance!r} must be > 0")

    @property
    def unit_normal(self) -> np.ndarray:
        n = np.asarray(self.normal, dtype=np.float64)
        return n / np.linalg.norm(n)

    def select(self, vertices: np.ndarray) -> np.ndarray:
        """The indices of the held vertices; holding none is a PneumaInputError."""
        where = f"point = {list(self.point)!r}" if self.point is not None else f"box = {list(self.box)!r}"
        what = f"roller (normal = {list(self.normal)!r}, {where})"
        require(len(self.normal) == vertices.shape[1], f"{what}: its normal must have {vertices.shape[1]} components "
                                                       f"on this {vertices.shape[1]}D body")
        if self.point is not None:
            chosen = np.abs((vertices - np.asarray(self.point, dtype=np.float64)) @ self.unit_normal) <= self.tolerance
        else:
            chosen = in_box(vertices, self.box, what)
        nodes = np.flatnonzero(chosen)
        require(len(nodes) > 0, f"{what} holds no mesh vertex")
        return nodes


def vector(name: str, value) -> tuple[float, ...]:
    """A point or direction of 2 or 3 finite numbers (PneumaInputError naming it otherwise)."""
    require(shape_of(value) in ((2,), (3,)), f"{name} = {value!r} must be a list of 2 (2D) or 3 (3D) numbers")
    return tuple(require_finite(name, v) for v in value)


def require_box(name: str, box) -> None:
    """Refuse, naming it, a box that is not [x0, y0, x1, y1] (2D) or [x0, y0, z0, x1, y1, z1] (3D) of finite
    numbers with each lower bound below its upper one."""
    require(shape_of(box) in ((4,), (6,)),
            f"{name} = {box!r} must be [x0, y0, x1, y1] (or [x0, y0, z0, x1, y1, z1] in 3D)")
    for v in box:
        require_finite(name, v)
    half = len(box) // 2
    require(all(box[i] < box[half + i] for i in range(half)),
            f"{name} = {list(box)!r} must have x0 < x1 and y0 < y1" + (" and z0 < z1" if half == 3 else ""))


def in_box(points: np.ndarray, box, what: str = "box") -> np.ndarray:
    """Which points (k, d) lie in the closed box [x0, y0, (z0,) x1, y1, (z1)] of 2 d numbers."""
    d = points.shape[1]
    require(len(box) == 2 * d, f"{what}: box = {list(box)!r} must have {2 * d} numbers on this {d}D body")
    lower, upper = np.asarray(box[:d], dtype=np.float64), np.asarray(box[d:], dtype=np.float64)
    return np.all((points >= lower) & (points <= upper), axis=1)


@dataclass(frozen=True)
class Mesh:
    """A triangle mesh with the vertex sets a pneumatic scene needs.

    vertices: (n, 2) rest positions (the nodes); triangles: (m, 3) counter-clockwise corner indices
    (linear elements), or (m, 6) for quadratic ones: the corners, then the midside nodes of edges 01,
    12 and 20; chambers: the nodes of each chamber wall in the scene's order (quadratic: corner, midside,
    corner, ...), a closed loop, or for a chamber cut by symmetry lines an open chain from line to line,
    oriented so its enclosed area (enclosed_area with wall_origins) is positive; wall_origins: per chamber
    None (a closed loop) or the origin o of an open wall's area, on the lines; boundary: the nodes on the
    body's outer boundary; pinned: the clamped nodes (none without a clamp); tip: the tip's nodes (the right
    edge by default); rollers: per roller, (its held nodes, its unit normal).
    """

    vertices: np.ndarray
    triangles: np.ndarray
    chambers: tuple[np.ndarray, ...]
    boundary: np.ndarray
    pinned: np.ndarray
    tip: np.ndarray
    wall_origins: tuple[np.ndarray | None, ...]
    rollers: tuple[tuple[np.ndarray, np.ndarray], ...]

    @property
    def n_vertices(self) -> int:
        return len(self.vertices)

    @property
    def n_triangles(self) -> int:
        return len(self.triangles)

    dim = 2
    elements = property(lambda self: self.triangles, doc="the elements (the dimension-neutral name of triangles)")
    n_elements = n_triangles
    measure = property(lambda self: self.area, doc="the body's rest measure: its area in 2D, its volume in 3D")

    @property
    def order(self) -> int:
        """1 for linear triangles, 2 for quadratic ones."""
        return 1 if self.triangles.shape[1] == 3 else 2

    @property
    def area(self) -> float:
        """Total rest area of the triangles (curved ones' included: see nodal_areas)."""
        if self.order == 2:
            return float(np.sum(self.nodal_areas()))
        return float(np.sum(triangle_areas(self.vertices, self.triangles)))

    def display_triangles(self) -> np.ndarray:
        """Linear triangles to draw: the triangles themselves, or each quadratic one split in four at its
        midside nodes (corner triangles, then the middle one)."""
        return self.triangles if self.order == 1 else split_in_four(self.triangles)

    def nodal_measures(self) -> np.ndarray:
        """The integral of each node's shape function over the body: nodal_areas() in 2D."""
        return self.nodal_areas()

    def nodal_areas(self) -> np.ndarray:
        """The integral of each node's shape function over the body, sum_t int_t N_a dA: a third of the
        area of the triangles at a node for linear elements. For quadratic ones int N_a det(dX/dxi) dxi
        by the degree-4 rule, exact (N_a and det dX/dxi are quadratic): 0 at corners and a third of the
        triangle's area at midside nodes on a straight-sided triangle, and the exact measure of a triangle
        with a curved (parabolic) side. Either way the exact weights of a load linear in x."""
        out = np.zeros(self.n_vertices)
        if self.order == 1:
            np.add.at(out, self.triangles.ravel(), np.repeat(triangle_areas(self.vertices, self.triangles) / 3, 3))
            return out
        points, weights = TRIANGLE_P2.cell.rules[4]
        measures = 0.5 * jacobians(self.vertices, self.triangles, points) * weights  # (m, 6 points)
        np.add.at(out, self.triangles.ravel(), (measures @ TRIANGLE_P2.shape_functions(points)).ravel())
        return out


def triangle_areas(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    p0, p1, p2 = (vertices[triangles[:, i]] for i in range(3))
    e1, e2 = p1 - p0, p2 - p0
    return 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])


@dataclass(frozen=True)
class Geometry:
    """A body shape with named chamber shapes, a mesh density and the named node sets: the clamp (None, the
    default: none), the tip (the right edge by default) and the rollers.

    A chamber lies inside the body, or is cut by symmetry lines: roller lines along an edge of the body. A
    chamber crossing such lines keeps its part on the body's side (cut_by_lines), a notch in the body's
    outline whose wall runs from line to line; its area is closed by the flat cap along the lines."""

    body: object
    chambers: tuple[tuple[str, object], ...]
    max_area: float | None = si_default(0.0012, PLANE_AREA, scaled=False)  # None: 0.0012, unitless scenes only
    clamp: PointSet | None = None
    order: int = 1
    refinements: int = 0
    tip: PointSet = field(default_factory=lambda: PointSet("right"))
    rollers: tuple[Roller, ...] = ()

    dim = 2

    def __post_init__(self):
        require(self.max_area is None or require_finite("max_area", self.max_area) > 0,
                f"max_area = {self.max_area!r} must be > 0")
        require(self.order in ORDERS, f"order = {self.order!r} must be 1 (linear triangles) or 2 (quadratic)")
        require(self.refinements in range(MAX_REFINEMENTS + 1),
                f"refinements = {self.refinements!r} must be an integer from 0 to {MAX_REFINEMENTS}")
        require(len(self.chambers) <= MAX_SHAPES, f"{len(self.chambers)} chambers: at most {MAX_SHAPES} are allowed")
        require(len(self.rollers) <= MAX_SHAPES, f"{len(self.rollers)} rollers: at most {MAX_SHAPES} are allowed")
        for roller in self.rollers:
            require(len(roller.normal) == 2,
                    f"roller normal = {list(roller.normal)!r}: a 2D body's rollers have 2 components")
        for name, shape in self.chambers:
            require(callable(getattr(shape, "polygon", None)), f"chamber {name!r}: a {type(shape).__name__} wall needs "
                                                               f"a body from a mesh file or 3D shapes (a 3D body)")
        body = self.body.polygon()
        polygons = [(name, shape.polygon()) for name, shape in self.chambers]
        points = len(body) + sum(len(p) for _, p in polygons)
        require(points <= MAX_WALL_POINTS, f"the body and chamber outlines have {points} points in all; "
                                           f"at most {MAX_WALL_POINTS} are allowed")
        names = [name for name, _ in polygons]
        require_distinct("chamber names", names)
        for name in names:
            check_heading("chamber name", name)
        for what, poly in [("the body", body)] + [(f"chamber {name!r}", poly) for name, poly in polygons]:
            require_spaced(what, poly)
        outline, _, walls = self.outline()
        if any(origin is not None for _, origin in walls):
            require_spaced("the body with its cut chambers", outline)
            require(not polygon_self_intersects(outline), "the body's outline, with the chambers cut by symmetry "
                                                          "lines notched into it, crosses itself")
        polygons = [(name, poly) for (name, poly), (_, origin) in zip(polygons, walls) if origin is None]
        for name, poly in polygons:
            outside = ~points_in_polygon(poly, outline) | (distance_to_polygon(poly, outline) < MARGIN)
            crossing = segments_cross(poly, np.roll(poly, -1, axis=0), outline, np.roll(outline, -1, axis=0)).any()
            require(not outside.any() and not crossing,
                    f"chamber {name!r} is not inside the body (a wall point at {poly[np.argmax(outside)].tolist()} "
                    f"lies outside it or closer than {MARGIN:g} to its boundary)")
        for i, (name_a, a) in enumerate(polygons):
            for name_b, b in polygons[i + 1:]:
                touching = (points_in_polygon(a, b).any() or points_in_polygon(b, a).any()
                            or distance_to_polygon(a, b).min() < MARGIN
                            or segments_cross(a, np.roll(a, -1, axis=0), b, np.roll(b, -1, axis=0)).any())
                require(not touching, f"chambers {name_a!r} and {name_b!r} overlap (or are closer than {MARGIN:g})")

    def outline(self) -> tuple[np.ndarray, np.ndarray, list]:
        """(outline, markers, walls): the body's outline with the chambers cut by symmetry lines notched into it
        (the body polygon itself when none is), its per-segment markers (OUTER_MARKER on the body, OUTER_MARKER + c
        on the wall of chamber c = 1, 2, ...), and per chamber (wall points, origin) as cut_by_lines gives them."""
        body = self.body.polygon()
        tol = CUT_TOLERANCE * float(np.ptp(body, axis=0).max())
        lines = symmetry_lines(body, self.rollers, tol)
        outline, markers, walls = body, np.full(len(body), OUTER_MARKER), []
        for c, (name, shape) in enumerate(self.chambers, start=1):
            wall, origin = cut_by_lines(shape.polygon(), lines, tol, f"chamber {name!r}")
            if origin is not None:
                outline, markers = notch(outline, markers, wall, origin, OUTER_MARKER + c, tol, f"chamber {name!r}")
            walls.append((wall, origin))
        return outline, markers, walls

    def mesh(self) -> Mesh:
        """Mesh the body minus its chambers with Triangle ('pqa<max_area>'), split every triangle in four
        `refinements` times (uniform refinement: h halved each time), add a midside node to every edge for
        quadratic triangles, and name the node sets. A refined or quadratic mesh has its boundary nodes on the
        exact curves of ellipses and rounded corners (onto_curves; module docstring). In a limits.budget,
        Triangle adds at most limits.element_cap points and a mesh past the budget is refused."""
        require(self.max_area is not None, "max_area = None: the Scene sets the default (0.0012 in a unitless scene); "
                                           "give max_area to mesh a Geometry on its own")
        outline, outline_markers, walls = self.outline()
        closed = [c for c, (_, origin) in enumerate(walls, start=1) if origin is None]
        loops = [outline] + [walls[c - 1][0] for c in closed]
        offsets = np.cumsum([0] + [len(p) for p in loops])
        ring = lambda n, offset: offset + np.column_stack([np.arange(n), (np.arange(n) + 1) % n])
        pslg = {
            "vertices": np.vstack(loops),
            "segments": np.vstack([ring(len(p), o) for p, o in zip(loops, offsets)]),
            "segment_markers": np.concatenate([outline_markers] + [np.full(len(walls[c - 1][0]), OUTER_MARKER + c)
                                                                   for c in closed]),
        }
        if closed:
            pslg["holes"] = np.array([interior_point(p) for p in loops[1:]])
        weight = 4 ** self.refinements * (4 if self.order == 2 else 1)  # linear triangles per Triangle's one
        cap = limits.element_cap(weight)  # Triangle adds at most this many points (S), then stops
        out = triangulate(pslg, f"pqa{self.max_area:.17f}" + ("" if cap is None else f"S{cap}"))  # no exponent
        added = len(out["vertices"]) - len(pslg["vertices"])
        limits.check_mesh(len(out["triangles"]), weight, "Triangle", cap if cap is not None and added >= cap else None)
        vertices = np.asarray(out["vertices"], dtype=np.float64)
        triangles = orient_counter_clockwise(vertices, np.asarray(out["triangles"], dtype=np.int64))
        segments, markers = np.asarray(out["segments"], dtype=np.int64), out["segment_markers"].ravel()
        shapes = [self.body] + [shape for _, shape in self.chambers]  # the shape of marker OUTER_MARKER + c
        curves = {OUTER_MARKER + c: shape.project for c, shape in enumerate(shapes) if hasattr(shape, "project")}
        if self.order == 2 or self.refinements:
            vertices = onto_curves(vertices, segments, markers, curves, triangles)
        for _ in range(self.refinements):
            vertices, mid = with_edge_midpoints(vertices, triangles)
            triangles = split_in_four(np.column_stack([triangles, mid(triangles[:, [0, 1, 2]], triangles[:, [1, 2, 0]])]))
            segments, markers = halved(segments, markers, mid)
            vertices = onto_curves(vertices, segments, markers, curves, triangles)
        mid = None
        if self.order == 2:
            vertices, mid = with_edge_midpoints(vertices, triangles)
            triangles = np.column_stack([triangles, mid(triangles[:, [0, 1, 2]], triangles[:, [1, 2, 0]])])
            vertices = onto_curves(vertices, *halved(segments, markers, mid), curves, triangles)
        chambers = []
        for c, (_, origin) in enumerate(walls, start=1):
            nodes = chain(segments[markers == OUTER_MARKER + c], closed=origin is None)
            nodes = nodes if enclosed_area(vertices[nodes], origin) > 0 else nodes[::-1].copy()
            if mid is not None:  # corner, midside, corner, ...: each edge from its first corner
                starts = nodes if origin is None else nodes[:-1]
                edges = np.column_stack([starts, mid(starts, np.roll(nodes, -1)[:len(starts)])]).ravel()
                nodes = edges if origin is None else np.append(edges, nodes[-1])
            chambers.append(nodes)
        outer = segments[markers == OUTER_MARKER]
        boundary = np.unique(outer if mid is None else np.column_stack([outer, mid(outer[:, 0], outer[:, 1])]))
        return Mesh(vertices, triangles, tuple(chambers), boundary, clamped(self.clamp, vertices),
                    self.tip.select(vertices, "tip"), tuple(origin for _, origin in walls),
                    tuple((roller.select(vertices), roller.unit_normal) for roller in self.rollers))


def require_spaced(what: str, polygon: np.ndarray) -> None:
    """Refuse an outline with two points closer than MIN_SPACING of its size (Triangle crashes on them)."""
    size = float(np.ptp(polygon, axis=0).max())
    require(np.isfinite(size), f"{what}: its outline points overflow to infinity")
    require(not has_close_pair((polygon - polygon.min(axis=0)) / size, MIN_SPACING),
            f"{what}: two of its outline points coincide (closer than {MIN_SPACING:g} of its size {size:.3g}): "
            f"a radius, size or point spacing too small, or coordinates too large, to mesh")


def has_close_pair(points: np.ndarray, r: float) -> bool:
    """Whether two of the points (n, 2) lie within distance r (<=) of each other. Sorted by x, point i can only
    be that close to the points after it whose x is at most x_i + r: those candidate pairs (all pairs at worst,
    when the points share one x) are compared at once."""
    p = points[np.argsort(points[:, 0], kind="stable")]
    counts = np.searchsorted(p[:, 0], p[:, 0] + r, side="right") - np.arange(1, len(p) + 1)
    first = np.repeat(np.arange(len(p)), counts)
    second = first + 1 + np.arange(len(first)) - np.repeat(np.cumsum(counts) - counts, counts)
    return bool(np.any(np.sum((p[second] - p[first]) ** 2, axis=1) <= r * r))


def with_edge_midpoints(vertices: np.ndarray, elements: np.ndarray, edges=((0, 1), (1, 2), (2, 0))):
    """The vertices with the midpoint of every edge of the (corner) elements appended, and mid(a, b): the
    index of the midpoint of edge (a, b), elementwise over index arrays. edges: the corner pairs of an
    element that are its edges (a triangle's by default)."""
    unique = np.unique(np.sort(np.vstack([elements[:, list(e)] for e in edges]), axis=1), axis=0)
    n = len(vertices)
    keys = unique[:, 0] * n + unique[:, 1]

    def mid(a, b):
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        return n + np.searchsorted(keys, lo * n + hi)

    return np.vstack([vertices, 0.5 * (vertices[unique[:, 0]] + vertices[unique[:, 1]])]), mid


def halved(segments: np.ndarray, markers: np.ndarray, mid) -> tuple[np.ndarray, np.ndarray]:
    """Boundary segments (s, 2) and their markers split at their midpoint nodes mid(a, b): (2 s, 2), (2 s,)."""
    halves = mid(segments[:, 0], segments[:, 1])
    return (np.vstack([np.column_stack([segments[:, 0], halves]), np.column_stack([halves, segments[:, 1]])]),
            np.concatenate([markers, markers]))


def onto_curves(vertices: np.ndarray, segments: np.ndarray, markers: np.ndarray, curves: dict,
                triangles: np.ndarray) -> np.ndarray:
    """The vertices with every node of the boundary segments of marker m moved onto the exact curve of the
    shape they came from, curves[m] (its project: an ellipse, a rounded corner; a marker without a curve, a
    straight polygon, leaves its nodes). A node on segments of two markers stays: the end of a chamber wall
    cut by a symmetry line, on the line. A triangle (linear (m, 3) or quadratic (m, 6)) the moves would fold
    (det dX/dxi <= 0 at one of its nodes, where the mesh is too coarse for the curve) keeps its nodes where
    they were: a quadratic one's midside nodes at its edges' middles."""
    count = len(vertices)
    lowest, highest = np.full(count, np.iinfo(np.int64).max), np.full(count, -1)
    np.minimum.at(lowest, segments.ravel(), np.repeat(markers, 2))
    np.maximum.at(highest, segments.ravel(), np.repeat(markers, 2))
    moved = vertices.copy()
    for marker, project in curves.items():
        nodes = np.flatnonzero((lowest == marker) & (highest == marker))
        moved[nodes] = project(vertices[nodes])
    linear = triangles.shape[1] == 3
    at_nodes = triangle_areas(moved, triangles)[:, None] if linear else jacobians(moved, triangles,
                                                                                    TRIANGLE_P2.reference_nodes)
    folded = triangles[np.min(at_nodes, axis=1) <= 0].ravel()
    moved[folded] = vertices[folded]
    return moved


def jacobians(vertices: np.ndarray, triangles: np.ndarray, points: np.ndarray) -> np.ndarray:
    """det dX/dxi (m, p) of quadratic triangles (m, 6) at reference points (p, 2), dX/dxi = sum_a X_a dN_a/dxi
    (isoparametric: twice the area of a straight-sided triangle, the same at every point)."""
    j = np.swapaxes(vertices[triangles], 1, 2)[:, None] @ TRIANGLE_P2.shape_gradients(points)[None]  # (m, p, 2, 2)
    return j[..., 0, 0] * j[..., 1, 1] - j[..., 0, 1] * j[..., 1, 0]


def split_in_four(triangles: np.ndarray) -> np.ndarray:
    """The four corner-and-midpoint triangles of each (m, 6) triangle (corners, then edge midpoints 01, 12,
    20): the three corner triangles, then the middle one; all counter-clockwise when the input is."""
    c0, c1, c2, m01, m12, m20 = triangles.T
    return np.vstack([np.column_stack(t) for t in ((c0, m01, m20), (m01, c1, m12), (m20, m12, c2), (m01, m12, m20))])


@dataclass(frozen=True)
class BeamGeometry:
    """The reference beam: a rectangle L x H centred at the origin with an elliptical chamber (a, b) at (cx, cy)."""

    length: float = 3.5
    height: float = 0.8
    a: float = 0.85
    b: float = 0.22
    cx: float = 0.0
    cy: float = 0.0
    chamber_points: int = 128
    max_area: float = 0.0012
    order: int = 1
    refinements: int = 0

    def __post_init__(self):
        for name in ("length", "height", "a", "b", "cx", "cy", "max_area"):
            require_finite(name, getattr(self, name))
        for name in ("length", "height", "a", "b", "max_area"):
            require(getattr(self, name) > 0, f"{name} = {getattr(self, name)!r} must be > 0")
        require(
            isinstance(self.chamber_points, (int, np.integer)) and self.chamber_points >= 8,
            f"chamber_points = {self.chamber_points!r} must be an integer >= 8",
        )
        require(
            abs(self.cy) + self.b < self.height / 2 - MARGIN,
            f"chamber escapes the beam vertically: |cy| + b = {abs(self.cy) + self.b:.4g} "
            f"(cy = {self.cy:g}, b = {self.b:g}) must be < H/2 - {MARGIN:g} = {self.height / 2 - MARGIN:.4g}",
        )
        require(
            abs(self.cx) + self.a < self.length / 2,
            f"chamber escapes the beam horizontally: |cx| + a = {abs(self.cx) + self.a:.4g} "
            f"(cx = {self.cx:g}, a = {self.a:g}) must be < L/2 = {self.length / 2:.4g}",
        )

    def general(self) -> Geometry:
        """The same beam as a general Geometry (body rectangle, one ellipse chamber named 'main', left clamp)."""
        return Geometry(Rectangle((0.0, 0.0), (self.length, self.height)),
                        (("main", Ellipse((self.cx, self.cy), (self.a, self.b), self.chamber_points)),),
                        self.max_area, PointSet("left"), order=self.order, refinements=self.refinements)

    def mesh(self) -> Mesh:
        return self.general().mesh()


def triangulate(pslg: dict, flags: str) -> dict:
    """triangulation.triangulate, with its failure (RuntimeError, or no triangle made) a PneumaInputError."""
    try:
        out = triangulation.triangulate(pslg, flags)
    except RuntimeError:
        out = {}
    require(len(out.get("triangles", ())) > 0, "Triangle could not mesh the geometry (it ran out of floating-point "
                                               "precision: features too small for the body's size?)")
    return out


def orient_counter_clockwise(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Return triangles with every vertex triple ordered counter-clockwise."""
    clockwise = triangle_areas(vertices, triangles) < 0
    fixed = triangles.copy()
    fixed[clockwise] = fixed[clockwise][:, [0, 2, 1]]
    return fixed


def chain(edges: np.ndarray, closed: bool = True) -> np.ndarray:
    """Order the undirected edges of one curve into its nodes: a closed loop (first node not repeated) or an
    open chain from one end to the other."""
    neighbours: dict[int, list[int]] = {}
    for i, j in edges:
        neighbours.setdefault(int(i), []).append(int(j))
        neighbours.setdefault(int(j), []).append(int(i))
    ends = [v for v, n in neighbours.items() if len(n) == 1]
    if any(len(n) > 2 for n in neighbours.values()) or len(ends) != (0 if closed else 2):
        raise PneumaInputError(f"Triangle could not keep a chamber wall a simple {'closed loop' if closed else 'open chain'}")
    start = int(edges[0][0]) if closed else ends[0]
    nodes, previous, current = [start], None, start
    while True:
        following = [v for v in neighbours[current] if v != previous]
        if not following or following[0] == start:
            break
        previous, current = current, following[0]
        nodes.append(current)
    if len(nodes) != len(neighbours):
        raise PneumaInputError("Triangle split a chamber wall into more than one piece")
    return np.array(nodes, dtype=np.int64)
