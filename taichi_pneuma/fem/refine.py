"""Midside nodes and uniform refinement of simplex meshes: the midpoint of every edge of an element table, boundary
segments split at those midpoints, and triangles split in four at them.
"""

from __future__ import annotations

import numpy as np


def with_edge_midpoints(vertices: np.ndarray, elements: np.ndarray, edges=((0, 1), (1, 2), (2, 0))):
    """The vertices with the midpoint of every edge of the (corner) elements appended, and mid(a, b): the
    index of the midpoint of edge (a, b), elementwise over index arrays. edges: the corner pairs of an
    element that are its edges (a triangle's by default)."""
    unique = np.unique(np.sort(np.vstack([elements[:, list(e)] for e in edges]), axis=1), axis=0)
    n = len(vertices)
    keys = unique[:, 0] * n + unique[:, 1]

    def mid(a, b):
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        return n + np.searchsorted(keys, lo * n + hi)

    return np.vstack([vertices, 0.5 * (vertices[unique[:, 0]] + vertices[unique[:, 1]])]), mid


def halved(segments: np.ndarray, markers: np.ndarray, mid) -> tuple[np.ndarray, np.ndarray]:
    """Boundary segments (s, 2) and their markers split at their midpoint nodes mid(a, b): (2 s, 2), (2 s,)."""
    halves = mid(segments[:, 0], segments[:, 1])
    return (
        np.vstack([np.column_stack([segments[:, 0], halves]), np.column_stack([halves, segments[:, 1]])]),
        np.concatenate([markers, markers]),
    )


def split_in_four(triangles: np.ndarray) -> np.ndarray:
    """The four corner-and-midpoint triangles of each (m, 6) triangle (corners, then edge midpoints 01, 12,
    20): the three corner triangles, then the middle one; all counter-clockwise when the input is."""
    c0, c1, c2, m01, m12, m20 = triangles.T
    return np.vstack([np.column_stack(t) for t in ((c0, m01, m20), (m01, c1, m12), (m20, m12, c2), (m01, m12, m20))])
