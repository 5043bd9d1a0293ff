"""Structured tetrahedral meshes without a mesh generator: layers of prisms over a triangle mesh, each prism
split into three tetrahedra. Two uses: a 2D mesh extruded through a depth (the plane-strain body in 3D),
and an octant of a thick spherical shell (a pressurised sphere, closed by three symmetry planes).

Node v of layer k is k n + v (n nodes per layer). A prism over triangle (a, b, c), a < b < c, between
layers k and k + 1 is split as

    (a_k, b_k, c_k, c_k+1),   (a_k, b_k, b_k+1, c_k+1),   (a_k, a_k+1, b_k+1, c_k+1),

which cuts each of its quadrilateral sides (p, q), p < q, along the diagonal p_k - q_k+1: the rule depends
on the side alone, so neighbouring prisms cut their shared side alike and the mesh is conforming.
"""

from __future__ import annotations

import numpy as np

from .mesh import Mesh


def layered_tets(n: int, triangles: np.ndarray, layers: int) -> np.ndarray:
    """The tetrahedra (3 m layers, 4) of `layers` layers of prisms over the triangles (m, 3) of n nodes per layer."""
    a, b, c = np.sort(triangles, axis=1).T
    out = []
    for k in range(layers):
        lo, hi = k * n, (k + 1) * n
        out += [
            np.column_stack(t)
            for t in (
                (a + lo, b + lo, c + lo, c + hi),
                (a + lo, b + lo, b + hi, c + hi),
                (a + lo, a + hi, b + hi, c + hi),
            )
        ]
    return np.vstack(out)


def layered_sides(n: int, edges: np.ndarray, layers: int) -> np.ndarray:
    """The triangles (2 e layers, 3) of the prisms' sides over the edges (e, 2), cut as the prisms cut them."""
    p, q = np.sort(edges, axis=1).T
    out = []
    for k in range(layers):
        lo, hi = k * n, (k + 1) * n
        out += [np.column_stack((p + lo, q + lo, q + hi)), np.column_stack((p + lo, q + hi, p + hi))]
    return np.vstack(out)


def extrude(mesh: Mesh, depth: float, layers: int = 1) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """The linear triangles of a 2D mesh extruded along z from 0 to depth in equal layers: (vertices (n (layers
    + 1), 3), tetrahedra, and per chamber its wall: the sides over its wall's edges, through the depth)."""
    corners = mesh.triangles[:, :3]
    used = np.unique(corners)  # the corner nodes (a quadratic mesh's midside nodes are left out)
    number = np.full(mesh.n_vertices, -1)
    number[used] = np.arange(len(used))
    n = len(used)
    z = np.linspace(0.0, depth, layers + 1)
    vertices = np.vstack([np.column_stack([mesh.vertices[used], np.full(n, zk)]) for zk in z])
    walls = []
    for loop, origin in zip(mesh.chambers, mesh.wall_origins):
        nodes = number[loop[:: mesh.order]]  # the wall's corners
        pairs = np.column_stack([nodes, np.roll(nodes, -1)])
        walls.append(layered_sides(n, pairs if origin is None else pairs[:-1], layers))
    return vertices, layered_tets(n, number[corners], layers), walls


def octant_grid(divisions: int) -> tuple[np.ndarray, np.ndarray]:
    """The triangle x, y, z >= 0, x + y + z = 1 cut into divisions^2 triangles: (points (p, 3), triangles)."""
    index = {}
    points: list[tuple[int, int, int]] = []
    for i in range(divisions + 1):
        for j in range(divisions + 1 - i):
            index[i, j] = len(points)
            points.append((i, j, divisions - i - j))
    triangles = []
    for i in range(divisions):
        for j in range(divisions - i):
            triangles.append((index[i, j], index[i + 1, j], index[i, j + 1]))
            if i + j < divisions - 1:
                triangles.append((index[i + 1, j], index[i + 1, j + 1], index[i, j + 1]))
    return np.array(points, dtype=np.float64) / divisions, np.array(triangles)


def spherical_shell_octant(
    inner: float, outer: float, divisions: int, layers: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An octant (x, y, z >= 0) of the shell inner <= |x| <= outer: the octant triangle's grid projected onto
    the sphere, extruded radially in equal layers. Returns (vertices, tetrahedra, the inner surface's
    triangles): the cavity wall, open on the three coordinate planes."""
    points, triangles = octant_grid(divisions)
    directions = points / np.linalg.norm(points, axis=1, keepdims=True)
    radii = np.linspace(inner, outer, layers + 1)
    vertices = np.vstack([r * directions for r in radii])
    return vertices, layered_tets(len(points), triangles, layers), triangles
