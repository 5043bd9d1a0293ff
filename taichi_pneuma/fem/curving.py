"""Curved quadratic tetrahedra on gmsh's shapes: the midside node of every edge on a curved surface of the solid moved
onto that surface, unless the move would fold an element.

gmsh meshes a solid with straight-sided tetrahedra whose corners lie on the shapes' surfaces, and a quadratic
tetrahedron gets a node at the middle of each edge (tetmesh.tet_mesh), so a round wall stays a polyhedron: a chord
of length h sags inside a surface of curvature radius R by h^2 / (8 R), and the displacement near it converges as
h^2 whatever the elements' order. As the 2D meshes do on their curves (planar.onto_curves), the midside node of an
edge gmsh classified on a model entity is put at the point of that entity closest to the edge's middle
(OpenCASCADE's projection, gmsh.model.getClosestPoint), so that the isoparametric elements follow the exact
surface:

- an edge of a 1D mesh element goes onto its geometric curve (where two surfaces meet: a cylinder's rim, a chamber
  wall's rim on a symmetry plane);
- any other edge of a 2D mesh element onto its surface (the outer surface, the chamber walls, the faces between
  material regions and across a cut plane);
- interior edges, and the edges on planes and straight lines, stay straight.

edge_targets() finds these (edge, point) pairs while gmsh's model is open (gmsh_mesher keeps them with the mesh); a
move over MAX_SAG of its edge's length (a mesh far too coarse for the curvature, or the closest point of a trimmed
surface's untrimmed carrier) is not made. curve() then moves the nodes of a quadratic mesh and undoes the moves that
would fold an element: each element's map X(xi) = sum_a X_a N_a(xi) must keep

    det dX/dxi (xi) >= FLOOR det dX/dxi of the straight element (6 times its volume)

at its ten nodes and its quadrature points; every moved midside node of an element that fails goes back to the
middle of its edge, and the elements around those nodes are checked again until none fails (each round only takes
nodes back, and a straight element passes, so it ends).
"""

from __future__ import annotations

import numpy as np

from .elements import ElementFamily

MAX_SAG = 0.25  # the largest move, over its edge's length (a chord over 106 degrees of a circle)
FLOOR = 0.25  # det dX/dxi of a curved element at its nodes and quadrature points, over its straight element's
FLAT = ("Plane", "Line")  # gmsh's types of the entities whose edges stay straight


def edge_targets(gmsh, local: np.ndarray, vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(edges (k, 2) by their corners' rows in vertices, points (k, 3)): the edges of gmsh's 1D and 2D mesh elements
    on curved entities and their midside nodes' places on those entities (module docstring). local: the row of
    gmsh node tag t in vertices, or -1 (a node no tetrahedron has)."""
    n = len(vertices)
    taken: set[int] = set()
    edges, points = [np.zeros((0, 2), dtype=np.int64)], [np.zeros((0, 3))]
    for dim, kind, sides in ((1, 1, [[0, 1]]), (2, 2, [[0, 1], [1, 2], [2, 0]])):
        for _, tag in gmsh.model.getEntities(dim):
            nodes = gmsh.model.mesh.getElementsByType(kind, tag)[1].astype(np.int64).reshape(-1, dim + 1)
            pairs = np.sort(local[nodes][:, sides].reshape(-1, 2), axis=1)
            pairs = np.unique(pairs[pairs.min(axis=1) >= 0], axis=0)
            keys = (pairs[:, 0] * n + pairs[:, 1]).tolist()
            pairs = pairs[np.array([k not in taken for k in keys], dtype=bool)]  # a curve's edges are not redone
            taken.update(keys)
            if not len(pairs) or gmsh.model.getType(dim, tag) in FLAT:
                continue
            a, b = vertices[pairs[:, 0]], vertices[pairs[:, 1]]
            middle = 0.5 * (a + b)
            target = np.reshape(gmsh.model.getClosestPoint(dim, tag, middle.ravel())[0], (-1, 3))
            move, length = np.linalg.norm(target - middle, axis=1), np.linalg.norm(b - a, axis=1)
            kept = (move > 1e-12 * length) & (move <= MAX_SAG * length)
            edges.append(pairs[kept])
            points.append(target[kept])
    return np.concatenate(edges), np.concatenate(points)


def jacobian_ratios(vertices: np.ndarray, elements: np.ndarray, family: ElementFamily) -> np.ndarray:
    """(m,) the least det dX/dxi of each quadratic tetrahedron at its nodes and quadrature points, over its corners'
    det[X1 - X0, X2 - X0, X3 - X0] (its straight element's, the same everywhere)."""
    points = np.vstack([family.reference_nodes, family.rule[0]])
    x = vertices[elements]
    jacobian = np.einsum("mai,paj->mpij", x, family.shape_gradients(points))
    corners = x[:, 1:4] - x[:, :1]
    return np.linalg.det(jacobian).min(axis=1) / np.linalg.det(corners)


def curve(
    vertices: np.ndarray, elements: np.ndarray, family: ElementFamily, nodes: np.ndarray, points: np.ndarray
) -> np.ndarray:
    """The vertices of the quadratic tetrahedra `elements` (straight: every midside node at its edge's middle) with
    the midside nodes `nodes` moved to `points`, less the moves that would fold an element (module docstring)."""
    moved = vertices.copy()
    moved[nodes] = points
    straight = np.ones(len(vertices), dtype=bool)
    straight[nodes] = False
    check = np.flatnonzero(~straight[elements[:, 4:]].all(axis=1))
    while len(check):
        folded = check[jacobian_ratios(moved, elements[check], family) < FLOOR]
        back = np.unique(elements[folded, 4:])
        back = back[~straight[back]]
        moved[back], straight[back] = vertices[back], True
        check = np.flatnonzero(np.isin(elements[:, 4:], back).any(axis=1))
    return moved
