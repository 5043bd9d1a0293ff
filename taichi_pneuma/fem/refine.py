"""Edge nodes and uniform refinement of simplex meshes: the nodes of every edge of an element table (its midpoint, or
order - 1 evenly spaced ones), boundary segments split at those nodes, and triangles split in four at midpoints.
"""

from __future__ import annotations

import numpy as np


def with_edge_nodes(vertices: np.ndarray, elements: np.ndarray, edges, order: int):
    """The vertices with order - 1 nodes on every edge of the (corner) elements appended, node t = 1..order - 1 of
    edge (a, b), a < b, at ((order - t) X_a + t X_b) / order (the midpoint (X_a + X_b) / 2 at order 2), and
    along(a, b): the indices (..., order - 1) of edge (a, b)'s nodes from a to b, elementwise over index arrays.
    edges: the corner pairs of an element that are its edges."""
    unique = np.unique(np.sort(np.vstack([elements[:, list(e)] for e in edges]), axis=1), axis=0)
    n, inner = len(vertices), order - 1
    keys = unique[:, 0] * n + unique[:, 1]
    t = np.arange(1, order)

    def along(a, b):
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        first = n + inner * np.searchsorted(keys, lo * n + hi)
        forward = np.asarray(a <= b)[..., None]
        return np.where(forward, first[..., None] + t - 1, first[..., None] + inner - t)

    lo, hi = vertices[unique[:, 0]][:, None], vertices[unique[:, 1]][:, None]
    new = ((order - t)[None, :, None] * lo + t[None, :, None] * hi) / order
    return np.vstack([vertices, new.reshape(-1, vertices.shape[1])]), along


def subdivided(segments: np.ndarray, markers: np.ndarray, along) -> tuple[np.ndarray, np.ndarray]:
    """Boundary segments (s, 2) and their markers cut at their edge nodes along(a, b) (s, p - 1) into p pieces
    each: (p s, 2), (p s,), the first pieces of every segment, then the second ones, ..."""
    chain = np.column_stack([segments[:, :1], along(segments[:, 0], segments[:, 1]), segments[:, 1:]])
    pieces = [chain[:, k : k + 2] for k in range(chain.shape[1] - 1)]
    return np.vstack(pieces), np.tile(markers, len(pieces))


def split_in_four(triangles: np.ndarray) -> np.ndarray:
    """The four corner-and-midpoint triangles of each (m, 6) triangle (corners, then edge midpoints 01, 12,
    20): the three corner triangles, then the middle one; all counter-clockwise when the input is."""
    c0, c1, c2, m01, m12, m20 = triangles.T
    return np.vstack([np.column_stack(t) for t in ((c0, m01, m20), (m01, c1, m12), (m20, m12, c2), (m01, m12, m20))])
