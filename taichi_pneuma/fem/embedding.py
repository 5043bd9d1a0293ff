"""Points embedded in a mesh: each point written as barycentric weights of the corners of a linear simplex of the
mesh that contains it, so that it follows the piecewise-linear interpolant of the nodes, p = sum_i w_i x_i.

The linear simplices (pieces) of an element are its family's split (fem/elements.py): a linear element is its own
piece; a triangle of order p the p^2 triangles of its node lattice (a quadratic one: four, through its midside
nodes); a quadratic tetrahedron the eight tetrahedra through its midside nodes (each of positive volume, an eighth
of the element's on a straight one): one at each corner, and the inner octahedron cut along its diagonal from the
middle of edge 20 (node 6) to that of edge 13 (node 8) into four.

Location: the pieces' centroids in a k-d tree; for each point the barycentric coordinates
lambda = [1 - sum(T^-1 (p - X_0)), T^-1 (p - X_0)], T = [X_1 - X_0, ..., X_d - X_0], in its k nearest pieces
(k four times larger for the points not yet found, up to MAX_CANDIDATES; CHUNK points at a time, so that the
arrays stay small whatever the number of points). Each piece's distance outside is
max_i(-lambda_i / |grad lambda_i|) (lambda_i over the height of corner i, exact for one violated facet); a point
within TOLERANCE times the body's bounding-box diagonal of its nearest piece is inside (on the boundary included).

embed() also takes a point just outside the mesh, as a point on a curved surface lies outside the straight-sided
pieces that approximate it (a thread on a round outer wall: the sagitta of a facet of side h on a radius R is
h^2 / 8R). It is moved onto the nearest point of the body's surface (its straight pieces) where that is at most SNAP
times that piece's shortest side away; farther out, it lies outside the body (a chamber's cavity is outside it too)
and is refused.
"""

from __future__ import annotations

import numpy as np

from ..errors import require
from .self_intersection import surface_pieces

TOLERANCE = 1e-9  # of the body's bounding-box diagonal
SNAP = 0.25  # embed() snaps a point this close to the surface, in its nearest surface piece's shortest side
GRAZE = 0.1  # first_crossing: a segment's end this near a facet's plane, in its shortest side, is not through it
FIRST_CANDIDATES = 8
MAX_CANDIDATES = 512  # pieces searched per point at most (the nearest by centroid)
CHUNK = 1024  # fibre segments first_crossing tests at once: their candidate pairs' arrays stay small


def pieces(mesh) -> np.ndarray:
    """The linear simplices (m p, d + 1) of the mesh's elements (see the module docstring)."""
    return mesh.family.split_cells(mesh.elements)


def _coordinates(inverse, origin, gradient_norms, points, candidates) -> tuple[np.ndarray, np.ndarray]:
    """(lambda (p, c, d + 1), distance outside (p, c)) of points (p, d) in candidate pieces (p, c)."""
    local = np.einsum("pcij,pcj->pci", inverse[candidates], points[:, None, :] - origin[candidates])
    lam = np.concatenate([1.0 - local.sum(axis=2, keepdims=True), local], axis=2)
    return lam, np.max(-lam / gradient_norms[candidates], axis=2)


def _search(mesh, points: np.ndarray) -> tuple:
    """For points (P, d): (the pieces, their corners, T^-1, |grad lambda_i|, the nearest piece of each point, its
    distance outside it, the tolerance): the k-d tree search of the module docstring."""
    simplices = pieces(mesh)
    corners = mesh.vertices[simplices]  # (s, d + 1, d)
    inverse = np.linalg.inv(np.swapaxes(corners[:, 1:] - corners[:, :1], 1, 2))  # (s, d, d): T^-1
    gradients = np.concatenate([-inverse.sum(axis=1, keepdims=True), inverse], axis=1)  # grad lambda_i, (s, d+1, d)
    norms = np.linalg.norm(gradients, axis=2)
    tolerance = TOLERANCE * float(np.linalg.norm(np.ptp(mesh.vertices, axis=0)))
    from scipy.spatial import cKDTree  # imported here: a scene without fibres does not load it

    tree = cKDTree(corners.mean(axis=1))
    best = np.zeros(len(points), dtype=np.int64)
    outside = np.full(len(points), np.inf)
    most = min(MAX_CANDIDATES, len(simplices))
    for start in range(0, len(points), CHUNK):
        todo, k = np.arange(start, min(start + CHUNK, len(points))), FIRST_CANDIDATES
        while len(todo):
            k = min(k, most)
            _, near = tree.query(points[todo], k=k)
            near = near.reshape(len(todo), k)
            _, distance = _coordinates(inverse, corners[:, 0], norms, points[todo], near)
            pick = np.argmin(distance, axis=1)
            better = distance[np.arange(len(todo)), pick] < outside[todo]
            best[todo[better]] = near[better, pick[better]]
            outside[todo[better]] = distance[better, pick[better]]
            if k == most:
                break
            todo, k = todo[outside[todo] > tolerance], 4 * k
    return simplices, corners, inverse, norms, best, outside, tolerance


def nearest_on_segments(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The point of segment ab nearest p, row by row (k, d)."""
    e = b - a
    t = np.clip(np.sum((p - a) * e, axis=1) / np.maximum(np.sum(e * e, axis=1), 1e-300), 0.0, 1.0)
    return a + t[:, None] * e


def nearest_on_triangles(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """The point of triangle abc nearest p, row by row (k, 3): p's foot on the triangle's plane where it lies inside
    the triangle (barycentric coordinates >= 0), else the nearest point of its three sides."""
    u, v, w = b - a, c - a, p - a
    uu, uv, vv, wu, wv = (np.sum(x * y, axis=1) for x, y in ((u, u), (u, v), (v, v), (w, u), (w, v)))
    denominator = np.maximum(uu * vv - uv * uv, 1e-300)
    s, t = (vv * wu - uv * wv) / denominator, (uu * wv - uv * wu) / denominator
    foot = a + s[:, None] * u + t[:, None] * v
    sides = np.stack([nearest_on_segments(p, x, y) for x, y in ((a, b), (b, c), (c, a))], axis=1)
    side = sides[np.arange(len(p)), np.argmin(np.linalg.norm(sides - p[:, None], axis=2), axis=1)]
    return np.where(((s >= 0) & (t >= 0) & (s + t <= 1))[:, None], foot, side)


def onto_surface(mesh, points: np.ndarray, candidates: int = 16) -> tuple[np.ndarray, np.ndarray]:
    """(feet (P, d), reach (P,)): each point's nearest point on the body's surface (its straight pieces,
    self_intersection.surface_pieces; among the `candidates` nearest by centroid) and SNAP times that piece's
    shortest side, the farthest a point is snapped onto it."""
    from scipy.spatial import cKDTree

    facets = surface_pieces(mesh)
    corners = mesh.vertices[facets]  # (f, 3, d); a 2D segment as (a, b, b)
    k = min(candidates, len(facets))
    _, near = cKDTree(corners.mean(axis=1)).query(points, k=k)
    near = near.reshape(len(points), k)
    p = np.repeat(points, k, axis=0)
    a, b, c = (corners[near.ravel(), i] for i in range(3))
    feet = (nearest_on_segments(p, a, b) if mesh.dim == 2 else nearest_on_triangles(p, a, b, c)).reshape(
        len(points), k, -1
    )
    pick = np.argmin(np.linalg.norm(feet - points[:, None], axis=2), axis=1)
    rows = np.arange(len(points))
    sides = np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2)
    shortest = np.where(sides > 0, sides, np.inf).min(axis=1)
    return feet[rows, pick], SNAP * shortest[near[rows, pick]]


def inside(mesh, points, snapping: bool = False) -> np.ndarray:
    """Whether each point (P, d) lies in the body (on its boundary included; a chamber's cavity is outside); with
    snapping, or within the reach of its nearest point on the surface that embed() snaps it by (onto_surface)."""
    points = np.asarray(points, dtype=float).reshape(-1, mesh.dim)
    *_, outside, tolerance = _search(mesh, points)
    found = outside <= tolerance
    if snapping and not found.all():
        feet, reach = onto_surface(mesh, points[~found])
        found[~found] = np.linalg.norm(feet - points[~found], axis=1) <= reach
    return found


def embed(mesh, points, what: str) -> tuple[np.ndarray, np.ndarray]:
    """(nodes (P, d + 1) int64, weights (P, d + 1) float64): each point (P, d) as the barycentric weights of the
    corners of a linear piece of the mesh that contains it, after a point just outside is snapped onto the surface
    (onto_surface: the module docstring); a point farther outside the body is a PneumaInputError naming `what`, the
    point and the body's bounding box."""
    points = np.asarray(points, dtype=float).reshape(-1, mesh.dim)
    simplices, corners, inverse, norms, best, outside, tolerance = _search(mesh, points)
    low, high = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
    out = np.flatnonzero(outside > tolerance)
    bad = out
    if len(out):  # snapped onto the surface where near it, then found again
        feet, reach = onto_surface(mesh, points[out])
        near = np.linalg.norm(feet - points[out], axis=1) <= reach
        moved = points.copy()
        moved[out[near]] = feet[near]
        *_, best, outside, _ = _search(mesh, moved)
        bad, points = np.flatnonzero(outside > tolerance), moved
    require(
        len(bad) == 0,
        f"{what}: {len(bad)} of its {len(points)} points lie outside the body (or in a chamber), the first "
        f"{[round(float(v), 6) for v in points[bad[0]]] if len(bad) else ''} (the body's bounding box is "
        f"{[round(float(v), 6) for v in (*low, *high)]})",
    )
    lam, _ = _coordinates(inverse, corners[:, 0], norms, points, best[:, None])
    weights = np.clip(lam[:, 0], 0.0, None)
    return simplices[best].astype(np.int64), weights / weights.sum(axis=1, keepdims=True)


def first_crossing(mesh, starts: np.ndarray, ends: np.ndarray) -> tuple[int, np.ndarray] | None:
    """The first segment (its index and the crossing point) from starts[s] to ends[s] (s, d) that passes through the
    body's boundary (self_intersection.surface_pieces, its outer surface and every chamber's wall in straight
    pieces): one end farther than the facet's reach on either side of its line or plane (signed distances h_p > tol >
    -tol > h_q), and the point where it meets that plane, x = p + h_p / (h_p - h_q) (q - p), within the facet (its
    barycentric coordinates in the facet's corners >= -1e-9). A segment between two points of the body that does so
    leaves the body there (through a chamber's wall or the outer surface); one that only touches the boundary, or
    runs along it, does not count. The reach, tol, is GRAZE times the facet's shortest side (at least TOLERANCE times
    the body's bounding-box diagonal): the pieces of a curved surface (a quadratic facet split in four through
    midside nodes on the surface) need not be convex where the surface is, and a segment between points on two
    neighbouring pieces may pass the plane of one without leaving the body, by up to about the pieces' sag on the
    surface, side^2 / (8 R): under a tenth of the side where the side is under 0.8 R. Where the first segment
    crosses more than once, its crossing nearest its start; None: no segment crosses. Candidates: the facets whose
    ball about their centroid through their corners meets the segment's ball about its midpoint (a k-d tree of the
    facets' centroids), CHUNK segments at a time."""
    from scipy.spatial import cKDTree  # imported here, as in embed

    corners = mesh.vertices[surface_pieces(mesh)[:, : mesh.dim]]  # (f, d, d): a 2D piece (a, b, b) as (a, b)
    sides = np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2)
    centroid = corners.mean(axis=1)
    radius = np.linalg.norm(corners - centroid[:, None], axis=2).max(axis=1)
    tree = cKDTree(centroid)
    reach = np.maximum(TOLERANCE * float(np.linalg.norm(np.ptp(mesh.vertices, axis=0))), GRAZE * sides.min(axis=1))
    for first in range(0, len(starts), CHUNK):
        p, q = starts[first : first + CHUNK], ends[first : first + CHUNK]
        middle, half = (p + q) / 2, np.linalg.norm(q - p, axis=1) / 2
        near = tree.query_ball_point(middle, half + radius.max())
        segment = np.repeat(np.arange(len(p)), [len(n) for n in near])
        facet = np.concatenate(near).astype(np.int64) if len(segment) else segment
        close = np.linalg.norm(centroid[facet] - middle[segment], axis=1) <= half[segment] + radius[facet]
        facet, segment = facet[close], segment[close]
        found = _crossing(corners[facet], p[segment], q[segment], segment, reach[facet])
        if found is not None:
            k, x = found
            return first + k, x
    return None


def _crossing(corners, p, q, segment, tol: np.ndarray) -> tuple[int, np.ndarray] | None:
    """Of the pairs (facet corners (c, d, d), segment number segment[c] from p to q (c, d), the facet's reach tol
    (c,)), the crossing (first_crossing's test) of the lowest segment number, nearest that segment's start: (that
    number, the crossing point); None if no pair crosses."""
    d = p.shape[1]
    frame = corners[:, 1:] - corners[:, :1]  # (c, d - 1, d)
    normal = np.column_stack([-frame[:, 0, 1], frame[:, 0, 0]]) if d == 2 else np.cross(frame[:, 0], frame[:, 1])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    hp = np.einsum("ci,ci->c", normal, p - corners[:, 0])
    hq = np.einsum("ci,ci->c", normal, q - corners[:, 0])
    through = ((hp > tol) & (hq < -tol)) | ((hp < -tol) & (hq > tol))
    t = hp / np.where(through, hp - hq, 1.0)
    x = p + t[:, None] * (q - p)
    gram = np.einsum("cid,cjd->cij", frame, frame)
    lam = np.linalg.solve(gram, np.einsum("cid,cd->ci", frame, x - corners[:, 0])[..., None])[..., 0]
    inside = np.flatnonzero(through & np.all(lam >= -1e-9, axis=1) & (lam.sum(axis=1) <= 1 + 1e-9))
    if not len(inside):
        return None
    pick = inside[np.lexsort((t[inside], segment[inside]))[0]]
    return int(segment[pick]), x[pick]
