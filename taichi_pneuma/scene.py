"""The reference scene as data, validated, and its builder: a scene -> an EnergyModel of exactly its terms."""

from __future__ import annotations

import math
from dataclasses import dataclass, field


from . import runtime
from .errors import require, require_finite
from .geometry import BeamGeometry, Mesh, signed_area
from .model import EnergyModel
from .terms import AreaChamber, Clamp, NeoHookean
from .terms.elastic import lame_parameters


@dataclass(frozen=True)
class Material:
    """Isotropic stable neo-Hookean material: Young's modulus E > 0, Poisson's ratio -1 < nu < 0.5."""

    youngs_modulus: float = 1e4
    poisson_ratio: float = 0.45

    def __post_init__(self):
        e = require_finite("E", self.youngs_modulus)
        nu = require_finite("nu", self.poisson_ratio)
        require(e > 0, f"E = {self.youngs_modulus!r} must be > 0")
        require(-1 < nu < 0.5, f"nu = {self.poisson_ratio!r} must lie in (-1, 0.5)")


@dataclass(frozen=True)
class BeamScene:
    """A clamped beam with one area-controlled chamber (SPEC.md's reference scene by default)."""

    geometry: BeamGeometry = field(default_factory=BeamGeometry)
    material: Material = field(default_factory=Material)
    chamber_stiffness: float = 1e5
    clamp_stiffness: float = 1e9

    def __post_init__(self):
        for name, value in (("k", self.chamber_stiffness), ("K_pin", self.clamp_stiffness)):
            require_finite(name, value)
            require(value > 0, f"{name} = {value!r} must be > 0")

    def build(self) -> "BuiltScene":
        """Mesh the geometry and instantiate exactly the terms this scene names."""
        runtime.ensure_initialised()
        mesh = self.geometry.mesh()
        rest_area = signed_area(mesh.vertices[mesh.chamber_loop])
        # Round-off scales, from the stiffest modulus (lam grows without bound as nu -> 1/2):
        # forces below 1e-6 (mu + lam) sqrt(body area), energies below 1e-12 (mu + lam) (body area).
        modulus = sum(lame_parameters(self.material.youngs_modulus, self.material.poisson_ratio))
        model = EnergyModel(mesh.vertices, force_floor=1e-6 * modulus * math.sqrt(mesh.area),
                            energy_resolution=1e-12 * modulus * mesh.area)
        config = model.config
        elastic = model.add(NeoHookean(config, mesh.triangles, self.material.youngs_modulus, self.material.poisson_ratio))
        chamber = model.add(AreaChamber(config, mesh.chamber_loop, self.chamber_stiffness, rest_area))
        model.add(Clamp(config, mesh.pinned, self.clamp_stiffness))
        return BuiltScene(self, mesh, model, elastic, chamber, rest_area)


@dataclass
class BuiltScene:
    scene: BeamScene
    mesh: Mesh
    model: EnergyModel
    elastic: NeoHookean
    chamber: AreaChamber
    rest_area: float
