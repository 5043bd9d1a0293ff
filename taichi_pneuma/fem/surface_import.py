"""Bodies from triangle surfaces (STL, OBJ, PLY, OFF: what CAD tools export for 3D printing), repaired, remeshed and
filled with tetrahedra by gmsh.

A surface file is triangles only: no unit (SurfaceBody.scale, required, is the length of one file unit in the
scene's units: 1 for a file in the scene's own unit, 0.001 for a file in mm read into a scene in m), no solids and no
names. Its chambers are its cavities: a Cavity names the one that encloses its `inside` point. A chamber may also be a
closed surface file of its own (SurfaceChamber: the air it holds, drawn as a part of its own), read at its own scale or
the body's, repaired as the body's file is and added to the body's shells as one more cavity: it must be one closed
surface, inside the body's outer shell and in no other cavity, enclosing none, and apart from every other surface
(surface_clearance.py: a gap of more than TOUCH_TOLERANCE times the body's size, else it touches or crosses).

Size: a file is read within meshfile's limits (MAX_MESH_BYTES, a memory bound); its facets are then counted against
the budget before anything else reads them (limits.Budget.check_facets: gmsh's classification and reparametrisation
hold about BYTES_PER_FACET a facet, and take about 50 us each), so a huge export is refused in a line, not meshed for
minutes.

Repair, before gmsh (the readers' resource guards first: meshfile.read_mesh):

    merged      vertices closer than MERGE_TOLERANCE times the surface's size are one (an exporter writes each
                triangle's corners apart: an STL has no shared vertices)
    dropped     a triangle with a repeated corner or of no area; a triangle given twice, in either orientation, once
    refused     an edge of one triangle only (a hole, naming how many and where the first is), an edge of more than
                two (a surface through itself along an edge, or two shells sharing one)
    oriented    then flipped facets are turned: each closed piece consistently (gmsh's reparametrisation of a curved
                patch refuses facets of mixed orientation; oriented()), out of the rubber as a solid's boundary
                is (the outer shell outward, a cavity's wall into the cavity); a piece that cannot be (one-sided:
                it passes through itself) is refused

Shells: the surface's connected pieces. The one of the largest bounding box is the body's outer surface; every
other one bounds a cavity, and each cavity must be a chamber's (a cavity no chamber names is refused, naming its
place; so is a chamber whose point is in no cavity, or two chambers in one). A point is inside a shell when a ray from
it crosses the shell an odd number of times.

Meshing: gmsh classifies the surface into patches at edges sharper than CLASSIFY_DEGREES, makes a geometry of them
(each patch reparametrised), remeshes it at the scene's sizes (gmsh_mesher.MeshSizes, graded near the chamber walls
as a body from shapes is) and fills the rubber with tetrahedra (Delaunay). A surface that crosses itself fails there,
and is refused with gmsh's words. The remeshed surface's triangles are chords of the file's facets: a curve is
resolved by the file and by the mesh size near it, whichever is coarser. Quadratic tetrahedra put their boundary
edges' midside nodes on the file's surface (gmsh's closest point on its patches, curving.edge_targets), not on the
remeshed triangles' chords.
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ..errors import quoted, require, require_finite
from ..io.registry import key
from ..io.units import LENGTH
from ..limits import Budget
from .body import Body, SizeEstimate
from .gmsh_mesher import MAX_TETS, MeshSizes, estimate_from_measures, read_tetrahedra, set_sizes
from .gmsh_session import session
from .mesh import Mesh
from .meshfile import TRIANGLES, cells_of, read_mesh
from .solids import TRIPLE
from .supports import PointSet
from .surface_clearance import closest_approach, crosses
from .tetmesh import check_order, tet_mesh

SURFACE_SUFFIXES = (".stl", ".obj", ".ply", ".off")
MERGE_TOLERANCE = 1e-9
TOUCH_TOLERANCE = 1e-6  # a chamber's own surface closer than this times the body's size to another surface touches it
CLASSIFY_DEGREES = 40.0


def surface_file(file) -> str:
    """The absolute path of a surface file (refused unless of SURFACE_SUFFIXES)."""
    require(
        isinstance(file, str) and file.lower().endswith(SURFACE_SUFFIXES),
        f"file = {quoted(file)}: a surface is read from a {', '.join(SURFACE_SUFFIXES)} file",
    )
    return os.path.abspath(file)


@dataclass(frozen=True)
class SurfaceBody:
    """A body bounded by the triangles of a surface file (module docstring): file (an absolute path, a scene file's
    relative to its folder) and scale (the length of one file unit in the scene's units)."""

    file: str = key(doc="the surface file, relative to the scene file")
    scale: float = key(doc="the length of one file unit in the scene's units (required: the file has none)")
    name = "surface"

    def __post_init__(self):
        object.__setattr__(self, "file", surface_file(self.file))
        require(require_finite("scale", self.scale) > 0, f"scale = {self.scale!r} must be > 0")


@dataclass(frozen=True)
class SurfaceChamber:
    """A chamber of a surface body drawn as a closed surface file of its own (module docstring): file (as
    SurfaceBody's) and scale (the length of one file unit in the scene's units; None: the body's)."""

    file: str = key(doc="the chamber's surface file, relative to the scene file")
    scale: float | None = key(None, "the length of one file unit in the scene's units (none: the body's scale)")
    name = "surface"

    def __post_init__(self):
        object.__setattr__(self, "file", surface_file(self.file))
        require(
            self.scale is None or require_finite("scale", self.scale) > 0,
            f"scale = {self.scale!r} must be > 0 (or left out: the body's)",
        )


@dataclass(frozen=True)
class Cavity:
    """A chamber of a surface body: the cavity that encloses the point `inside` (in the scene's units)."""

    inside: tuple[float, float, float] = key(doc=f"{TRIPLE}, a point in the cavity", unit=LENGTH)
    name = "cavity"

    def __post_init__(self):
        require(
            np.shape(self.inside) == (3,) and all(math.isfinite(float(v)) for v in self.inside),
            f"inside = {self.inside!r} must be three numbers [x, y, z]",
        )


@dataclass(frozen=True)
class Shells:
    """A repaired surface: vertices (n, 3) in the scene's units, triangles (m, 3), and the shell of each triangle
    (0: the outer one)."""

    vertices: np.ndarray
    triangles: np.ndarray
    shell: np.ndarray

    @property
    def count(self) -> int:
        return int(self.shell.max()) + 1

    @property
    def vertex_shell(self) -> np.ndarray:
        """The shell of each vertex (a vertex lies on the triangles of one shell only)."""
        shell = np.empty(len(self.vertices), dtype=np.int64)
        shell[self.triangles] = self.shell[:, None]
        return shell

    def facets(self, k: int) -> np.ndarray:
        """The triangles of shell k as (t, 3, 3) corners."""
        return self.vertices[self.triangles[self.shell == k]]

    def encloses(self, k: int, point) -> bool:
        """Whether shell k encloses the point: a ray along a slightly skew direction (a segment from the point out
        past the shell's bounding box) crosses it an odd number of times (Moller-Trumbore on every triangle)."""
        x = self.facets(k)
        start = np.asarray(point, dtype=np.float64)
        direction = np.array([1.0, 1e-3 * math.sqrt(2), 1e-3 * math.sqrt(3)])
        reach = 2 * float(np.linalg.norm(np.ptp(x.reshape(-1, 3), axis=0))) + float(np.abs(x - start).max())
        count = len(x)
        hits = crosses(np.tile(start, (count, 1)), np.tile(start + reach * direction, (count, 1)), x)
        return bool(np.count_nonzero(hits) % 2)

    def where(self, k: int) -> list[float]:
        """A place to name shell k by in a message: the mean of its triangles' corners."""
        return np.round(self.facets(k).reshape(-1, 3).mean(axis=0), 6).tolist()


def joined(parts: list[Shells]) -> Shells:
    """The shells of several repaired surfaces as one, in order (the first's outer shell stays shell 0)."""
    offsets = np.cumsum([0] + [len(p.vertices) for p in parts])
    counts = np.cumsum([0] + [p.count for p in parts])
    return Shells(
        np.concatenate([p.vertices for p in parts]),
        np.concatenate([p.triangles + offsets[i] for i, p in enumerate(parts)]),
        np.concatenate([p.shell + counts[i] for i, p in enumerate(parts)]),
    )


def read_surface(path: str) -> tuple[np.ndarray, np.ndarray]:
    """A surface file's points (n, 3) and triangles (m, 3), as read (meshfile.read_mesh's limits and memo)."""
    source = read_mesh(path)
    triangles, _ = cells_of(source, TRIANGLES, None, path)
    return np.asarray(source.points, dtype=np.float64)[:, :3], triangles


def repaired(points: np.ndarray, triangles: np.ndarray, path: str) -> Shells:
    """The surface merged, cleaned and split into shells, the outer one first; refused where it is open or
    non-manifold (module docstring)."""
    from scipy.sparse import coo_matrix  # here: a run without a surface body does not load SciPy's graphs
    from scipy.sparse.csgraph import connected_components

    require(len(triangles) > 0, f"surface file {quoted(path)} has no triangles")
    size = float(np.ptp(points, axis=0).max())
    require(size > 0, f"surface file {quoted(path)}: its triangles have no extent")
    key = np.round((points - points.min(axis=0)) / (MERGE_TOLERANCE * size)).astype(np.int64)
    _, first, merged = np.unique(key, axis=0, return_index=True, return_inverse=True)
    vertices, triangles = points[first], merged.reshape(-1)[triangles]
    x = vertices[triangles]
    area = np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1)
    distinct = (triangles[:, 0] != triangles[:, 1]) & (triangles[:, 1] != triangles[:, 2])
    triangles = triangles[distinct & (triangles[:, 0] != triangles[:, 2]) & (area > 1e-14 * size**2)]
    _, once = np.unique(np.sort(triangles, axis=1), axis=0, return_index=True)
    triangles = triangles[np.sort(once)]
    edges = np.sort(triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    open_edges = unique[counts == 1]
    require(
        len(open_edges) == 0,
        f"surface file {quoted(path)} has a hole: {len(open_edges)} edges of one triangle only, the first at "
        f"{np.round(vertices[open_edges[0]].mean(axis=0), 6).tolist() if len(open_edges) else []} (close it in the "
        f"CAD tool, or export a closed solid)",
    )
    crowded = unique[counts > 2]
    require(
        len(crowded) == 0,
        f"surface file {quoted(path)} is not a solid's boundary: {len(crowded)} edges shared by more than two "
        f"triangles, the first at {np.round(vertices[crowded[0]].mean(axis=0), 6).tolist() if len(crowded) else []}",
    )
    triangles = oriented(vertices, triangles, path)
    n = len(triangles)
    rows = np.repeat(np.arange(n), 3)
    adjacency = coo_matrix((np.ones(3 * n), (rows, triangles.reshape(-1))), shape=(n, len(vertices))).tocsr()
    _, shell = connected_components(adjacency @ adjacency.T, directed=False)
    extent = [np.prod(np.ptp(vertices[triangles[shell == k]].reshape(-1, 3), axis=0)) for k in range(shell.max() + 1)]
    order = np.argsort(extent)[::-1]  # the largest bounding box first: the outer surface
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    triangles = np.where((rank[shell] > 0)[:, None], triangles[:, ::-1], triangles)  # a cavity's wall faces into it
    used, triangles = np.unique(triangles, return_inverse=True)
    return Shells(vertices[used], triangles.reshape(-1, 3), rank[shell])


def oriented(vertices: np.ndarray, triangles: np.ndarray, path: str) -> np.ndarray:
    """The triangles of a closed manifold surface turned so that each piece (triangles joined across edges) is
    consistently oriented, outward from what it encloses: two triangles sharing an edge run along it in opposite
    directions, and the piece's signed volume sum x0 . (x1 x x2) / 6 is positive. A breadth-first spanning tree of
    the pieces (one virtual root joined to a triangle of each) carries the turns: a triangle turns if the tree edges
    from it to the root hold an odd number of pairs that run their edge the same way (pointer doubling sums them). A
    piece left inconsistent (a surface through itself, one-sided) is refused."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import breadth_first_order, connected_components

    n = len(triangles)
    directed = triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    _, key = np.unique(np.sort(directed, axis=1), axis=0, return_inverse=True)
    order = np.argsort(key.reshape(-1), kind="stable")  # each edge's two triangles (closed, manifold) side by side
    one, two = order[0::2], order[1::2]
    same = directed[one, 0] == directed[two, 0]  # both run the edge the same way: one of the two must turn
    t1, t2 = one // 3, two // 3
    pieces, piece = connected_components(coo_matrix((np.ones(len(t1)), (t1, t2)), shape=(n, n)), directed=False)
    roots = np.unique(piece, return_index=True)[1]
    rows = np.concatenate([t1, t2, np.full(pieces, n)])
    cols = np.concatenate([t2, t1, roots])
    flags = coo_matrix((np.concatenate([same, same, np.zeros(pieces, bool)]) + 1.0, (rows, cols)), (n + 1, n + 1))
    flags = flags.tocsr()
    _, up = breadth_first_order(flags, n, directed=True, return_predecessors=True)
    up[n] = n
    turn = np.asarray(flags[up, np.arange(n + 1)]).ravel() == 2
    while np.any(up != n):  # turn[v]: the parity from v up to up[v]; doubling the step until it reaches the root
        turn, up = turn ^ turn[up], up[up]
    require(
        not np.any(same ^ turn[t1] ^ turn[t2]),
        f"surface file {quoted(path)} cannot be oriented: a piece of it has no consistent inside (it passes through "
        f"itself)",
    )
    triangles = np.where(turn[:n, None], triangles[:, ::-1], triangles)
    x = vertices[triangles]
    signed = np.bincount(piece, np.einsum("ij,ij->i", x[:, 0], np.cross(x[:, 1], x[:, 2])), pieces)
    return np.where((signed[piece] < 0)[:, None], triangles[:, ::-1], triangles)


@dataclass(frozen=True)
class SurfaceGeometry(Body):
    """A 3D body from a surface file (module docstring): the body, its chambers (name, Cavity or SurfaceChamber) in
    order, the mesh sizes, the element order, the clamp, tip and rollers (as planar.Geometry's)."""

    body: SurfaceBody
    chambers: tuple
    sizes: MeshSizes
    order: int = 1
    clamp: PointSet | None = None
    tip: PointSet = field(default_factory=lambda: PointSet("right"))
    rollers: tuple = ()

    dim = 3

    def __post_init__(self):
        check_order(self.order)
        self.check_supports()
        require(
            self.sizes.through_wall is None,
            "mesh.through_wall: a surface body's walls are not measured; give mesh.near_chambers",
        )
        for name, shape in self.chambers:
            require(
                isinstance(shape, Cavity | SurfaceChamber),
                f'chamber {name!r}: a surface body\'s chambers are its cavities (shape = "cavity", inside = [x, y, z]) '
                f'or closed surfaces of their own (shape = "surface", file = ...)',
            )

    @property
    def files(self) -> list[tuple[str, float]]:
        """The surface files read, each with its scale: the body's, then each SurfaceChamber's in order."""
        own = [shape for _, shape in self.chambers if isinstance(shape, SurfaceChamber)]
        return [(self.body.file, self.body.scale)] + [
            (shape.file, self.body.scale if shape.scale is None else shape.scale) for shape in own
        ]

    def check_facets(self, budget: Budget) -> None:
        """Refuse its surface files past the budget by their triangles, as read (before repair)."""
        facets = sum(len(read_surface(path)[1]) for path, _ in self.files)
        budget.check_facets(facets, "the surface of " + " and ".join(quoted(path) for path, _ in self.files))

    @cached_property
    def shells(self) -> Shells:
        """The files' triangles, scaled into the scene's units and repaired, joined: the body's shells, then one
        shell of each SurfaceChamber's file, turned to face into its air as the body's cavities do (once: the size
        estimate and the mesh read them both)."""
        parts = []
        for path, scale in self.files:
            points, triangles = read_surface(path)
            parts.append(repaired(points * scale, triangles, path))
            require(
                len(parts) == 1 or parts[-1].count == 1,
                f"chamber surface file {quoted(path)} holds {parts[-1].count} closed surfaces; a chamber's file "
                f"holds one (the air of one chamber)",
            )
        own = [Shells(part.vertices, part.triangles[:, ::-1], part.shell) for part in parts[1:]]  # into the air
        return joined(parts[:1] + own)

    def cavities(self, shells: Shells) -> dict[str, int]:
        """name -> the shell of its cavity, in the chambers' order: a SurfaceChamber's own shell (placed:
        check_placed), a Cavity's the one around its point; every cavity a chamber's (module docstring)."""
        own = [name for name, shape in self.chambers if isinstance(shape, SurfaceChamber)]
        first = shells.count - len(own)  # the first chamber file's shell
        found = {name: first + i for i, name in enumerate(own)}
        self.check_placed(shells, found, first)
        for name, cavity in self.chambers:
            if not isinstance(cavity, Cavity):
                continue
            inside = [k for k in range(1, shells.count) if shells.encloses(k, cavity.inside)]
            require(
                len(inside) == 1, f"chamber {name!r}: inside = {list(cavity.inside)} lies in no cavity of the surface"
            )
            taken = [other for other, k in found.items() if k == inside[0]]
            require(
                not taken, f"chamber {name!r}: its point lies in the cavity of chamber {taken[0] if taken else ''!r}"
            )
            found[name] = inside[0]
        for k in range(1, first):
            require(
                k in found.values(),
                f"the surface encloses {first - 1} cavities; the one about {shells.where(k)} is no chamber's (add a "
                f"[[chambers]] table with inside = a point in it)",
            )
        return {name: found[name] for name, _ in self.chambers}  # in the chambers' order: the mesh's walls keep it

    def check_placed(self, shells: Shells, own: dict[str, int], first: int) -> None:
        """Refuse a chamber file's shell (own: name -> shell, from `first` on) that comes within TOUCH_TOLERANCE
        times the body's size of another shell (it touches or crosses it), lies outside the body's outer shell, in
        another cavity, or around one (the shells apart, one corner of each tells which encloses which)."""
        size = float(np.ptp(shells.facets(0).reshape(-1, 3), axis=0).max())
        names = {k: name for name, k in own.items()}
        for name, k in own.items():
            wall = shells.facets(k)
            for j in range(k):
                other = (
                    "the body's outer surface"
                    if j == 0
                    else f"the body's cavity about {shells.where(j)}"
                    if j < first
                    else f"the cavity of chamber {names[j]!r}"
                )
                met = closest_approach(wall, shells.facets(j), TOUCH_TOLERANCE * size)
                require(
                    met is None,
                    f"chamber {name!r}: its surface touches or crosses {other} at "
                    f"{np.round(met[1], 6).tolist() if met else []} (a chamber's surface lies inside the body, apart "
                    f"from every other surface)",
                )
                corner, others = wall[0, 0], shells.facets(j)[0, 0]
                require(j > 0 or shells.encloses(0, corner), f"chamber {name!r}: its surface lies outside the body")
                require(j == 0 or not shells.encloses(j, corner), f"chamber {name!r}: its surface lies inside {other}")
                require(j == 0 or not shells.encloses(k, others), f"chamber {name!r}: its surface encloses {other}")

    @property
    def mesh_sizes(self) -> MeshSizes:
        """The sizes gmsh meshes at: the scene's (a surface body's walls are not measured: no through_wall)."""
        return self.sizes

    def size_estimate(self) -> SizeEstimate:
        """Tetrahedra as a body from shapes estimates them (gmsh_mesher.estimate_from_measures), from the rubber's
        volume (the shells' signed volumes) and the cavities' wall area; nodes: a fifth of them (and one per edge,
        about 1.2 per tetrahedron, when quadratic)."""
        shells = self.shells
        x = shells.vertices[shells.triangles]
        cross = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
        signed = np.einsum("ij,ij->i", x[:, 0], np.cross(x[:, 1], x[:, 2])) / 6
        volume = sum(abs(signed[shells.shell == k].sum()) * (1 if k == 0 else -1) for k in range(shells.count))
        walls = float(np.linalg.norm(cross[shells.shell > 0], axis=1).sum() / 2)
        tets = estimate_from_measures(max(volume, 0.0), walls, self.sizes)
        return SizeEstimate(tets, tets / 5 + (1.2 * tets if self.order == 2 else 0))

    def mesh_values(self) -> dict:
        """order and the mesh sizes."""
        return {"order": self.order, **dataclasses.asdict(self.sizes)}

    def mesh(self, budget: Budget = Budget()) -> Mesh:
        """Repair, remesh and fill with tetrahedra (module docstring), under the budget (its facets counted first)."""
        self.check_facets(budget)
        shells = self.shells
        cavities = self.cavities(shells)
        cap = budget.element_cap(self.family.weight)
        with session() as gmsh:
            surface = gmsh.model.addDiscreteEntity(2)
            gmsh.model.mesh.addNodes(2, surface, np.arange(1, len(shells.vertices) + 1), shells.vertices.ravel())
            gmsh.model.mesh.addElementsByType(surface, 2, [], (shells.triangles + 1).ravel())
            gmsh.model.mesh.classifySurfaces(math.radians(CLASSIFY_DEGREES), True, True, math.pi)
            gmsh.model.mesh.createGeometry()
            patches: dict[int, list[int]] = {}
            vertex_shell = shells.vertex_shell  # gmsh's node tag = vertex row + 1
            for _, tag in gmsh.model.getEntities(2):
                nodes = gmsh.model.mesh.getElementsByType(2, tag)[1]
                patches.setdefault(int(vertex_shell[int(nodes[0]) - 1]), []).append(tag)
            loops = [gmsh.model.geo.addSurfaceLoop(patches[k]) for k in range(shells.count)]
            volume = gmsh.model.geo.addVolume(loops)
            gmsh.model.geo.synchronize()
            walls = {name: patches[k] for name, k in cavities.items()}
            set_sizes(gmsh, self.sizes, [s for tags in walls.values() for s in tags])
            gmsh.model.mesh.generate(3)
            meshed = read_tetrahedra(gmsh, {volume: 0}, walls, (), MAX_TETS if cap is None else cap)
        budget.check_mesh(len(meshed.tets), self.family.weight, "gmsh")
        return tet_mesh(
            meshed.vertices,
            meshed.tets,
            meshed.chambers,
            order=self.order,
            clamp=self.clamp,
            tip=self.tip,
            rollers=self.rollers,
            curved=(meshed.curved_edges, meshed.curved_points),
        )
