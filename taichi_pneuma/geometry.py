"""Shapes -> Triangle meshes: a rectangular beam with an elliptical chamber punched out.

The body is meshed by Shewchuk's Triangle (``triangle`` package) with the flags
``p q a<max_area>``: a planar straight-line graph, quality (20 degree minimum angle)
refinement and a maximum triangle area; a hole point at the chamber centre removes
the chamber's inside. The chamber wall is recovered from the output segments as a
closed vertex loop oriented counter-clockwise, so its signed shoelace area

    A(x) = 1/2 sum_i (x_i y_{i+1} - x_{i+1} y_i)

is positive at rest.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import triangle

from .errors import require, require_finite

OUTER_MARKER = 1
CHAMBER_MARKER = 2


@dataclass(frozen=True)
class Mesh:
    """A triangle mesh with the vertex sets a pneumatic scene needs.

    vertices: (n, 2) rest positions; triangles: (m, 3) counter-clockwise vertex indices;
    chamber_loop: vertex indices of the chamber wall, counter-clockwise (positive area);
    pinned: the clamped wall (x <= min x + 1e-6); tip: the right edge (x >= max x - 1e-6).
    """

    vertices: np.ndarray
    triangles: np.ndarray
    chamber_loop: np.ndarray
    pinned: np.ndarray
    tip: np.ndarray

    @property
    def n_vertices(self) -> int:
        return len(self.vertices)

    @property
    def n_triangles(self) -> int:
        return len(self.triangles)

    @property
    def area(self) -> float:
        """Total rest area of the triangles."""
        p0, p1, p2 = (self.vertices[self.triangles[:, i]] for i in range(3))
        e1, e2 = p1 - p0, p2 - p0
        return 0.5 * float(np.sum(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]))


@dataclass(frozen=True)
class BeamGeometry:
    """A rectangle L x H centred at the origin with an elliptical chamber (semi-axes a, b) at (cx, cy)."""

    length: float = 3.5
    height: float = 0.8
    a: float = 0.85
    b: float = 0.22
    cx: float = 0.0
    cy: float = 0.0
    chamber_points: int = 128
    max_area: float = 0.0012

    def __post_init__(self):
        for name in ("length", "height", "a", "b", "cx", "cy", "max_area"):
            require_finite(name, getattr(self, name))
        for name in ("length", "height", "a", "b", "max_area"):
            require(getattr(self, name) > 0, f"{name} = {getattr(self, name)!r} must be > 0")
        require(
            isinstance(self.chamber_points, (int, np.integer)) and self.chamber_points >= 8,
            f"chamber_points = {self.chamber_points!r} must be an integer >= 8",
        )
        margin = 1e-3
        require(
            abs(self.cy) + self.b < self.height / 2 - margin,
            f"chamber escapes the beam vertically: |cy| + b = {abs(self.cy) + self.b:.4g} "
            f"(cy = {self.cy:g}, b = {self.b:g}) must be < H/2 - {margin:g} = {self.height / 2 - margin:.4g}",
        )
        require(
            abs(self.cx) + self.a < self.length / 2,
            f"chamber escapes the beam horizontally: |cx| + a = {abs(self.cx) + self.a:.4g} "
            f"(cx = {self.cx:g}, a = {self.a:g}) must be < L/2 = {self.length / 2:.4g}",
        )

    def chamber_polygon(self) -> np.ndarray:
        """The chamber's ellipse sampled at chamber_points angles, counter-clockwise, (k, 2)."""
        t = np.linspace(0.0, 2.0 * np.pi, self.chamber_points, endpoint=False)
        return np.column_stack([self.cx + self.a * np.cos(t), self.cy + self.b * np.sin(t)])

    def mesh(self) -> Mesh:
        """Mesh the beam with Triangle ('pqa<max_area>') and name its vertex sets."""
        half_l, half_h = self.length / 2, self.height / 2
        outer = np.array([[-half_l, -half_h], [half_l, -half_h], [half_l, half_h], [-half_l, half_h]])
        k = self.chamber_points
        ring = lambda n, offset: offset + np.column_stack([np.arange(n), (np.arange(n) + 1) % n])
        pslg = {
            "vertices": np.vstack([outer, self.chamber_polygon()]),
            "segments": np.vstack([ring(4, 0), ring(k, 4)]),
            "segment_markers": np.r_[np.full(4, OUTER_MARKER), np.full(k, CHAMBER_MARKER)],
            "holes": np.array([[self.cx, self.cy]]),
        }
        out = triangle.triangulate(pslg, f"pqa{self.max_area:.17f}")  # fixed-point: Triangle reads no exponent
        vertices = np.asarray(out["vertices"], dtype=np.float64)
        triangles = orient_counter_clockwise(vertices, np.asarray(out["triangles"], dtype=np.int64))
        chamber_edges = out["segments"][out["segment_markers"].ravel() == CHAMBER_MARKER]
        loop = chain_loop(chamber_edges)
        if signed_area(vertices[loop]) < 0:
            loop = loop[::-1].copy()
        x = vertices[:, 0]
        pinned = np.flatnonzero(x <= x.min() + 1e-6)
        tip = np.flatnonzero(x >= x.max() - 1e-6)
        return Mesh(vertices, triangles, loop, pinned, tip)


def signed_area(polygon: np.ndarray) -> float:
    """Shoelace area of a closed polygon (k, 2); positive when counter-clockwise."""
    x, y = polygon[:, 0], polygon[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def orient_counter_clockwise(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Return triangles with every vertex triple ordered counter-clockwise."""
    p0, p1, p2 = (vertices[triangles[:, i]] for i in range(3))
    e1, e2 = p1 - p0, p2 - p0
    clockwise = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] < 0
    fixed = triangles.copy()
    fixed[clockwise] = fixed[clockwise][:, [0, 2, 1]]
    return fixed


def chain_loop(edges: np.ndarray) -> np.ndarray:
    """Order the undirected edges of one closed curve into a vertex loop (first vertex not repeated)."""
    neighbours: dict[int, list[int]] = {}
    for i, j in edges:
        neighbours.setdefault(int(i), []).append(int(j))
        neighbours.setdefault(int(j), []).append(int(i))
    if any(len(n) != 2 for n in neighbours.values()):
        raise RuntimeError("chamber wall segments do not form a simple closed loop")
    start = int(edges[0][0])
    loop, previous, current = [start], None, start
    while True:
        a, b = neighbours[current]
        nxt = a if a != previous else b
        if nxt == start:
            break
        loop.append(nxt)
        previous, current = current, nxt
    if len(loop) != len(neighbours):
        raise RuntimeError("chamber wall segments form more than one loop")
    return np.array(loop, dtype=np.int64)
