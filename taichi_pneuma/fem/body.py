"""The one protocol of a scene's geometry, whatever it is made from: 2D shapes (planar.Geometry), 3D shapes
(solid_geometry.SolidGeometry), mesh files (meshfile.MeshGeometry) and the CAD files to come. A Body is

    dim                 its dimension (2: plane strain triangles, 3: tetrahedra), a class attribute
    order               its element order, and so its family (the Lagrange family of that order on the dim-simplex)
    chambers            (name, shape) per chamber, in the order the scene's controls follow
    clamp, tip, rollers its supports (supports.py), checked together and selecting their nodes alike (node_sets)
    mesh(budget)        the Mesh, made under the budget's element cap (limits.Budget) or refused
    size_estimate()     a SizeEstimate, before meshing: the resource limits are checked on it (fem/sizing.py)
    mesh_values()       its [mesh] table's values, as a scene file writes them

A geometry is a frozen dataclass with the fields order, chambers, clamp, tip and rollers and a class attribute dim;
Body adds the rest as methods, so each geometry keeps its own field order (and its positional constructor), and
declares mesh, size_estimate and mesh_values as abstract: a new kind of geometry is one class that gives them.
"""

from __future__ import annotations

import abc
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ..errors import require
from ..limits import Budget
from .elements import ElementFamily, family_for
from .mesh import Mesh
from .shapes import MAX_SHAPES
from .supports import PointSet, Roller, node_sets


@dataclass(frozen=True)
class SizeEstimate:
    """A body's mesh, estimated before meshing: elements of its family, nodes, the node count of each chamber wall
    (a 2D wall's self-contact pairs are counted from it; a 3D body has none) and what the estimate rests on (words
    for the refusal, e.g. "meshed area 0.3 / max_area 0.001, 132 outline points"; "" where nothing is to be said)."""

    elements: float
    nodes: float
    walls: tuple[int, ...] = ()
    basis: str = ""


class Body(metaclass=abc.ABCMeta):
    """A scene's geometry (module docstring)."""

    dim: ClassVar[int]
    order: int
    chambers: tuple[tuple[str, Any], ...]
    clamp: PointSet | None
    tip: PointSet
    rollers: tuple[Roller, ...]

    @abc.abstractmethod
    def mesh(self, budget: Budget = Budget()) -> Mesh:
        """The body's mesh with its chambers' walls and node sets, within the budget (or refused)."""

    @abc.abstractmethod
    def size_estimate(self) -> SizeEstimate:
        """The mesh mesh() would make, estimated without making it."""

    def check_facets(self, budget: Budget) -> None:
        """Refuse surface files whose triangles, as read, pass the budget before meshing reads them further
        (limits.Budget.check_facets; a surface body's, fem/surface_import.py: no other body has any)."""
        return None

    @abc.abstractmethod
    def mesh_values(self) -> dict:
        """Its [mesh] table's values by key (None: not written), as a scene file gives them."""

    @property
    def chamber_names(self) -> list[str]:
        return [name for name, _ in self.chambers]

    @property
    def family(self) -> ElementFamily:
        """The element family its mesh is made of: the Lagrange family of its order on the dim-simplex."""
        return family_for(self.dim, self.order)

    def check_supports(self) -> None:
        """Refuse more than MAX_SHAPES rollers, and a roller whose normal has not dim components."""
        require(len(self.rollers) <= MAX_SHAPES, f"{len(self.rollers)} rollers: at most {MAX_SHAPES} are allowed")
        for roller in self.rollers:
            require(
                len(roller.normal) == self.dim,
                f"roller normal = {list(roller.normal)!r}: a {self.dim}D body's rollers have {self.dim} components",
            )

    def node_sets(self, vertices: np.ndarray) -> tuple:
        """(pinned, tip, rollers) on a mesh of these vertices: supports.node_sets of its clamp, tip and rollers."""
        return node_sets(self.clamp, self.tip, self.rollers, vertices)
