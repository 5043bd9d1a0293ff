"""A 3D scene's geometry from parametric shapes: the body (a fem.solids shape or a fem.pneunet.PneuNet), its
chambers, the mesh sizes, the element order and the node sets, meshed by gmsh into a tetrahedral Mesh.

    SolidGeometry(body, chambers, sizes, order, clamp, tip, rollers)

A body shape's chambers are fem.solids shapes (ellipsoid, box, rounded box, cylinder, an extruded 2D
chamber shape), cut out of it. A PneuNet makes its own chambers c1 .. cn and its volume group "layer";
a scene names the chambers it drives by those groups (fem.meshfile.MeshSurface, as for a mesh file's
groups), and a generated chamber it does not name stays an empty, unloaded cavity.

mesh() runs gmsh_mesher.mesh_solid (linear tetrahedra) and hands its arrays to tetmesh.tet_mesh, which
orients each chamber wall out of the cavity and, for order 2, adds a midside node to every edge: with `curved`
(the default) those of the edges on the shapes' curved surfaces on the surfaces, where that folds no element
(curving.py), so that a quadratic element follows a round wall; without it every one at its edge's middle (a
round wall is then the polyhedron of gmsh's flat triangles). Every roller plane (a roller with a point) that passes
through the body splits it for gmsh (gmsh_mesher.Solid's cuts), so that the mesh carries nodes on it for the roller
to hold: a symmetry plane through a full section, not only a face of a half model. The tetrahedra's region tags are
the volume groups' (region_groups: name -> tag).

size_estimate() is the resource guard's count, before meshing: the tetrahedra estimated from the rubber's
volume over the volume of a regular tetrahedron of the local edge length (gmsh_mesher.estimate_tets; gmsh
builds the solid, nothing is meshed), and about one node per TETS_PER_NODE tetrahedra (a Delaunay mesh
has 5 to 6), plus one per edge (about 1.2 per tetrahedron) for quadratic elements. A PneuNet's walls (0.08
by default) are thinner than its usual edge lengths, and gmsh meshes them with edges about their thickness,
2.5 to 13 times the count of the size alone; counting the rubber within `size` of the chambers at edges of
THIN_WALL times the thinnest wall brings the estimate to 0.97-1.71 times gmsh's count at sizes 0.1-0.5 (the
old shipped pneunet_3d, linear at 0.2: 1.24), erring towards refusing; graded finer near the chambers, GRADED_THIN_WALL
times that (the shipped pneunet_3d, 0.12 near its chambers: 1.0). Meshing then runs
under the budget's element_cap (mesh(budget), limits.Budget), gmsh's output is checked against it (a quadratic
tetrahedron counted 8 times, its family's weight, as sizing.check_mesh_size counts it), and the budget's check_mesh
refuses a mesh past it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field, replace
from functools import cached_property

from ..errors import require, require_distinct
from ..io.output import check_heading
from ..limits import Budget
from .body import Body, SizeEstimate
from .gmsh_mesher import MAX_TETS, MeshSizes, Solid, estimate_tets, mesh_solid
from .mesh import Mesh
from .meshfile import MeshSurface
from .pneunet import PneuNet
from .supports import PointSet
from .tetmesh import check_order, tet_mesh
from .wall_thickness import thinnest_wall

TETS_PER_NODE = 5
EDGES_PER_TET = 1.2  # a tetrahedral mesh has about 1.2 edges per tetrahedron (Euler: E ~ V + T)
THIN_WALL = 1.5  # a PneuNet's walls counted at edges of THIN_WALL times their thickness (estimate_sizes)
# ... and a PneuNet meshed finer near its chambers (near_chambers < size) counted GRADED_THIN_WALL times: gmsh grades
# its 0.08 walls denser than the size field asks, 1.2-1.8 times the estimate at sizes 0.2-0.3, near 0.08-0.12
GRADED_THIN_WALL = 1.8


def is_solid_shape(shape) -> bool:
    """Whether shape is a 3D body or chamber shape (fem.solids) or a generated body (PneuNet)."""
    return isinstance(shape, PneuNet) or callable(getattr(shape, "build", None))


@dataclass(frozen=True)
class SolidGeometry(Body):
    """A 3D body from shapes (module docstring): body, chambers (name, shape) in order, mesh sizes, element
    order (1: linear tetrahedra, 2: quadratic), clamp, tip and rollers (as planar.Geometry's), and whether quadratic
    tetrahedra follow the curved surfaces (curved)."""

    body: object
    chambers: tuple
    sizes: MeshSizes
    order: int = 1
    clamp: PointSet | None = None
    tip: PointSet = field(default_factory=lambda: PointSet("right"))
    rollers: tuple = ()
    curved: bool = True

    dim = 3

    def __post_init__(self):
        check_order(self.order)
        self.check_supports()
        require(is_solid_shape(self.body), f"body: {self.body!r} is not a 3D shape")
        generated = isinstance(self.body, PneuNet)
        groups = self.groups()
        for name, shape in self.chambers:
            check_heading("chamber name", name)
            if generated:
                require(
                    isinstance(shape, MeshSurface),
                    f"chamber {name!r}: a pneunet body makes its own chambers c1 .. c{self.body.chambers}; name "
                    f'one by shape = "mesh_surface" and group = "c1" ...',
                )
                require(
                    shape.group in groups,
                    f"chamber {name!r}: group = {shape.group!r} is none of the pneunet's chambers {', '.join(groups)}",
                )
            else:
                require(
                    is_solid_shape(shape) and not isinstance(shape, PneuNet),
                    f"chamber {name!r}: a 3D body's chambers are 3D shapes (ellipsoid, box, rounded_box, "
                    f"cylinder, extrusion of a 2D chamber shape), not {type(shape).__name__}",
                )
        require_distinct("chamber names", [name for name, _ in self.chambers])
        if generated:
            require_distinct("chamber groups", [shape.group for _, shape in self.chambers])
        self.solid()  # validates the shapes together (names, counts)

    def groups(self) -> list[str]:
        """The generated chambers' names (a PneuNet's c1 .. cn)."""
        return [name for name, _ in self.body.solid().chambers] if isinstance(self.body, PneuNet) else []

    def solid(self) -> Solid:
        """The gmsh_mesher.Solid: a PneuNet's own, or the body with the scene's chambers."""
        if isinstance(self.body, PneuNet):
            return self.body.solid()
        return Solid(self.body, tuple(self.chambers))

    @cached_property
    def wall(self) -> float:
        """The thinnest rubber around the chambers (wall_thickness.thinnest_wall)."""
        return thinnest_wall(self.solid())

    @cached_property
    def mesh_sizes(self) -> MeshSizes:
        """The sizes gmsh meshes at: the scene's, with mesh.through_wall made an edge length near the chambers (the
        thinnest wall over it)."""
        return self.sizes if self.sizes.through_wall is None else self.sizes.for_wall(self.wall)

    def estimate_sizes(self) -> MeshSizes:
        """The sizes the count is estimated at: mesh_sizes, but for a PneuNet whose walls (its thinnest rubber, t)
        are thinner than its edge length, edges of THIN_WALL t counted within `size` of the chambers: gmsh
        meshes a thin wall with edges about its thickness (module docstring)."""
        sizes = self.mesh_sizes
        near = THIN_WALL * self.body.thinnest if isinstance(self.body, PneuNet) else sizes.near
        if near >= sizes.near:
            return sizes
        return MeshSizes(sizes.size, near, sizes.size)

    def size_estimate(self) -> SizeEstimate:
        """Tetrahedra and nodes estimated before meshing (module docstring)."""
        graded = isinstance(self.body, PneuNet) and self.mesh_sizes.near < self.sizes.size
        tets = int(round(estimate_tets(self.solid(), self.estimate_sizes()) * (GRADED_THIN_WALL if graded else 1)))
        nodes = tets / TETS_PER_NODE + (EDGES_PER_TET * tets if self.family.edges else 0)
        return SizeEstimate(tets, int(round(nodes)))

    def mesh_values(self) -> dict:
        """order, the mesh sizes (MeshSizes' fields) and curved."""
        return {"order": self.order, **dataclasses.asdict(self.sizes), "curved": self.curved}

    def mesh(self, budget: Budget = Budget()) -> Mesh:
        """Mesh with gmsh under the budget and build the Mesh (module docstring)."""
        weight = self.family.weight
        cap = budget.element_cap(weight)
        cuts = tuple((roller.normal, roller.point) for roller in self.rollers if roller.point is not None)
        meshed = mesh_solid(replace(self.solid(), cuts=cuts), self.mesh_sizes, MAX_TETS if cap is None else cap)
        budget.check_mesh(len(meshed.tets), weight, "gmsh")
        walls = {
            name: meshed.chambers[shape.group if isinstance(shape, MeshSurface) else name]
            for name, shape in self.chambers
        }
        groups = {name: k for k, name in enumerate(meshed.region_names, start=1)}
        return tet_mesh(
            meshed.vertices,
            meshed.tets,
            walls,
            regions=meshed.regions,
            order=self.order,
            clamp=self.clamp,
            tip=self.tip,
            rollers=self.rollers,
            region_groups=groups,
            curved=(meshed.curved_edges, meshed.curved_points) if self.curved else None,
        )
