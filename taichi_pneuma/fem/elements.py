"""Element families as data: Lagrange elements on a simplex, of any order on segments and triangles, up to 2 on
tetrahedra (fem/lagrange.py builds them from the simplex lattice).

A family is its reference cell (the unit simplex of dimension d, with its quadrature rules), its order p
and its node numbering: the d + 1 corners, then each listed edge's p - 1 nodes from its first corner to its
second, then (a triangle of order 3 or more) its interior nodes. In barycentric coordinates
L_0 = 1 - sum_i xi_i, L_i = xi_i (i = 1..d) its shape functions are the lattice's (lagrange.py), e.g.

    order 1:  N_i = L_i,
    order 2:  N_i = L_i (2 L_i - 1) at corner i,   N_ij = 4 L_i L_j at the middle of edge ij,
    order 3:  N_i = L_i (3 L_i - 1) (3 L_i - 2) / 2,   9/2 L_i L_j (3 L_i - 1) on edge ij near i,   27 L_0 L_1 L_2,

and every quantity a solver needs follows from that: the reference nodes, the shape functions and
their gradients dN/dxi, and, on a mesh with node positions X_a (isoparametric),

    dX/dxi = sum_a X_a (dN_a/dxi)(xi_q)   (= [X_1 - X_0, ..., X_d - X_0] on straight-sided elements),
    G_qa = dN_a/dX = (dN_a/dxi)(xi_q) (dX/dxi)^-1,
    W_q = w_q det dX/dxi / d!   (rule weights w_q sum to 1, the reference simplex has volume 1/d!).

Rules are keyed by their degree (exact for every polynomial of that degree; Simplex.rule gives the conical
product rule of lagrange.py for a degree without a fixed one); a family integrates its energy with the rule
of its quadrature_degree, 2 p - 2: 1 point for linear elements (F is constant), degree 2 for quadratic ones,
4 for cubic ones (exact for their small-strain stiffness, whose integrand dN_a/dX . dN_b/dX is of degree
2 p - 2 on a straight element). facets: each boundary facet's nodes, the facet's corners first, then its
other nodes in its facet family's order, oriented so the outward normal follows: for a triangle (segment
facets, element counter-clockwise) the outward normal lies to the right of the facet's direction; for a
tetrahedron (triangle facets, element of positive volume det[X_1 - X_0, X_2 - X_0, X_3 - X_0] > 0) the
facet's corners c_0, c_1, c_2 turn counter-clockwise seen from outside, (c_1 - c_0) x (c_2 - c_0) pointing
out, and a quadratic facet is a 6-node triangle in the triangle's own numbering (corners, then the middles
of edges 01, 12, 20).

The families (FAMILIES, the registry every lookup reads: family_for, family_of, the orders a scene may ask):
triangles of order 1, 2 and 3, tetrahedra of order 1 and 2; segments of order 1 to 3 are the triangles'
facets. The tetrahedron's edges are numbered (0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3), which is VTK's
(and meshio's) 10-node tetrahedron; the cubic triangle's numbering is VTK's Lagrange triangle's (meshio's and
gmsh's triangle10).

A family also answers what the code around the solver asks of an element, so that a new family is one entry
here: its cell names in files (meshio_cell, vtk_cell), the family of its boundary facets (facet_family: a
tetrahedron's are triangles, a triangle's segments; a 2D chamber wall's area form is the segment's,
terms/chambers/wall.py), the node permutation that reverses its orientation (mirror), the linear simplices it
is cut into (split: drawing, the embedding of points; a 3D body is drawn by its facets), the mesh of its order
made from a linear one (lift: edge nodes shared between neighbours, interior nodes; placed_interior puts those
where a curved boundary says), the degree of the rule that integrates N_a det dX/dxi exactly (measure_degree:
nodal measures, a wall's volume; 3 p - 2 on a curved triangle), its words in messages (adjective) and its cost
(weight: linear elements' worth of memory and time, for the resource limits: a quadratic triangle 4, it has as
many nodes as four linear ones and a Hessian block 4 times larger; a cubic one 9, as many nodes as nine linear
ones, its Hessian block 11 times; a quadratic tetrahedron 8, its Hessian block 6.25 times a linear one's, its
measured memory 6.2 times).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..errors import PneumaInputError, require
from .lagrange import conical_rule, facet_nodes, lattice, permuted, shape_values, split_triangles
from .refine import with_edge_nodes


@dataclass(frozen=True)
class Simplex:
    """The reference simplex of dimension dim (corners 0, e_1, ..., e_d) and its quadrature rules:
    degree -> (points (p, dim), weights (p,) summing to 1)."""

    dim: int
    rules: dict
    plural: str

    @property
    def corners(self) -> np.ndarray:
        return np.vstack([np.zeros(self.dim), np.eye(self.dim)])

    def rule(self, degree: int) -> tuple[np.ndarray, np.ndarray]:
        """The rule of this degree: the fixed one where there is one, else the conical product rule (lagrange)."""
        return self.rules[degree] if degree in self.rules else conical_rule(self.dim, degree)


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
    "triangles",
)
TET_A, TET_B = (5 + 3 * math.sqrt(5)) / 20, (5 - math.sqrt(5)) / 20  # the degree-2 rule's barycentric weights
TETRAHEDRON = Simplex(
    3,
    {
        1: (np.array([[0.25, 0.25, 0.25]]), np.array([1.0])),
        2: (symmetric_points((TET_A, TET_B, TET_B, TET_B)), np.full(4, 0.25)),
    },
    "tetrahedra",
)


@dataclass(frozen=True)
class ElementFamily:
    """The Lagrange family of order `order` on `cell` (fem/lagrange.py): its nodes are the lattice's, numbered
    corners, then each of `edges`' order - 1 nodes from its first corner, then the interior. facet_corners: each
    boundary facet's corners (oriented as the module docstring says), whose nodes (facets) follow from
    facet_family's lattice; pieces: the linear simplices that fill a tetrahedron (a triangle's are its lattice's
    triangles, split)."""

    name: str
    cell: Simplex
    order: int
    quadrature_degree: int
    edges: tuple = ()
    facet_corners: tuple = ()
    meshio_cell: str = ""
    vtk_cell: int = 0
    facet_family: ElementFamily | None = None
    measure_degree: int = 1
    weight: int = 1
    pieces: tuple = ()
    adjective: str = "linear"

    @property
    def dim(self) -> int:
        return self.cell.dim

    @property
    def words(self) -> str:
        """The elements in words, in messages: "triangles" (linear ones unmarked), "quadratic tetrahedra"..."""
        return self.cell.plural if self.order == 1 else f"{self.adjective} {self.cell.plural}"

    @cached_property
    def nodes(self) -> tuple[tuple[int, ...], ...]:
        """The lattice points alpha (k, d + 1) of the nodes, in node order (lagrange.lattice)."""
        return lattice(self.dim, self.order, self.edges)

    @property
    def n_nodes(self) -> int:
        return len(self.nodes)

    @cached_property
    def facets(self) -> tuple:
        """Each boundary facet's nodes: its corners, then its edges' and interior nodes in facet_family's order."""
        if self.facet_family is None:
            return self.facet_corners
        return tuple(facet_nodes(self.nodes, self.facet_family.nodes, corners) for corners in self.facet_corners)

    @cached_property
    def mirror(self) -> tuple:
        """The node permutation that swaps corners 1 and 2: the element in the opposite orientation."""
        return permuted(self.nodes, (0, 2, 1, *range(3, self.dim + 1)))

    @cached_property
    def split(self) -> tuple:
        """The linear simplices (corner node tuples) the element is cut into: a segment's order pieces, a
        triangle's order^2 lattice triangles (lagrange.split_triangles), else `pieces` (a linear element: itself)."""
        if self.dim == 1:  # the segments between consecutive nodes: corner 0, the edge nodes, corner 1
            along = (0, *range(2, self.order + 1), 1)
            return tuple(zip(along[:-1], along[1:]))
        if self.dim == 2:
            return split_triangles(self.nodes, self.order)
        return self.pieces or (tuple(range(self.dim + 1)),)

    @property
    def outline(self) -> tuple:
        """A triangle's boundary walked through its nodes: each facet's first node, then its edge nodes."""
        return tuple(node for facet in self.facets for node in (facet[0], *facet[2:]))

    @property
    def reference_nodes(self) -> np.ndarray:
        """(k, d) node positions on the reference cell: alpha_1..d / order."""
        return np.array(self.nodes, dtype=np.float64)[:, 1:] / self.order

    @property
    def rule(self) -> tuple[np.ndarray, np.ndarray]:
        return self.cell.rule(self.quadrature_degree)

    def shape_functions(self, points: np.ndarray) -> np.ndarray:
        """N_a at reference points (p, d): (p, k)."""
        return shape_values(self.nodes, self.order, barycentric(points))[0]

    def shape_gradients(self, points: np.ndarray) -> np.ndarray:
        """dN_a/dxi at reference points (p, d): (p, k, d), dN/dxi = sum_i dN/dL_i dL_i/dxi."""
        partial = shape_values(self.nodes, self.order, barycentric(points))[1]
        return partial @ np.vstack([-np.ones(self.dim), np.eye(self.dim)])

    def quadrature(self, vertices: np.ndarray, elements: np.ndarray, rule=None) -> tuple[np.ndarray, np.ndarray]:
        """The rest gradients G (m, nq, k, d) and weights W (m, nq) at the points of `rule` (default: the family's
        own) of elements (m, k) with node positions vertices (n, d), from the Jacobian at each point
        (isoparametric: an element whose edge nodes are off its straight edges is curved; on a straight-sided
        one this is the corners' [X_1 - X_0, ..., X_d - X_0])."""
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
        """The linear simplices (split x m, d + 1) of cells (m, k): each cell's first piece, then each one's
        second, ... (a quadratic triangle: its three corner triangles, then the middle one)."""
        return np.vstack([cells[:, list(piece)] for piece in self.split])

    def mirrored(self, cells: np.ndarray, flip: np.ndarray) -> np.ndarray:
        """The cells (m, k) with those where flip (m,) is true in the opposite orientation (mirror's order)."""
        return np.where(flip[:, None], cells[:, list(self.mirror)], cells)

    def facet_pieces(self, facets: np.ndarray) -> np.ndarray:
        """The linear pieces (segments in 2D, triangles in 3D) of boundary facets (f, nodes per facet), split as
        facet_family's."""
        assert self.facet_family is not None, f"a {self.name} has no facet family"
        return self.facet_family.split_cells(facets)

    def drawn(self, elements: np.ndarray, surface: np.ndarray) -> np.ndarray:
        """The linear triangles that draw a mesh of this family: a triangle mesh's elements split, a 3D body's
        surface facets (its boundary) split as their family's."""
        return self.split_cells(elements) if self.dim == 2 else self.facet_pieces(surface)

    def lift(self, vertices: np.ndarray, corners: np.ndarray):
        """(vertices, elements, along) of this family on the mesh of linear elements corners (m, d + 1): the
        order - 1 nodes of every edge appended once, shared by its elements, at (order - t) / order X_a +
        t / order X_b (refine.with_edge_nodes; along(a, b) their indices from a to b, (..., order - 1)); then each
        element's interior nodes at its lattice points' barycentric combination of its corners. Order 1: the mesh
        as it is (along None)."""
        if self.order == 1:
            return vertices, corners, None
        vertices, along = with_edge_nodes(vertices, corners, self.edges, self.order)
        columns = [corners] + [along(corners[:, i], corners[:, j]) for i, j in self.edges]
        inner = np.array(self.nodes[self.dim + 1 + len(self.edges) * (self.order - 1) :], dtype=np.float64)
        if len(inner):
            centres = np.einsum("ic,mcx->mix", inner / self.order, vertices[corners]).reshape(-1, self.dim)
            columns.append(len(vertices) + np.arange(len(centres)).reshape(len(corners), len(inner)))
            vertices = np.vstack([vertices, centres])
        return vertices, np.column_stack(columns), along

    @cached_property
    def interior_weights(self) -> np.ndarray:
        """B (i, b): the interior nodes at B times the boundary nodes (corners and edge nodes) reproduce every
        quadratic map exactly (least squares on the products L_i L_j at the lattice points): where curved
        boundaries moved edge nodes by O(h^2), the interior nodes follow the quadratic map the element's
        boundary describes, which keeps the isoparametric map's higher derivatives O(h^s) (the mapped element
        converges at its full order; at its straight centroid an order-3 element's interior node would not)."""
        L = np.array(self.nodes, dtype=np.float64) / self.order
        quadratics = np.column_stack([L[:, i] * L[:, j] for i in range(self.dim + 1) for j in range(i, self.dim + 1)])
        boundary = self.dim + 1 + len(self.edges) * (self.order - 1)
        return quadratics[boundary:] @ np.linalg.pinv(quadratics[:boundary])

    def placed_interior(self, vertices: np.ndarray, elements: np.ndarray) -> np.ndarray:
        """The vertices with each element's interior nodes put at interior_weights times its boundary nodes (no
        change for a family without interior nodes)."""
        boundary = self.dim + 1 + len(self.edges) * (self.order - 1)
        if boundary == self.n_nodes:
            return vertices
        out = vertices.copy()
        out[elements[:, boundary:]] = np.einsum("ib,mbx->mix", self.interior_weights, vertices[elements[:, :boundary]])
        return out


def barycentric(points: np.ndarray) -> np.ndarray:
    """L (p, d + 1) at reference points (p, d): L_0 = 1 - sum_i xi_i, L_i = xi_i."""
    points = np.atleast_2d(points)
    return np.column_stack([1.0 - points.sum(axis=1), points])


SEGMENT = Simplex(1, {}, "segments")
SEGMENTS = tuple(
    ElementFamily(f"P{p} segment", SEGMENT, order=p, quadrature_degree=2 * p - 2, edges=((0, 1),) if p > 1 else ())
    for p in (1, 2, 3)
)
TRIANGLE_P1 = ElementFamily(
    "P1 triangle",
    TRIANGLE,
    order=1,
    quadrature_degree=1,
    facet_corners=((0, 1), (1, 2), (2, 0)),
    meshio_cell="triangle",
    vtk_cell=5,
    facet_family=SEGMENTS[0],
)
TRIANGLE_P2 = ElementFamily(
    "P2 triangle",
    TRIANGLE,
    order=2,
    quadrature_degree=2,
    edges=((0, 1), (1, 2), (2, 0)),
    facet_corners=((0, 1), (1, 2), (2, 0)),
    meshio_cell="triangle6",
    vtk_cell=22,
    facet_family=SEGMENTS[1],
    measure_degree=4,
    weight=4,
    adjective="quadratic",
)
TRIANGLE_P3 = ElementFamily(
    "P3 triangle",
    TRIANGLE,
    order=3,
    quadrature_degree=4,
    edges=((0, 1), (1, 2), (2, 0)),
    facet_corners=((0, 1), (1, 2), (2, 0)),
    meshio_cell="triangle10",
    vtk_cell=69,  # VTK_LAGRANGE_TRIANGLE
    facet_family=SEGMENTS[2],
    measure_degree=7,
    weight=9,
    adjective="cubic",
)
TET_EDGES = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))
TET_FACETS = ((1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1))
TET_P1 = ElementFamily(
    "P1 tetrahedron",
    TETRAHEDRON,
    order=1,
    quadrature_degree=1,
    facet_corners=TET_FACETS,
    meshio_cell="tetra",
    vtk_cell=10,
    facet_family=TRIANGLE_P1,
)
TET_P2 = ElementFamily(
    "P2 tetrahedron",
    TETRAHEDRON,
    order=2,
    quadrature_degree=2,
    edges=TET_EDGES,
    facet_corners=TET_FACETS,
    meshio_cell="tetra10",
    vtk_cell=24,
    facet_family=TRIANGLE_P2,
    measure_degree=2,
    weight=8,
    # eight tetrahedra of positive volume, an eighth of the element's on a straight one: one at each corner, and
    # the inner octahedron cut along its diagonal 6-8 (nodes 4-9 are the middles of edges 01, 12, 20, 03, 13, 23)
    pieces=(
        (0, 4, 6, 7),
        (4, 1, 5, 8),
        (6, 5, 2, 9),
        (7, 8, 9, 3),
        (6, 8, 7, 4),
        (6, 8, 9, 7),
        (6, 8, 5, 9),
        (6, 8, 4, 5),
    ),
    adjective="quadratic",
)
FAMILIES = (TRIANGLE_P1, TRIANGLE_P2, TRIANGLE_P3, TET_P1, TET_P2)


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


def positively_oriented(vertices: np.ndarray, cells: np.ndarray, family: ElementFamily) -> np.ndarray:
    """The cells (m, k) of `family` mirrored (corners 1 and 2 swapped, ElementFamily.mirror) where
    det[X_1 - X_0, ..., X_d - X_0] < 0 (a triangle clockwise, a tetrahedron of negative volume); a flat one (|det|
    at most 1e-12 of its bounding box's measure) is refused."""
    x = vertices[cells[:, : family.dim + 1]]
    det = np.linalg.det(np.swapaxes(x[:, 1:] - x[:, :1], 1, 2))
    flat = np.abs(det) <= 1e-12 * float(np.ptp(vertices, axis=0).prod())
    which = family.name.split()[-1]
    require(not flat.any(), f"{which} {int(np.argmax(flat))} (nodes {cells[np.argmax(flat)].tolist()}) is flat")
    return family.mirrored(cells, det < 0)


def boundary_facets(family: ElementFamily, elements: np.ndarray) -> np.ndarray:
    """The facets (f, nodes per facet) of the elements' table that belong to one element only: the mesh's
    boundary, each facet in its element's node order (outward normal to the right in 2D, corners
    counter-clockwise seen from outside in 3D)."""
    facets = elements[:, np.array(family.facets)].reshape(-1, len(family.facets[0]))
    corners = np.sort(facets[:, : family.dim], axis=1)
    _, index, counts = np.unique(corners, axis=0, return_index=True, return_counts=True)
    return facets[np.sort(index[counts == 1])]
