"""A 3D body with chamber cavities and material regions -> a linear tetrahedral mesh, by gmsh.

The solid is built with OpenCASCADE (fem.solids shapes) and split by one boolean *fragment* of the
body with every chamber and region shape. The chamber pieces inside the body are the cavities and are
removed (pieces outside the body are dropped); every other piece inside the body is rubber, tagged with
the last region whose shape contains it (0: the base material). A chamber wall is the part of the
cavity's boundary shared with the rubber; where a chamber crosses the body's boundary (a symmetry plane
of a half model) its wall is open, its rim on that plane, and the flat cap across it is not meshed (no
rubber there): with an origin o on the plane, V = 1/3 int_wall (x - o) . n dA, as x - o is normal to n on the
cap. Whether such a plane is a symmetry plane (rollers) is the scene's check. Physical groups name what is read
back: the volume groups 'body' and each region, a surface group per chamber.

Mesh size: tetrahedra of edge length about `size` in the bulk and `near` (MeshSizes.near_chambers)
within `near` of the chamber walls, growing linearly to `size` over the grading distance d beyond
(gmsh Distance and Threshold fields). Before meshing, the tetrahedron count is estimated as the volume
over the volume of a regular tetrahedron of the local edge length h, h^3 / (6 sqrt 2):

    tets ~ 6 sqrt 2 [ (V - A t) / size^3 + A int_0^t ds / h(s)^3 ],   t = near + d,

with V the rubber's volume and A the chamber walls' area (from OpenCASCADE). gmsh's Delaunay meshes
have 0.55-0.95 times that many, fewer the finer the mesh (more only where the mesh is much coarser than
the thinnest wall, where the walls, not the size, set the count: the PneuNet, 0.08 walls, has 2.5 times
the estimate at size 0.2 and 5 times at 0.3, a few thousand tetrahedra either way): a solid whose
estimate exceeds max_tets is refused before meshing, and a mesh that still comes out larger is refused
after.

Returned arrays (SolidMesh): vertices (n, 3); tets (m, 4), each positively oriented,
det[x1 - x0, x2 - x0, x3 - x0] > 0; per chamber its wall triangles (f, 3) oriented outward from the
cavity, i.e. (x1 - x0) x (x2 - x0) points from the air into the rubber, so that for a closed wall

    V = 1/3 sum_faces (centroid . n) area = 1/6 sum_faces x0 . (x1 x x2) > 0

is the cavity's volume; boundary (b, 3): the triangles of the body's outer surface (cavity walls
excluded), oriented outward from the body; regions (m,) the tag of each tetrahedron, k >= 1 the k-th
entry of Solid.regions (region_names); curved_edges (k, 2) and curved_points (k, 3): the edges on curved
surfaces and curves of the solid and the places of their midside nodes on them (curving.edge_targets), for
quadratic tetrahedra that follow the shapes.

gmsh is a GPL-licensed optional dependency (pip install 'taichi-pneuma[3d]'); each call opens a session of it
(gmsh_session.py): it initialises it, works silently in a model of its own and finalises it (or, if the caller has
gmsh initialised already, removes only its own model and restores the options it set).

Meshes are cached on disk (io/cache.py: the user's cache folder, PNEUMA_CACHE_DIR moves it or turns it off):
the arrays of mesh_solid, and the rubber's volume and the walls' area that estimate_tets needs, each keyed by
everything that decides them: the solid's shapes and their parameters, the sizes, the surface meshers, gmsh's
version and this mesher's source (the files of gmsh_cache.MESHER_SOURCES). A hit runs no gmsh at all and returns
the very arrays gmsh made; the limits are checked on it as on a fresh mesh. A cached file is checked before use (a
regular file; its key's inputs, as text, those of this call; its content hash that of its arrays: io/cache.py; then
shapes, dtypes, indices in range, positive tetrahedra) and a bad one is meshed afresh and replaced.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import require, require_distinct, require_finite
from ..io import cache
from .curving import edge_targets
from .elements import TET_P1, positively_oriented
from .gmsh_cache import CACHE_BYTES_PER_TET, cache_key, valid_measures, valid_mesh
from .gmsh_session import session

MAX_TETS = 200_000
MAX_SHAPES = 64
REGULAR_TET = 1 / (6 * np.sqrt(2))  # volume of the regular tetrahedron of unit edge
BODY_GROUP = "body"
# gmsh's surface meshers, (Mesh.Algorithm, Mesh.MeshSizeFromCurvature), tried in turn until every surface and
# volume is meshed: Frontal-Delaunay with the sizes alone; then Delaunay with edges also shortened to 2 pi R / 12 on
# surfaces of curvature radius R. Frontal-Delaunay leaves a coarsely meshed B-spline surface (an ellipsoid:
# OpenCASCADE makes the dilated sphere one) without triangles: the 3D reference beam's chamber at sizes 0.13-0.5.
# (MeshAdapt loops on a small ellipsoid in a coarse mesh until gmsh crashes.)
SURFACE_MESHERS = ((6, 0), (5, 12))
MAX_SAMPLING = 200  # points per direction on a wall surface for its distance field
WALL_DIGITS = 10  # significant digits of a measured thickness and the size from it: 2 mm, not 1.999999999999999
# a tetrahedron's four faces (corners in its local numbering), each oriented outward for a positive tetrahedron
TET_FACES = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])


@dataclass(frozen=True)
class MeshSizes:
    """Target tetrahedron edge length: `size` in the bulk, `near_chambers` (default size; at most size) within
    that distance of the chamber walls, growing linearly to `size` over `distance` (default 2 size) beyond. Or,
    instead of near_chambers, `through_wall`: that many edges through the thinnest wall, near_chambers = t /
    through_wall with t the solid's thinnest_wall (for_wall makes the sizes that mesh it)."""

    size: float
    near_chambers: float | None = None
    distance: float | None = None
    through_wall: float | None = None

    def __post_init__(self):
        require(require_finite("size", self.size) > 0, f"size = {self.size!r} must be > 0")
        for name in ("near_chambers", "distance", "through_wall"):
            value = getattr(self, name)
            require(value is None or require_finite(name, value) > 0, f"{name} = {value!r} must be > 0")
        require(
            self.near_chambers is None or self.through_wall is None,
            f"near_chambers = {self.near_chambers!r} and through_wall = {self.through_wall!r}: give one of them (the "
            "edge length near the chambers, or the edges through the thinnest wall that set it)",
        )

    def for_wall(self, thickness: float) -> MeshSizes:
        """The sizes with near_chambers = thickness / through_wall (given), to WALL_DIGITS."""
        assert self.through_wall is not None  # sizes that give near_chambers mesh as they are
        return MeshSizes(self.size, float(f"{thickness / self.through_wall:.{WALL_DIGITS}g}"), self.distance)

    @property
    def near(self) -> float:
        """The edge length near the chambers: near_chambers, never above size (a size set below a scene's
        near_chambers makes the mesh uniform at that size)."""
        return self.size if self.near_chambers is None else min(float(self.near_chambers), float(self.size))

    @property
    def grading(self) -> float:
        return 2 * self.size if self.distance is None else float(self.distance)

    @property
    def shell(self) -> float:
        """The thickness of the layer over the walls where the size is below `size`."""
        return self.near + self.grading if self.near < self.size else 0.0

    def shell_density(self) -> float:
        """int over the shell's thickness of 1 / h(s)^3 ds: h = near up to s = near, then growing linearly
        to size at s = near + grading."""
        near, far = self.near, float(self.size)
        if self.shell == 0.0:
            return 0.0
        return 1 / near**2 + self.grading / (far - near) * (1 / near**2 - 1 / far**2) / 2


@dataclass(frozen=True)
class Solid:
    """A body shape with named chamber shapes (cavities) and named material-region shapes (the part of
    the body inside a region's shape gets that region's material; later regions win where they overlap). A shape
    is any object with build(occ) -> the new volume's tag (fem.solids' shapes; __post_init__ checks it has one).
    cuts: planes (unit normal, point) the mesh must carry nodes on (a roller's symmetry plane through the body):
    each one that passes through the body's bounding box splits the body, so that the tetrahedra meet on it
    (conforming: its faces are shared, no boundary) and its nodes lie on it."""

    body: Any
    chambers: tuple[tuple[str, Any], ...]
    regions: tuple[tuple[str, Any], ...] = ()
    cuts: tuple[tuple[tuple[float, ...], tuple[float, ...]], ...] = ()

    def __post_init__(self):
        for what, entries in (("chambers", self.chambers), ("regions", self.regions)):
            require(len(entries) <= MAX_SHAPES, f"{len(entries)} {what}: at most {MAX_SHAPES} are allowed")
        names = [name for name, _ in self.chambers + self.regions]
        require(
            all(isinstance(n, str) and n and n != BODY_GROUP for n in names),
            f"chamber and region names {names!r} must be non-empty strings other than {BODY_GROUP!r}",
        )
        require_distinct("chamber and region names", names)
        for what, shape in [("body", self.body)] + list(self.chambers + self.regions):
            require(callable(getattr(shape, "build", None)), f"{what}: {shape!r} is not a 3D shape")
        for normal, point in self.cuts:
            require(
                np.shape(normal) == np.shape(point) == (3,) and np.isfinite([*normal, *point]).all() and any(normal),
                f"cut plane {normal!r}, {point!r}: its normal (not zero) and point must be three finite numbers each",
            )


@dataclass(frozen=True, eq=False)
class SolidMesh:
    """The arrays of a meshed Solid (see the module docstring for their orientation)."""

    vertices: np.ndarray
    tets: np.ndarray
    chambers: dict[str, np.ndarray]
    boundary: np.ndarray
    regions: np.ndarray
    region_names: tuple[str, ...] = field(default=())
    curved_edges: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=np.int64))
    curved_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))


class _Pieces:
    """The fragmented solid: the rubber pieces with their region tags, and each chamber's wall surfaces."""

    def __init__(self, gmsh, solid: Solid):
        occ = gmsh.model.occ
        body = solid.body.build(occ)
        tools = [shape.build(occ) for _, shape in solid.chambers + solid.regions]
        tools += _half_spaces(occ, body, solid.cuts)  # their pieces are rubber (inside) or dropped (outside)
        _, pieces = occ.fragment([(3, body)], [(3, t) for t in tools])
        occ.synchronize()
        volumes = [{tag for _, tag in p} for p in pieces]
        first = 1 + len(solid.chambers)  # the first region's pieces (the cut planes' after the regions')
        inside, chambers, regions = volumes[0], volumes[1:first], volumes[first : first + len(solid.regions)]
        cavities = [c & inside for c in chambers]
        for (name, _), cavity in zip(solid.chambers, cavities):
            require(cavity, f"chamber {name!r} lies outside the body")
        for (name, _), region in zip(solid.regions, regions):
            require(region & inside, f"region {name!r} lies outside the body")
        for i, (a, c) in enumerate(zip(solid.chambers, cavities)):
            for b, d in zip(solid.chambers[i + 1 :], cavities[i + 1 :]):
                require(not c & d, f"chambers {a[0]!r} and {b[0]!r} overlap")
        hollow = set().union(*cavities)
        self.rubber = {tag: 0 for tag in sorted(inside - hollow)}
        for k, region in enumerate(regions, start=1):
            self.rubber.update({tag: k for tag in region if tag in self.rubber})
        require(self.rubber, "the chambers fill the whole body: no rubber is left")
        rubber_faces = _faces(gmsh, self.rubber, combined=False)
        self.walls = {}
        for (name, _), cavity in zip(solid.chambers, cavities):
            surface = _faces(gmsh, cavity)
            others = set().union(*(c for c in cavities if c is not cavity))
            require(not surface & _faces(gmsh, others, combined=False), f"chamber {name!r} touches another chamber")
            self.walls[name] = sorted(surface & rubber_faces)
            require(self.walls[name], f"chamber {name!r} has no wall inside the body")
        dropped = set().union(*volumes) - set(self.rubber)
        occ.remove([(3, v) for v in sorted(dropped)], recursive=True)
        occ.synchronize()
        self.volume = sum(occ.getMass(3, v) for v in self.rubber)
        self.wall_area = sum(occ.getMass(2, s) for walls in self.walls.values() for s in walls)


def _half_spaces(occ, body: int, cuts) -> list[int]:
    """For each cut plane (n, point) through the body's bounding box (its corners on both sides by more than 1e-9 of
    its diagonal), a box holding the side n . (x - point) >= 0 of everything: a box [-s, s]^2 x [0, s] turned from
    z to n about the origin, then moved to point."""
    box = np.reshape(occ.getBoundingBox(3, body), (2, 3))
    corners = np.array([[box[i, 0], box[j, 1], box[k, 2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    diagonal = float(np.linalg.norm(box[1] - box[0]))
    tools = []
    for normal, point in cuts:
        n, p = np.asarray(normal, dtype=np.float64), np.asarray(point, dtype=np.float64)
        n = n / np.linalg.norm(n)
        side = (corners - p) @ n
        if not (side.min() < -1e-9 * diagonal and side.max() > 1e-9 * diagonal):
            continue
        reach = 2 * (diagonal + float(np.linalg.norm(p - box.mean(axis=0))))
        tag = occ.addBox(-reach, -reach, 0.0, 2 * reach, 2 * reach, reach)
        axis, angle = np.cross([0.0, 0.0, 1.0], n), float(np.arccos(np.clip(n[2], -1.0, 1.0)))
        if np.linalg.norm(axis) < 1e-12:
            axis = np.array([1.0, 0.0, 0.0])  # n = +-z: no turn, or half a turn about x
        if angle:
            occ.rotate([(3, tag)], 0.0, 0.0, 0.0, *axis, angle)
        occ.translate([(3, tag)], *p)
        tools.append(tag)
    return tools


def _faces(gmsh, volumes, combined: bool = True) -> set[int]:
    """The surface tags bounding the volumes: of their union (combined), or of each one."""
    if not volumes:
        return set()
    return {abs(t) for _, t in gmsh.model.getBoundary([(3, v) for v in volumes], combined=combined, oriented=False)}


def estimate_tets(solid: Solid, sizes: MeshSizes) -> float:
    """The estimated tetrahedron count of mesh_solid(solid, sizes) (module docstring), from the solid's
    geometry alone: gmsh builds it (or the cache has its measures), nothing is meshed."""
    entry = cache_key("measures", solid)
    cached = cache.load("gmsh-measures", entry, valid_measures, 4096)
    if cached is not None:
        volume, wall_area = map(float, cached["measures"])
        return estimate_from_measures(volume, wall_area, sizes)
    with session() as gmsh:
        pieces = _Pieces(gmsh, solid)
    cache.store("gmsh-measures", entry, {"measures": np.array([pieces.volume, pieces.wall_area])})
    return estimate_from_measures(pieces.volume, pieces.wall_area, sizes)


def estimate_from_measures(volume: float, wall_area: float, sizes: MeshSizes) -> float:
    """The tetrahedra of a rubber volume whose chamber walls have this area, at these sizes (module docstring)."""
    area = min(wall_area, volume / sizes.shell) if sizes.shell else 0.0
    bulk = volume - area * sizes.shell
    return (bulk / sizes.size**3 + area * sizes.shell_density()) / REGULAR_TET


def _check_estimate(volume: float, wall_area: float, sizes: MeshSizes, max_tets: int) -> None:
    estimate = estimate_from_measures(volume, wall_area, sizes)
    require(
        estimate <= max_tets,
        f"the mesh would have about {estimate:.3g} tetrahedra (volume {volume:.4g}, size {sizes.size:g}, "
        f"near chambers {sizes.near:g}); the limit is {max_tets} tetrahedra (--max-triangles raises it)",
    )


def _check_count(tets: int, max_tets: int) -> None:
    require(tets <= max_tets, f"the mesh has {tets} tetrahedra; the limit is {max_tets} (--max-triangles raises it)")


def mesh_solid(
    solid: Solid,
    sizes: MeshSizes,
    max_tets: int = MAX_TETS,
    verbose: bool = False,
    surface_meshers: tuple = SURFACE_MESHERS,
) -> SolidMesh:
    """Mesh the solid with linear tetrahedra (gmsh: OpenCASCADE fragment, Delaunay), or raise one
    PneumaInputError: bad geometry, an estimate or a mesh over max_tets (--max-triangles raises it), or
    gmsh failing (its error line quoted). surface_meshers: the (Mesh.Algorithm, Mesh.MeshSizeFromCurvature)
    pairs tried in turn (a study that must keep one mesh pins one). A mesh in the cache (module docstring) is
    returned without running gmsh."""
    entry = cache_key("mesh", solid, sizes, tuple(tuple(pair) for pair in surface_meshers))
    cached = cache.load(
        "gmsh-mesh",
        entry,
        lambda arrays: valid_mesh(arrays, len(solid.chambers), len(solid.regions)),
        CACHE_BYTES_PER_TET * max(max_tets, 1) + 2**20,
    )
    if cached is not None:
        volume, wall_area = map(float, cached["measures"])
        _check_estimate(volume, wall_area, sizes, max_tets)
        _check_count(len(cached["tets"]), max_tets)
        return SolidMesh(
            cached["vertices"],
            cached["tets"],
            {name: cached[f"chamber{i}"] for i, (name, _) in enumerate(solid.chambers)},
            cached["boundary"],
            cached["regions"],
            tuple(name for name, _ in solid.regions),
            cached["curved_edges"],
            cached["curved_points"],
        )
    meshed, measures = _mesh(solid, sizes, max_tets, verbose, surface_meshers)
    cache.store(
        "gmsh-mesh",
        entry,
        {
            "vertices": meshed.vertices,
            "tets": meshed.tets,
            "boundary": meshed.boundary,
            "regions": meshed.regions,
            "measures": measures,
            "curved_edges": meshed.curved_edges,
            "curved_points": meshed.curved_points,
            **{f"chamber{i}": meshed.chambers[name] for i, (name, _) in enumerate(solid.chambers)},
        },
    )
    return meshed


def _mesh(
    solid: Solid, sizes: MeshSizes, max_tets: int, verbose: bool, surface_meshers: tuple
) -> tuple[SolidMesh, np.ndarray]:
    """gmsh's mesh of the solid, and the rubber's volume and the walls' area."""
    with session(verbose) as gmsh:
        pieces = _Pieces(gmsh, solid)
        _check_estimate(pieces.volume, pieces.wall_area, sizes, max_tets)
        model = gmsh.model
        for k, name in enumerate([BODY_GROUP] + [name for name, _ in solid.regions]):
            tags = [v for v, r in pieces.rubber.items() if r == k]
            if tags:  # a region wholly overridden by later ones has no group
                model.addPhysicalGroup(3, tags, name=name)
        for name, walls in pieces.walls.items():
            model.addPhysicalGroup(2, walls, name=name)
        set_sizes(gmsh, sizes, [s for walls in pieces.walls.values() for s in walls])
        for attempt, (algorithm, curvature) in enumerate(surface_meshers, start=1):
            gmsh.option.setNumber("Mesh.Algorithm", algorithm)
            gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", curvature)
            model.mesh.clear()
            try:
                model.mesh.generate(3)
            except Exception:
                if attempt == len(surface_meshers):
                    raise
                continue
            if _complete(gmsh, pieces):
                break
        names = tuple(name for name, _ in solid.regions)
        return read_tetrahedra(gmsh, pieces.rubber, pieces.walls, names, max_tets), np.array(
            [pieces.volume, pieces.wall_area]
        )


def _complete(gmsh, pieces: _Pieces) -> bool:
    """Whether every rubber volume has tetrahedra and every chamber wall triangles."""
    return all(len(_elements(gmsh, 3, [v], 4, 4)) for v in pieces.rubber) and all(
        len(_elements(gmsh, 2, [s], 2, 3)) for walls in pieces.walls.values() for s in walls
    )


def set_sizes(gmsh, sizes: MeshSizes, walls: list[int]) -> None:
    """Edge length `size` everywhere, `near` within `near` of the walls, growing linearly to `size` over the
    grading distance beyond (gmsh Distance and Threshold fields; the walls sampled at about near / 2)."""
    option = gmsh.option.setNumber
    option("Mesh.MeshSizeMax", sizes.size)
    for name in ("Mesh.MeshSizeFromPoints", "Mesh.MeshSizeFromCurvature", "Mesh.MeshSizeExtendFromBoundary"):
        option(name, 0)
    if sizes.near < sizes.size:
        field = gmsh.model.mesh.field
        distance = field.add("Distance")
        field.setNumbers(distance, "SurfacesList", walls)
        extent = max(np.ptp(np.reshape(gmsh.model.getBoundingBox(2, s), (2, 3)), axis=0).max() for s in walls)
        field.setNumber(distance, "Sampling", int(np.clip(2 * extent / sizes.near, 20, MAX_SAMPLING)))
        threshold = field.add("Threshold")
        field.setNumber(threshold, "InField", distance)
        for key, value in (
            ("SizeMin", sizes.near),
            ("SizeMax", sizes.size),
            ("DistMin", sizes.near),
            ("DistMax", sizes.near + sizes.grading),
        ):
            field.setNumber(threshold, key, value)
        field.setAsBackgroundMesh(threshold)


def _elements(gmsh, dim: int, entities, kind: int, corners: int) -> np.ndarray:
    """The node tags (k, corners) of the elements of gmsh type `kind` on the given entities."""
    blocks = [gmsh.model.mesh.getElementsByType(kind, tag)[1] for tag in entities]
    return np.concatenate(blocks).astype(np.int64).reshape(-1, corners) if blocks else np.zeros((0, corners), np.int64)


def read_tetrahedra(
    gmsh, rubber: dict[int, int], walls: dict[str, list[int]], region_names: tuple[str, ...], max_tets: int
) -> SolidMesh:
    """The mesh's arrays: rubber, volume tag -> region (0 the base material, k the k-th of region_names); walls,
    chamber name -> its surface tags. Nodes renumbered 0..n-1 (those of tetrahedra only), tetrahedra oriented, faces
    matched to the tetrahedra's boundary faces for their orientation."""
    blocks = {
        k: _elements(gmsh, 3, [v for v, r in rubber.items() if r == k], 4, 4) for k in range(len(region_names) + 1)
    }
    tags = np.concatenate(list(blocks.values()))
    regions = np.concatenate([np.full(len(b), k) for k, b in blocks.items()])
    require(
        all(len(b) for k, b in blocks.items() if any(r == k for r in rubber.values())),
        "gmsh left a part of the body without tetrahedra",
    )
    _check_count(len(tags), max_tets)
    position, points = node_points(gmsh)
    used, tets = np.unique(tags, return_inverse=True)
    tets = tets.reshape(-1, 4)
    vertices = points[position[used]]
    tets = positively_oriented(vertices, tets, TET_P1)
    faces = tets[:, TET_FACES].reshape(-1, 3)
    keys = face_keys(faces, len(vertices))
    unique, first, counts = np.unique(keys, return_index=True, return_counts=True)
    outer = first[counts == 1]  # faces of one tetrahedron only: the body's surface, walls included
    index = {int(k): int(i) for k, i in zip(keys[outer], outer)}
    local = np.full(len(position), -1, dtype=np.int64)
    local[used] = np.arange(len(used))
    chambers, on_wall = {}, set()
    for name, surfaces in walls.items():
        triangles = local[_elements(gmsh, 2, surfaces, 2, 3)]
        require(len(triangles) > 0, f"gmsh left the wall of chamber {name!r} without triangles")
        wall_keys = face_keys(triangles, len(vertices))
        rows = [index.get(int(k), -1) for k in wall_keys]
        require(min(rows, default=-1) >= 0, f"chamber {name!r}: its wall mesh does not match the tetrahedra's faces")
        chambers[name] = faces[rows][:, ::-1].copy()  # outward from the rubber = into the cavity: reversed
        on_wall.update(rows)
    boundary = faces[[i for i in outer if i not in on_wall]]
    return SolidMesh(
        vertices, tets, chambers, boundary, regions.astype(np.int64), region_names, *edge_targets(gmsh, local, vertices)
    )


def node_points(gmsh) -> tuple[np.ndarray, np.ndarray]:
    """gmsh's nodes: position[tag] = the row of node `tag` in points (n, 3)."""
    node_tags, coords, _ = gmsh.model.mesh.getNodes()
    position = np.empty(int(node_tags.max()) + 1, dtype=np.int64)
    position[node_tags.astype(np.int64)] = np.arange(len(node_tags))
    return position, coords.reshape(-1, 3)


def face_keys(faces: np.ndarray, n: int) -> np.ndarray:
    """One integer per triangle, the same for any order of its corners: sorted corners in base n."""
    s = np.sort(faces, axis=1).astype(np.int64)
    return (s[:, 0] * n + s[:, 1]) * n + s[:, 2]


def cavity_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """1/6 sum_faces x0 . (x1 x x2): the volume a closed surface encloses, positive when its faces are
    oriented outward from the enclosed region."""
    x = vertices[faces]
    return float(np.einsum("ij,ij->", x[:, 0], np.cross(x[:, 1], x[:, 2])) / 6)
