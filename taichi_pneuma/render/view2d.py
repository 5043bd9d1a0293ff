"""What a 2D frame draws of a body besides its states: its element edges (all, or the outline only), its chambers
as triangles, and the world box a frame shows (render.frames)."""

from __future__ import annotations

import numpy as np

from ..errors import require
from ..fem.mesh import Mesh
from ..fem.triangulation import triangulate


def view_bounds(tracks: list) -> tuple[np.ndarray, np.ndarray]:
    """The world box (lo, hi) a frame shows: every step's positions of every track, their rest shapes and targets,
    and the closed obstacles (at every step's offset) that reach within a tenth of the body's size of that box."""
    points = np.concatenate(
        [t.states.reshape(-1, 2) for t in tracks]
        + [t.mesh.vertices[:, :2] for t in tracks]
        + [t.targets for t in tracks if t.targets is not None]
    )
    lo, hi = points.min(axis=0), points.max(axis=0)
    near = 0.1 * float(np.max(hi - lo))
    for t in tracks:
        for outline, closed, offsets in t.obstacles:
            shapes = outline[None] + offsets[:, None]
            if closed and np.all(shapes.min(axis=(0, 1)) <= hi + near) and np.all(shapes.max(axis=(0, 1)) >= lo - near):
                lo, hi = np.minimum(lo, shapes.min(axis=(0, 1))), np.maximum(hi, shapes.max(axis=(0, 1)))
    return lo, hi


def chamber_triangles(mesh: Mesh) -> np.ndarray:
    """Triangulate every chamber's rest wall loop (no added points); reused on every deformed loop."""
    parts = []
    for loop in mesh.chambers:
        k = len(loop)
        ring = np.column_stack([np.arange(k), (np.arange(k) + 1) % k])
        out = triangulate({"vertices": mesh.vertices[loop], "segments": ring}, "p")
        require(len(out["vertices"]) == k, "chamber wall loop could not be triangulated without extra points")
        parts.append(loop[out["triangles"]])
    return np.concatenate(parts)


def mesh_edges(mesh: Mesh, boundary_only: bool = False) -> np.ndarray:
    """Unique undirected edges (e, 2) of the element outlines: a quadratic triangle's sides are drawn as
    two segments each, through their midside nodes; boundary_only: the edges of one element only (the
    body's outline and the chamber walls)."""
    assert mesh.family is not None  # (Mesh fills it in)
    t = mesh.triangles[:, list(mesh.family.outline)]
    edges = np.sort(np.stack([t, np.roll(t, -1, axis=1)], axis=2).reshape(-1, 2), axis=1)
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    return unique[counts == 1] if boundary_only else unique
