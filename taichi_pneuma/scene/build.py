"""A scene as data, validated, and its builder: a scene -> an EnergyModel of exactly the terms it names.

A scene is a body with chambers (fem/body.py's Body: 2D shapes, 3D shapes or a mesh file; also the clamped
nodes, the rollers and the tip),
a material (optionally one per region), a schedule of chamber commands, and a tuple of effects. The
builder refuses supports that leave a rigid-body motion free (fem/supports.py), then adds elasticity, one
chamber term per chamber (of the chamber's kind), the clamp (when there is one: no [clamp], no clamp), and a
roller term per roller of the geometry (both of stiffness clamp_stiffness); each effect
the scene names adds its own term(s), and an effect it does not name adds nothing: no field is
allocated and no kernel compiled or launched for it. Each rigid obstacle (terms/obstacles.py Obstacle) adds its
contact term last; a moving one's translation rides in the commands vector after the chambers' (Schedule.commands).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .. import runtime
from ..errors import require, require_finite
from ..fem.body import Body
from ..fem.mesh import Mesh
from ..fem.planar import BeamGeometry
from ..fem.self_intersection import surface_crossing, surface_pieces
from ..fem.supports import require_held
from ..io.keys import dotted
from ..io.output import check_stem
from ..io.tomltext import dumps
from ..io.units import NODAL_STIFFNESS, UNITLESS, Units, defaults, given, resolved, si_default
from ..limits import Budget
from ..materials import Law, Material, MaterialForm, PresetMaterial
from ..terms import VOLUMETRIC, Clamp, Elasticity, NormalClamp
from ..terms.base import Term
from ..terms.chambers import Chamber
from ..terms.effects import Effect
from ..terms.model import EnergyModel
from ..terms.nodal_volume import grouping_for, require_volumetric
from .dotted_edits import edited
from .region import Region
from .scene_keys import CLAMP_STIFFNESS, REPLACED, SCENE, scene_arguments
from .schedule import MAX_STRETCH, ChamberControl, Schedule, area_ramp


@dataclass(frozen=True)
class Scene:
    """A whole scene. controls: one ChamberControl per chamber of geometry, in the same order; units: the
    system its numbers are in (io/units.py; unitless by default), into which presets are converted; max_stretch: the
    largest principal stretch a run may reach before it warns that it has left the material model's range
    (MAX_STRETCH by default); volumetric: where the law's volumetric part U(J) is evaluated, "element" (at each
    quadrature point), "nodal" (on the nodes' patch volume ratios, for linear elements and the isochoric laws:
    they then do not lock as nu -> 1/2; terms/nodal_volume.py) or "mixed" (on each element's volume ratio, one
    pressure per element: the P2/P0 element, for quadratic elements and the isochoric laws); fibers: embedded
    tension-only cords (terms/fibers.py Fiber), each adding its term after the effects'.

    A parameter with a unit left None in it or in its parts (units.si_default: a chamber kind's atmosphere, the
    material's E, gravity's g, the clamp stiffness, ...) is set on construction to its SI default converted into
    the scene's units (resolve_defaults); a numerical default for unitless scenes (an area penalty's stiffness,
    a contact's dhat, a 2D geometry's max_area) left None in a scene with units is refused, naming its
    scene-file key."""

    geometry: Body
    controls: tuple[ChamberControl, ...]
    increments: int
    material: MaterialForm = field(default_factory=Material)
    regions: tuple[Region, ...] = ()
    clamp_stiffness: float | None = si_default(CLAMP_STIFFNESS, NODAL_STIFFNESS)  # 1/2 K |u|^2 per node
    effects: tuple[Effect, ...] = ()
    name: str = "scene"
    targets: tuple = ()  # targets.Target poses for inverse control (apps.reach), in order
    units: Units = UNITLESS
    max_stretch: float = MAX_STRETCH
    volumetric: str = "element"
    fibers: tuple = ()  # terms.fibers.Fiber: embedded tension-only cords
    layers: tuple = ()  # terms.sheets.Layer: strain-limiting sheets bonded to faces of the body
    obstacles: tuple = ()  # terms.obstacles.Obstacle: rigid obstacles the body's boundary touches
    ends_at_limit_point: bool = False  # the ramp is meant to stop at a limit point (schedule.ends_at_limit_point)

    def __post_init__(self):
        self.resolve_defaults()
        check_stem(self.name)  # the result files are named after the scene
        require(
            require_finite("max_stretch", self.max_stretch) > 1,
            f"max_stretch = {self.max_stretch!r} must be > 1 (a principal stretch; 1 is the rest state)",
        )
        require(
            self.volumetric in VOLUMETRIC,
            f"volumetric = {self.volumetric!r} is not one of {', '.join(map(repr, VOLUMETRIC))}",
        )
        require_finite("clamp stiffness", self.clamp_stiffness)
        require(self.clamp_stiffness > 0, f"clamp stiffness = {self.clamp_stiffness!r} must be > 0")
        require(
            len(self.controls) == len(self.geometry.chambers),
            f"{len(self.controls)} chamber controls for {len(self.geometry.chambers)} chambers",
        )
        kinds = [e.name for e in self.effects]
        require(len(set(kinds)) == len(kinds), f"effects {kinds!r} name one effect twice")
        names = [o.name for o in self.obstacles]
        require(len(set(names)) == len(names), f"obstacle names {names!r} must be distinct")
        frictions = [f"{o.name}.friction" for o in self.obstacles if o.friction]  # heads its friction's columns
        require(not set(frictions) & set(names), f"obstacle names {names!r}: one is another's '<name>.friction'")
        clash = sorted(set(names) & {*self.chamber_names, "clamp", *kinds})
        require(not clash, f"obstacle name {clash[0] if clash else ''!r} is a chamber's, an effect's or the clamp's")
        _ = self.schedule  # validates the increments against the keyframes
        law, _ = self.law_parameters()  # resolves the presets, checks that the body has one law
        grouping = grouping_for(self.volumetric, self.geometry.order)
        if grouping != "element":
            require_volumetric(grouping, law, self.geometry.order)

    def resolve_defaults(self) -> None:
        """Set every default left None (units.si_default) of the scene, its geometry, its material and regions,
        its chamber kinds and its effects to its value in the scene's units (units.defaults, the conversion that
        scene files and the Python API share)."""

        def put(name, value):
            object.__setattr__(self, name, value)

        units, dim = self.units, self.dim
        for name, value in defaults(self, units, dim, "clamp").items():
            put(name, value)
        put("geometry", resolved(self.geometry, units, dim, "mesh"))  # a 2D Geometry's max_area
        put("material", resolved(self.material, units, dim, "material"))
        put(
            "regions",
            tuple(
                dataclasses.replace(r, material=resolved(r.material, units, dim, f"material.regions[{i}]"))
                for i, r in enumerate(self.regions)
            ),
        )
        put(
            "controls",
            tuple(
                dataclasses.replace(
                    c, schedule=dataclasses.replace(c.schedule, kind=resolved(c.kind, units, dim, f"chambers[{i}]"))
                )
                for i, c in enumerate(self.controls)
            ),
        )
        put("effects", tuple(resolved(e, units, dim, f"effects.{e.name}") for e in self.effects))
        put("obstacles", tuple(resolved(o, units, dim, f"obstacles[{i}]") for i, o in enumerate(self.obstacles)))

    def to_toml(self) -> str:
        """This scene as a scene file (TOML); scenefile.load_scene reads it back to an equal scene."""
        return dumps(SCENE_FILE.write_table(self))

    def with_value(self, key: str, value) -> Scene:
        """A copy with one dotted scene-file key changed (e.g. "chambers[0].center[1]", 0.1, or a short name
        of io/keys.py: "cy", "E", "nu", "k", ...), validated like a scene file; a bad key or value raises
        PneumaInputError naming the key."""
        return self.with_values({key: value})

    def fitted_stretch(self) -> tuple[float, str] | None:
        """(the smallest stretch, the preset) of the presets its material and regions name that state the range of
        data they were fitted to (materials/presets.py): past it their stresses are extrapolated; None if none."""
        fits = [
            (form.fitted_stretch, form.preset)
            for form in (self.material, *(region.material for region in self.regions))
            if isinstance(form, PresetMaterial) and form.fitted_stretch is not None
        ]
        return min(fits) if fits else None

    def with_values(self, values: dict) -> Scene:
        """A copy with several dotted keys (or short names) changed at once (validated once, after all are set)."""
        return edited(SCENE_FILE, self, {dotted(key): value for key, value in values.items()}, REPLACED)

    @property
    def schedule(self) -> Schedule:
        return Schedule(self.increments, tuple(c.schedule for c in self.controls), self.obstacles)

    @property
    def dim(self) -> int:
        """The body's dimension (Body.dim): 2 for plane strain triangles, 3 for tetrahedra."""
        return self.geometry.dim

    @property
    def chamber_names(self) -> list[str]:
        return self.geometry.chamber_names

    def law_parameters(self) -> tuple[type[Law], list[np.ndarray]]:
        """The body's law and the parameter vector of the material and of each region, in the scene's units
        (PneumaInputError naming the region whose law differs: a body has one law)."""
        law, base = self.material.law_parameters(self.units)
        rows = [base]
        for i, region in enumerate(self.regions):
            other, row = region.material.law_parameters(self.units)
            require(
                other is law,
                f"material.regions[{i}]: its law {other.name!r} is not the body's {law.name!r}: a "
                f"body has one law (E and nu: stable_neo_hookean; law = neo_hookean, mooney_rivlin, "
                f"yeoh and presets: isochoric_polynomial)",
            )
            rows.append(row)
        return law, rows

    def element_material(self, mesh: Mesh) -> tuple[type[Law], np.ndarray]:
        """The material law of the body and its parameter vector for every element, (m, p): the base material's,
        then each region's for the elements it contains (Region.contains), in order; a region that contains no
        element is refused, naming it."""
        law, (base, *rows) = self.law_parameters()
        parameters = np.tile(base, (mesh.n_elements, 1))
        for i, (region, row) in enumerate(zip(self.regions, rows)):
            taken = region.contains(mesh)
            require(
                taken.any(),
                f"material.regions[{i}]: "
                + (
                    f"box = {list(region.box)} holds no element's centroid (the body's bounding box is "
                    f"{[round(float(v), 6) for v in (*mesh.vertices.min(axis=0), *mesh.vertices.max(axis=0))]})"
                    if region.box is not None
                    else f"group = {region.group!r} has no elements"
                ),
            )
            parameters[taken] = row
        return law, parameters

    def build(self, budget: Budget = Budget()) -> BuiltScene:
        """Mesh the geometry and instantiate exactly the terms this scene names, the mesh and the effects' terms
        under the budget (limits.Budget: Budget() caps nothing; the commands give Budget(--max-triangles))."""
        runtime.ensure_initialised()
        mesh = self.geometry.mesh(budget)
        require_held(mesh.vertices, support_rows(mesh, self.effects), describe_supports(mesh, self.effects))
        law, parameters = self.element_material(mesh)
        # Round-off scales, from the stiffest modulus (neo-Hookean: mu + lam, which grows without bound as
        # nu -> 1/2): forces below 1e-6 modulus (body measure)^((d - 1) / d) (a stress times the measure of a
        # cross-section: sqrt(area) in 2D, volume^(2/3) in 3D), energies below 1e-12 modulus (body measure).
        modulus = float(np.max(law.modulus(parameters)))
        model = EnergyModel(
            mesh.vertices,
            force_floor=1e-6 * modulus * mesh.measure ** ((mesh.dim - 1) / mesh.dim),
            energy_resolution=1e-12 * modulus * mesh.measure,
        )
        config = model.config
        elastic = model.add(
            VOLUMETRIC[grouping_for(self.volumetric, mesh.order)](config, mesh.elements, law, parameters)
        )
        chambers = [
            model.add(control.term(config, loop, name, mesh.order, origin))
            for control, loop, origin, name in zip(self.controls, mesh.chambers, mesh.wall_origins, self.chamber_names)
        ]
        stiffness = given(self.clamp_stiffness, "clamp stiffness")
        if len(mesh.pinned):
            model.add(Clamp(config, mesh.pinned, stiffness))
        for nodes, normal in mesh.rollers:
            model.add(NormalClamp(config, nodes, normal, stiffness))
        lumped_area = mesh.nodal_measures()
        effects = {
            effect.name: [model.add(t) for t in effect.terms(config, mesh, lumped_area, budget)]
            for effect in self.effects
        }
        for spec in (*self.fibers, *(layer.in_units(self.units) for layer in self.layers)):
            for term in spec.terms(config, mesh, lumped_area, budget):
                model.add(term)
        obstacles = [[model.add(t) for t in spec.terms(config, mesh, lumped_area, budget)] for spec in self.obstacles]
        contacts = [terms[0] for terms in obstacles]
        parts = [t for terms in obstacles for t in terms[1:] if t.reports_contact]  # not a held object's weight
        return BuiltScene(self, mesh, model, elastic, chambers, effects, contacts, parts)


def support_rows(mesh: Mesh, effects) -> list:
    """What holds the body, as support rows (nodes, d x d projector) (fem/supports.py): the clamp (every
    component), each roller (its normal component), and the effects that hold motions (Effect.holds: the
    ground under gravity, inertia)."""
    return (
        [(mesh.pinned, np.eye(mesh.dim))]
        + [(nodes, np.outer(n, n)) for nodes, n in mesh.rollers]
        + [row for effect in effects for row in effect.holds(mesh, effects)]
    )


def describe_supports(mesh: Mesh, effects) -> str:
    """The supports in words: 'clamp 17 vertices' (or 'no clamp'), each roller by its normal with its count,
    the support effects by name (ground)."""
    clamp = f"clamp {len(mesh.pinned)} vertices" if len(mesh.pinned) else "no clamp"
    rollers = [
        f"roller [{', '.join(f'{c:.3g}' for c in n + 0.0)}] {len(nodes)} vertices"  # + 0.0: no -0
        for nodes, n in mesh.rollers
    ]
    return ", ".join([clamp] + rollers + [effect.name for effect in effects if effect.support])


# The scene file's declaration (scene_keys.SCENE), whose values make a Scene
SCENE_FILE = dataclasses.replace(SCENE, make=lambda values: Scene(**scene_arguments(values)), cls=Scene)


@dataclass
class BuiltScene:
    """A meshed scene: its EnergyModel, and handles on the terms a run drives or reports (obstacles: the
    obstacles' contact terms on the body's nodes, in the scene's order; obstacle_parts: their other terms that exert a
    force, the barriers on the body's sides and faces ('<name>.edges', reported with the nodes') and the friction
    terms of those with friction > 0)."""

    scene: Scene
    mesh: Mesh
    model: EnergyModel
    elastic: Elasticity
    chambers: list[Chamber]
    effects: dict[str, list[Term]]
    obstacles: list = field(default_factory=list)
    obstacle_parts: list = field(default_factory=list)

    @property
    def clamp(self) -> Term | None:
        """The clamp's term, or None in a scene without one."""
        return next((t for t in self.model.terms if isinstance(t, Clamp)), None)

    def contact_terms(self) -> list[Term]:
        """Every term that reports a contact force, each under its reported_as: the effects' (ground, self_contact,
        and ground.friction), then the obstacles' (their names), then their parts (the edges' under the obstacle's
        name, the friction terms' as '<name>.friction')."""
        effects = [t for terms in self.effects.values() for t in terms if t.reports_contact]
        return effects + list(self.obstacles) + list(self.obstacle_parts)

    def moving_offsets(self, commands: np.ndarray) -> list:
        """(term, translation (3,)) of each moving obstacle at the commands (Schedule.commands: the chambers'
        commands, then 3 per moving obstacle); none for a vector of the chambers' commands alone."""
        offsets = np.asarray(commands[len(self.chambers) :], dtype=float).reshape(-1, 3)
        moving = [term for term, spec in zip(self.obstacles, self.scene.obstacles) if spec.moving]
        return list(zip(moving, offsets))

    def set_commands(self, commands: np.ndarray) -> None:
        """The chambers' commands, then each moving obstacle's translation; a vector of the chambers' commands alone
        leaves the obstacles where they are."""
        for chamber, command in zip(self.chambers, commands):
            chamber.set_command(command)
        for term, offset in self.moving_offsets(commands):
            term.set_offset(offset)

    def sweeps(self, start: np.ndarray, end: np.ndarray) -> int:
        """Into how many equal parts the change of commands from start to end is cut so that no obstacle moves
        farther than its sweep in one (n = max over the moving obstacles of ceil(|t_end - t_start| / sweep), at
        least 1): a part of the body shorter along the motion than the sweep is all an obstacle can pass between
        two equilibria without overlapping it at one of them (Obstacle.terms bounds n by MAX_SWEEPS)."""
        moves = [
            np.linalg.norm(b - a) / term.sweep
            for (term, a), (_, b) in zip(self.moving_offsets(start), self.moving_offsets(end))
        ]
        return max([1, *(math.ceil(move) for move in moves)])

    @cached_property
    def surface_pieces(self) -> np.ndarray:
        """The body's surface as straight pieces (fem/self_intersection.py surface_pieces)."""
        return surface_pieces(self.mesh)

    def surface_crossing(self) -> str | None:
        """Where the body's surface passes through itself in the model's current state, in words (the first two
        pieces that share no node and cross: fem/self_intersection.py surface_crossing), or None. Each piece is
        named by its nodes and by the part of the surface it lies on: a chamber's wall (every node of it on the
        wall) or the outer surface."""
        config = self.model.config
        x = config.rest + config.u
        crossing = surface_crossing(x, self.surface_pieces)
        if crossing is None:
            return None
        dim = self.mesh.dim
        kind = "segment" if dim == 2 else "triangle"

        def named(row: int) -> str:
            nodes = list(dict.fromkeys(int(v) for v in self.surface_pieces[row]))  # a 2D (a, b, b): a, b
            part = next(
                (
                    f"the wall of chamber {c.chamber_name!r}"
                    for c in self.chambers
                    if np.isin(nodes, c.loop_vertices).all()
                ),
                "the outer surface",
            )
            return f"{kind} (nodes {', '.join(map(str, nodes))}) of {part}"

        where = ", ".join(f"{v:.4g}" for v in crossing.point[:dim])
        return f"{named(crossing.first)} and {named(crossing.second)} cross near ({where})"

    def obstacle_overlap(self) -> str | None:
        """The first obstacle that overlaps the body in its current state, in words (ObstacleContact.overlap), or
        None."""
        return next((fault for fault in (term.overlap() for term in self.obstacles) if fault is not None), None)


def reference_scene(
    cy: float = 0.15,
    cx: float = 0.0,
    growth: float = 3.5,
    steps: int = 36,
    E: float = 1e4,
    nu: float = 0.45,
    k: float = 1e5,
    max_area: float = 0.0012,
    chamber_points: int = 128,
    order: int = 1,
    refinements: int = 0,
    **long_names,
) -> Scene:
    """The reference scene: the clamped 3.5 x 0.8 beam, one ellipse chamber at (cx, cy) ramped in area from 1 to
    growth over steps commanded areas (rest included); E, nu: Young's modulus and Poisson's ratio; k: the
    chamber's area penalty stiffness (the names of the command line's flags; youngs_modulus,
    poisson_ratio, chamber_stiffness are accepted for them too). order 2 meshes it with quadratic
    triangles, refinements splits every triangle in four that often."""
    E, nu = long_names.pop("youngs_modulus", E), long_names.pop("poisson_ratio", nu)
    k = long_names.pop("chamber_stiffness", k)
    if long_names:
        raise TypeError(f"reference_scene() got an unexpected keyword argument {next(iter(long_names))!r}")
    beam = BeamGeometry(
        cx=cx, cy=cy, max_area=max_area, chamber_points=chamber_points, order=order, refinements=refinements
    )
    return Scene(
        beam.general(),
        (ChamberControl(area_ramp(growth, steps, k)),),
        steps - 1,
        Material(E, nu),
        name=f"reference_cy{cy:+.2f}",
    )
