"""What every geometry shares, 2D shapes (planar.Geometry), 3D shapes (solid_geometry.SolidGeometry) and mesh files
(meshfile.MeshGeometry): its dimension, its element order and family, and its supports: the clamp, the tip and the
rollers (supports.py), checked together and selecting their nodes on the geometry's mesh alike.

A geometry is a frozen dataclass with the fields order, clamp, tip and rollers and a class attribute dim; Body adds
the rest as methods, so each geometry keeps its own field order (and its positional constructor).
"""

from __future__ import annotations

import numpy as np

from ..errors import require
from .elements import ElementFamily, family_for
from .shapes import MAX_SHAPES
from .supports import PointSet, Roller, node_sets


class Body:
    """The part of a geometry that its dimension, order and supports make (module docstring)."""

    dim: int
    order: int
    clamp: PointSet | None
    tip: PointSet
    rollers: tuple[Roller, ...]

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
