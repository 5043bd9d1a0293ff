"""The thinnest rubber around a chamber: the least distance from its wall to any boundary of the body it does not
touch (the outer surface, another chamber's wall); what a mesh sized from the walls (mesh.through_wall) needs.

    t = min over points p of the wall of  min over points q of the others of  |p - q|

thinnest_wall builds the solid in gmsh (gmsh_mesher's fragment), meshes its surfaces with triangles at most
WALL_SAMPLING of the body's diagonal long, and leaves out the boundaries that touch a chamber's wall (a symmetry plane
its open wall ends on: the distance to them is zero at the rim and says nothing about the wall). On the triangles,
the wall's points are its triangles' corners and centroids (wall_points), and the candidates for each point the
CANDIDATES triangles of the others whose centroids lie nearest (scipy's cKDTree); dist(p, T) is exact: the distance
to p's projection onto T's plane where that falls inside T (barycentric coordinates all >= 0), else to the nearest of
T's three edges (segments a + s (b - a), s clipped to [0, 1]) (nearest_triangles). Where the surfaces are curved,
each triangle's chord lies off the curve by up to h^2 / (8 R) (edge h, curvature radius R), and the nearest points
are seldom corners of the triangles: from the REFINED nearest points on, OpenCASCADE's projections to and fro
between the two exact surfaces (ALTERNATIONS, until the distance falls by less than CONVERGED; where each falls inside
the surface's trimmed face) give the distance of their nearest points. The thickness is cached like the mesh.
"""

from __future__ import annotations

import numpy as np

from ..errors import require
from ..io import cache
from .gmsh_cache import cache_key
from .gmsh_mesher import WALL_DIGITS, Solid, _elements, _faces, _Pieces, node_points
from .gmsh_session import session

CANDIDATES = 12  # triangles of the others tested exactly per wall point, the nearest by centroid
WALL_SAMPLING = 1 / 50  # thinnest_wall's surface mesh: edges at most this fraction of the body's diagonal
REFINED = 16  # ... and the wall points nearest the other boundaries on it, measured again on the exact surfaces
ALTERNATIONS = 5000  # at most so many projections to and fro between the two surfaces, to their nearest points,
CONVERGED = 1e-12  # until the distance falls by less than this fraction (a ball near a plane: by R / (R + d) each)


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
    from scipy.spatial import cKDTree  # here: a 2D run, which imports this module, does not load scipy.spatial

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


def thinnest_wall(solid: Solid) -> float:
    """The thinnest rubber around any of the solid's chambers (module docstring), or one PneumaInputError where no
    chamber has a boundary apart from its wall. Cached like the solid's measures."""
    entry = cache_key("wall", solid)
    cached = cache.load("gmsh-wall", entry, _valid_wall, 4096)
    if cached is not None:
        return float(cached["thinnest"][0])
    with session() as gmsh:
        pieces = _Pieces(gmsh, solid)
        model = gmsh.model
        box = np.reshape(model.getBoundingBox(-1, -1), (2, 3))
        gmsh.option.setNumber("Mesh.MeshSizeMax", WALL_SAMPLING * float(np.linalg.norm(box[1] - box[0])))
        gmsh.option.setNumber("Mesh.Algorithm", 5)  # Delaunay: Frontal-Delaunay leaves B-spline surfaces bare
        model.mesh.generate(2)
        position, points = node_points(gmsh)

        def triangles(surface: int) -> np.ndarray:
            return points[position[_elements(gmsh, 2, [surface], 2, 3)]].reshape(-1, 3, 3)

        def curves(surfaces) -> set[int]:
            return {abs(t) for _, t in model.getBoundary([(2, s) for s in surfaces], False, False)}

        def closest(surface: int, point: np.ndarray) -> np.ndarray | None:
            projected, uv = model.getClosestPoint(2, surface, point)
            return np.asarray(projected) if model.isInside(2, surface, uv, parametric=True) else None

        def exact(point: np.ndarray, wall: int, other: int, measured: float) -> float:
            """The distance of the nearest points of the two surfaces from point on, by alternating projections
            (the measured one where a projection falls outside a surface's trimmed face)."""
            distance = measured
            for _ in range(ALTERNATIONS):
                across = closest(other, point)
                back = None if across is None else closest(wall, across)
                if back is None:
                    return measured
                point, last, distance = back, distance, float(np.linalg.norm(back - across))
                if last - distance <= CONVERGED * distance:
                    break
            return distance

        faces, thinnest = _faces(gmsh, pieces.rubber), float("inf")
        for walls in pieces.walls.values():
            rim = curves(walls)
            apart = [s for s in sorted(faces - set(walls)) if not curves([s]) & rim]
            if not apart:
                continue
            blocks, own = [triangles(s) for s in apart], [triangles(s) for s in walls]
            owner = np.repeat(apart, [len(b) for b in blocks])
            wall = np.concatenate(own)
            on = np.repeat(walls, [len(b) for b in own])
            samples = wall_points(wall)
            distances, nearest = nearest_triangles(samples, np.concatenate(blocks))
            for i in np.argsort(distances)[:REFINED]:
                surfaces = int(on[i // 3 if i < 3 * len(wall) else i - 3 * len(wall)]), int(owner[nearest[i]])
                thinnest = min(thinnest, exact(samples[i], *surfaces, float(distances[i])))
    require(np.isfinite(thinnest), "no chamber has a boundary of the body apart from its wall to measure to")
    thinnest = float(f"{thinnest:.{WALL_DIGITS}g}")
    cache.store("gmsh-wall", entry, {"thinnest": np.array([thinnest])})
    return thinnest


def _valid_wall(arrays: dict) -> bool:
    """A cached wall thickness: one finite positive double."""
    value = arrays["thinnest"]
    return value.dtype == np.float64 and value.shape == (1,) and bool(np.isfinite(value[0]) and value[0] > 0)
