"""The exact section of a body by a plane fixed in the rest body: the surface triangles clipped at the plane, and
the cut face of every tetrahedron the plane crosses, so the cut edge is straight (no tetrahedron removed whole).

The plane is x[axis] = value at rest, the side sign (x[axis] - value) > 0 removed. A node's signed distance is
d = sign (X[axis] - value) at rest; a node is kept where d <= 0. Every point drawn is a blend of two nodes,

    p = (1 - t) x_a + t x_b,    t = d_a / (d_a - d_b)  on an edge from a removed node a to a kept node b,

(a node itself: a = b, t = 0), fixed at rest and evaluated at each step's positions: the section is material, it
moves with the body, and the cut of a straight rest edge stays on that edge. A triangle is clipped against the plane
(Sutherland-Hodgman: its kept corners and the crossings of its edges, in order, fanned into triangles, orientation
kept); a tetrahedron with corners on both sides is cut in a triangle (one corner alone on its side: the crossings
of its three edges) or a quadrilateral (two and two: the crossings of edges p1 n1, p1 n2, p2 n2, p2 n1, a cycle, as
two triangles), oriented with its rest normal towards the removed side (towards the eye that chose it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

AXES = "xyz"


@dataclass(frozen=True, eq=False)
class Section:
    """A section (module docstring): the plane x[axis] = value, the side sign (x[axis] - value) > 0 removed; points
    (1 - t) x[a] + t x[b]; the kept surface triangles (k, 3) into points and the triangle of the input each came
    from; the same for the chamber walls; the cut triangles (c, 3) into points and the tetrahedron of each."""

    axis: int
    value: float
    sign: float
    a: np.ndarray
    b: np.ndarray
    t: np.ndarray
    surface: np.ndarray
    surface_of: np.ndarray
    walls: np.ndarray
    cut: np.ndarray
    cut_of: np.ndarray

    def points(self, x: np.ndarray) -> np.ndarray:
        """The section's points (p, 3) at node positions x (n, 3)."""
        return x[self.a] * (1 - self.t)[:, None] + x[self.b] * self.t[:, None]

    def values(self, nodal: np.ndarray) -> np.ndarray:
        """Node values (n,) (or (n, ...)) interpolated to the points, as the positions are."""
        t = self.t.reshape(-1, *([1] * (np.ndim(nodal) - 1)))
        return nodal[self.a] * (1 - t) + nodal[self.b] * t


class _Points:
    """The section's points: every node first (point i = node i), then the edge crossings, each made once."""

    def __init__(self, n: int, d: np.ndarray):
        self.d, self.a, self.b, self.t = d, list(range(n)), list(range(n)), [0.0] * n
        self.crossing: dict[tuple[int, int], int] = {}

    def on_edge(self, removed: int, kept: int) -> int:
        if (removed, kept) not in self.crossing:
            self.crossing[removed, kept] = len(self.a)
            self.a.append(removed)
            self.b.append(kept)
            self.t.append(self.d[removed] / (self.d[removed] - self.d[kept]))
        return self.crossing[removed, kept]


def _clip(triangles: np.ndarray, points: _Points) -> tuple[np.ndarray, np.ndarray]:
    """The kept parts of triangles (k, 3) as triangles into points, and the input triangle of each."""
    kept = points.d[triangles] <= 0
    whole = np.flatnonzero(kept.all(axis=1))
    pieces, of = [triangles[whole]], [whole]
    for f in np.flatnonzero(kept.any(axis=1) & ~kept.all(axis=1)):
        polygon = []
        for k in range(3):
            p, q = triangles[f, k], triangles[f, (k + 1) % 3]
            if kept[f, k]:
                polygon.append(p)
            if kept[f, k] != kept[f, (k + 1) % 3]:
                polygon.append(points.on_edge(q, p) if kept[f, k] else points.on_edge(p, q))
        fan = np.array([[polygon[0], polygon[j], polygon[j + 1]] for j in range(1, len(polygon) - 1)])
        pieces.append(fan)
        of.append(np.full(len(fan), f))
    return np.concatenate(pieces).reshape(-1, 3).astype(np.int64), np.concatenate(of).astype(np.int64)


def _cut(tetrahedra: np.ndarray, points: _Points) -> tuple[np.ndarray, np.ndarray]:
    """The cut triangles (c, 3) into points of the tetrahedra (m, 4) the plane crosses, and their tetrahedra."""
    removed = points.d[tetrahedra] > 0
    count = removed.sum(axis=1)
    triangles, of = [], []
    for e in np.flatnonzero((count > 0) & (count < 4)):
        up, down = tetrahedra[e][removed[e]], tetrahedra[e][~removed[e]]
        if len(up) == 1:
            triangles.append([points.on_edge(up[0], q) for q in down])
        elif len(up) == 3:
            triangles.append([points.on_edge(p, down[0]) for p in up])
        else:
            (p1, p2), (n1, n2) = up, down
            quad = [points.on_edge(p1, n1), points.on_edge(p1, n2), points.on_edge(p2, n2), points.on_edge(p2, n1)]
            triangles += [quad[:3], [quad[0], quad[2], quad[3]]]
            of.append(e)
        of.append(e)
    return np.array(triangles, dtype=np.int64).reshape(-1, 3), np.array(of, dtype=np.int64)


def section_of(
    rest: np.ndarray,
    surface: np.ndarray,
    walls: np.ndarray,
    tetrahedra: np.ndarray | None,
    axis: int,
    value: float,
    sign: float,
) -> Section:
    """The Section of the body at rest (nodes (n, 3), surface and wall triangles, linear tetrahedra (m, 4) or None:
    no cut face) by the plane x[axis] = value, the side sign (x[axis] - value) > 0 removed."""
    points = _Points(len(rest), sign * (rest[:, axis] - value))
    kept, kept_of = _clip(surface, points)
    kept_walls, _ = _clip(walls, points)
    cut, cut_of = _cut(tetrahedra, points) if tetrahedra is not None else (np.zeros((0, 3), np.int64), np.zeros(0, int))
    a, b, t = (np.array(v) for v in (points.a, points.b, points.t))
    at_rest = rest[a] * (1 - t)[:, None] + rest[b] * t[:, None]
    tiny = 1e-12 * float(np.ptp(rest, axis=0).max()) ** 2

    def normals(triangles: np.ndarray) -> np.ndarray:
        x = at_rest[triangles]
        return np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]).reshape(-1, 3)

    # a corner on the plane makes zero-area pieces: dropped
    kept_keep, walls_keep, cut_keep = (np.linalg.norm(normals(f), axis=1) > tiny for f in (kept, kept_walls, cut))
    kept, kept_of, kept_walls, cut, cut_of = (
        kept[kept_keep],
        kept_of[kept_keep],
        kept_walls[walls_keep],
        cut[cut_keep],
        cut_of[cut_keep],
    )
    flip = sign * normals(cut)[:, axis] < 0  # the cut faces' rest normals towards the removed side
    cut[flip] = cut[flip][:, ::-1]
    return Section(axis, value, sign, a, b, t.astype(float), kept, kept_of, kept_walls, cut, cut_of)


def plane_facing(rest: np.ndarray, towards_eye: np.ndarray) -> tuple[int, float, float]:
    """(axis, value, sign) of the mid-plane of the rest bounding box normal to the world axis closest to the
    direction towards the eye, the eye's side removed."""
    axis = int(np.argmax(np.abs(towards_eye)))
    return axis, float((rest[:, axis].min() + rest[:, axis].max()) / 2), float(np.sign(towards_eye[axis]) or 1.0)
