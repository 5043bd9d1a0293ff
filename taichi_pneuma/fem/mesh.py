"""The mesh a scene is solved on: node positions, the element table and the node sets a pneumatic scene needs."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .elements import TRIANGLE_P2
from .refine import split_in_four


@dataclass(frozen=True)
class Mesh:
    """A triangle mesh with the vertex sets a pneumatic scene needs.

    vertices: (n, 2) rest positions (the nodes); triangles: (m, 3) counter-clockwise corner indices
    (linear elements), or (m, 6) for quadratic ones: the corners, then the midside nodes of edges 01,
    12 and 20; chambers: the nodes of each chamber wall in the scene's order (quadratic: corner, midside,
    corner, ...), a closed loop, or for a chamber cut by symmetry lines an open chain from line to line,
    oriented so its enclosed area (enclosed_area with wall_origins) is positive; wall_origins: per chamber
    None (a closed loop) or the origin o of an open wall's area, on the lines; boundary: the nodes on the
    body's outer boundary; pinned: the clamped nodes (none without a clamp); tip: the tip's nodes (the right
    edge by default); rollers: per roller, (its held nodes, its unit normal).
    """

    vertices: np.ndarray
    triangles: np.ndarray
    chambers: tuple[np.ndarray, ...]
    boundary: np.ndarray
    pinned: np.ndarray
    tip: np.ndarray
    wall_origins: tuple[np.ndarray | None, ...]
    rollers: tuple[tuple[np.ndarray, np.ndarray], ...]

    @property
    def n_vertices(self) -> int:
        return len(self.vertices)

    @property
    def n_triangles(self) -> int:
        return len(self.triangles)

    dim = 2
    elements = property(lambda self: self.triangles, doc="the elements (the dimension-neutral name of triangles)")
    n_elements = n_triangles
    measure = property(lambda self: self.area, doc="the body's rest measure: its area in 2D, its volume in 3D")

    @property
    def order(self) -> int:
        """1 for linear triangles, 2 for quadratic ones."""
        return 1 if self.triangles.shape[1] == 3 else 2

    @property
    def area(self) -> float:
        """Total rest area of the triangles (curved ones' included: see nodal_areas)."""
        if self.order == 2:
            return float(np.sum(self.nodal_areas()))
        return float(np.sum(triangle_areas(self.vertices, self.triangles)))

    def display_triangles(self) -> np.ndarray:
        """Linear triangles to draw: the triangles themselves, or each quadratic one split in four at its
        midside nodes (corner triangles, then the middle one)."""
        return self.triangles if self.order == 1 else split_in_four(self.triangles)

    def nodal_measures(self) -> np.ndarray:
        """The integral of each node's shape function over the body: nodal_areas() in 2D."""
        return self.nodal_areas()

    def nodal_areas(self) -> np.ndarray:
        """The integral of each node's shape function over the body, sum_t int_t N_a dA: a third of the
        area of the triangles at a node for linear elements. For quadratic ones int N_a det(dX/dxi) dxi
        by the degree-4 rule, exact (N_a and det dX/dxi are quadratic): 0 at corners and a third of the
        triangle's area at midside nodes on a straight-sided triangle, and the exact measure of a triangle
        with a curved (parabolic) side. Either way the exact weights of a load linear in x."""
        out = np.zeros(self.n_vertices)
        if self.order == 1:
            np.add.at(out, self.triangles.ravel(), np.repeat(triangle_areas(self.vertices, self.triangles) / 3, 3))
            return out
        points, weights = TRIANGLE_P2.cell.rules[4]
        measures = 0.5 * jacobians(self.vertices, self.triangles, points) * weights  # (m, 6 points)
        np.add.at(out, self.triangles.ravel(), (measures @ TRIANGLE_P2.shape_functions(points)).ravel())
        return out


def triangle_areas(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    p0, p1, p2 = (vertices[triangles[:, i]] for i in range(3))
    e1, e2 = p1 - p0, p2 - p0
    return 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])



def jacobians(vertices: np.ndarray, triangles: np.ndarray, points: np.ndarray) -> np.ndarray:
    """det dX/dxi (m, p) of quadratic triangles (m, 6) at reference points (p, 2), dX/dxi = sum_a X_a dN_a/dxi
    (isoparametric: twice the area of a straight-sided triangle, the same at every point)."""
    j = np.swapaxes(vertices[triangles], 1, 2)[:, None] @ TRIANGLE_P2.shape_gradients(points)[None]  # (m, p, 2, 2)
    return j[..., 0, 0] * j[..., 1, 1] - j[..., 0, 1] * j[..., 1, 0]

