"""A material region of a scene: the material of the elements in a box, or of a mesh's named volume group."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import require
from ..fem.mesh import Mesh
from ..fem.supports import in_box, require_box
from ..materials import MaterialForm


@dataclass(frozen=True)
class Region:
    """A material for the elements whose centroid lies in box [x0, y0, x1, y1] ([x0, y0, z0, x1, y1, z1] in 3D),
    or (3D) for the tetrahedra of a named volume group of the mesh (a mesh file's physical group, a PneuNet's
    "layer"); later regions win."""

    box: tuple[float, float, float, float] | None
    material: MaterialForm
    group: str | None = None

    def __post_init__(self):
        require((self.box is None) != (self.group is None), "give exactly one of 'box' and 'group'")
        if self.box is not None:
            require_box("box", self.box)
        else:
            require(isinstance(self.group, str) and self.group != "", f"group = {self.group!r} must name a group")

    def contains(self, mesh: Mesh) -> np.ndarray:
        """Which of the mesh's elements the region takes (a group the mesh lacks is refused, naming its groups)."""
        if self.box is not None:
            return in_box(mesh.vertices[mesh.elements].mean(axis=1), self.box, "material region")
        groups = getattr(mesh, "region_groups", {})
        require(
            self.group in groups,
            f"material region group = {self.group!r}: the mesh has no such volume group "
            f"(its groups: {', '.join(groups) or 'none'})",
        )
        return mesh.regions == groups[self.group]
