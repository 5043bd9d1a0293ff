"""The mesh a scene is solved on, 2D or 3D: node positions, the element table, its element family
(fem.elements: the family answers every per-element question) and the node sets a pneumatic scene needs.

Planar meshes come from planar.Geometry (Triangle), tetrahedral ones from tetmesh.tet_mesh (gmsh, mesh files,
structured layers). Both are this one type; what differs is data: a 2D chamber wall is a loop of nodes, a 3D one a
set of facets, and only a 3D source has named volume groups.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .elements import ElementFamily, boundary_facets, family_of


@dataclass(frozen=True)
class Mesh:
    """A mesh with the node sets a pneumatic scene needs.

    vertices: (n, d) rest positions (the nodes); elements: (m, k) node indices of elements of `family`
    (corners, then midside nodes in the family's order) of positive measure (counter-clockwise triangles,
    tetrahedra of positive volume); chambers: per chamber (in the scene's order) its wall: in 2D the wall's
    nodes (quadratic: corner, midside, corner, ...), a closed loop, or for a chamber cut by symmetry lines an open
    chain from line to line, oriented so its enclosed area (polygons.enclosed_area with wall_origins) is
    positive; in 3D its facets (f, 3 or 6) oriented outward from the cavity; wall_origins: per chamber None (a
    closed wall) or what closes an open one (2D: the origin o of its area, on the lines; 3D: a tetmesh.Closure);
    boundary: the nodes on the body's outer boundary (not on a chamber wall alone); pinned: the clamped nodes
    (none without a clamp); tip: the tip's nodes (the right side by default); rollers: per roller, (its held
    nodes, its unit normal); family: the elements' family (None: told by the table's node count, family_of);
    surface: every boundary facet of the body oriented outward (None: found from the elements); regions: a
    region tag per element (None: 0 for all); region_groups: named regions' tags (name -> tag, e.g. a mesh
    file's physical groups of tetrahedra, a PneuNet's "layer").
    """

    vertices: np.ndarray
    elements: np.ndarray
    chambers: tuple[np.ndarray, ...]
    boundary: np.ndarray
    pinned: np.ndarray
    tip: np.ndarray
    wall_origins: tuple
    rollers: tuple[tuple[np.ndarray, np.ndarray], ...]
    family: ElementFamily | None = None
    surface: np.ndarray | None = None
    regions: np.ndarray | None = None
    region_groups: dict = field(default_factory=dict)

    def __post_init__(self):
        if self.family is None:
            object.__setattr__(self, "family", family_of(self.elements, self.vertices.shape[1]))
        if self.surface is None:
            object.__setattr__(self, "surface", boundary_facets(self.family, self.elements))
        if self.regions is None:
            object.__setattr__(self, "regions", np.zeros(len(self.elements), dtype=np.int64))

    @property
    def _family(self) -> ElementFamily:
        """family, which __post_init__ told where it was not given."""
        assert self.family is not None
        return self.family

    @property
    def dim(self) -> int:
        return self._family.dim

    @property
    def order(self) -> int:
        """1 for linear elements, 2 for quadratic ones."""
        return self._family.order

    @property
    def n_vertices(self) -> int:
        return len(self.vertices)

    @property
    def n_elements(self) -> int:
        return len(self.elements)

    @cached_property
    def fields(self):
        """The mesh's per-element fields (fields.ElementFields: det F, the largest stretch, stress at any positions),
        made once: their quadrature over the rest elements is shared by everything that reads the mesh's fields."""
        from .fields import ElementFields  # NumPy and Taichi's laws: a mesh alone does not load them

        return ElementFields(self.vertices, self.elements)

    triangles = property(lambda self: self.elements, doc="a 2D mesh's elements, its triangles")
    n_triangles = n_elements

    @property
    def measure(self) -> float:
        """The body's rest measure, its area in 2D, its volume in 3D (curved elements' included: nodal_measures)."""
        return float(np.sum(self.nodal_measures()))

    area = volume = measure

    def nodal_measures(self) -> np.ndarray:
        """The integral of each node's shape function over the body, sum_e int_e N_a det(dX/dxi) dxi, by the rule
        of the family's measure_degree: exact on straight elements (a third of the adjacent area at a linear
        triangle's corners, a quarter of the adjacent volume at a linear tetrahedron's; 0 at a quadratic
        triangle's corners and a third of its area at its midside nodes; -1/20 and 1/5 of the volume at a
        quadratic tetrahedron's), and on a quadratic triangle with curved (parabolic) sides: the consistent nodal
        weights of a uniform load, exact for a load linear in x."""
        family = self._family
        rule = family.cell.rule(family.measure_degree)
        _, weights = family.quadrature(self.vertices, self.elements, rule)
        out = np.zeros(self.n_vertices)
        np.add.at(out, self.elements, weights @ family.shape_functions(rule[0]))
        return out

    nodal_areas = nodal_measures

    def display_triangles(self) -> np.ndarray:
        """Linear triangles to draw: a 2D mesh's elements, a 3D one's surface facets, each split as its family's
        split says (a quadratic triangle in four at its midside nodes: corner triangles, then the middle one)."""
        assert self.surface is not None  # __post_init__ found it where it was not given
        return self._family.drawn(self.elements, self.surface)


def triangle_areas(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """The signed areas (m,) of the triangles' corner triples: positive where counter-clockwise."""
    p0, p1, p2 = (vertices[triangles[:, i]] for i in range(3))
    e1, e2 = p1 - p0, p2 - p0
    return 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
