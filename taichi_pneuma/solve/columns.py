"""The history's columns that measure a step's state, declared once: COLUMNS, a registry the history CSV (its
header's units and its rows, records.StepRecord.row), the summary's extremes (records.Run.extremes), the ParaView
files' field data and the history plot's response panels (render/plots.py) all read. A new column is one entry.

The history's other columns are read off the records themselves: the step, each chamber's command, area, area
ratio and pressure (one set per chamber), each contact term's force (fx, fy, in 3D fz, magnitude), the clamp's
reaction (simulate.clamp_reaction), the solver's figures (records.SOLVER_COLUMNS) and the columns the terms add
(Term.columns(), a reach's targets: StepRecord.extra).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..fem.fields import ElementFields
from ..fem.tip import tip_measures, tip_twist_of
from ..io.units import ANGLE, FORCE, LENGTH, MEASURES, MOMENT, PRESSURE, TIME, in_dimension
from ..scene.build import BuiltScene
from ..terms.base import Term


@dataclass
class StepState:
    """What a column measures: the equilibrium u (n, d) of the built scene (its model holding u), the mesh's
    ElementFields, and the tip's rotation and twist (degrees) in the state it was solved from (rest: 0), from which
    this state's angles are continued (fem/tip.py: the whole turn from rest)."""

    built: BuiltScene
    u: np.ndarray
    fields: ElementFields
    near: tuple[float, float] = (0.0, 0.0)

    @cached_property
    def tip(self) -> tuple[np.ndarray, float]:
        """The tip's mean displacement (d,) and its rotation in degrees (fem/tip.py tip_measures)."""
        return tip_measures(self.built.mesh, self.u, self.near[0])

    @cached_property
    def contact_forces(self) -> list[tuple[Term, np.ndarray]]:
        """Each contact term with the force it exerts on the body's nodes, f = -dE/du (n, d), in the model's
        order."""
        return [(term, -term.gradient()) for term in self.built.contact_terms()]

    def measure(self) -> dict[str, float]:
        """Every column of COLUMNS that this state has (its measure is not None), by name."""
        values = {column.name: column.measure(self) for column in COLUMNS}
        return {name: value for name, value in values.items() if value is not None}


def blocked_force(state: StepState) -> float | None:
    """|sum of the forces the obstacles exert on the body| (the force the body exerts on the objects it presses
    on); None without obstacles."""
    built = state.built
    if not built.obstacles:
        return None
    obstacles = (*built.obstacles, *built.obstacle_parts)
    on_obstacles = np.zeros(built.mesh.dim)
    for term, f in state.contact_forces:
        if any(term is obstacle for obstacle in obstacles):
            on_obstacles += f.sum(axis=0)
    return float(np.linalg.norm(on_obstacles))


def tip_component(axis: int) -> Callable[[StepState], float | None]:
    """The measure of the tip's mean displacement along axis (0: x, 1: y, 2: z; None past the body's dimension)."""
    return lambda state: float(state.tip[0][axis]) if axis < state.built.mesh.dim else None


# where a column stands in the history's row (records.StepRecord.row): after the chambers' columns, after the
# contact terms' forces, or after the solver's figures (before its seconds)
AFTER_CHAMBERS, AFTER_CONTACT, AFTER_SOLVER = "chambers", "contact", "solver"


@dataclass(frozen=True)
class Column:
    """One measured history column: its name; its dimension (io/units.py: LENGTH, ANGLE, FORCE ...; its unit in a
    scene with units, in_dimension's in 3D; "" for a pure number); measure(state), its value at a StepState (None
    where the scene has no such measure: no twist in 2D); extremes: whether the summary gives its range over the
    run (records.Run.extremes); panel: the plot panel that draws it against the driving pressure (render/plots.py
    RESPONSES; None: not drawn) and label, its legend entry there when the panel draws more than one curve; after:
    where it stands in the row (AFTER_CHAMBERS, AFTER_CONTACT, AFTER_SOLVER)."""

    name: str
    dimension: str
    measure: Callable[[StepState], float | None]
    extremes: bool = False
    panel: str | None = None
    label: str = ""
    after: str = AFTER_SOLVER


COLUMNS = (
    Column("tip_dx", LENGTH, tip_component(0), True, "extension", after=AFTER_CHAMBERS),
    Column("tip_dy", LENGTH, tip_component(1), True, "deflection", after=AFTER_CHAMBERS),
    Column("tip_dz", LENGTH, tip_component(2), True, after=AFTER_CHAMBERS),
    Column("tip_rotation", ANGLE, lambda s: s.tip[1], True, "bending", "bending angle", AFTER_CHAMBERS),
    Column(
        "tip_twist",
        ANGLE,
        lambda s: tip_twist_of(s.built.mesh, s.u, s.near[1]),
        True,
        "bending",
        "twist about x",
        AFTER_CHAMBERS,
    ),
    Column("blocked_force", FORCE, blocked_force, True, "obstacles", "net (blocked force)", AFTER_CONTACT),
    Column("min_det", "", lambda s: s.built.elastic.min_determinant()),
    Column("max_stretch", "", lambda s: s.fields.largest_stretch(s.built.mesh.vertices + s.u)),
)

# the dimensions of the history columns no entry of COLUMNS measures and no scene names: the solver's seconds and
# the columns a reach adds (inverse.frames)
OTHER_DIMENSIONS = {
    "seconds": TIME,
    "target_x": LENGTH,
    "target_y": LENGTH,
    "target_z": LENGTH,
    "target_angle": ANGLE,
    "tip_x": LENGTH,
    "tip_y": LENGTH,
    "tip_z": LENGTH,
    "tip_error": LENGTH,
}


def history_dimensions(scene, contacts=(), dim: int = 2) -> dict[str, str]:
    """The dimension of every history column (records.StepRecord.row) with one, for a scene (its chambers'
    commands have their kinds' dimensions; a chamber's measure is a volume in 3D), the names of its contact
    terms (their fx, fy, fz, magnitude) and the body's dimension dim: those of COLUMNS and OTHER_DIMENSIONS; the
    clamp's reaction (clamp.fx, ...: forces; clamp.mx, .my, .mz: moments); a held object's height."""
    dimensions = {column.name: in_dimension(column.dimension, dim) for column in COLUMNS if column.dimension}
    dimensions.update(OTHER_DIMENSIONS)
    for name, control in zip(scene.chamber_names, scene.controls):
        dimensions.update(
            {
                f"{name}.command": in_dimension(control.kind.dimension, dim),
                f"{name}.area": MEASURES[dim],
                f"{name}.pressure": PRESSURE,
            }
        )
    force, moment = in_dimension(FORCE, dim), in_dimension(MOMENT, dim)
    for name in contacts:
        dimensions.update({f"{name}.{part}": force for part in ("fx", "fy", "fz", "magnitude")})
    dimensions.update({f"clamp.f{axis}": force for axis in "xyz"})
    dimensions.update({f"clamp.m{axis}": moment for axis in "xyz"})
    dimensions.update({f"{o.name}.dy": LENGTH for o in scene.obstacles if o.weight is not None})  # held objects
    return dimensions
