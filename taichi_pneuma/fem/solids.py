"""3D shapes for bodies, chambers and material regions, each built as an OpenCASCADE solid in gmsh.

Axes: x along the body (the clamp at its left end), y up (the bending direction of a 2D scene),
z the depth (a 2D shape in the x-y plane is extruded along z). Shapes are axis-aligned:

- Box(center, size): the box center +- size / 2;
- RoundedBox(center, size, radius): the same box with every edge and corner rounded at `radius`,
  i.e. the inner box (size - 2 radius) swept by a ball of that radius;
- Ellipsoid(center, semi_axes): sum ((x_i - c_i) / a_i)^2 <= 1;
- Cylinder(center, radius, length, axis): a circular cylinder along axis 'x', 'y' or 'z';
- HalfCylinder(center, radius, length, axis, base, fillet): the half of that cylinder (axis 'x' or 'z') above the
  plane y = center y, on a box of height `base` below it as wide as the diameter: a flat bottom face and a round
  top, the section of a fibre-reinforced bending actuator's body (a base) and of its chamber (none, its edges
  rounded at `fillet` as a moulded chamber's are);
- Cut(shape, tools): a shape less other shapes (a block with slots cut into it);
- Extrusion(profile, depth, z): a 2D shape of the scene format (fem.shapes: Rectangle, Ellipse,
  RoundedRectangle, Polygon, RectangleUnion) swept along z from z - depth / 2 to z + depth / 2.
  Rectangles, ellipses and rounded rectangles are built from their exact curves (the 2D shape's
  `points` sampling does not apply: the 3D mesh size does); any other shape from its polygon().

The shapes a scene file names are parts declared as every named part is (io/registry.py): their fields its
keys (key(): doc and unit), their class attribute name its `shape = "..."`, registered in SOLIDS (the shapes bodies
and chambers share, in that order; scene/shape_keys.py reads them); the extrusion's profile is a 2D shape's table.

Each shape's build(occ) adds it to the current gmsh model through gmsh.model.occ and returns the new
volume's tag; gmsh itself is only imported by fem.gmsh_mesher, which calls these.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import require, require_finite, require_positive, shape_of
from ..io.registry import Registry, key
from ..io.units import LENGTH
from .shapes import PLANAR_BODIES, PLANAR_CHAMBERS, Ellipse, Rectangle, RoundedRectangle

AXES = ("x", "y", "z")
TRIPLE = "[x, y, z]"
SOLIDS: Registry = Registry("3D shape")  # shape = "..." of a 3D body or chamber, in the order registered


def _vector(name: str, value, positive: bool = False) -> tuple[float, float, float]:
    """value as three finite numbers (all > 0 if positive), or a PneumaInputError naming it."""
    require(shape_of(value) == (3,), f"{name} = {value!r} must be three numbers [x, y, z]")
    vector = (require_finite(name, value[0]), require_finite(name, value[1]), require_finite(name, value[2]))
    if positive:
        require(min(vector) > 0, f"{name} = {list(value)!r} must be > 0 in each of x, y, z")
    return vector


@SOLIDS.register
@dataclass(frozen=True)
class Box:
    """The axis-aligned box center +- size / 2."""

    center: tuple[float, float, float] = key(doc=TRIPLE, unit=LENGTH)
    size: tuple[float, float, float] = key(doc=TRIPLE, unit=LENGTH)
    name = "box"

    def __post_init__(self):
        _vector("center", self.center)
        _vector("size", self.size, positive=True)

    def build(self, occ) -> int:
        corner = np.subtract(self.center, np.divide(self.size, 2))
        return occ.addBox(*corner, *self.size)


@SOLIDS.register
@dataclass(frozen=True)
class RoundedBox:
    """A box whose 12 edges are quarter cylinders and 8 corners eighth spheres of `radius`
    (0 < radius < half the shortest side)."""

    center: tuple[float, float, float] = key(doc=TRIPLE, unit=LENGTH)
    size: tuple[float, float, float] = key(doc=TRIPLE, unit=LENGTH)
    radius: float = key(doc="below half the shortest side", unit=LENGTH)
    name = "rounded_box"

    def __post_init__(self):
        _vector("center", self.center)
        shortest = min(_vector("size", self.size, positive=True))
        r = require_finite("radius", self.radius)
        require(
            0 < r < shortest / 2, f"radius = {self.radius!r} must lie in (0, {shortest / 2:g}) (half the shortest side)"
        )

    def build(self, occ) -> int:
        before = set(occ.getEntities(1))
        box = Box(self.center, self.size).build(occ)
        edges = sorted(tag for _, tag in set(occ.getEntities(1)) - before)
        ((_, volume),) = occ.fillet([box], edges, [self.radius])
        return volume


@dataclass(frozen=True)
class Cut:
    """shape less the union of the tools (each a shape of this module): one volume, which the tools must not split."""

    shape: Any
    tools: tuple

    def build(self, occ) -> int:
        body = self.shape.build(occ)
        tools = [(3, tool.build(occ)) for tool in self.tools]
        cut, _ = occ.cut([(3, body)], tools)
        require(len(cut) == 1, f"the cut leaves {len(cut)} volumes: its tools must not split the shape")
        return cut[0][1]


@SOLIDS.register
@dataclass(frozen=True)
class Cylinder:
    """A circular cylinder of `radius` and `length` along `axis` ('x', 'y' or 'z'), centred on center."""

    center: tuple[float, float, float] = key(doc=TRIPLE, unit=LENGTH)
    radius: float = key(unit=LENGTH)
    length: float = key(unit=LENGTH)
    axis: str = key("z", "its axis", allowed=AXES)
    name = "cylinder"

    def __post_init__(self):
        _vector("center", self.center)
        require_positive("radius", self.radius)
        require_positive("length", self.length)
        require(self.axis in AXES, f"axis = {self.axis!r} is not one of {', '.join(AXES)}")

    def build(self, occ) -> int:
        direction = np.eye(3)[AXES.index(self.axis)] * self.length
        return occ.addCylinder(*(np.asarray(self.center) - direction / 2), *direction, self.radius)


@SOLIDS.register
@dataclass(frozen=True)
class HalfCylinder:
    """The half y >= center y of the circular cylinder of `radius` and `length` along `axis` ('x' or 'z', normal to
    y) centred on center, standing on a box of height `base` (>= 0) below the plane y = center y, of the cylinder's
    diameter and length: its flat face lies in the plane y = center y - base, its round side above. fillet > 0
    (with no base) rounds its edges (where the flat face meets the round side and the end caps) to that radius,
    as a moulded chamber's are: a sharp edge of a pressurised chamber is a stress singularity whose elements
    fold first."""

    center: tuple[float, float, float] = key(doc=f"{TRIPLE}: the middle of the flat face", unit=LENGTH)
    radius: float = key(unit=LENGTH)
    length: float = key(unit=LENGTH)
    axis: str = key("x", "its axis", allowed=("x", "z"))
    base: float = key(0.0, "the height of a box under the flat face, as wide as the diameter", unit=LENGTH)
    fillet: float = key(0.0, "the radius its edges are rounded to (0: sharp; with no base)", unit=LENGTH)
    name = "half_cylinder"

    def __post_init__(self):
        _vector("center", self.center)
        require_positive("radius", self.radius)
        require_positive("length", self.length)
        require(
            self.axis in ("x", "z"),
            f"axis = {self.axis!r} is not one of x, z (a half cylinder's flat face is normal to y)",
        )
        require(require_finite("base", self.base) >= 0, f"base = {self.base!r} must be >= 0")
        largest = min(self.radius, self.length) / 2
        require(
            0 <= require_finite("fillet", self.fillet) < largest,
            f"fillet = {self.fillet!r} must lie in [0, {largest:g}) (half the smaller of radius and length)",
        )
        require(
            self.fillet == 0 or self.base == 0,
            f"fillet = {self.fillet!r} takes base = 0, not {self.base!r} (a base's sides meet the round side smoothly)",
        )

    def build(self, occ) -> int:
        before = set(occ.getEntities(1))
        cylinder = Cylinder(self.center, self.radius, self.length, self.axis).build(occ)
        reach = 2 * (self.radius + self.length)  # a box over everything above the flat face
        corner = np.subtract(self.center, reach / 2) * [1, 0, 1] + [0, self.center[1], 0]
        upper = occ.addBox(*corner, reach, reach, reach)
        (kept, *_), _ = occ.intersect([(3, cylinder)], [(3, upper)])
        if self.fillet > 0:
            edges = sorted(tag for _, tag in set(occ.getEntities(1)) - before)
            ((_, volume),) = occ.fillet([kept[1]], edges, [self.fillet])
            return volume
        if self.base == 0:
            return kept[1]
        along = np.eye(3)[AXES.index(self.axis)]
        size = along * self.length + (1 - along) * 2 * self.radius
        size[1] = self.base
        corner = np.asarray(self.center) - size / 2 - [0, self.base / 2, 0]
        (fused, *_), _ = occ.fuse([kept], [(3, occ.addBox(*corner, *size))])
        return fused[1]


@SOLIDS.register
@dataclass(frozen=True)
class Ellipsoid:
    """The ellipsoid of semi-axes (a, b, c) along x, y, z about center."""

    center: tuple[float, float, float] = key(doc=TRIPLE, unit=LENGTH)
    semi_axes: tuple[float, float, float] = key(doc="[a, b, c]", unit=LENGTH)
    name = "ellipsoid"

    def __post_init__(self):
        _vector("center", self.center)
        _vector("semi_axes", self.semi_axes, positive=True)

    def build(self, occ) -> int:
        ball = occ.addSphere(*self.center, 1.0)
        occ.dilate([(3, ball)], *self.center, *self.semi_axes)
        return ball


@dataclass(frozen=True)
class Extrusion:
    """A 2D profile shape (in the x-y plane, with a polygon() method) swept along z over depth, centred on z."""

    profile: object  # its table is the 2D shapes' of the body or the chambers (scene/shape_keys.py extrusion)
    depth: float = key(doc="its extent along z", unit=LENGTH)
    z: float = key(0.0, "the z of its middle", unit=LENGTH)
    name = "extrusion"

    def __post_init__(self):
        require(
            callable(getattr(self.profile, "polygon", None)),
            f"profile = {self.profile!r} is not a 2D shape ({', '.join({**PLANAR_BODIES, **PLANAR_CHAMBERS})})",
        )
        require_positive("depth", self.depth)
        require_finite("z", self.z)

    def build(self, occ) -> int:
        z0 = self.z - self.depth / 2
        surface = _section(occ, self.profile, z0)
        extruded = occ.extrude([(2, surface)], 0.0, 0.0, self.depth)
        return next(tag for dim, tag in extruded if dim == 3)


def _section(occ, shape, z: float) -> int:
    """The plane surface of a 2D shape at height z: exact curves for rectangles, ellipses and rounded
    rectangles, the polygon() outline for any other shape."""
    if isinstance(shape, (Rectangle, RoundedRectangle)):
        (cx, cy), (w, h) = shape.center, shape.size
        radius = shape.radius if isinstance(shape, RoundedRectangle) else 0.0
        return occ.addRectangle(cx - w / 2, cy - h / 2, z, w, h, roundedRadius=radius)
    if isinstance(shape, Ellipse):
        (cx, cy), (a, b) = shape.center, shape.semi_axes
        # OpenCASCADE wants the major radius first: for b > a the ellipse's first axis is y
        return occ.addDisk(cx, cy, z, a, b) if a >= b else occ.addDisk(cx, cy, z, b, a, xAxis=[0, 1, 0])
    points = [occ.addPoint(x, y, z) for x, y in shape.polygon()]
    lines = [occ.addLine(p, q) for p, q in zip(points, points[1:] + points[:1])]
    return occ.addPlaneSurface([occ.addCurveLoop(lines)])
