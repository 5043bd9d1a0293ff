"""The rigid obstacles' shapes (an [[obstacles]] table's shape): plane, box, sphere, cylinder and capsule, each a
frozen dataclass of its keys (io/registry.py key: doc and unit), registered in OBSTACLE_SHAPES under its name, with

    kind          the kernels' shape index: its branch of signed_distance (terms/obstacle_distance.py)
    parameters()  the floats the kernels read: a point, a vector, a radius, a half-length
    linear        whether its signed distance is affine in x (a plane): the step bound is then exact
    outline()     its boundary in the x-y plane, drawn in a 2D scene's frames and ParaView files
    surface()     its boundary in 3D as triangles (and the creases a drawing outlines), drawn by ParaView's files
                  (render/paraview_parts.py) and the 3D frames and the live window (render/guides3d.py) alike
    features()    the feature set the edge barriers keep the body's surface from (terms/obstacle_edges.py)

so that a new shape is its class here and its signed distance in terms/obstacle_distance.py: nothing else
dispatches on the shape.

A sphere, a cylinder (flat caps) and a capsule (hemispherical caps) are triangulated as surfaces of revolution about
their axis (SEGMENTS points round, a pole point at each end, LATITUDES rings from a pole to a sphere's equator), a box
as its 12 triangles, a plane as a square patch of half-size reach centred on the point of the plane nearest a given
centre. Every point lies on the shape's boundary; the triangles are wound outwards (a plane's towards its normal).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numpy as np

from ..errors import require, require_finite, require_positive
from ..io.registry import Registry, key
from ..io.units import LENGTH

PLANE, SPHERE, BOX, CYLINDER, CAPSULE = range(5)  # the kernels' shape kinds
AXES = ("x", "y", "z")
POINT = "[x, y] (2D) or [x, y, z]"
OBSTACLE_SHAPES: Registry[type[Shape]] = Registry("obstacle shape")
SEGMENTS = 48  # points round a surface of revolution
LATITUDES = 12  # rings from pole to equator of a sphere, and of each cap of a capsule
SIGNS = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)  # box corners
BOX_EDGES = np.array([(i, j) for i in range(8) for j in range(i + 1, 8) if np.sum(SIGNS[i] != SIGNS[j]) == 1])
BOX_TRIANGLES = np.array(
    [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1)]  # outward
    + [(2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]
)
NO_EDGES = np.zeros((0, 2), dtype=int)


def vector(name: str, value, length: int | None = None) -> tuple[float, ...]:
    """A point or vector given as [x, y] (z = 0; 2D scenes only) or [x, y, z], as 3 floats."""
    require(
        isinstance(value, (tuple, list)) and len(value) in ((2, 3) if length is None else (length,)),
        f"{name} = {value!r} must be " + ("[x, y] or [x, y, z]" if length is None else f"{length} numbers"),
    )
    values = [require_finite(name, v) for v in value]
    return (*values, 0.0)[:3]


def axis_vector(axis: str) -> tuple[float, float, float]:
    require(axis in AXES, f"axis = {axis!r} is not one of {', '.join(AXES)}")
    k = AXES.index(axis)
    return float(k == 0), float(k == 1), float(k == 2)


class Surface(NamedTuple):
    """A shape's boundary in 3D where it is placed: points (k, 3), triangles (t, 3) of point indices wound outwards,
    and edges (e, 2) of point indices, the creases a drawing outlines (a box's 12, a plane's square's 4; none on a
    round surface)."""

    points: np.ndarray
    triangles: np.ndarray
    edges: np.ndarray


class Shape:
    """An obstacle shape (module docstring): kind, vectors (its keys that are points or vectors, which a 3D scene
    must give with 3 numbers), linear, and parameters(), outline(), surface() and features()."""

    name: ClassVar[str]  # its shape key's value
    kind: ClassVar[int]
    linear: ClassVar[bool] = False
    vectors: ClassVar[tuple[str, ...]] = ("center",)

    def parameters(self) -> np.ndarray:
        """The PARAMETERS floats its kernel branch reads (terms/obstacle_distance.py), the first 3 its position."""
        raise NotImplementedError

    def outline(self, reach: float) -> tuple[np.ndarray, bool]:
        """Its boundary in the x-y plane (a 2D scene's), as points (k, 2) and whether they close into a loop (a
        plane's line is the open segment of half-length reach about its point)."""
        raise NotImplementedError

    def surface(self, reach: float, centre: np.ndarray) -> Surface:
        """Its boundary in 3D where it is placed (module docstring); reach and centre (3,) place a plane's patch."""
        raise NotImplementedError

    def features(self, at: np.ndarray, dim: int) -> tuple[np.ndarray, np.ndarray, float]:
        """(points (k, dim), edges (m, 2, dim), R): a feature set F within R of which the shape lies, when its
        position is at (3,) (its parameters()[:3] moved by its offset), for the edge barriers
        (terms/obstacle_edges.py); none, the default, where it has none (a plane)."""
        return np.zeros((0, dim)), np.zeros((0, 2, dim)), 0.0


def circle(center, radius: float, points: int = 64) -> np.ndarray:
    """points on the circle of radius about center[:2], counter-clockwise."""
    theta = np.linspace(0.0, 2 * np.pi, points, endpoint=False)
    return np.asarray(center[:2], dtype=float) + radius * np.column_stack([np.cos(theta), np.sin(theta)])


def revolution(profile: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The surface of revolution about z of a profile (k, 2) of (radius, z) from pole to pole (its first and last
    radius 0): (points, triangles), each pole one point, each inner profile point a ring of SEGMENTS, triangles
    wound outwards."""
    theta = np.linspace(0.0, 2 * np.pi, SEGMENTS, endpoint=False)
    rings = [np.column_stack([r * np.cos(theta), r * np.sin(theta), np.full(SEGMENTS, z)]) for r, z in profile[1:-1]]
    points = np.vstack([[[0.0, 0.0, profile[0, 1]]], *rings, [[0.0, 0.0, profile[-1, 1]]]])
    top, j = len(points) - 1, np.arange(SEGMENTS)
    ring = lambda k: 1 + k * SEGMENTS + j  # noqa: E731
    after = lambda k: 1 + k * SEGMENTS + (j + 1) % SEGMENTS  # noqa: E731
    last = len(rings) - 1
    triangles = [np.column_stack([np.zeros(SEGMENTS, dtype=int), after(0), ring(0)])]
    for k in range(last):
        triangles.append(np.column_stack([ring(k), after(k), after(k + 1)]))
        triangles.append(np.column_stack([ring(k), after(k + 1), ring(k + 1)]))
    triangles.append(np.column_stack([np.full(SEGMENTS, top), ring(last), after(last)]))
    return points, np.vstack(triangles)


def revolved(center, profile: np.ndarray, rotation: np.ndarray) -> Surface:
    """The revolution() of profile (its ends taken to the axis: the poles) turned by rotation (3, 3) (z to the
    shape's axis) and moved to center."""
    profile[[0, -1], 0] = 0.0
    points, triangles = revolution(profile)
    return Surface(np.array(center, dtype=float) + points @ rotation.T, triangles, NO_EDGES)


def frame(axis: str) -> np.ndarray:
    """The rotation (3, 3) taking z to the axis (its columns: two unit vectors across it, then along it)."""
    along = np.array(axis_vector(axis))
    first = np.roll(along, 1)  # x -> y, y -> z, z -> x: a right-handed (first, along x first, along)
    return np.column_stack([first, np.cross(along, first), along])


def hemisphere(radius: float, z: float, sign: float) -> np.ndarray:
    """The profile (radius, z) of the cap of a sphere centred at height z, from its pole (sign -1: below, +1:
    above) to its equator, equator included."""
    phi = np.linspace(0.5 * np.pi, 0.0, LATITUDES + 1)
    return np.column_stack([radius * np.cos(phi), z + sign * radius * np.sin(phi)])


def ball(at: np.ndarray, radius: float, dim: int) -> tuple[np.ndarray, np.ndarray, float]:
    """features() of the ball (2D: the disc) of radius about at: its centre, R the radius."""
    return at[None, :dim], np.zeros((0, 2, dim)), float(radius)


def corners(at: np.ndarray, extent: np.ndarray, dim: int) -> tuple[np.ndarray, np.ndarray, float]:
    """features() of the box at +- extent (3,) about at: its corners (SIGNS; 2D the 4 of the rectangle) and, in 3D,
    its 12 edges, R = 0."""
    if dim == 2:
        return at[:2] + SIGNS[::2, :2] * extent[:2], np.zeros((0, 2, 2)), 0.0
    points = at + SIGNS * extent
    return points, points[BOX_EDGES], 0.0


def stadium(center, half: np.ndarray, radius: float, points: int = 32) -> np.ndarray:
    """The points within radius of the segment center -+ half (2D), its outline counter-clockwise."""
    c, half = np.asarray(center[:2], dtype=float), np.asarray(half, dtype=float)
    start = np.arctan2(half[1], half[0]) - np.pi / 2
    theta = start + np.linspace(0.0, np.pi, points)
    cap = radius * np.column_stack([np.cos(theta), np.sin(theta)])
    return np.vstack([c + half + cap, c - half - cap])


@OBSTACLE_SHAPES.register
@dataclass(frozen=True)
class Plane(Shape):
    """The half-space on the normal's side of the plane (2D: the line) through point."""

    point: tuple = key(doc=f"a point of it, {POINT}", unit=LENGTH)
    normal: tuple = key(doc="[nx, ny] or [nx, ny, nz], towards the body")
    name = "plane"
    kind = PLANE
    linear = True
    vectors = ("point", "normal")

    def __post_init__(self):
        vector("point", self.point)
        n = np.array(vector("normal", self.normal))
        require(np.linalg.norm(n) > 0, f"normal = {self.normal!r} must not be zero")

    def parameters(self) -> np.ndarray:
        n = np.array(vector("normal", self.normal))
        return np.array([*vector("point", self.point), *(n / np.linalg.norm(n)), 0.0, 0.0])

    def outline(self, reach: float) -> tuple[np.ndarray, bool]:
        p, n = np.array(self.point[:2], dtype=float), np.array(self.normal[:2], dtype=float)
        along = np.array([-n[1], n[0]]) / np.linalg.norm(n)
        return np.array([p - reach * along, p + reach * along]), False

    def surface(self, reach: float, centre: np.ndarray) -> Surface:
        """The square of half-side reach in the plane about the point of it nearest centre, and its 4 sides."""
        n = np.array(self.normal, dtype=float) / np.linalg.norm(self.normal)
        p = np.array(self.point, dtype=float)
        middle = centre - np.dot(centre - p, n) * n
        helper = np.eye(3)[int(np.argmin(np.abs(n)))]
        t1 = np.cross(n, helper) / np.linalg.norm(np.cross(n, helper))
        t2 = np.cross(n, t1)
        square = [middle + reach * (a * t1 + b * t2) for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        return Surface(np.array(square), np.array([[0, 1, 2], [0, 2, 3]]), np.array([[0, 1], [1, 2], [2, 3], [3, 0]]))


@OBSTACLE_SHAPES.register
@dataclass(frozen=True)
class Box(Shape):
    """An axis-aligned box; its size [w, h] in 2D ([w, h, depth] in 3D)."""

    center: tuple = key(doc=POINT, unit=LENGTH)
    size: tuple = key(doc="[w, h] (2D) or [w, h, depth]", unit=LENGTH)
    name = "box"
    kind = BOX
    vectors = ("center", "size")

    def __post_init__(self):
        vector("center", self.center)
        for s in vector("size", self.size)[: len(self.size)]:
            require_positive("size", s)

    def parameters(self) -> np.ndarray:
        half = [0.5 * s for s in self.size] + [1e300]  # a 2D box has no z extent
        return np.array([*vector("center", self.center), *half[:3], 0.0, 0.0])

    def outline(self, reach: float) -> tuple[np.ndarray, bool]:
        c, (w, h) = np.array(self.center[:2], dtype=float), np.array(self.size[:2], dtype=float) / 2
        return c + np.array([[-w, -h], [w, -h], [w, h], [-w, h]]), True

    def surface(self, reach: float, centre: np.ndarray) -> Surface:
        points = np.array(self.center, dtype=float) + SIGNS * (np.array(self.size, dtype=float) / 2)
        return Surface(points, BOX_TRIANGLES, BOX_EDGES)

    def features(self, at: np.ndarray, dim: int) -> tuple[np.ndarray, np.ndarray, float]:
        """Its corners and edges, R = 0."""
        return corners(at, self.parameters()[3:6], dim)


@OBSTACLE_SHAPES.register
@dataclass(frozen=True)
class Sphere(Shape):
    """A ball (2D: a disc) of the given radius."""

    center: tuple = key(doc=POINT, unit=LENGTH)
    radius: float = key(unit=LENGTH)
    name = "sphere"
    kind = SPHERE

    def __post_init__(self):
        vector("center", self.center)
        require_positive("radius", self.radius)

    def parameters(self) -> np.ndarray:
        return np.array([*vector("center", self.center), 0.0, 0.0, 0.0, self.radius, 0.0])

    def outline(self, reach: float) -> tuple[np.ndarray, bool]:
        return circle(self.center, self.radius), True

    def surface(self, reach: float, centre: np.ndarray) -> Surface:
        phi = np.linspace(-0.5 * np.pi, 0.5 * np.pi, 2 * LATITUDES + 1)
        profile = np.column_stack([self.radius * np.cos(phi), self.radius * np.sin(phi)])
        return revolved(self.center, profile, np.eye(3))

    def features(self, at: np.ndarray, dim: int) -> tuple[np.ndarray, np.ndarray, float]:
        """Its centre, R its radius."""
        return ball(at, self.radius, dim)


@OBSTACLE_SHAPES.register
@dataclass(frozen=True)
class Cylinder(Shape):
    """A circular cylinder with flat caps, its axis along x, y or z (2D: along z a disc, along x or y a rectangle)."""

    center: tuple = key(doc=POINT, unit=LENGTH)
    radius: float = key(unit=LENGTH)
    length: float = key(doc="its length along the axis (a capsule's: of its segment)", unit=LENGTH)
    axis: str = key("z", "its axis (2D: z a circle)", allowed=AXES)
    name = "cylinder"
    kind = CYLINDER

    def __post_init__(self):
        vector("center", self.center)
        require_positive("radius", self.radius)
        require_positive("length", self.length)
        axis_vector(self.axis)

    def parameters(self) -> np.ndarray:
        return np.array([*vector("center", self.center), *axis_vector(self.axis), self.radius, 0.5 * self.length])

    def outline(self, reach: float) -> tuple[np.ndarray, bool]:
        if self.axis == "z":
            return circle(self.center, self.radius), True
        along = np.array(axis_vector(self.axis)[:2]) * self.length / 2
        across = np.array([-along[1], along[0]]) / np.linalg.norm(along) * self.radius
        c = np.array(self.center[:2], dtype=float)
        return np.array([c - along - across, c + along - across, c + along + across, c - along + across]), True

    def profile(self) -> np.ndarray:
        """Its (radius, z) profile from pole to pole along its axis: the flat caps and the side."""
        r, h = self.radius, 0.5 * self.length
        return np.array([[0.0, -h], [r, -h], [r, h], [0.0, h]])

    def surface(self, reach: float, centre: np.ndarray) -> Surface:
        return revolved(self.center, self.profile(), frame(self.axis))

    def features(self, at: np.ndarray, dim: int) -> tuple[np.ndarray, np.ndarray, float]:
        """In 2D along z its centre, R its radius; along x or y the rectangle's corners; in 3D none (its rims and
        flat caps are not a feature set within one R)."""
        if dim == 3:
            return super().features(at, dim)
        if self.axis == "z":
            return ball(at, self.radius, dim)
        v = np.abs(np.array(axis_vector(self.axis)))
        return corners(at, 0.5 * self.length * v + self.radius * (1.0 - v), dim)


@OBSTACLE_SHAPES.register
@dataclass(frozen=True)
class Capsule(Cylinder):
    """The points within radius of a segment of the given length along x, y or z (2D along x or y: a stadium)."""

    name = "capsule"
    kind = CAPSULE

    def outline(self, reach: float) -> tuple[np.ndarray, bool]:
        if self.axis == "z":
            return circle(self.center, self.radius), True
        return stadium(self.center, np.array(axis_vector(self.axis)[:2]) * self.length / 2, self.radius), True

    def profile(self) -> np.ndarray:
        """A hemisphere, the side and a hemisphere."""
        r, h = self.radius, 0.5 * self.length
        return np.vstack([hemisphere(r, -h, -1.0), hemisphere(r, h, 1.0)[::-1]])

    def features(self, at: np.ndarray, dim: int) -> tuple[np.ndarray, np.ndarray, float]:
        """Its axis segment (2D along z: its centre), R its radius."""
        if dim == 2 and self.axis == "z":
            return ball(at, self.radius, dim)
        v = np.array(axis_vector(self.axis))
        ends = np.array([at - 0.5 * self.length * v, at + 0.5 * self.length * v])[:, :dim]
        return ends, (ends[None] if dim == 3 else np.zeros((0, 2, dim))), float(self.radius)
