"""Element families as data: Lagrange elements on a simplex, of order 1 or 2.

A family is its reference cell (the unit simplex of dimension d, with its quadrature rules), its order
and its node numbering: the d + 1 corners, then (order 2) one node at the middle of each listed edge.
In barycentric coordinates L_0 = 1 - sum_i xi_i, L_i = xi_i (i = 1..d) its shape functions are

    order 1:  N_i = L_i,
    order 2:  N_i = L_i (2 L_i - 1) at corner i,   N_ij = 4 L_i L_j at the middle of edge ij,

and every quantity a solver needs follows from that: the reference nodes, the shape functions and
their gradients dN/dxi, and, on a mesh of straight-sided elements with corner positions X_0..X_d,

    dX/dxi = [X_1 - X_0, ..., X_d - X_0],   G_qa = dN_a/dX = (dN_a/dxi)(xi_q) (dX/dxi)^-1,
    W_q = w_q |det dX/dxi| / d!   (rule weights w_q sum to 1, the reference simplex has volume 1/d!).

Rules are keyed by their degree (exact for every polynomial of that degree); a family integrates its
energy with the rule of its quadrature_degree: 1 point for linear elements (F is constant), degree 2
for quadratic ones (exact for their small-strain stiffness). facets: each boundary facet's nodes, the
facet's corners first (for a counter-clockwise triangle in its sense of traversal, so the outward
normal lies to the right), then its midside node.

A new family is one more entry: tetrahedra add a Simplex(3) with its rules and the edge list
(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3) of the mesh's convention.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import PneumaInputError


@dataclass(frozen=True)
class Simplex:
    """The reference simplex of dimension dim (corners 0, e_1, ..., e_d) and its quadrature rules:
    degree -> (points (p, dim), weights (p,) summing to 1)."""

    dim: int
    rules: dict

    @property
    def corners(self) -> np.ndarray:
        return np.vstack([np.zeros(self.dim), np.eye(self.dim)])


TRIANGLE = Simplex(2, {1: (np.array([[1 / 3, 1 / 3]]), np.array([1.0])),
                       2: (np.array([[1 / 6, 1 / 6], [2 / 3, 1 / 6], [1 / 6, 2 / 3]]), np.full(3, 1 / 3))})


@dataclass(frozen=True)
class ElementFamily:
    """A Lagrange family on `cell`: order 1 (corners) or 2 (corners, then the middles of `edges`)."""

    name: str
    cell: Simplex
    order: int
    quadrature_degree: int
    edges: tuple = ()
    facets: tuple = ()

    @property
    def dim(self) -> int:
        return self.cell.dim

    @property
    def n_nodes(self) -> int:
        return self.dim + 1 + len(self.edges)

    @property
    def reference_nodes(self) -> np.ndarray:
        """(k, d) node positions on the reference cell."""
        corners = self.cell.corners
        return np.vstack([corners] + [0.5 * (corners[[i]] + corners[[j]]) for i, j in self.edges])

    @property
    def rule(self) -> tuple[np.ndarray, np.ndarray]:
        return self.cell.rules[self.quadrature_degree]

    def _barycentric(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """L (p, d + 1) at points (p, d), and dL/dxi (d + 1, d)."""
        points = np.atleast_2d(points)
        return np.column_stack([1.0 - points.sum(axis=1), points]), np.vstack([-np.ones(self.dim), np.eye(self.dim)])

    def shape_functions(self, points: np.ndarray) -> np.ndarray:
        """N_a at reference points (p, d): (p, k)."""
        L, _ = self._barycentric(points)
        if self.order == 1:
            return L
        return np.column_stack([L * (2 * L - 1)] + [4 * L[:, i] * L[:, j] for i, j in self.edges])

    def shape_gradients(self, points: np.ndarray) -> np.ndarray:
        """dN_a/dxi at reference points (p, d): (p, k, d)."""
        L, dL = self._barycentric(points)
        if self.order == 1:
            return np.broadcast_to(dL, (len(L), *dL.shape)).copy()
        corners = (4 * L - 1)[:, :, None] * dL[None]
        mids = [4 * (L[:, i, None] * dL[j] + L[:, j, None] * dL[i]) for i, j in self.edges]
        return np.concatenate([corners, np.stack(mids, axis=1)], axis=1)

    def quadrature(self, vertices: np.ndarray, elements: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The rest gradients G (m, nq, k, d) and weights W (m, nq) at the rule's points of straight-sided
        elements (m, k) with node positions vertices (n, d)."""
        points, weights = self.rule
        d = self.dim
        corners = vertices[elements[:, :d + 1]]
        jacobian = np.stack([corners[:, i] - corners[:, 0] for i in range(1, d + 1)], axis=2)  # dX/dxi
        inverse, volume = np.linalg.inv(jacobian), np.linalg.det(jacobian) / math.factorial(d)
        gradients = np.stack([dn @ inverse for dn in self.shape_gradients(points)], axis=1)
        return gradients, volume[:, None] * weights[None, :]


TRIANGLE_P1 = ElementFamily("P1 triangle", TRIANGLE, order=1, quadrature_degree=1,
                            facets=((0, 1), (1, 2), (2, 0)))
TRIANGLE_P2 = ElementFamily("P2 triangle", TRIANGLE, order=2, quadrature_degree=2,
                            edges=((0, 1), (1, 2), (2, 0)), facets=((0, 1, 3), (1, 2, 4), (2, 0, 5)))
FAMILIES = (TRIANGLE_P1, TRIANGLE_P2)


def family_of(elements: np.ndarray, dim: int) -> ElementFamily:
    """The family of a (m, k) element table in dimension dim, told by its node count k."""
    k = np.shape(elements)[1]
    for family in FAMILIES:
        if (family.dim, family.n_nodes) == (dim, k):
            return family
    raise PneumaInputError(f"elements of {k} nodes in {dim}D: not one of "
                           + ", ".join(f"{f.name} ({f.n_nodes} nodes, {f.dim}D)" for f in FAMILIES))


def boundary_facets(family: ElementFamily, elements: np.ndarray) -> np.ndarray:
    """The facets (f, nodes per facet) of the elements' table that belong to one element only: the mesh's
    boundary, each facet in its element's node order (outward normal to the right in 2D)."""
    facets = elements[:, np.array(family.facets)].reshape(-1, len(family.facets[0]))
    corners = np.sort(facets[:, :family.dim], axis=1)
    _, index, counts = np.unique(corners, axis=0, return_index=True, return_counts=True)
    return facets[np.sort(index[counts == 1])]
