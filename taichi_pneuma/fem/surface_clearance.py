"""How close two triangle surfaces come: the clearance between a surface body's separate chamber surface and the
body's other surfaces (fem/surface_import.py), where a chamber that touches or crosses another surface is refused.

The gap between two triangles is 0 where they meet (an edge of one crosses the other: Moller-Trumbore with the
segment's parameter in [0, 1]), else the least of the 6 distances from a corner of one to the other triangle and the
9 distances between an edge of each (two triangles apart are closest at a corner or at a pair of edges).

    point - triangle   the projection's barycentric coordinates all >= 0: the distance to the plane; else the least
                       distance to the three edges
    point - segment    |p - (a + s (b - a))|, s = (p - a).(b - a) / |b - a|^2 clamped to [0, 1]
    segment - segment  the closest points of the two lines, where both parameters lie in [0, 1]; else (the least
                       over the parameter square lies on its border) the least of the 4 endpoint - segment distances

Only pairs of triangles whose bounding spheres (about the centroid, through the farthest corner) come within the
gap are measured: the triangles are put into classes of radius within a factor of 2, and each pair of classes is
searched with a k-d tree, so a few large facets beside many small ones do not make every pair a candidate.
"""

from __future__ import annotations

import numpy as np

CHUNK = 200_000  # triangle pairs measured at once


def point_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rowwise distance from p to the segment [a, b] (module docstring); all (k, 3)."""
    d = b - a
    s = np.clip(np.einsum("ij,ij->i", p - a, d) / np.maximum(np.einsum("ij,ij->i", d, d), 1e-300), 0.0, 1.0)
    return np.linalg.norm(p - a - s[:, None] * d, axis=1)


def point_triangle(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Rowwise distance from p (k, 3) to the triangle t (k, 3, 3) (module docstring)."""
    a, b, c = t[:, 0], t[:, 1], t[:, 2]
    n = np.cross(b - a, c - a)
    area2 = np.maximum(np.einsum("ij,ij->i", n, n), 1e-300)
    # barycentric coordinates of the projection: the signed areas of the sub-triangles over the whole
    u = np.einsum("ij,ij->i", np.cross(c - b, p - b), n) / area2
    v = np.einsum("ij,ij->i", np.cross(a - c, p - c), n) / area2
    w = 1.0 - u - v
    plane = np.abs(np.einsum("ij,ij->i", p - a, n)) / np.sqrt(area2)
    edges = np.minimum(np.minimum(point_segment(p, a, b), point_segment(p, b, c)), point_segment(p, c, a))
    return np.where((u >= 0) & (v >= 0) & (w >= 0), plane, edges)


def segment_segment(p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    """Rowwise distance between the segments [p0, p1] and [q0, q1] (module docstring)."""
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a, e, b = (np.einsum("ij,ij->i", x, y) for x, y in ((d1, d1), (d2, d2), (d1, d2)))
    c, f = np.einsum("ij,ij->i", d1, r), np.einsum("ij,ij->i", d2, r)
    denominator = a * e - b * b
    ok = denominator > 1e-12 * np.maximum(a * e, 1e-300)  # not parallel
    s = (b * f - c * e) / np.where(ok, denominator, 1.0)
    t = (a * f - b * c) / np.where(ok, denominator, 1.0)
    interior = ok & (s >= 0) & (s <= 1) & (t >= 0) & (t <= 1)
    lines = np.linalg.norm(r + s[:, None] * d1 - t[:, None] * d2, axis=1)  # the lines' least distance
    ends = np.minimum(
        np.minimum(point_segment(p0, q0, q1), point_segment(p1, q0, q1)),
        np.minimum(point_segment(q0, p0, p1), point_segment(q1, p0, p1)),
    )
    return np.where(interior, lines, ends)


def crosses(p: np.ndarray, q: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Rowwise: whether the segment [p, q] meets the triangle t (Moller-Trumbore, the parameter in [0, 1])."""
    direction = q - p
    e1, e2 = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]
    h = np.cross(direction, e2)
    det = np.einsum("ij,ij->i", e1, h)
    ok = np.abs(det) > 1e-300
    det = np.where(ok, det, 1.0)
    s = p - t[:, 0]
    u = np.einsum("ij,ij->i", s, h) / det
    k = np.cross(s, e1)
    v = np.einsum("ij,ij->i", direction, k) / det
    along = np.einsum("ij,ij->i", e2, k) / det
    return ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (along >= 0) & (along <= 1)


def triangle_gaps(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rowwise gap between the triangles a (k, 3, 3) and b (k, 3, 3): 0 where they meet (module docstring)."""
    gap = np.full(len(a), np.inf)
    met = np.zeros(len(a), dtype=bool)
    for i in range(3):
        j = (i + 1) % 3
        met |= crosses(a[:, i], a[:, j], b) | crosses(b[:, i], b[:, j], a)
        gap = np.minimum(gap, np.minimum(point_triangle(a[:, i], b), point_triangle(b[:, i], a)))
        for m in range(3):
            n = (m + 1) % 3
            gap = np.minimum(gap, segment_segment(a[:, i], a[:, j], b[:, m], b[:, n]))
    return np.where(met, 0.0, gap)


def spheres(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each triangle's bounding sphere: centroid and the distance to its farthest corner."""
    centre = t.mean(axis=1)
    return centre, np.linalg.norm(t - centre[:, None], axis=2).max(axis=1)


def candidates(a: np.ndarray, b: np.ndarray, gap: float) -> tuple[np.ndarray, np.ndarray]:
    """The pairs (rows of a, rows of b) of triangles whose bounding spheres come within gap (module docstring)."""
    from scipy.spatial import cKDTree  # here: a run without a surface chamber does not load SciPy's trees

    (ca, ra), (cb, rb) = spheres(a), spheres(b)
    rows, cols = [], []
    classes = []  # per set: (its rows in a radius class, the class's bound on the radius)
    for radius in (ra, rb):
        level = np.floor(np.log2(np.maximum(radius, 1e-300))).astype(np.int64)
        classes.append([(np.flatnonzero(level == k), 2.0 ** (k + 1)) for k in np.unique(level)])
    for ia, bound_a in classes[0]:
        tree_a = cKDTree(ca[ia])
        for ib, bound_b in classes[1]:
            near = tree_a.sparse_distance_matrix(cKDTree(cb[ib]), bound_a + bound_b + gap, output_type="ndarray")
            i, j = ia[near["i"]], ib[near["j"]]
            keep = near["v"] <= ra[i] + rb[j] + gap
            rows.append(i[keep])
            cols.append(j[keep])
    return np.concatenate(rows), np.concatenate(cols)


def closest_approach(a: np.ndarray, b: np.ndarray, gap: float) -> tuple[float, np.ndarray] | None:
    """The least gap between the triangle sets a (p, 3, 3) and b (q, 3, 3), and the centroid of a's triangle there,
    where it is at most `gap`; None where they stay farther apart."""
    rows, cols = candidates(a, b, gap)
    best: tuple[float, np.ndarray] | None = None
    for start in range(0, len(rows), CHUNK):
        i, j = rows[start : start + CHUNK], cols[start : start + CHUNK]
        gaps = triangle_gaps(a[i], b[j])
        k = int(np.argmin(gaps))
        if gaps[k] <= gap and (best is None or gaps[k] < best[0]):
            best = (float(gaps[k]), a[i[k]].mean(axis=0))
    return best
