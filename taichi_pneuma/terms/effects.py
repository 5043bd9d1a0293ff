"""Effects a scene may name, each a small spec that builds its term(s) when (and only when) it is named.

An effect is a frozen dataclass registered in EFFECTS under its name (@EFFECTS.register, io/registry.py): its
fields are the keys of its [effects.<name>] table in a scene file, read and written with the types their
annotations declare (float: any number; int, str, bool; tuple or list: an array), a field's default being the
key's, its doc and unit the field's metadata (io/registry.py key).
Its terms(config, mesh, lumped_area, budget) returns the terms it adds to the energy model, checking what they
would allocate against the budget (limits.Budget: self-contact's pairs) before allocating it;
lumped_area[i] is the integral of node i's shape function over the body (mesh.nodal_measures(): a third of
the rest area of the triangles at a linear-element vertex, a quarter of the tetrahedra's volume in 3D; mass =
density x it).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from ..errors import require, require_finite, require_positive
from ..fem.self_intersection import surface_pieces
from ..fem.supports import PointSet
from ..io.registry import Registry
from ..io.units import ACCELERATION, DENSITY, LENGTH, NODAL_STIFFNESS, PRESSURE, TIME, given, si_default, unit
from ..limits import wall_pairs
from .contact import SelfContact as SelfContactTerm
from .friction import frictional, slip_length
from .gravity import Gravity as GravityTerm
from .inertia import Inertia
from .obstacle_shapes import Plane
from .obstacles import ObstacleContact, check_friction


class Effect:
    """Base of the effect specs: a name (the key in a scene file's [effects] table) and terms().

    What the rest of the program asks of an effect without knowing it: contact, whether its terms report
    contact forces (stored per vertex and step, and counted by limits.py); ground_height, the height y of
    a ground line the output draws (npz ground_height, the video), or None; support, whether the run's
    first line lists it among the supports; holds(), the rigid motions its terms hold."""

    name: ClassVar[str] = "effect"
    contact = False
    support = False

    @property
    def ground_height(self) -> float | None:
        return None

    def terms(self, config, mesh, lumped_area, budget) -> list:
        raise NotImplementedError

    def holds(self, mesh, effects) -> list:
        """The rigid-body motions its terms hold in a scene of these effects, as support rows (nodes, d x d
        projector) (fem/supports.py): none by default."""
        return []

    def pairs(self, walls: list[int]) -> int:
        """The contact pairs its terms hold for chamber walls of these node counts (limits.py counts their memory)."""
        return 0


EFFECTS: Registry[type[Effect]] = Registry("effect")  # name -> the effect, filled by @EFFECTS.register


@EFFECTS.register
@dataclass(frozen=True)
class Gravity(Effect):
    """Body weight: density rho (mass per unit area in 2D, per unit volume in 3D) under acceleration g along -y."""

    density: float = field(metadata=unit(DENSITY))
    g: float | None = si_default(9.81, ACCELERATION)
    name = "gravity"

    def __post_init__(self):
        require_positive("density", self.density)
        require_positive("g", self.g, allow_none=True)

    def terms(self, config, mesh, lumped_area, budget) -> list:
        return [GravityTerm(config, self.density * lumped_area, given(self.g, "gravity g"))]


@EFFECTS.register
@dataclass(frozen=True)
class Ground(Effect):
    """Ground contact: a log barrier (threshold dhat, stiffness kappa) keeps the body's outer boundary above the line
    (in 3D the plane) y = height; with friction mu > 0, Coulomb friction too, smoothed over the slip friction_slip
    (None: dhat / 10) (terms/friction.py)."""

    height: float = field(metadata=unit(LENGTH))
    dhat: float | None = si_default(0.01, LENGTH, scaled=False)
    stiffness: float | None = si_default(1e3, NODAL_STIFFNESS, scaled=False)
    friction: float = 0.0
    friction_slip: float | None = field(default=None, metadata=unit(LENGTH))
    name = "ground"
    contact = True
    support = True

    @property
    def ground_height(self) -> float:
        return self.height

    def __post_init__(self):
        require_finite("height", self.height)
        require_positive("dhat", self.dhat, allow_none=True)
        require_positive("stiffness", self.stiffness, allow_none=True)
        check_friction(self.friction, self.friction_slip)

    def holds(self, mesh, effects) -> list:
        """A one-sided contact holds a body only where a load presses it on: with gravity, the normal (y)
        displacement of the nodes of the body's bottom (where it comes to rest on a level ground; so the
        vertical translation and the tilts, not whether the body would topple), and with friction their motion
        along the ground too (static friction); without gravity, nothing."""
        if not any(effect.name == Gravity.name for effect in effects):
            return []
        held = np.eye(mesh.dim) if self.friction > 0 else np.diag(np.eye(mesh.dim)[1])
        return [(PointSet("bottom").select(mesh.vertices, "ground"), held)]

    def terms(self, config, mesh, lumped_area, budget) -> list:
        lowest = float(mesh.vertices[mesh.boundary, 1].min())
        require(
            lowest > self.height, f"ground height = {self.height!r} must lie below the body (lowest point {lowest:.6g})"
        )
        ground = Plane((0.0, self.height, 0.0), (0.0, 1.0, 0.0))  # the body on its +y side
        dhat, stiffness = given(self.dhat, "ground dhat"), given(self.stiffness, "ground stiffness")
        contact = ObstacleContact(config, mesh.boundary, ground, "ground", dhat, stiffness)
        return frictional(contact, self.friction, self.friction_slip)


@EFFECTS.register
@dataclass(frozen=True)
class SelfContact(Effect):
    """Self-contact of chamber walls: point-edge log barriers (threshold dhat, stiffness kappa) on every wall."""

    dhat: float | None = si_default(0.005, LENGTH, scaled=False)
    stiffness: float | None = si_default(1e4, NODAL_STIFFNESS, scaled=False)
    name = "self_contact"
    contact = True

    def __post_init__(self):
        require_positive("dhat", self.dhat, allow_none=True)
        require_positive("stiffness", self.stiffness, allow_none=True)

    def terms(self, config, mesh, lumped_area, budget) -> list:
        require(
            mesh.dim == 2,
            "self_contact is 2D only: a 3D scene cannot have [effects.self_contact] (the contact of "
            "a collapsing 3D chamber's walls is not modelled)",
        )
        require(
            all(origin is None for origin in mesh.wall_origins),
            "self_contact: a chamber cut by a symmetry line is not supported (its wall would meet its mirror image)",
        )
        walls = list(mesh.chambers)
        budget.check_pairs(self.pairs([len(wall) for wall in walls]), "self-contact")  # before allocating them
        return [SelfContactTerm(config, walls, given(self.dhat, "dhat"), given(self.stiffness, "stiffness"))]

    def pairs(self, walls: list[int]) -> int:
        return wall_pairs(walls)


@EFFECTS.register
@dataclass(frozen=True)
class SurfaceContact(Effect):
    """Contact of the body's whole surface with itself, 2D and 3D (terms/surface_contact.py): IPC barriers of
    threshold dhat (default: DHAT_FRACTION of the body's bounding-box diagonal) and stiffness kappa (a pressure)
    between any two pieces of the surface that share no node: chamber walls against each other and themselves, the
    outer surface against itself; with friction mu > 0, Coulomb friction between them too, smoothed over the slip
    friction_slip (None: dhat / 10)."""

    dhat: float | None = field(default=None, metadata=unit(LENGTH))
    stiffness: float | None = si_default(1e5, PRESSURE)
    friction: float = 0.0
    friction_slip: float | None = field(default=None, metadata=unit(LENGTH))
    name = "surface_contact"
    contact = True

    DHAT_FRACTION = 1e-3

    def __post_init__(self):
        require_positive("dhat", self.dhat, allow_none=True)
        require_positive("stiffness", self.stiffness, allow_none=True)
        check_friction(self.friction, self.friction_slip)

    def terms(self, config, mesh, lumped_area, budget) -> list:
        from .surface_contact import SurfaceContact as SurfaceContactTerm  # ipctk: imported where it is used
        from .surface_contact import SurfaceFriction

        dhat = self.dhat or self.DHAT_FRACTION * float(np.linalg.norm(np.ptp(mesh.vertices, axis=0)))
        term = SurfaceContactTerm(config, surface_pieces(mesh), dhat, given(self.stiffness, "stiffness"))
        nearest = term.min_distance()
        require(
            nearest == np.inf,
            f"surface_contact: dhat = {dhat:.4g} must be less than the smallest distance at rest between two pieces "
            f"of the body's surface that share no node ({nearest:.4g}): give a smaller dhat",
        )
        if self.friction == 0:
            return [term]
        return [term, SurfaceFriction(term, self.friction, slip_length(self.friction_slip, dhat))]


@EFFECTS.register
@dataclass(frozen=True)
class Dynamics(Effect):
    """Motion instead of quasistatics: inertia of the lumped masses (density rho), backward Euler with
    time step dt, one time step per schedule increment."""

    density: float = field(metadata=unit(DENSITY))
    dt: float = field(metadata=unit(TIME))
    name = "dynamics"

    def __post_init__(self):
        require_positive("density", self.density)
        require_positive("dt", self.dt)

    def holds(self, mesh, effects) -> list:
        """Inertia holds every motion (its Hessian, the lumped masses / dt^2, is positive definite): a free body
        moves."""
        return [(np.arange(mesh.n_vertices), np.eye(mesh.dim))]

    def terms(self, config, mesh, lumped_area, budget) -> list:
        require(
            mesh.order == 1,
            "dynamics needs linear triangles (order = 1): the quadratic triangle's "
            "row-sum lumped mass vanishes at its corners",
        )
        return [Inertia(config, self.density * lumped_area, self.dt)]
