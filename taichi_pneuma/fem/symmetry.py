"""Half and quarter models: chambers cut by symmetry lines.

A roller line along an edge of the body is a symmetry line, and a chamber may cross it. Such a chamber is clipped to
the body's side of its lines and notched into the body's outline (no hole point); its wall is recovered as an open
chain from line to line, and its area is closed by the flat cap along the lines: with the origin o on them (their
crossing, for two), the cap adds nothing,

    A(x) = 1/2 sum_i (x_i - o) x (x_{i+1} - o)      over the open chain,

oriented positive at rest (polygons.enclosed_area). A chamber between two parallel lines (a channel) is refused.
"""

from __future__ import annotations

import numpy as np

from ..errors import require
from .polygons import enclosed_area, signed_area

OUTER_MARKER = 1  # the segment marker of the body's outline; chamber c's wall has OUTER_MARKER + c
CUT_TOLERANCE = 1e-9  # points this close to a symmetry line, relative to the body's size, lie on it


def symmetry_lines(body: np.ndarray, rollers, tol: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """The roller lines that run along an edge of the body (the body on one side, two of its vertices on the
    line, within tol), each as (unit normal pointing into the body, a point of the line)."""
    lines = []
    for roller in rollers:
        if roller.point is None:
            continue
        n, p = roller.unit_normal, np.asarray(roller.point, dtype=np.float64)
        s = (body - p) @ n
        if s.max() <= tol:
            n, s = -n, -s
        if s.min() >= -tol and np.count_nonzero(np.abs(s) <= tol) >= 2:
            lines.append((n, p))
    return lines


def clip(polygon: np.ndarray, n: np.ndarray, p: np.ndarray, tol: float) -> np.ndarray:
    """Sutherland-Hodgman: the part of a closed polygon on the side n . (x - p) >= 0. A vertex within tol of the
    line is moved onto it and kept; an edge crossing the line adds its crossing point."""
    s = (polygon - p) @ n
    out = []
    for i in range(len(polygon)):
        j = (i + 1) % len(polygon)
        if s[i] >= -tol:
            out.append(polygon[i] - s[i] * n if s[i] <= tol else polygon[i])
        if (s[i] > tol and s[j] < -tol) or (s[i] < -tol and s[j] > tol):
            out.append(polygon[i] + s[i] / (s[i] - s[j]) * (polygon[j] - polygon[i]))
    return np.array(out).reshape(-1, 2)


def cut_by_lines(polygon: np.ndarray, lines, tol: float, what: str) -> tuple[np.ndarray, np.ndarray | None]:
    """A chamber polygon (counter-clockwise) cut by the symmetry lines it crosses, as (wall, origin).

    Uncut: the polygon itself and None. Cut: the part on the body's side of the lines; its points on the lines
    (the cap) must be one run, on one line or on two crossing ones; the wall is the rest, an open chain from
    line to line that keeps the chamber on its left, and the origin of its enclosed area is the middle of the
    cap (one line) or the lines' crossing (two). A chamber cut into more than one wall (e.g. by two parallel
    lines) is refused: its cap would not be flat."""
    cutting = [(n, p) for n, p in lines if ((polygon - p) @ n).min() < -tol]
    if not cutting:
        return polygon, None
    for n, p in cutting:
        polygon = clip(polygon, n, p, tol)
        require(len(polygon) >= 3, f"{what} lies beyond a symmetry line")
    on = np.column_stack([np.abs((polygon - p) @ n) <= tol for n, p in cutting])
    cap = on.any(axis=1)
    starts, ends = np.flatnonzero(cap & ~np.roll(cap, 1)), np.flatnonzero(cap & ~np.roll(cap, -1))
    single = (
        f"{what}: the symmetry lines must cut it into one wall from line to line (not between two parallel "
        f"lines, nor crossing a line more than twice)"
    )
    require(len(starts) == 1, single)
    k, m, count = starts[0], ends[0], len(polygon)
    wall = polygon[(m + np.arange((k - m) % count + 1)) % count]
    require(len(wall) >= 3, single)
    holding = on[(k + np.arange((m - k) % count + 1)) % count]
    if holding.all(axis=0).any():
        return wall, 0.5 * (wall[0] + wall[-1])
    used = np.flatnonzero(holding.any(axis=0))
    normals = np.array([cutting[i][0] for i in used])
    require(
        len(used) == 2 and abs(np.linalg.det(normals)) > 1e-12,
        f"{what}: its cap runs along {len(used)} symmetry lines; a cap on one line or two crossing ones is supported",
    )
    origin = np.linalg.solve(normals, [normals[i] @ cutting[line][1] for i, line in enumerate(used)])
    return wall, origin


def notch(
    outline: np.ndarray, markers: np.ndarray, wall: np.ndarray, origin: np.ndarray, marker: int, tol: float, what: str
):
    """The outline (counter-clockwise, with per-segment markers) with the cap between an open wall's ends cut
    out and the wall put in its place, reversed (the material on the left); the wall's segments get `marker`.

    Each end must lie on a body segment (marker OUTER_MARKER); the part of the outline left out must be the
    cap: the outline's area must drop by the wall's enclosed area (origin: see cut_by_lines)."""
    a, b = outline, np.roll(outline, -1, axis=0)
    e = b - a
    count = len(outline)

    def locate(point):
        t = np.clip(np.sum((point - a) * e, axis=1) / np.sum(e * e, axis=1), 0.0, 1.0)
        d = np.linalg.norm(point - (a + t[:, None] * e), axis=1)
        d[markers != OUTER_MARKER] = np.inf
        i = int(np.argmin(d))
        require(
            d[i] <= tol,
            f"{what} ends at {point.tolist()} on a symmetry line, off the body's edge (outside the body, or in "
            "another chamber)",
        )
        return i, t[i]

    (ia, ta), (ib, tb) = locate(wall[0]), locate(wall[-1])
    steps = count if ia == ib and tb < ta else (ib - ia) % count
    walk = (ia + 1 + np.arange(steps)) % count
    cut = np.vstack([wall[:1], outline[walk], wall[-1:], wall[-2:0:-1]])
    expected = signed_area(outline) - enclosed_area(wall, origin)
    require(
        steps > 0 and abs(signed_area(cut) - expected) <= 1e-9 * abs(signed_area(outline)),
        f"{what}: the symmetry lines cut it off the body's edge (its cap is not a part of that edge)",
    )
    return cut, np.concatenate([[markers[ia]], markers[walk], np.full(len(wall) - 1, marker)])
