"""Tetrahedral meshes of 3D bodies with cavity chambers: tet_mesh(), the mesh.Mesh of plain arrays, and Closure,
how an open chamber wall is closed.

A mesh generator or a mesh file hands over vertices (n, 3), tetrahedra (m, 4) or (m, 10) (VTK's node
order: corners, then the middles of edges 01, 12, 20, 03, 13, 23), each chamber's wall as triangles
(f, 3) by their corners and, optionally, the outer boundary's triangles and a region tag per
tetrahedron. tet_mesh() drops the nodes no tetrahedron uses, turns every tetrahedron to positive volume,
adds midside nodes to a 4-node mesh for quadratic elements (order 2: at the edges' middles, or, for the
edges given as curved, on the shapes' surfaces where that folds no element, curving.curve; a 10-node mesh is
read as is and may be curved), finds the body's boundary facets (elements.boundary_facets) and takes each chamber
wall as the facets with those corners, oriented outward from the cavity (into the rubber: the reverse of
the body's outward facet), so that its enclosed volume

    V = 1/3 integral of (x - o) . n dA over the wall

is positive at rest. A wall that is open (a chamber cut by symmetry planes, as in a half or quarter
model) is closed by flat caps in the roller planes that hold its rim (Closure): with the origin o on
every cap plane the caps add nothing, (x - o) . n = 0 on them. Two parallel cap planes (a chamber
through the whole depth between two rollers) cannot both hold o; their direction e is projected out
instead, V = 1/r integral of (x - o) . P n dA with P = I - e e^T and r = 3 - (directions projected
out), whose integrand also vanishes on those caps, and whose divergence theorem still gives the
volume (div P (x - o) / r = 1).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import require
from .curving import curve
from .elements import ElementFamily, boundary_facets, family_for, family_of, positively_oriented
from .mesh import Mesh
from .supports import PointSet, node_sets

PARALLEL = 1 - 1e-9  # |n1 . n2| above it: parallel planes


@dataclass(frozen=True)
class Closure:
    """How an open chamber wall is closed by flat caps in symmetry planes: its volume is 1/r times the
    integral of (x - origin) . projector n over the wall, r = the projector's rank (module docstring)."""

    origin: np.ndarray
    projector: np.ndarray


def facet_keys(facets: np.ndarray, n: int) -> np.ndarray:
    """One integer per facet, the same for any order of its three corners."""
    corners = np.sort(facets[:, :3], axis=1).astype(np.int64)
    return (corners[:, 0] * n + corners[:, 1]) * n + corners[:, 2]


def used_nodes(vertices: np.ndarray, tets: np.ndarray, faces: list[np.ndarray]):
    """The vertices the tetrahedra use, and the tetrahedra and faces renumbered to them."""
    used = np.unique(tets)
    number = np.full(len(vertices), -1, dtype=np.int64)
    number[used] = np.arange(len(used))
    return vertices[used], number[tets], [number[f] for f in faces]


def check_midside_nodes(vertices: np.ndarray, tets: np.ndarray, family: ElementFamily) -> None:
    """Refuse quadratic tetrahedra whose midside nodes are not near the middles of the family's edges 01, 12, 20,
    03, 13, 23 (within a quarter of the edge: another node order, such as gmsh's own, lands half an edge away)."""
    for k, (i, j) in enumerate(family.edges):
        a, b, m = vertices[tets[:, i]], vertices[tets[:, j]], vertices[tets[:, 4 + k]]
        off = np.linalg.norm(m - 0.5 * (a + b), axis=1) > 0.25 * np.linalg.norm(b - a, axis=1)
        require(
            not off.any(),
            f"10-node tetrahedron {int(np.argmax(off))}: node {4 + k} is not near the middle of "
            f"edge {i}{j} (the node order must be VTK's: edges 01, 12, 20, 03, 13, 23)",
        )


def closure(name: str, vertices: np.ndarray, wall: np.ndarray, rollers) -> Closure | None:
    """None for a closed wall (every edge in two of its triangles); for an open one the Closure of the roller
    planes that hold its rim (module docstring), or a PneumaInputError naming the chamber."""
    corners = wall[:, :3]
    edges = np.sort(np.vstack([corners[:, [0, 1]], corners[:, [1, 2]], corners[:, [2, 0]]]), axis=1)
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    require(counts.max() <= 2, f"chamber {name!r}: an edge of its wall belongs to more than two of its triangles")
    if counts.min() == 2:
        return None
    rim = vertices[np.unique(unique[counts == 1])]
    planes = [
        (r.unit_normal, np.asarray(r.point, dtype=np.float64), r.tolerance) for r in rollers if r.point is not None
    ]
    on = np.array([np.abs((rim - p) @ n) <= tol for n, p, tol in planes]).reshape(len(planes), len(rim))
    off = ~on.any(axis=0)
    require(
        not off.any(),
        f"chamber {name!r}: its wall is open, and its rim at {rim[np.argmax(off)].tolist()} lies "
        f"on no roller plane (a symmetry plane closing it: [[rollers]] with a point)",
    )
    groups: list[list] = []  # the planes holding the rim, parallel ones together (each plane once)
    for n, p, tol in (planes[i] for i in np.flatnonzero(on.any(axis=1))):
        group = next((g for g in groups if abs(n @ g[0][0]) > PARALLEL), None)
        if group is None:
            groups.append([(n, p)])
        elif all(abs(group[0][0] @ (p - q)) > tol for _, q in group):
            group.append((n, p))
    require(all(len(g) <= 2 for g in groups), f"chamber {name!r}: its rim lies on three parallel roller planes")
    single = [g[0] for g in groups if len(g) == 1]
    normals, projector = [g[0][0] for g in groups], np.eye(3)
    for n in (g[0][0] for g in groups if len(g) == 2):
        require(
            all(abs(n @ m) < 1e-9 for m in normals if m is not n),
            f"chamber {name!r}: a pair of parallel roller planes closing it is not perpendicular to the others",
        )
        projector -= np.outer(n, n)
    require(np.trace(projector) > 0.5, f"chamber {name!r}: closed by parallel roller planes in every direction")
    origin = rim.mean(axis=0)
    if single:  # the point nearest the rim's centre on every single plane
        single_normals, offsets = np.array([n for n, _ in single]), np.array([n @ p for n, p in single])
        origin = origin + np.linalg.lstsq(single_normals, offsets - single_normals @ origin, rcond=None)[0]
    return Closure(origin, projector)


def check_order(order) -> None:
    """Refuse an element order without a tetrahedron family (family_for names the orders there are)."""
    family_for(3, order)


def tet_mesh(
    vertices: np.ndarray,
    tets: np.ndarray,
    chambers: dict[str, np.ndarray],
    boundary: np.ndarray | None = None,
    regions: np.ndarray | None = None,
    order: int = 1,
    clamp: PointSet | None = None,
    tip: PointSet = PointSet("right"),
    rollers=(),
    region_groups: dict | None = None,
    curved: tuple[np.ndarray, np.ndarray] | None = None,
) -> Mesh:
    """The Mesh of plain arrays (module docstring): vertices (n, 3); tets (m, 4) or (m, 10); chambers: name ->
        its wall's triangles (f, 3) (or (f, 6): the first three columns are used), in the scene's order;
        boundary: the outer boundary's triangles (None: every boundary facet on no chamber wall); regions: (m,)
        region tags (region_groups: the names of some, name -> tag); order 1 or 2; the clamp (None, the default:
        no node clamped), the tip and the rollers select their nodes; curved: (edges (k, 2) by their corners, points
    (k, 3)), the places of those edges' midside nodes on the exact surfaces (gmsh_mesher.SolidMesh's curved_edges and
    curved_points), for a 4-node mesh made quadratic."""
    vertices = np.asarray(vertices, dtype=np.float64)
    tets = np.asarray(tets)
    require(
        vertices.ndim == 2 and vertices.shape[1] == 3 and len(vertices) >= 4 and np.isfinite(vertices).all(),
        f"vertices must be finite (n, 3) coordinates, not an array of shape {vertices.shape}",
    )
    require(
        tets.ndim == 2 and tets.shape[1] in (4, 10) and len(tets) > 0 and np.issubdtype(tets.dtype, np.integer),
        f"tetrahedra must be an (m, 4) or (m, 10) integer array, not {tets.dtype} of shape {tets.shape}",
    )
    require(tets.min() >= 0 and tets.max() < len(vertices), "a tetrahedron names a vertex that does not exist")
    check_order(order)
    given_family = family_of(tets, 3)
    require(
        given_family.order in (1, order),
        f"the mesh has {given_family.n_nodes}-node tetrahedra ({given_family.words}): set order = {given_family.order}",
    )
    regions = np.zeros(len(tets), dtype=np.int64) if regions is None else np.asarray(regions, dtype=np.int64)
    require(regions.shape == (len(tets),), f"regions: {regions.shape} tags for {len(tets)} tetrahedra")
    names = list(chambers)
    given = [
        np.asarray(chambers[name], dtype=np.int64).reshape(-1, np.shape(chambers[name])[-1])[:, :3] for name in names
    ] + ([] if boundary is None else [np.asarray(boundary, dtype=np.int64)[:, :3]])
    for name, faces in zip(names + ["boundary"], given):
        require(
            faces.size == 0 or (faces.min() >= 0 and faces.max() < len(vertices)),
            f"{name}: a triangle names a vertex that does not exist",
        )
    edges, points = (np.zeros((0, 2), dtype=np.int64), np.zeros((0, 3))) if curved is None else curved
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    require(
        edges.size == 0 or (edges.min() >= 0 and edges.max() < len(vertices) and np.shape(points) == (len(edges), 3)),
        "curved: an edge names a vertex that does not exist, or its points are not one (x, y, z) per edge",
    )
    vertices, tets, given = used_nodes(vertices, tets.astype(np.int64), given + [edges])
    edges = given.pop()
    kept = edges.min(axis=1) >= 0  # edges of nodes no tetrahedron uses are dropped with them
    edges, points = edges[kept], np.asarray(points, dtype=np.float64)[kept]
    family = family_for(3, order)
    tets = positively_oriented(vertices, tets, given_family)
    if given_family is family and family.edges:
        check_midside_nodes(vertices, tets, family)
    elif given_family is not family:  # corners only: a midside node on every edge, curved ones on the surfaces
        vertices, tets, along = family.lift(vertices, tets)
        nodes = np.minimum(along(edges[:, 0], edges[:, 1])[:, 0], len(vertices) - 1)
        require(
            np.array_equal(vertices[nodes], 0.5 * (vertices[edges[:, 0]] + vertices[edges[:, 1]])),
            "a curved edge is not an edge of the tetrahedra",
        )
        vertices = curve(vertices, tets, family, nodes, points)
    surface = boundary_facets(family, tets)
    n = len(vertices)
    keys = facet_keys(surface, n)
    order_of_keys = np.argsort(keys)

    def facets_of(faces: np.ndarray, what: str) -> np.ndarray:
        """The rows of `surface` with the corners of faces (f, 3); a face not on the boundary is refused."""
        require(len(faces) > 0 and faces.min() >= 0, f"{what} has no triangle on the mesh")
        wanted = facet_keys(faces, n)
        at = np.minimum(np.searchsorted(keys, wanted, sorter=order_of_keys), len(keys) - 1)
        rows = order_of_keys[at]
        missing = keys[rows] != wanted
        require(
            not missing.any(),
            f"{what}: triangle {faces[np.argmax(missing)].tolist()} is not a face on the mesh's boundary",
        )
        return rows

    facet_family = family.facet_family
    assert facet_family is not None  # a tetrahedron's facets are triangles
    walls, origins, taken = [], [], np.zeros(len(surface), dtype=bool)
    for name, faces in zip(names, given):
        rows = facets_of(faces, f"chamber {name!r}")
        require(not taken[rows].any(), f"chamber {name!r} shares wall triangles with another chamber")
        taken[rows] = True
        wall = surface[rows][:, list(facet_family.mirror)]
        walls.append(wall)
        origins.append(closure(name, vertices, wall, rollers))
    outer = surface[facets_of(given[-1], "boundary")] if boundary is not None else surface[~taken]
    pinned, tip_nodes, held = node_sets(clamp, tip, rollers, vertices)
    return Mesh(
        vertices,
        tets,
        tuple(walls),
        np.unique(outer),
        pinned,
        tip_nodes,
        tuple(origins),
        held,
        family,
        surface,
        regions,
        dict(region_groups or {}),
    )
