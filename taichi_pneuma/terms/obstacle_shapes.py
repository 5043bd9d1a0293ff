"""The rigid obstacles' shapes (an [[obstacles]] table's shape): plane, box, sphere, cylinder and capsule, each a
frozen dataclass of its keys (io/registry.py key: doc and unit), registered in OBSTACLE_SHAPES under its name, with
kind (the kernels' shape index, terms/obstacle_distance.py), parameters() (the floats the kernels read: a point, a
vector, a radius, a half-length) and outline() (its boundary in the x-y plane, drawn in a 2D scene's frames).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..errors import require, require_finite, require_positive
from ..io.registry import Registry, key
from ..io.units import LENGTH

PLANE, SPHERE, BOX, CYLINDER, CAPSULE = range(5)  # the kernels' shape kinds
AXES = ("x", "y", "z")
POINT = "[x, y] (2D) or [x, y, z]"
OBSTACLE_SHAPES: Registry[type[Shape]] = Registry("obstacle shape")


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


class Shape:
    """An obstacle shape: kind (its kernel's shape index), vectors (its keys that are points or vectors, which a
    3D scene must give with 3 numbers) and parameters(): the PARAMETERS floats the kernels read."""

    name: ClassVar[str]  # its shape key's value
    kind = PLANE
    vectors: tuple[str, ...] = ("center",)

    def parameters(self) -> np.ndarray:
        raise NotImplementedError

    def outline(self, reach: float) -> tuple[np.ndarray, bool]:
        """Its boundary in the x-y plane (a 2D scene's), as points (k, 2) and whether they close into a loop (a
        plane's line is the open segment of half-length reach about its point)."""
        raise NotImplementedError


def circle(center, radius: float, points: int = 64) -> np.ndarray:
    """points on the circle of radius about center[:2], counter-clockwise."""
    theta = np.linspace(0.0, 2 * np.pi, points, endpoint=False)
    return np.asarray(center[:2], dtype=float) + radius * np.column_stack([np.cos(theta), np.sin(theta)])


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
