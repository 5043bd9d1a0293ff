"""Whether the body's surface passes through itself: the first two of its pieces that cross.

The surface (every boundary facet, the outer one and the chamber walls alike) is taken as straight pieces
(surface_pieces): triangles in 3D, a quadratic facet split at its midside nodes into four; segments in 2D, a
quadratic edge split at its middle node into two. Two pieces that share a node are neighbours and never
counted; any other two must not cross.

Broad phase. Each piece's axis-aligned box [lo, hi] is entered in every cell of a uniform grid of side h (the
median of the boxes' largest sides, or 1/SPAN of the largest where that is more) that it covers; two pieces are
candidates where they share a cell and their boxes overlap, each pair counted once, in the lowest cell both boxes
cover (the cell max(first_i, first_j), the componentwise largest of the two boxes' first cells). On a surface a
cell holds a few pieces, so the work grows like the number of pieces, not its square.

Narrow phase, with a touching tolerance e = TOUCH times the longer of the two pieces' longest sides:

3D, triangles T and S (Moller's interval test). With n_T the unit normal of T and a_T a corner of it, the signed
distances of S's corners to T's plane are s_k = (x_k - a_T) . n_T, and likewise t_k of T's corners to S's plane.
T and S cross where each straddles the other's plane by more than e,

    max_k s_k > e,  min_k s_k < -e,  max_k t_k > e,  min_k t_k < -e,

and the two segments in which they meet the line L of the planes' intersection (direction D = n_T x n_S,
normalised) overlap by more than e along it: T meets S's plane at the points x_i + (x_j - x_i) t_i / (t_i - t_j)
of its sides (i, j) with t_i t_j < 0 (and at a corner with t_k = 0), whose projections on D span [lo_T, hi_T];
the overlap is min(hi_T, hi_S) - max(lo_T, lo_S). A triangle that only touches the other's plane (a corner, a
side or itself lying in it: coplanar triangles, overlapping or not), or touches the other triangle along a side,
or enters it by no more than e, does not cross.

2D, segments ab and cd: they cross where c and d lie on opposite sides of line ab, each farther than e from it,
and a and b on opposite sides of line cd likewise (signed distances (b - a) x (p - a) / |b - a|); collinear or
touching segments do not. The crossing point is a + (b - a) t_a / (t_a - t_b), t the distances of a, b to cd.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

TOUCH = 1e-6  # two pieces closer than this times their longest side touch; only deeper ones cross
SPAN = 32  # the grid's cell side is at least the largest box's side / SPAN: no box covers more than (SPAN + 1)^d


class Crossing(NamedTuple):
    """Pieces first < second (rows of the pieces' table) that cross, and a point (d,) where they do."""

    first: int
    second: int
    point: np.ndarray


def surface_pieces(mesh) -> np.ndarray:
    """The body's boundary (mesh.surface: the outer one and the chamber walls, oriented outward from the body) as
    straight pieces (f, 3) of node indices: in 3D triangles (a quadratic facet split at its midside nodes into
    four), in 2D segments (a, b) as (a, b, b) (a quadratic edge split at its middle node into two)."""
    pieces = mesh.family.facet_pieces(mesh.surface)  # an edge: (corner, corner, its nodes in between)
    return pieces if mesh.dim == 3 else pieces[:, [0, 1, 1]]


def box_pairs(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(i, j), i < j: every pair of the boxes [lo_k, hi_k] (n, d) that overlap (lo_i <= hi_j and lo_j <= hi_i on
    every axis), by the uniform grid of the module docstring."""
    n, d = lo.shape
    sides = np.max(hi - lo, axis=1)
    size = max(float(np.median(sides)), float(np.max(sides)) / SPAN) if n else 0.0
    size = size if size > 0 else 1.0  # boxes of no extent (points): any cell side sorts them
    origin = lo.min(axis=0) if n else np.zeros(d)
    first = np.floor((lo - origin) / size).astype(np.int64)
    last = np.floor((hi - origin) / size).astype(np.int64)
    span = last - first + 1
    count = span.prod(axis=1)  # cells each box covers
    owner = np.repeat(np.arange(n), count)
    k = np.arange(len(owner)) - np.repeat(np.cumsum(count) - count, count)
    cells = np.empty((len(owner), d), dtype=np.int64)
    for axis in range(d):  # k as a multi-index within the owner's block of cells
        cells[:, axis] = first[owner, axis] + k % span[owner, axis]
        k //= span[owner, axis]
    extent = last.max(axis=0) + 1 if n else np.ones(d, dtype=np.int64)
    key = cells[:, 0].copy()
    for axis in range(1, d):
        key = key * extent[axis] + cells[:, axis]
    order = np.argsort(key, kind="stable")  # stable: owners ascend within a cell
    key, owner, cells = key[order], owner[order], cells[order]
    starts = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    ends = np.r_[starts[1:], len(key)]
    after = np.repeat(ends, ends - starts) - np.arange(len(key)) - 1  # entries after each one in its cell
    a = np.repeat(np.arange(len(key)), after)
    b = a + 1 + np.arange(len(a)) - np.repeat(np.cumsum(after) - after, after)
    i, j = owner[a], owner[b]
    keep = np.ones(len(a), dtype=bool)
    for axis in range(d):  # column by column: gathers of contiguous 1D arrays
        low, high = np.ascontiguousarray(lo[:, axis]), np.ascontiguousarray(hi[:, axis])
        start, cell = np.ascontiguousarray(first[:, axis]), np.ascontiguousarray(cells[:, axis])
        keep &= (low[i] <= high[j]) & (low[j] <= high[i]) & (cell[a] == np.maximum(start[i], start[j]))
    return i[keep], j[keep]


def _longest_side(p: np.ndarray) -> np.ndarray:
    """The longest side (m,) of each piece's corners p (m, k, d)."""
    return np.max(np.linalg.norm(p - np.roll(p, 1, axis=1), axis=2), axis=1)


def segments_cross(p: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(whether segment p_m crosses q_m (m,), the crossing points (m, 2)) for segments p, q (m, 2, 2)
    (module docstring)."""
    e = TOUCH * np.maximum(_longest_side(p), _longest_side(q))

    def distances(s, points):  # signed distances (m, 2) of points (m, 2, 2) to the line of segment s (m, 2, 2)
        v = s[:, 1] - s[:, 0]
        r = points - s[:, None, 0]
        length = np.linalg.norm(v, axis=1)[:, None]
        with np.errstate(invalid="ignore", divide="ignore"):
            return (v[:, None, 0] * r[..., 1] - v[:, None, 1] * r[..., 0]) / length

    tq, tp = distances(p, q), distances(q, p)
    cross = (tq.max(axis=1) > e) & (tq.min(axis=1) < -e) & (tp.max(axis=1) > e) & (tp.min(axis=1) < -e)
    with np.errstate(invalid="ignore", divide="ignore"):
        point = p[:, 0] + (p[:, 1] - p[:, 0]) * (tp[:, :1] / (tp[:, :1] - tp[:, 1:]))
    return cross, point


def _plane_segment(x: np.ndarray, t: np.ndarray, direction: np.ndarray) -> tuple[np.ndarray, ...]:
    """(lo, hi, x_lo, x_hi): the span (m,) along direction (m, 3) of where triangles x (m, 3, 3), whose corners lie
    at signed distances t (m, 3) from a plane, meet it (sides with t_i t_j < 0, corners with t_k = 0), and the
    points (m, 3) at its ends."""
    i, j = np.array([0, 1, 2]), np.array([1, 2, 0])
    ti, tj = t[:, i], t[:, j]
    with np.errstate(invalid="ignore", divide="ignore"):
        sides = x[:, i] + (x[:, j] - x[:, i]) * (ti / (ti - tj))[..., None]
    points = np.concatenate([sides, x], axis=1)  # (m, 6, 3)
    valid = np.concatenate([ti * tj < 0, t == 0], axis=1)
    along = np.einsum("mki,mi->mk", points, direction)
    low = np.argmin(np.where(valid, along, np.inf), axis=1)
    high = np.argmax(np.where(valid, along, -np.inf), axis=1)
    rows = np.arange(len(x))
    return along[rows, low], along[rows, high], points[rows, low], points[rows, high]


def triangles_cross(p: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(whether triangle p_m crosses q_m (m,), a point (m, 3) of their crossing: the middle of the overlap of the
    segments in which they meet the planes' line) for triangles p, q (m, 3, 3) (module docstring)."""
    e = TOUCH * np.maximum(_longest_side(p), _longest_side(q))
    origin = p[:, :1]  # positions relative to a corner of p, for round-off
    p, q = p - origin, q - origin

    def unit_normal(x):
        n = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
        with np.errstate(invalid="ignore", divide="ignore"):
            return n / np.linalg.norm(n, axis=1)[:, None]

    n_p, n_q = unit_normal(p), unit_normal(q)
    s = np.einsum("mki,mi->mk", q - p[:, :1], n_p)  # q's corners from p's plane
    t = np.einsum("mki,mi->mk", p - q[:, :1], n_q)  # p's corners from q's plane
    straddle = (s.max(axis=1) > e) & (s.min(axis=1) < -e) & (t.max(axis=1) > e) & (t.min(axis=1) < -e)
    cross = np.zeros(len(p), dtype=bool)
    point = np.full((len(p), 3), np.nan)
    if np.any(straddle):
        k = np.flatnonzero(straddle)
        direction = np.cross(n_p[k], n_q[k])
        direction /= np.linalg.norm(direction, axis=1)[:, None]
        lo_p, hi_p, xlo_p, xhi_p = _plane_segment(p[k], t[k], direction)
        lo_q, hi_q, xlo_q, xhi_q = _plane_segment(q[k], s[k], direction)
        cross[k] = np.minimum(hi_p, hi_q) - np.maximum(lo_p, lo_q) > e[k]
        start = np.where((lo_p >= lo_q)[:, None], xlo_p, xlo_q)
        end = np.where((hi_p <= hi_q)[:, None], xhi_p, xhi_q)
        point[k] = 0.5 * (start + end)
    return cross, point + origin[:, 0]


def surface_crossing(x: np.ndarray, pieces: np.ndarray) -> Crossing | None:
    """The first pair (lowest first, then second) of pieces (f, 3) (surface_pieces: triangles in 3D, segments
    (a, b, b) in 2D) at node positions x (n, d) that share no node and cross (segments_cross, triangles_cross),
    or None: box_pairs on their boxes, then the narrow phase on the candidates."""
    corners = x[pieces]  # (f, 3, d)
    i, j = box_pairs(corners.min(axis=1), corners.max(axis=1))
    nodes = [np.ascontiguousarray(pieces[:, k]) for k in range(3)]
    ends = [column[j] for column in nodes]
    shared = np.zeros(len(i), dtype=bool)
    for column in nodes:
        start = column[i]
        for end in ends:
            shared |= start == end
    i, j = i[~shared], j[~shared]
    if x.shape[1] == 2:
        cross, point = segments_cross(corners[i, :2], corners[j, :2])
    else:
        cross, point = triangles_cross(corners[i], corners[j])
    hits = np.flatnonzero(cross)
    if not len(hits):
        return None
    first = hits[np.lexsort((j[hits], i[hits]))[0]]
    return Crossing(int(i[first]), int(j[first]), point[first])


def winding(x: np.ndarray, pieces: np.ndarray, q: np.ndarray) -> float:
    """The winding number about the point q (d,) of the closed surface of the pieces (surface_pieces) at positions x
    (n, d): 1 inside the body, 0 outside it or in a chamber's cavity. 2D: the sum of the angles
    atan2(r_a x r_b, r_a . r_b) / 2 pi that the segments (a, b) subtend (r = x - q); 3D: the sum of the solid angles
    2 atan2(r_a . (r_b x r_c), |r_a||r_b||r_c| + (r_a . r_b)|r_c| + (r_b . r_c)|r_a| + (r_c . r_a)|r_b|) / 4 pi
    of the triangles (Van Oosterom and Strackee)."""
    ra, rb, rc = (x[pieces[:, k]] - q for k in range(3))
    if x.shape[1] == 2:
        cross = ra[:, 0] * rb[:, 1] - ra[:, 1] * rb[:, 0]
        return float(np.arctan2(cross, np.sum(ra * rb, axis=1)).sum() / (2 * np.pi))
    la, lb, lc = (np.linalg.norm(r, axis=1) for r in (ra, rb, rc))
    ab, bc, ca = (np.sum(p * r, axis=1) for p, r in ((ra, rb), (rb, rc), (rc, ra)))
    below = la * lb * lc + ab * lc + bc * la + ca * lb
    return float(2 * np.arctan2(np.sum(ra * np.cross(rb, rc), axis=1), below).sum() / (4 * np.pi))
