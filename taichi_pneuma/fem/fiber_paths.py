"""The curves an embedded fibre follows (a [[fibers]] table's `path`, chosen by its `layout` key): each a frozen
dataclass whose fields are its keys, checked on construction, with curves(spacing), a list of polylines (k, d)
sampling its curves with segments no longer than spacing (a closed curve's last point is not repeated: `closed`
says it joins its first), sample(spacing), all of them stacked, and size(spacing), the (curves, points) that
curves(spacing) makes, counted exactly without sampling (what the caps are checked on before any point is made).
axis is 'z' when not given.

    line      start, end: a straight cord (2D or 3D)
    polyline  points, at least 2: a cord through them (2D or 3D)
    rings     center (of the first ring), axis, radius, count, spacing: `count` closed circles of `radius` about
              the axis through center, the k-th centred at center + k spacing e_axis (3D)
    helix     center (a point on the axis where the helix starts), axis, radius, turns (or extent: its axial
              extent, extent / pitch turns), pitch (axial advance per
              turn) or angle (winding angle from the axis, degrees: pitch = 2 pi radius / tan(angle)),
              handedness, phase (the start angle, degrees) (3D)
    crossed   the keys of helix but handedness: a right-handed and a left-handed helix of the same start (3D)

A helix or crossed layout of `strands` n > 1 is n helices of each hand, their starts 360 / n degrees apart (a braid
of n carriers each way).

A helix or crossed pair with `flat` (a depth >= 0) winds on a D section instead of the circle: the half of the circle
above the plane through the axis normal to y (axis x or z), its two sides continued straight down to `flat` below the
axis and joined there by a straight bottom (a fibre-reinforced bending actuator's section: the thread runs around
its round top and across its flat base). Its perimeter P = pi radius + 2 flat + 2 radius takes the circle's place:
pitch = P / tan(angle), and the curve at parameter t is the point at arc length (phase / 360 + s t) P along the
section (counted from its top, counter-clockwise about +axis), advanced pitch t along the axis.

A helix is x(t) = center + radius (cos theta e_1 + sin theta e_2) + pitch t e_axis, t in [0, turns], with
theta = phase + s 2 pi t, s = +1 for a right-handed helix and -1 for a left-handed one, where (e_1, e_2, e_axis)
is the right-handed frame (y, z, x), (z, x, y), (x, y, z) of axis x, y, z: a right-handed helix turns
counter-clockwise seen from +axis (looking back down it) while it advances along +axis (the right-hand rule
about +axis, as a common screw thread); a left-handed one clockwise.

In 2D only line and polyline apply (a layer of cords per unit depth); PLANAR names them. Each layout is registered
in LAYOUTS under its name (io/registry.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from ..errors import require, require_finite, require_positive, shape_of
from ..io.registry import Registry
from ..io.units import LENGTH, unit

AXES = ("x", "y", "z")
FRAMES = {"x": (1, 2, 0), "y": (2, 0, 1), "z": (0, 1, 2)}  # (e_1, e_2, e_axis) indices: right-handed
HANDEDNESS = ("right", "left")
MAX_STRANDS = 256  # helices of one hand in a helix or crossed layout (a braid)
LAYOUTS: Registry[type[Layout]] = Registry("fibre layout")  # name -> the layout, filled by @LAYOUTS.register


def _point(name: str, value) -> np.ndarray:
    """value as 2 or 3 finite numbers, or a PneumaInputError naming it."""
    require(shape_of(value) in ((2,), (3,)), f"{name} = {value!r} must be a point [x, y] or [x, y, z]")
    return np.array([require_finite(name, v) for v in value])


def ceiling(x: float) -> int:
    """ceil(x), x capped at 2^62 (a count past every cap; an infinite quotient of finite numbers, 1e300 / 1e-300,
    has no ceiling)."""
    return math.ceil(min(x, 2.0**62))


def pieces(corners: np.ndarray, spacing: float, closed: bool = False) -> list[int]:
    """How many equal pieces no longer than spacing each side of the polyline through corners is cut into:
    max(1, ceil(|b - a| / spacing)) (closed: the side from the last corner back to the first too)."""
    ends = np.vstack([corners, corners[:1]]) if closed else corners
    return [max(1, ceiling(float(np.linalg.norm(b - a)) / spacing)) for a, b in zip(ends[:-1], ends[1:])]


def sampled(corners: np.ndarray, spacing: float, closed: bool = False) -> np.ndarray:
    """The polyline through corners (k, d) with each side cut into its pieces(corners, spacing, closed) (closed:
    the side from the last corner back to the first too, whose end is not repeated): sum(pieces) points, one more
    if open."""
    ends = np.vstack([corners, corners[:1]]) if closed else corners
    cuts = pieces(corners, spacing, closed)
    parts = [a + np.outer(np.arange(n) / n, b - a) for a, b, n in zip(ends[:-1], ends[1:], cuts)]
    return np.vstack(parts if closed else [*parts, ends[-1:]])


class Layout:
    """A fibre's curves: curves(spacing) -> polylines; name: its layout key's value; closed: whether each joins its
    last point to its first; planar: whether it applies in 2D."""

    name: ClassVar[str]
    closed = False
    planar = True

    def curves(self, spacing: float) -> list[np.ndarray]:
        raise NotImplementedError

    def size(self, spacing: float) -> tuple[int, int]:
        """(curves, points) of curves(spacing), counted without sampling."""
        raise NotImplementedError

    def sample(self, spacing: float) -> np.ndarray:
        """Every curve's samples (P, d), curve after curve."""
        return np.vstack(self.curves(spacing))

    @property
    def dim(self) -> int:
        return 3


@LAYOUTS.register
@dataclass(frozen=True)
class Line(Layout):
    """A straight cord from start to end."""

    name = "line"

    start: tuple = field(metadata=unit(LENGTH))
    end: tuple = field(metadata=unit(LENGTH))

    def __post_init__(self):
        a, b = _point("start", self.start), _point("end", self.end)
        require(len(a) == len(b), f"start = {list(self.start)!r} and end = {list(self.end)!r} differ in dimension")
        require(np.any(a != b), f"start = end = {list(self.start)!r}: a line needs two distinct points")

    @property
    def dim(self) -> int:
        return len(self.start)

    def curves(self, spacing: float) -> list[np.ndarray]:
        return [sampled(np.array([self.start, self.end], dtype=float), spacing)]

    def size(self, spacing: float) -> tuple[int, int]:
        return 1, sum(pieces(np.array([self.start, self.end], dtype=float), spacing)) + 1


@LAYOUTS.register
@dataclass(frozen=True)
class Polyline(Layout):
    """A cord through points (at least 2), in order."""

    name = "polyline"

    points: tuple = field(metadata=unit(LENGTH))

    def __post_init__(self):
        require(
            isinstance(self.points, (tuple, list)) and len(self.points) >= 2,
            f"points = {self.points!r} must list at least 2 points",
        )
        corners = [_point(f"points[{i}]", p) for i, p in enumerate(self.points)]
        require(len({len(c) for c in corners}) == 1, f"points = {list(self.points)!r} mix 2D and 3D points")
        steps = np.linalg.norm(np.diff(np.array(corners), axis=0), axis=1)
        require(np.all(steps > 0), f"points = {list(self.points)!r} repeat a point ({int(np.argmin(steps)) + 1})")

    @property
    def dim(self) -> int:
        return len(self.points[0])

    def curves(self, spacing: float) -> list[np.ndarray]:
        return [sampled(np.array(self.points, dtype=float), spacing)]

    def size(self, spacing: float) -> tuple[int, int]:
        return 1, sum(pieces(np.array(self.points, dtype=float), spacing)) + 1


def _frame(center, axis: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(center, e_1, e_2, e_axis) of the right-handed frame about axis."""
    e = np.eye(3)
    i, j, k = FRAMES[axis]
    return np.array(center, dtype=float), e[i], e[j], e[k]


def _check_axis_center(center, axis) -> None:
    require(shape_of(center) == (3,), f"center = {center!r} must be a point [x, y, z] (3D)")
    _point("center", center)
    require(axis in AXES, f"axis = {axis!r} is not one of {', '.join(AXES)}")


@LAYOUTS.register
@dataclass(frozen=True)
class Rings(Layout):
    """count closed circles of radius about the axis, the first centred at center, the next ones spacing apart
    along +axis."""

    name = "rings"

    center: tuple = field(metadata=unit(LENGTH))
    radius: float = field(metadata=unit(LENGTH))
    count: int
    spacing: float = field(metadata=unit(LENGTH))
    axis: str = "z"
    closed = True
    planar = False

    def __post_init__(self):
        _check_axis_center(self.center, self.axis)
        require_positive("radius", self.radius)
        require(
            isinstance(self.count, int) and not isinstance(self.count, bool) and self.count >= 1,
            f"count = {self.count!r} must be a whole number >= 1",
        )
        require_positive("spacing", self.spacing)

    def ring_points(self, spacing: float) -> int:
        """The points of each ring: max(3, ceil(2 pi radius / spacing)), a triangle at the least."""
        return max(3, ceiling(2 * math.pi * self.radius / spacing))

    def curves(self, spacing: float) -> list[np.ndarray]:
        c, e1, e2, ea = _frame(self.center, self.axis)
        n = self.ring_points(spacing)
        theta = 2 * math.pi * np.arange(n) / n
        circle = self.radius * (np.outer(np.cos(theta), e1) + np.outer(np.sin(theta), e2))
        return [c + k * self.spacing * ea + circle for k in range(self.count)]

    def size(self, spacing: float) -> tuple[int, int]:
        return self.count, self.count * self.ring_points(spacing)


@dataclass(frozen=True)
class Spiral(Layout):
    """What a helix and a crossed pair share: the axis, start, radius, turns and pitch (or angle) of a helix."""

    center: tuple = field(metadata=unit(LENGTH))
    radius: float = field(metadata=unit(LENGTH))
    turns: float | None = None
    axis: str = "z"
    pitch: float | None = field(default=None, metadata=unit(LENGTH))
    angle: float | None = None
    phase: float = 0.0
    flat: float | None = field(default=None, metadata=unit(LENGTH))
    extent: float | None = field(default=None, metadata=unit(LENGTH))
    strands: int = 1
    planar = False

    def __post_init__(self):
        _check_axis_center(self.center, self.axis)
        require_positive("radius", self.radius)
        require(
            (self.turns is None) != (self.extent is None),
            f"turns = {self.turns!r}, extent = {self.extent!r}: give exactly one of turns and extent",
        )
        require_positive(
            "turns" if self.extent is None else "extent", self.turns if self.extent is None else self.extent
        )
        require(
            isinstance(self.strands, int) and not isinstance(self.strands, bool) and 1 <= self.strands <= MAX_STRANDS,
            f"strands = {self.strands!r} must be a whole number from 1 to {MAX_STRANDS}",
        )
        require(
            (self.pitch is None) != (self.angle is None),
            f"pitch = {self.pitch!r}, angle = {self.angle!r}: give exactly one of pitch and angle",
        )
        if self.pitch is not None:
            require_positive("pitch", self.pitch)
        else:
            a = require_finite("angle", self.angle)
            require(0 < a < 90, f"angle = {self.angle!r} must lie in (0, 90) degrees (from the axis)")
        require_finite("phase", self.phase)
        if self.flat is not None:
            require(require_finite("flat", self.flat) >= 0, f"flat = {self.flat!r} must be >= 0")
            require(self.axis != "y", "flat: a D section's flat side is normal to y: the axis must be x or z, not y")

    @property
    def perimeter(self) -> float:
        """The section's perimeter: 2 pi radius, or the D section's pi radius + 2 flat + 2 radius (flat)."""
        if self.flat is None:
            return 2 * math.pi * self.radius
        return (math.pi + 2) * self.radius + 2 * self.flat

    def section(self, arc: np.ndarray) -> np.ndarray:
        """The points (k, 3) of the D section (flat) at arc lengths `arc` from its top, counter-clockwise about
        +axis, relative to center: the quarter arcs, the sides and the bottom sampled finely and interpolated."""
        assert self.flat is not None, "a D section's depth (only a helix with flat has one)"
        r, flat = self.radius, float(self.flat)
        up = np.eye(3)[1]
        side = np.cross(np.eye(3)[AXES.index(self.axis)], up)
        phi = np.linspace(0.0, math.pi / 2, 257)
        quarter = r * (np.outer(np.cos(phi), up) + np.outer(np.sin(phi), side))
        corners = np.array([r * side - flat * up, -r * side - flat * up, -r * side])
        outline = np.vstack([quarter, corners, quarter[::-1] - 2 * np.outer(quarter[::-1] @ side, side)])
        lengths = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(outline, axis=0), axis=1))])
        where = np.mod(arc, lengths[-1])
        return np.column_stack([np.interp(where, lengths, outline[:, k]) for k in range(3)])

    @property
    def advance(self) -> float:
        """The axial advance per turn: pitch, or 2 pi radius / tan(angle)."""
        if self.pitch is not None:
            return self.pitch
        assert self.angle is not None, "__post_init__ takes exactly one of pitch and angle"
        return self.perimeter / math.tan(math.radians(self.angle))

    @property
    def helix_length(self) -> float:
        """One helix's length: turns sqrt(P^2 + advance^2), P the section's perimeter."""
        return self.count * math.hypot(self.perimeter, self.advance)

    @property
    def count(self) -> float:
        """Its turns: turns, or extent / advance (its axial extent over the advance per turn)."""
        if self.turns is not None:
            return self.turns
        assert self.extent is not None, "__post_init__ takes exactly one of turns and extent"
        return self.extent / self.advance

    def helix_points(self, spacing: float) -> int:
        """The points of each helix: max(2, ceil(helix_length / spacing)) + 1."""
        return max(2, ceiling(self.helix_length / spacing)) + 1

    def helices(self, sense: int, spacing: float) -> list[np.ndarray]:
        """The strands of handedness sense (+1 right, -1 left), their phases 360 / strands degrees apart."""
        return [self.helix(sense, spacing, self.phase + 360 * k / self.strands) for k in range(self.strands)]

    def helix(self, sense: int, spacing: float, phase: float) -> np.ndarray:
        """The helix of handedness sense (+1 right, -1 left) starting at phase (degrees), sampled no coarser than
        spacing."""
        c, e1, e2, ea = _frame(self.center, self.axis)
        t = np.linspace(0.0, self.count, self.helix_points(spacing))
        if self.flat is not None:
            arc = (phase / 360 + sense * t) * self.perimeter
            return c + self.section(arc) + np.outer(self.advance * t, ea)
        theta = math.radians(phase) + sense * 2 * math.pi * t
        return (
            c
            + self.radius * (np.outer(np.cos(theta), e1) + np.outer(np.sin(theta), e2))
            + np.outer(self.advance * t, ea)
        )


@LAYOUTS.register
@dataclass(frozen=True)
class Helix(Spiral):
    """One helix of the given handedness ("right": counter-clockwise seen from +axis as it advances along +axis)."""

    name = "helix"

    handedness: str = "right"

    def __post_init__(self):
        super().__post_init__()
        require(
            self.handedness in HANDEDNESS, f"handedness = {self.handedness!r} is not one of {', '.join(HANDEDNESS)}"
        )

    def curves(self, spacing: float) -> list[np.ndarray]:
        return self.helices(1 if self.handedness == "right" else -1, spacing)

    def size(self, spacing: float) -> tuple[int, int]:
        return self.strands, self.strands * self.helix_points(spacing)


@LAYOUTS.register
@dataclass(frozen=True)
class Crossed(Spiral):
    """Two helices of opposite handedness (right, then left) on the same axis, start and pitch."""

    name = "crossed"

    def curves(self, spacing: float) -> list[np.ndarray]:
        return self.helices(1, spacing) + self.helices(-1, spacing)

    def size(self, spacing: float) -> tuple[int, int]:
        return 2 * self.strands, 2 * self.strands * self.helix_points(spacing)


PLANAR = tuple(name for name, cls in LAYOUTS.items() if cls.planar)
