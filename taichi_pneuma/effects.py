"""Effects a scene may name, each a small spec that builds its term(s) when (and only when) it is named.

An effect's terms(config, mesh, lumped_area) returns the terms it adds to the energy model;
lumped_area[i] is a third of the rest area of the triangles at vertex i (mass = density x it).
"""

from __future__ import annotations

from dataclasses import dataclass

from .errors import require, require_finite
from .terms.gravity import Gravity as GravityTerm


class Effect:
    """Base of the effect specs: a name (the key in a scene file's [effects] table) and terms()."""

    name = "effect"

    def terms(self, config, mesh, lumped_area) -> list:
        raise NotImplementedError


def _positive(name: str, value: float) -> None:
    require(require_finite(name, value) > 0, f"{name} = {value!r} must be > 0")


@dataclass(frozen=True)
class Gravity(Effect):
    """Body weight: density rho (mass per unit area) under acceleration g along -y."""

    density: float
    g: float = 9.81
    name = "gravity"

    def __post_init__(self):
        _positive("density", self.density)
        _positive("g", self.g)

    def terms(self, config, mesh, lumped_area) -> list:
        return [GravityTerm(config, self.density * lumped_area, self.g)]


EFFECTS = {cls.name: cls for cls in (Gravity,)}
