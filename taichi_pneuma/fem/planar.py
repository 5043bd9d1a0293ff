"""2D geometries meshed by Triangle: a body polygon with chamber polygons punched out (or notched in at symmetry
lines, symmetry.py), and its named vertex sets: the clamp, the tip, the rollers (supports.py).

The body is meshed by Shewchuk's Triangle (through triangulation.py's binding) with the flags ``p q a<max_area>``: a
planar straight-line graph (the body loop, then each chamber loop), quality (20 degree minimum angle) refinement and
a maximum triangle area; one hole point strictly inside each chamber removes its inside. Each chamber wall is
recovered from the output segments as a closed vertex loop oriented counter-clockwise, so its signed shoelace area
(polygons.enclosed_area) is positive at rest, or as an open chain from symmetry line to symmetry line. Chambers must
lie inside the body and apart from each other by at least MARGIN; otherwise a PneumaInputError names the chamber.

Curved boundaries: an ellipse and a rounded rectangle's corners are curves, which their polygon samples. For
quadratic triangles, and for meshes refined uniformly, every node on a boundary segment of such a shape (the
points Triangle adds on its chords, the refinements' new nodes, the midside nodes) is moved onto the exact
curve (the shape's project), so the isoparametric elements have curved sides and converge at their full order
(P2: about h^3 in displacement, h^4 in a chamber's area) where straight-sided ones stay at h^2, limited by the
polygon. Interior midside nodes stay at their edges' middles, straight sides (rectangles, polygons, a rounded
rectangle's sides, the symmetry lines) stay straight, and a midside node whose move would fold its triangle
(a mesh too coarse for the curve) stays at its edge's middle. The ends of a wall cut by a symmetry line stay
where the polygon crosses the line: on the curve when a polygon vertex lies on it (an ellipse centred on a
line along an axis, its points a multiple of 4), else on the chord, off by the chord's sag. Linear triangles
unrefined are Triangle's mesh of the polygons as they are (the reference scene's).

No two points of one outline may lie closer than polygons.MIN_SPACING times its size (Triangle crashes on
coincident points), and a geometry Triangle cannot mesh (it runs out of floating-point precision) is a
PneumaInputError too. Chamber names are distinct and head CSV columns, so none starts like a spreadsheet formula
(output.check_heading).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import PneumaInputError, require, require_distinct, require_finite
from ..io.output import check_heading
from ..io.units import PLANE_AREA, si_default
from ..limits import Budget
from .body import Body, SizeEstimate
from .elements import TRIANGLE_P1, TRIANGLE_P2, family_for, family_of, positively_oriented
from .mesh import Mesh, triangle_areas
from .polygons import (
    distance_to_polygon,
    enclosed_area,
    interior_point,
    points_in_polygon,
    polygon_self_intersects,
    require_spaced,
    segments_cross,
    signed_area,
)
from .refine import split_in_four, subdivided, with_edge_nodes
from .shapes import MAX_SHAPES, MAX_WALL_POINTS, Ellipse, Rectangle
from .supports import PointSet, Roller
from .symmetry import CUT_TOLERANCE, OUTER_MARKER, cut_by_lines, notch, symmetry_lines
from .triangulation import triangulate_or_refuse

MARGIN = 1e-3
MAX_REFINEMENTS = 4


@dataclass(frozen=True)
class Geometry(Body):
    """A body shape with named chamber shapes, a mesh density and the named node sets: the clamp (None, the
    default: none), the tip (the right edge by default) and the rollers.

    A chamber lies inside the body, or is cut by symmetry lines: roller lines along an edge of the body. A
    chamber crossing such lines keeps its part on the body's side (cut_by_lines), a notch in the body's
    outline whose wall runs from line to line; its area is closed by the flat cap along the lines."""

    body: Any  # a 2D shape: anything with polygon()
    chambers: tuple[tuple[str, Any], ...]
    max_area: float | None = si_default(0.0012, PLANE_AREA, scaled=False)  # None: 0.0012, unitless scenes only
    clamp: PointSet | None = None
    order: int = 1
    refinements: int = 0
    tip: PointSet = field(default_factory=lambda: PointSet("right"))
    rollers: tuple[Roller, ...] = ()

    dim = 2

    def __post_init__(self):
        require(
            self.max_area is None or require_finite("max_area", self.max_area) > 0,
            f"max_area = {self.max_area!r} must be > 0",
        )
        family_for(2, self.order)  # refuses an order without a triangle family, naming those there are
        require(
            self.refinements in range(MAX_REFINEMENTS + 1),
            f"refinements = {self.refinements!r} must be an integer from 0 to {MAX_REFINEMENTS}",
        )
        require(len(self.chambers) <= MAX_SHAPES, f"{len(self.chambers)} chambers: at most {MAX_SHAPES} are allowed")
        self.check_supports()
        for name, shape in self.chambers:
            require(
                callable(getattr(shape, "polygon", None)),
                f"chamber {name!r}: a {type(shape).__name__} wall needs "
                f"a body from a mesh file or 3D shapes (a 3D body)",
            )
        body = self.body.polygon()
        polygons = [(name, shape.polygon()) for name, shape in self.chambers]
        points = len(body) + sum(len(p) for _, p in polygons)
        require(
            points <= MAX_WALL_POINTS,
            f"the body and chamber outlines have {points} points in all; at most {MAX_WALL_POINTS} are allowed",
        )
        names = [name for name, _ in polygons]
        require_distinct("chamber names", names)
        for name in names:
            check_heading("chamber name", name)
        for what, poly in [("the body", body)] + [(f"chamber {name!r}", poly) for name, poly in polygons]:
            require_spaced(what, poly)
        outline, _, walls = self.outline()
        if any(origin is not None for _, origin in walls):
            require_spaced("the body with its cut chambers", outline)
            require(
                not polygon_self_intersects(outline),
                "the body's outline, with the chambers cut by symmetry lines notched into it, crosses itself",
            )
        polygons = [(name, poly) for (name, poly), (_, origin) in zip(polygons, walls) if origin is None]
        for name, poly in polygons:
            outside = ~points_in_polygon(poly, outline) | (distance_to_polygon(poly, outline) < MARGIN)
            crossing = segments_cross(poly, np.roll(poly, -1, axis=0), outline, np.roll(outline, -1, axis=0)).any()
            require(
                not outside.any() and not crossing,
                f"chamber {name!r} is not inside the body (a wall point at {poly[np.argmax(outside)].tolist()} "
                f"lies outside it or closer than {MARGIN:g} to its boundary)",
            )
        for i, (name_a, a) in enumerate(polygons):
            for name_b, b in polygons[i + 1 :]:
                touching = (
                    points_in_polygon(a, b).any()
                    or points_in_polygon(b, a).any()
                    or distance_to_polygon(a, b).min() < MARGIN
                    or segments_cross(a, np.roll(a, -1, axis=0), b, np.roll(b, -1, axis=0)).any()
                )
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

    def size_estimate(self) -> SizeEstimate:
        """The triangles and vertices estimated from the outlines (fem/sizing.py's fit), each uniform refinement
        multiplying them by 4, and each wall's node count (max_area as the Scene resolved it)."""
        assert self.max_area is not None, "a Scene resolves max_area"
        loops = [self.body.polygon()] + [shape.polygon() for _, shape in self.chambers]
        area = abs(signed_area(loops[0])) - sum(abs(signed_area(loop)) for loop in loops[1:])
        points = sum(len(loop) for loop in loops)
        nodes_per_point = 2**self.refinements * self.order
        triangles = (1.6 * area / self.max_area + 3 * points) * 4**self.refinements
        return SizeEstimate(
            triangles,
            triangles * self.family.weight / 2 + points,
            tuple(len(loop) * nodes_per_point for loop in loops[1:]),
            f"meshed area {area:.4g} / max_area {self.max_area:.3g}, {points} outline points",
        )

    def mesh_values(self) -> dict:
        """max_area and order (a refined geometry has no scene-file form: it is refused)."""
        require(
            self.refinements == 0,
            f"a geometry refined {self.refinements} times has no scene-file form (scene files have no refinements key)",
        )
        return {"max_area": self.max_area, "order": self.order}

    def mesh(self, budget: Budget = Budget()) -> Mesh:
        """Mesh the body minus its chambers with Triangle ('pqa<max_area>'), split every triangle in four
        `refinements` times (uniform refinement: h halved each time), add a midside node to every edge for
        quadratic triangles, and name the node sets. A refined or quadratic mesh has its boundary nodes on the
        exact curves of ellipses and rounded corners (onto_curves; module docstring). Triangle adds at most the
        budget's element_cap points and a mesh past the budget is refused (limits.Budget)."""
        require(
            self.max_area is not None,
            "max_area = None: the Scene sets the default (0.0012 in a unitless scene); "
            "give max_area to mesh a Geometry on its own",
        )
        outline, outline_markers, walls = self.outline()
        closed = [c for c, (_, origin) in enumerate(walls, start=1) if origin is None]
        loops = [outline] + [walls[c - 1][0] for c in closed]
        offsets = np.cumsum([0] + [len(p) for p in loops])
        ring = lambda n, offset: offset + np.column_stack([np.arange(n), (np.arange(n) + 1) % n])
        pslg = {
            "vertices": np.vstack(loops),
            "segments": np.vstack([ring(len(p), o) for p, o in zip(loops, offsets)]),
            "segment_markers": np.concatenate(
                [outline_markers] + [np.full(len(walls[c - 1][0]), OUTER_MARKER + c) for c in closed]
            ),
        }
        if closed:
            pslg["holes"] = np.array([interior_point(p) for p in loops[1:]])
        weight = 4**self.refinements * self.family.weight  # linear triangles per Triangle's one
        cap = budget.element_cap(weight)  # Triangle adds at most this many points (S), then stops
        out = triangulate_or_refuse(
            pslg, f"pqa{self.max_area:.17f}" + ("" if cap is None else f"S{cap}")
        )  # no exponent
        added = len(out["vertices"]) - len(pslg["vertices"])
        budget.check_mesh(len(out["triangles"]), weight, "Triangle", cap if cap is not None and added >= cap else None)
        vertices = np.asarray(out["vertices"], dtype=np.float64)
        triangles = positively_oriented(vertices, np.asarray(out["triangles"], dtype=np.int64), TRIANGLE_P1)
        segments, markers = np.asarray(out["segments"], dtype=np.int64), out["segment_markers"].ravel()
        shapes = [self.body] + [shape for _, shape in self.chambers]  # the shape of marker OUTER_MARKER + c
        curves = {OUTER_MARKER + c: shape.project for c, shape in enumerate(shapes) if hasattr(shape, "project")}
        family = self.family
        if family.order > 1 or self.refinements:
            vertices = onto_curves(vertices, segments, markers, curves, triangles)
        for _ in range(self.refinements):
            vertices, along = with_edge_nodes(vertices, triangles, TRIANGLE_P2.edges, 2)
            triangles = split_in_four(
                np.column_stack([triangles] + [along(triangles[:, i], triangles[:, j]) for i, j in TRIANGLE_P2.edges])
            )
            segments, markers = subdivided(segments, markers, along)
            vertices = onto_curves(vertices, segments, markers, curves, triangles)
        vertices, triangles, along = family.lift(vertices, triangles)
        if along is not None:  # the edge nodes on the curves, the interior ones where the boundary puts them
            vertices = onto_curves(vertices, *subdivided(segments, markers, along), curves, triangles)
        chambers = []
        for c, (_, origin) in enumerate(walls, start=1):
            nodes = chain(segments[markers == OUTER_MARKER + c], closed=origin is None)
            nodes = nodes if enclosed_area(vertices[nodes], origin) > 0 else nodes[::-1].copy()
            if along is not None:  # corner, its edge's nodes, corner, ...: each edge from its first corner
                starts = nodes if origin is None else nodes[:-1]
                edges = np.column_stack([starts, along(starts, np.roll(nodes, -1)[: len(starts)])]).ravel()
                nodes = edges if origin is None else np.append(edges, nodes[-1])
            chambers.append(nodes)
        outer = segments[markers == OUTER_MARKER]
        boundary = np.unique(outer if along is None else np.column_stack([outer, along(outer[:, 0], outer[:, 1])]))
        pinned, tip, rollers = self.node_sets(vertices)
        return Mesh(
            vertices,
            triangles,
            tuple(chambers),
            boundary,
            pinned,
            tip,
            tuple(origin for _, origin in walls),
            rollers,
            family,
        )


def jacobians(vertices: np.ndarray, triangles: np.ndarray, points: np.ndarray) -> np.ndarray:
    """det dX/dxi (m, p) of triangles (m, k) of any family at reference points (p, 2), dX/dxi = sum_a X_a dN_a/dxi
    (isoparametric: twice the area of a straight-sided triangle, the same at every point)."""
    family = family_of(triangles, 2)
    j = np.swapaxes(vertices[triangles], 1, 2)[:, None] @ family.shape_gradients(points)[None]  # (m, p, 2, 2)
    return j[..., 0, 0] * j[..., 1, 1] - j[..., 0, 1] * j[..., 1, 0]


def onto_curves(
    vertices: np.ndarray, segments: np.ndarray, markers: np.ndarray, curves: dict, triangles: np.ndarray
) -> np.ndarray:
    """The vertices with every node of the boundary segments of marker m moved onto the exact curve of the
    shape they came from, curves[m] (its project: an ellipse, a rounded corner; a marker without a curve, a
    straight polygon, leaves its nodes), and the triangles' interior nodes (order 3 and up) where their boundary
    nodes put them (ElementFamily.placed_interior). A node on segments of two markers stays: the end of a
    chamber wall cut by a symmetry line, on the line. A triangle (of any family) the moves would fold
    (det dX/dxi <= 0 at one of its nodes, where the mesh is too coarse for the curve) keeps its nodes where
    they were: its edge nodes on its straight edges."""
    count = len(vertices)
    lowest, highest = np.full(count, np.iinfo(np.int64).max), np.full(count, -1)
    np.minimum.at(lowest, segments.ravel(), np.repeat(markers, 2))
    np.maximum.at(highest, segments.ravel(), np.repeat(markers, 2))
    moved = vertices.copy()
    for marker, project in curves.items():
        nodes = np.flatnonzero((lowest == marker) & (highest == marker))
        moved[nodes] = project(vertices[nodes])
    family = family_of(triangles, 2)
    moved = family.placed_interior(moved, triangles)
    at_nodes = (
        triangle_areas(moved, triangles)[:, None]
        if family.order == 1
        else jacobians(moved, triangles, family.reference_nodes)
    )
    folded = triangles[np.min(at_nodes, axis=1) <= 0].ravel()
    moved[folded] = vertices[folded]
    return family.placed_interior(moved, triangles)


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
        return Geometry(
            Rectangle((0.0, 0.0), (self.length, self.height)),
            (("main", Ellipse((self.cx, self.cy), (self.a, self.b), self.chamber_points)),),
            self.max_area,
            PointSet("left"),
            order=self.order,
            refinements=self.refinements,
        )

    def mesh(self, budget: Budget = Budget()) -> Mesh:
        return self.general().mesh(budget)


def chain(edges: np.ndarray, closed: bool = True) -> np.ndarray:
    """Order the undirected edges of one curve into its nodes: a closed loop (first node not repeated) or an
    open chain from one end to the other."""
    neighbours: dict[int, list[int]] = {}
    for i, j in edges:
        neighbours.setdefault(int(i), []).append(int(j))
        neighbours.setdefault(int(j), []).append(int(i))
    ends = [v for v, n in neighbours.items() if len(n) == 1]
    if any(len(n) > 2 for n in neighbours.values()) or len(ends) != (0 if closed else 2):
        raise PneumaInputError(
            f"Triangle could not keep a chamber wall a simple {'closed loop' if closed else 'open chain'}"
        )
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
