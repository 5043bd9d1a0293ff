"""Operations on closed polygons (k, 2) and point sets in the plane: the shoelace area, segment crossings, the
even-odd inside test, distances to an outline, an interior point, a chamber wall's enclosed area, and the spacing
check that keeps coincident points away from Triangle (it crashes on them).

A chamber wall's enclosed area is the shoelace area of a closed loop,

    A(x) = 1/2 sum_i (x_i y_{i+1} - x_{i+1} y_i),

or, for a wall cut open by symmetry lines (symmetry.py), 1/2 sum_i (x_i - o) x (x_{i+1} - o) over the open chain,
with the origin o on the lines: the flat cap along them adds nothing.
"""

from __future__ import annotations

import numpy as np

from ..errors import require
from .triangulation import triangulate_or_refuse

MIN_SPACING = 1e-9


def signed_area(polygon: np.ndarray) -> float:
    """Shoelace area of a closed polygon (k, 2); positive when counter-clockwise."""
    x, y = polygon[:, 0], polygon[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def _cross(o, p, q):
    return (p[..., 0] - o[..., 0]) * (q[..., 1] - o[..., 1]) - (p[..., 1] - o[..., 1]) * (q[..., 0] - o[..., 0])


def segments_cross(a0, a1, b0, b1) -> np.ndarray:
    """Pairwise proper crossings between segments a (k, 2) and b (m, 2): a (k, m) boolean array."""
    A0, A1, B0, B1 = a0[:, None], a1[:, None], b0[None, :], b1[None, :]
    return (_cross(A0, A1, B0) * _cross(A0, A1, B1) < 0) & (_cross(B0, B1, A0) * _cross(B0, B1, A1) < 0)


def polygon_self_intersects(points: np.ndarray) -> bool:
    """Whether a closed polygon's non-adjacent edges cross (a proper segment intersection)."""
    a, b = points, np.roll(points, -1, axis=0)
    n = len(points)
    i, j = np.indices((n, n))
    adjacent = (np.abs(i - j) <= 1) | (np.abs(i - j) == n - 1)
    return bool(np.any(segments_cross(a, b, a, b) & ~adjacent))


def points_in_polygon(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Even-odd rule: which of points (k, 2) lie inside the closed polygon (m, 2)."""
    a, b = polygon, np.roll(polygon, -1, axis=0)
    px, py = points[:, 0:1], points[:, 1:2]
    straddles = (a[None, :, 1] > py) != (b[None, :, 1] > py)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_at = a[None, :, 0] + (py - a[None, :, 1]) * (b[None, :, 0] - a[None, :, 0]) / (b[None, :, 1] - a[None, :, 1])
    return np.count_nonzero(straddles & (px < x_at), axis=1) % 2 == 1


def distance_to_polygon(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Distance from each of points (k, 2) to the boundary of a closed polygon (m, 2)."""
    a, b = polygon[None, :], np.roll(polygon, -1, axis=0)[None, :]
    p = points[:, None]
    e = b - a
    t = np.clip(np.sum((p - a) * e, axis=2) / np.sum(e * e, axis=2), 0.0, 1.0)
    return np.min(np.linalg.norm(p - (a + t[..., None] * e), axis=2), axis=1)


def interior_point(polygon: np.ndarray) -> np.ndarray:
    """A point strictly inside a simple polygon: the centroid of the largest triangle of its triangulation."""
    k = len(polygon)
    tri = triangulate_or_refuse(
        {"vertices": polygon, "segments": np.column_stack([np.arange(k), (np.arange(k) + 1) % k])}, "p"
    )
    corners = tri["vertices"][tri["triangles"]]
    e1, e2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    return corners[np.argmax(np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]))].mean(axis=0)


def enclosed_area(points: np.ndarray, origin: np.ndarray | None = None) -> float:
    """The signed area a chamber wall encloses: the shoelace area of a closed loop (origin None), or for an
    open wall from symmetry line to symmetry line 1/2 sum_i (x_i - o) x (x_{i+1} - o), with the origin o on
    the lines (their intersection for two): the flat cap along the lines adds nothing."""
    if origin is None:
        return signed_area(points)
    r = points - origin
    return 0.5 * float(np.sum(r[:-1, 0] * r[1:, 1] - r[:-1, 1] * r[1:, 0]))


def require_spaced(what: str, polygon: np.ndarray) -> None:
    """Refuse an outline with two points closer than MIN_SPACING of its size (Triangle crashes on them)."""
    size = float(np.ptp(polygon, axis=0).max())
    require(np.isfinite(size), f"{what}: its outline points overflow to infinity")
    require(
        not has_close_pair((polygon - polygon.min(axis=0)) / size, MIN_SPACING),
        f"{what}: two of its outline points coincide (closer than {MIN_SPACING:g} of its size {size:.3g}): "
        f"a radius, size or point spacing too small, or coordinates too large, to mesh",
    )


def has_close_pair(points: np.ndarray, r: float) -> bool:
    """Whether two of the points (n, 2) lie within distance r (<=) of each other. Sorted by x, point i can only
    be that close to the points after it whose x is at most x_i + r: those candidate pairs (all pairs at worst,
    when the points share one x) are compared at once."""
    p = points[np.argsort(points[:, 0], kind="stable")]
    counts = np.searchsorted(p[:, 0], p[:, 0] + r, side="right") - np.arange(1, len(p) + 1)
    first = np.repeat(np.arange(len(p)), counts)
    second = first + 1 + np.arange(len(first)) - np.repeat(np.cumsum(counts) - counts, counts)
    return bool(np.any(np.sum((p[second] - p[first]) ** 2, axis=1) <= r * r))
