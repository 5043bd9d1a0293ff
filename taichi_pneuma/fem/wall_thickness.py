"""The thinnest rubber around a chamber: the least distance from its wall to any boundary of the body it does not
touch (the outer surface, another chamber's wall), on triangulated surfaces; what a mesh sized from the walls needs.

    t = min over points p of the wall of  min over triangles T of the others of  dist(p, T)

The wall's points are its triangles' corners and centroids (wall_points). The candidates for each point are the
CANDIDATES triangles of the others whose centroids lie nearest (scipy's cKDTree); dist(p, T) is exact: the distance
to p's projection onto T's plane where that falls inside T (barycentric coordinates all >= 0), else to the nearest of
T's three edges (segments a + s (b - a), s clipped to [0, 1]). nearest_triangles gives each point's distance and
triangle, from which gmsh_mesher.thinnest_wall finds the exact surfaces' nearest points.

Boundaries that touch the chamber's wall (a symmetry plane its open wall ends on) are left out by the caller: the
distance to them is zero at the rim and says nothing about the wall. Where the surfaces are curved, each triangle's
chord lies off the curve by up to h^2 / (8 R) (edge h, curvature radius R): the error of these distances, which
thinnest_wall's projections onto the exact surfaces remove.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

CANDIDATES = 12  # triangles of the others tested exactly per wall point, the nearest by centroid


def point_triangle_distances(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(n, k) distances from each point (n, 3) to each of its k triangles (n, k, 3, 3) (module docstring)."""
    p = points[:, None, :]
    a, b, c = triangles[..., 0, :], triangles[..., 1, :], triangles[..., 2, :]
    e1, e2 = b - a, c - a
    normal = np.cross(e1, e2)
    area2 = np.einsum("nkj,nkj->nk", normal, normal)
    w = p - a
    # barycentric coordinates of p's projection: (u, v) with w - u e1 - v e2 normal to the plane
    u = np.einsum("nkj,nkj->nk", np.cross(w, e2), normal) / area2
    v = np.einsum("nkj,nkj->nk", np.cross(e1, w), normal) / area2
    plane = np.abs(np.einsum("nkj,nkj->nk", w, normal)) / np.sqrt(area2)
    inside = (u >= 0) & (v >= 0) & (u + v <= 1)
    edges = np.min([_segment_distances(p, s, t) for s, t in ((a, b), (b, c), (c, a))], axis=0)
    return np.where(inside, plane, edges)


def _segment_distances(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """|p - (a + s (b - a))| at the nearest s in [0, 1]."""
    d = b - a
    s = np.clip(np.einsum("nkj,nkj->nk", p - a, d) / np.einsum("nkj,nkj->nk", d, d), 0.0, 1.0)
    return np.linalg.norm(p - a - s[..., None] * d, axis=-1)


def nearest_triangles(points: np.ndarray, others: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each point (n, 3): its distance to the nearest of the triangles others (k, 3, 3), and that triangle's
    index (module docstring: the CANDIDATES nearest by centroid, each tested exactly)."""
    k = min(CANDIDATES, len(others))
    _, nearest = cKDTree(others.mean(axis=1)).query(points, k=k)
    nearest = np.reshape(nearest, (len(points), k))
    distances = point_triangle_distances(points, others[nearest])
    best = distances.argmin(axis=1)
    rows = np.arange(len(points))
    return distances[rows, best], nearest[rows, best]


def wall_points(wall: np.ndarray) -> np.ndarray:
    """The points a wall (f, 3, 3) is measured from: its triangles' corners and centroids."""
    return np.concatenate([wall.reshape(-1, 3), wall.mean(axis=1)])
