"""Element families as data: Lagrange elements on a simplex, of order 1 or 2.

A family is its reference cell (the unit simplex of dimension d, with its quadrature rules), its order
and its node numbering: the d + 1 corners, then (order 2) one node at the middle of each listed edge.
In barycentric coordinates L_0 = 1 - sum_i xi_i, L_i = xi_i (i = 1..d) its shape functions are

    order 1:  N_i = L_i,
    order 2:  N_i = L_i (2 L_i - 1) at corner i,   N_ij = 4 L_i L_j at the middle of edge ij,

and every quantity a solver needs follows from that: the reference nodes, the shape functions and
their gradients dN/dxi, and, on a mesh with node positions X_a (isoparametric),

    dX/dxi = sum_a X_a (dN_a/dxi)(xi_q)   (= [X_1 - X_0, ..., X_d - X_0] on straight-sided elements),
    G_qa = dN_a/dX = (dN_a/dxi)(xi_q) (dX/dxi)^-1,
    W_q = w_q det dX/dxi / d!   (rule weights w_q sum to 1, the reference simplex has volume 1/d!).

Rules are keyed by their degree (exact for every polynomial of that degree); a family integrates its
energy with the rule of its quadrature_degree: 1 point for linear elements (F is constant), degree 2
for quadratic ones (exact for their small-strain stiffness, whose integrand dN_a/dX . dN_b/dX is of
degree 2). facets: each boundary facet's nodes, the facet's corners first, then its midside nodes,
oriented so the outward normal follows: for a triangle (segment facets, element counter-clockwise) the
outward normal lies to the right of the facet's direction; for a tetrahedron (triangle facets, element
of positive volume det[X_1 - X_0, X_2 - X_0, X_3 - X_0] > 0) the facet's corners c_0, c_1, c_2 turn
counter-clockwise seen from outside, (c_1 - c_0) x (c_2 - c_0) pointing out, and a quadratic facet is a
6-node triangle in the triangle's own numbering (corners, then the middles of edges 01, 12, 20).

The families: triangles and tetrahedra, linear and quadratic. The tetrahedron's edges are numbered
(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3), which is VTK's (and meshio's) 10-node tetrahedron.

A family also answers what the code around the solver asks of an element, so that a new family is added here (and
in the mesher that makes it): its cell names in files (meshio_cell, vtk_cell), the family of its boundary facets
(facet_family: a tetrahedron's are triangles; a triangle's edges have none), the node permutation that reverses
its orientation (mirror), the linear triangles it is drawn with (split, for a triangle family; a 3D body is drawn
by its facets), the degree of the rule that integrates N_a det dX/dxi exactly (measure_degree: nodal measures, a
wall's volume), and its cost (weight: linear elements' worth of memory and time, for the resource limits: a
quadratic triangle 4, it has as many nodes as four linear ones and a Hessian block 4 times larger; a quadratic
tetrahedron 8, its Hessian block 6.25 times a linear one's, its measured memory 6.2 times).
"""

from __future__ import annotations

import itertools
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


def symmetric_points(*orbits: tuple[float, ...]) -> np.ndarray:
    """The distinct permutations of each barycentric tuple (the points of a fully symmetric rule), as
    reference coordinates: the barycentric weights of corners 1..d."""
    points = [p for orbit in orbits for p in sorted(set(itertools.permutations(orbit)))]
    return np.array(points)[:, 1:]


DUNAVANT_A = (0.44594849091596488632, 0.091576213509770743460)  # the degree-4 rule's two orbits (a, a, 1 - 2a)
DUNAVANT_W = (0.22338158967801146570, 0.10995174365532186764)  # and their weights (Dunavant 1985)
TRIANGLE = Simplex(
    2,
    {
        1: (np.array([[1 / 3, 1 / 3]]), np.array([1.0])),
        2: (np.array([[1 / 6, 1 / 6], [2 / 3, 1 / 6], [1 / 6, 2 / 3]]), np.full(3, 1 / 3)),
        4: (symmetric_points(*((a, a, 1 - 2 * a) for a in DUNAVANT_A)), np.repeat(DUNAVANT_W, 3)),
    },
)
TET_A, TET_B = (5 + 3 * math.sqrt(5)) / 20, (5 - math.sqrt(5)) / 20  # the degree-2 rule's barycentric weights
TETRAHEDRON = Simplex(
    3,
    {
        1: (np.array([[0.25, 0.25, 0.25]]), np.array([1.0])),
        2: (symmetric_points((TET_A, TET_B, TET_B, TET_B)), np.full(4, 0.25)),
    },
)


@dataclass(frozen=True)
class ElementFamily:
    """A Lagrange family on `cell`: order 1 (corners) or 2 (corners, then the middles of `edges`)."""

    name: str
    cell: Simplex
    order: int
    quadrature_degree: int
    edges: tuple = ()
    facets: tuple = ()
    meshio_cell: str = ""
    vtk_cell: int = 0
    facet_family: ElementFamily | None = None
    mirror: tuple = ()
    split: tuple = ()
    measure_degree: int = 1
    weight: int = 1

    @property
    def dim(self) -> int:
        return self.cell.dim

    @property
    def n_nodes(self) -> int:
        return self.dim + 1 + len(self.edges)

    @property
    def outline(self) -> tuple:
        """A triangle's boundary walked through its nodes: each facet's first node, then its midside node(s)."""
        return tuple(node for facet in self.facets for node in (facet[0], *facet[2:]))

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

    def quadrature(self, vertices: np.ndarray, elements: np.ndarray, rule=None) -> tuple[np.ndarray, np.ndarray]:
        """The rest gradients G (m, nq, k, d) and weights W (m, nq) at the points of `rule` (default: the family's
        own) of elements (m, k) with node positions vertices (n, d), from the Jacobian at each point
        (isoparametric: a quadratic element whose midside nodes are off its edges' middles is curved; on a
        straight-sided one this is the corners' [X_1 - X_0, ..., X_d - X_0])."""
        points, weights = self.rule if rule is None else rule
        d = self.dim
        dn = self.shape_gradients(points)  # (nq, k, d)
        nodes = vertices[elements]
        edges = nodes[:, 1:] - nodes[:, :1]
        jacobian = np.einsum("mai,qaj->mqij", edges, dn[:, 1:])  # dX/dxi = sum_a (X_a - X_0) dN_a/dxi
        inverse, volume = np.linalg.inv(jacobian), np.linalg.det(jacobian) / math.factorial(d)
        gradients = np.einsum("qaj,mqji->mqai", dn, inverse)
        return gradients, volume * weights[None, :]

    def split_cells(self, cells: np.ndarray) -> np.ndarray:
        """The linear triangles (split x m, 3) that draw cells (m, k) of this triangle family: each cell's first
        piece, then each one's second, ... (a quadratic triangle: its three corner triangles, then the middle one)."""
        return np.vstack([cells[:, list(piece)] for piece in self.split])

    def mirrored(self, cells: np.ndarray, flip: np.ndarray) -> np.ndarray:
        """The cells (m, k) with those where flip (m,) is true in the opposite orientation (mirror's order)."""
        return np.where(flip[:, None], cells[:, list(self.mirror)], cells)


TRIANGLE_P1 = ElementFamily(
    "P1 triangle",
    TRIANGLE,
    order=1,
    quadrature_degree=1,
    facets=((0, 1), (1, 2), (2, 0)),
    meshio_cell="triangle",
    vtk_cell=5,
    mirror=(0, 2, 1),
    split=((0, 1, 2),),
)
TRIANGLE_P2 = ElementFamily(
    "P2 triangle",
    TRIANGLE,
    order=2,
    quadrature_degree=2,
    edges=((0, 1), (1, 2), (2, 0)),
    facets=((0, 1, 3), (1, 2, 4), (2, 0, 5)),
    meshio_cell="triangle6",
    vtk_cell=22,
    mirror=(0, 2, 1, 5, 4, 3),
    split=((0, 3, 5), (3, 1, 4), (5, 4, 2), (3, 4, 5)),
    measure_degree=4,
    weight=4,
)
TET_EDGES = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))
TET_P1 = ElementFamily(
    "P1 tetrahedron",
    TETRAHEDRON,
    order=1,
    quadrature_degree=1,
    facets=((1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1)),
    meshio_cell="tetra",
    vtk_cell=10,
    facet_family=TRIANGLE_P1,
    mirror=(0, 2, 1, 3),
)
TET_P2 = ElementFamily(
    "P2 tetrahedron",
    TETRAHEDRON,
    order=2,
    quadrature_degree=2,
    edges=TET_EDGES,
    facets=((1, 2, 3, 5, 9, 8), (0, 3, 2, 7, 9, 6), (0, 1, 3, 4, 8, 7), (0, 2, 1, 6, 5, 4)),
    meshio_cell="tetra10",
    vtk_cell=24,
    facet_family=TRIANGLE_P2,
    mirror=(0, 2, 1, 3, 6, 5, 4, 7, 9, 8),
    measure_degree=2,
    weight=8,
)
FAMILIES = (TRIANGLE_P1, TRIANGLE_P2, TET_P1, TET_P2)


ORDERS = tuple(sorted({f.order for f in FAMILIES}))


def family_for(dim: int, order: int) -> ElementFamily:
    """The family of order `order` on the simplex of dimension dim; another order is a PneumaInputError."""
    for f in FAMILIES:
        if (f.dim, f.order) == (dim, order):
            return f
    kinds = ", ".join(f"{f.order} ({f.name})" for f in FAMILIES if f.dim == dim)
    raise PneumaInputError(f"order = {order!r} must be one of {kinds}")


def family_of(elements: np.ndarray, dim: int) -> ElementFamily:
    """The family of a (m, k) element table in dimension dim, told by its node count k."""
    k = np.shape(elements)[1]
    for family in FAMILIES:
        if (family.dim, family.n_nodes) == (dim, k):
            return family
    raise PneumaInputError(
        f"elements of {k} nodes in {dim}D: not one of "
        + ", ".join(f"{f.name} ({f.n_nodes} nodes, {f.dim}D)" for f in FAMILIES)
    )


def boundary_facets(family: ElementFamily, elements: np.ndarray) -> np.ndarray:
    """The facets (f, nodes per facet) of the elements' table that belong to one element only: the mesh's
    boundary, each facet in its element's node order (outward normal to the right in 2D, corners
    counter-clockwise seen from outside in 3D)."""
    facets = elements[:, np.array(family.facets)].reshape(-1, len(family.facets[0]))
    corners = np.sort(facets[:, : family.dim], axis=1)
    _, index, counts = np.unique(corners, axis=0, return_index=True, return_counts=True)
    return facets[np.sort(index[counts == 1])]
