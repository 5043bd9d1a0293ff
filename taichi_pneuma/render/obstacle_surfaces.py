"""The obstacles' shapes (terms/obstacle_shapes.py) as cells for the ParaView files, at their placed position.

In 3D a triangulated surface whose every point lies on the shape's boundary: a sphere, a cylinder (flat caps) and a
capsule (hemispherical caps) as surfaces of revolution about their axis (SEGMENTS points round, a pole point at each
end), a box as its 12 triangles, a plane as a square patch of half-size reach centred on the point of the plane
nearest the given centre (the body's). In 2D the shape's outline in the x-y plane (Shape.outline), z = 0: a closed
one as a polygon, a plane's line as a segment of half-length reach about its point.
"""

from __future__ import annotations

import numpy as np

from ..io.vtk import LINE, POLYGON, TRIANGLE, VtkCell, pad3
from ..terms.obstacle_shapes import Box, Capsule, Cylinder, Plane, Shape, Sphere, axis_vector

SEGMENTS = 48  # points round a surface of revolution
LATITUDES = 12  # rings from pole to equator of a sphere, and of each cap of a capsule


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


def surface(shape: Shape, reach: float, centre: np.ndarray) -> tuple[np.ndarray, VtkCell, np.ndarray]:
    """(points (k, 3), cell type, cells) of a 3D shape's boundary (module docstring); reach and centre place a
    plane's patch."""
    if isinstance(shape, Plane):
        n = np.array(shape.normal, dtype=float) / np.linalg.norm(shape.normal)
        p = np.array(shape.point, dtype=float)
        middle = centre - np.dot(centre - p, n) * n
        helper = np.eye(3)[int(np.argmin(np.abs(n)))]
        t1 = np.cross(n, helper) / np.linalg.norm(np.cross(n, helper))
        t2 = np.cross(n, t1)
        corners = [middle + reach * (a * t1 + b * t2) for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        return np.array(corners), TRIANGLE, np.array([[0, 1, 2], [0, 2, 3]])
    if isinstance(shape, Box):
        half = np.array(shape.size, dtype=float) / 2
        signs = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)]) * 2 - 1
        faces = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]  # outward
        triangles = np.array([t for a, b, c, d in faces for t in ((a, b, c), (a, c, d))])
        return np.array(shape.center, dtype=float) + signs * half, TRIANGLE, triangles
    if isinstance(shape, Sphere):
        phi = np.linspace(-0.5 * np.pi, 0.5 * np.pi, 2 * LATITUDES + 1)
        profile = np.column_stack([shape.radius * np.cos(phi), shape.radius * np.sin(phi)])
        rotation = np.eye(3)
    else:
        assert isinstance(shape, Cylinder)  # and Capsule, its subclass
        r, h = shape.radius, 0.5 * shape.length
        if isinstance(shape, Capsule):
            profile = np.vstack([hemisphere(r, -h, -1.0), hemisphere(r, h, 1.0)[::-1]])
        else:
            profile = np.array([[0.0, -h], [r, -h], [r, h], [0.0, h]])
        rotation = frame(shape.axis)
    profile[[0, -1], 0] = 0.0  # the poles
    points, triangles = revolution(profile)
    return np.array(shape.center, dtype=float) + points @ rotation.T, TRIANGLE, triangles


def outline(shape: Shape, reach: float) -> tuple[np.ndarray, VtkCell, np.ndarray]:
    """(points (k, 3), cell type, cells) of a 2D shape's outline: one polygon, or a plane's one segment."""
    points, closed = shape.outline(reach)
    return pad3(points), POLYGON if closed else LINE, np.arange(len(points))[None, :]
