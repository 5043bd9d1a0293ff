"""Strain-limiting sheets: a scene's [[layers]], each a thin elastic sheet bonded to a face of the body (a
membrane on the boundary facets there, terms/membrane.py), so a sheet of 0.1 mm costs no elements of 0.1 mm.

The face is a side of the body's bounding box (fem/supports.py SIDES: left, right, bottom, top, and in 3D back
and front; the nodes within 1e-6 of that plane) or a closed box, as the clamp's; the sheet covers the facets of
the body's outer boundary (mesh.surface without the chamber walls: the facets all of whose nodes are outer
boundary nodes, mesh.boundary) all of whose nodes the face selects. A quadratic facet is split into linear pieces
through its midside nodes (a 6-node triangle into 4 triangles, ElementFamily.split; a 3-node edge into 2
segments), so the sheet follows every node.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import require, require_finite
from ..fem.mesh import Mesh
from ..fem.supports import PointSet
from ..io.units import LENGTH, PRESSURE, unit
from ..materials.isochoric import IsochoricPolynomial
from ..materials.presets import PresetMaterial
from .membrane import Membrane


def outer_facets(mesh: Mesh) -> np.ndarray:
    """The facets of the body's outer boundary: those of mesh.surface all of whose nodes are outer boundary nodes
    (so not a chamber wall's)."""
    surface = mesh.surface
    assert surface is not None  # Mesh.__post_init__ finds it
    return surface[np.isin(surface, mesh.boundary).all(axis=1)]


def linear_pieces(mesh: Mesh, facets: np.ndarray) -> np.ndarray:
    """The linear cells (triangles in 3D, segments in 2D) of facets of the mesh, a higher-order one split through
    its edge nodes as its facet family's split (ElementFamily.facet_pieces): a 6-node triangle into 4, an edge
    (c0, c1, mid) into (c0, mid) and (mid, c1)."""
    family = mesh.family
    assert family is not None  # Mesh.__post_init__ tells it
    return family.facet_pieces(facets)


@dataclass(frozen=True)
class Layer:
    """A sheet of thickness t (a length), Young's modulus E (a pressure) and Poisson's ratio nu in [0, 0.5) bonded
    to a face of the body: `side` (a side of its bounding box) or `box` ([x0, y0, x1, y1], in 3D [x0, y0, z0, x1,
    y1, z1]: the boundary facets whose nodes all lie in it); name: names it in messages. wrinkles: the sheet
    wrinkles (in 2D: goes slack) instead of carrying compression, tension-field theory's relaxed membrane (True,
    the default), or it is the plain Saint Venant-Kirchhoff membrane, which buckles (False; terms/membrane.py).

    preset: a material preset (materials/presets.py) instead of E and nu: the sheet's E and nu are the preset's
    small-strain ones, E = 2 mu0 (1 + nu) with mu0 = 2 (C10 + C01) and nu its Poisson's ratio (a given nu replaces
    it, as a region's does), converted into the scene's units as a region's preset is (in_units)."""

    name: str
    E: float | None = field(metadata=unit(PRESSURE))
    nu: float | None
    thickness: float = field(metadata=unit(LENGTH))
    side: str | None = None
    box: tuple | None = None
    wrinkles: bool = True
    preset: str | None = None

    def __post_init__(self):
        require(isinstance(self.name, str) and self.name.strip(), f"layer name = {self.name!r} must not be empty")
        if self.preset is not None:
            require(
                self.E is None, f"layer {self.name!r}: preset = {self.preset!r} gives E (and nu): drop E = {self.E!r}"
            )
            self._preset_material().resolved(1.0)  # validates the preset's name and a given nu
        else:
            require(
                self.E is not None and self.nu is not None,
                f"layer {self.name!r}: give E and nu, or a preset (E = {self.E!r}, nu = {self.nu!r})",
            )
            require(require_finite("E", self.E) > 0, f"layer {self.name!r}: E = {self.E!r} must be > 0")
        if self.nu is not None:
            nu = require_finite("nu", self.nu)
            require(0 <= nu < 0.5, f"layer {self.name!r}: nu = {self.nu!r} must be in [0, 0.5)")
        require(
            require_finite("thickness", self.thickness) > 0,
            f"layer {self.name!r}: thickness = {self.thickness!r} must be > 0",
        )
        require(
            isinstance(self.wrinkles, bool),
            f"layer {self.name!r}: wrinkles = {self.wrinkles!r} must be true or false",
        )
        _ = self.face  # validates side and box

    def _preset_material(self) -> PresetMaterial:
        assert self.preset is not None
        return PresetMaterial(self.preset, poisson_ratio=self.nu)

    def in_units(self, units) -> Layer:
        """This layer with E and nu in the scene's units (io/units.py Units): a preset's small-strain moduli from its
        parameters in those units (PresetMaterial.law_parameters, as a region's preset is resolved), the layer
        itself without a preset."""
        if self.preset is None:
            return self
        _, row = self._preset_material().law_parameters(units)
        E, nu = (
            float(f(row[None])[0]) for f in (IsochoricPolynomial.youngs_modulus, IsochoricPolynomial.poisson_ratio)
        )
        return replace(self, E=E, nu=nu, preset=None)

    @property
    def face(self) -> PointSet:
        return PointSet(self.side, self.box)

    def facets(self, mesh: Mesh) -> np.ndarray:
        """The outer boundary facets all of whose nodes the face selects (PneumaInputError naming the layer and
        its face where there is none)."""
        what = f"layer {self.name!r}"
        chosen = np.zeros(mesh.n_vertices, dtype=bool)
        chosen[self.face.select(mesh.vertices, what)] = True
        outer = outer_facets(mesh)
        facets = outer[chosen[outer].all(axis=1)]
        where = f"side = {self.side!r}" if self.side is not None else f"box = {list(self.box or ())!r}"
        require(
            len(facets) > 0,
            f"{what}: {where} selects {int(chosen.sum())} mesh node(s) but no facet of the body's outer boundary "
            f"(a facet is covered when all its nodes are selected)",
        )
        return facets

    def terms(self, config, mesh, lumped_area, budget) -> list:
        """The sheet's membrane (E and nu given: a preset's are in_units's, which Scene.build calls)."""
        require(self.preset is None, f"layer {self.name!r}: preset = {self.preset!r} needs in_units(units) first")
        assert self.E is not None and self.nu is not None  # (__post_init__: given without a preset)
        return [
            Membrane(config, linear_pieces(mesh, self.facets(mesh)), self.thickness, self.E, self.nu, self.wrinkles)
        ]
