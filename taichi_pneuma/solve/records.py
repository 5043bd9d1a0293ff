"""A run as plain records: per chamber (ChamberRecord) and per step (StepRecord) what was measured after each
solve, and the whole run (Run: the built scene, its steps and positions) with the figures read off them.
Files and pictures made from a run are result.Result's."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ..fem.tip import COLUMNS as TIP_COLUMNS
from ..scene.build import BuiltScene, Scene
from . import columns
from .columns import AFTER_CHAMBERS, AFTER_CONTACT, AFTER_SOLVER

# the history columns that count the solve, not measure the state it found: a ramp's step, its Newton iterations,
# residual, convergence, cut-backs, sub-increments and seconds (each an integer, a flag or a figure of the solver's)
SOLVER_COLUMNS = ("step", "iterations", "residual", "converged", "cuts", "substeps", "seconds")


@dataclass
class ChamberRecord:
    """One chamber after a solve: its kind's name, its command (area ratio, pressure, ...), area, area ratio
    and pressure."""

    control: str
    command: float
    area: float
    area_ratio: float
    pressure: float


@dataclass
class StepRecord:
    """One increment of the schedule, as measured after its solve, constructed by keyword.

    chambers: each chamber's ChamberRecord, by name; measures: the value of each column of the registry
    (columns.COLUMNS) the step has, by name (tip_dx, tip_dy (, tip_dz): the mean displacement of the tip nodes;
    tip_rotation: their rigid rotation in degrees, counter-clockwise positive, the whole turn from rest; in 3D
    tip_twist; with obstacles blocked_force; min_det; max_stretch; read also as the properties below); the solver's
    figures (SOLVER_COLUMNS); contact: per contact term (by its name: ground, self_contact, each obstacle's) the
    total force it exerts on the body (fx, fy) and the sum of its per-node force magnitudes, and in 3D (contact_fz)
    that force's z component; clamp: the clamp's reaction on the body, its force and its moment about the pinned
    nodes' rest centroid (simulate.clamp_reaction: fx, fy, mz; in 3D fx, fy, fz, mx, my, mz), empty without a
    clamp; extra: further columns by name, last in the row (a reach's target and tip error, inverse.frames).
    """

    step: int
    chambers: dict[str, ChamberRecord]
    measures: dict[str, float]
    iterations: int
    residual: float
    converged: bool
    cuts: int
    substeps: int
    seconds: float
    contact: dict[str, tuple[float, float, float]] = field(default_factory=dict)
    contact_fz: dict[str, float] = field(default_factory=dict)
    clamp: dict[str, float] = field(default_factory=dict)
    extra: dict[str, float] = field(default_factory=dict)

    @property
    def tip(self) -> np.ndarray:
        """The tip's mean displacement (d,) (fem/tip.py)."""
        return np.array([self.measures[column] for column in TIP_COLUMNS if column in self.measures])

    tip_dx = property(lambda self: self.measures["tip_dx"], doc="The tip's mean x displacement.")
    tip_dy = property(
        lambda self: self.measures["tip_dy"], doc="The tip's mean y displacement (the deflection of a beam along x)."
    )
    tip_rotation = property(
        lambda self: self.measures["tip_rotation"],
        doc="The tip's rigid rotation in degrees, the whole turn from rest (fem/tip.py).",
    )
    tip_twist = property(
        lambda self: self.measures.get("tip_twist"),
        doc="In 3D the tip's twist about x in degrees, the whole turn from rest (fem/tip.py), else None.",
    )
    blocked_force = property(
        lambda self: self.measures.get("blocked_force"),
        doc="With obstacles, the magnitude of the total force between the body and all of them, else None.",
    )
    min_det = property(lambda self: self.measures.get("min_det", math.nan), doc="The smallest det F of any element.")
    max_stretch = property(
        lambda self: self.measures.get("max_stretch", math.nan),
        doc="The largest principal stretch at any quadrature point (ElementFields.largest_stretch).",
    )

    def _measured(self, after: str) -> dict[str, float]:
        """The measured columns that stand after `after` in the row (columns.Column.after), in COLUMNS' order."""
        return {c.name: self.measures[c.name] for c in columns.COLUMNS if c.after == after and c.name in self.measures}

    def row(self) -> dict[str, float]:
        """Flat columns: step, <chamber>.<field> for each chamber, the measured columns after the chambers (tip_dx,
        tip_dy, ...), <contact>.fx/.fy(/.fz)/.magnitude, those after the contact (blocked_force),
        clamp.fx/.fy(/.fz)/(.mx/.my/).mz, the solver's figures with the measured columns after them (min_det,
        max_stretch) before its seconds, the extra columns."""
        row: dict[str, float] = {"step": self.step}
        for name, c in self.chambers.items():
            row.update(
                {
                    f"{name}.command": c.command,
                    f"{name}.area": c.area,
                    f"{name}.area_ratio": c.area_ratio,
                    f"{name}.pressure": c.pressure,
                }
            )
        row.update(self._measured(AFTER_CHAMBERS))
        for name, (fx, fy, magnitude) in self.contact.items():
            row.update({f"{name}.fx": fx, f"{name}.fy": fy})
            if name in self.contact_fz:
                row[f"{name}.fz"] = self.contact_fz[name]
            row[f"{name}.magnitude"] = magnitude
        row.update(self._measured(AFTER_CONTACT))
        row.update({f"clamp.{key}": value for key, value in self.clamp.items()})
        row.update(
            {
                "iterations": self.iterations,
                "residual": self.residual,
                "converged": self.converged,
                "cuts": self.cuts,
                "substeps": self.substeps,
            }
        )
        row.update(self._measured(AFTER_SOLVER))
        row["seconds"] = self.seconds
        row.update(self.extra)
        return row


@dataclass
class Run:
    """A run: the built scene and, per step (rest state first), its StepRecord and positions.

    Its fields: built (the BuiltScene: mesh, energy model, terms); steps (a StepRecord per step: chamber
    records, tip measures, Newton figures); positions (steps, n, d): the node positions per step; solves: the
    last Newton SolveRecord of each step (none for reaches); contact_forces (steps, n, d): the summed contact
    force per node, when the scene has contact, else None; seconds: wall time of the run; newton: the linear
    solver that served the run's Newton solves, their chord steps (iterations without a new Hessian) and the
    seconds per phase of an iteration, summed over the run. The properties below are figures read off these."""

    built: BuiltScene
    steps: list
    positions: np.ndarray
    solves: list = field(default_factory=list)
    contact_forces: np.ndarray | None = None
    seconds: float = math.nan
    newton: dict = field(default_factory=dict)

    @property
    def scene(self) -> Scene:
        """The Scene that was run (its geometry, materials, chambers, schedule, effects)."""
        return self.built.scene

    @property
    def mesh(self):
        """The mesh: rest nodes (n, d), elements, pinned, tip and boundary nodes, chamber walls."""
        return self.built.mesh

    @property
    def displacements(self) -> np.ndarray:
        """(steps, n, d) node displacements from the rest mesh, per step."""
        return self.positions - self.mesh.vertices

    @property
    def chamber_names(self) -> list[str]:
        """The chambers' names, in the scene's order: the column order of command, area, area_ratio, pressure."""
        return self.scene.chamber_names

    @cached_property
    def history(self) -> dict[str, np.ndarray]:
        """Every column of the history CSV by name, one value per step: 'tip_dx', 'tip_dy', 'tip_rotation',
        '<chamber>.command' / '.area' / '.area_ratio' / '.pressure', 'iterations', 'residual', 'converged',
        'cuts', 'min_det', 'seconds', and a reach's 'target_x', 'tip_error', ..."""
        rows = [s.row() for s in self.steps]
        return {name: np.array([row[name] for row in rows], dtype=float) for name in (rows[0] if rows else ())}

    def _chambers(self, key: str) -> np.ndarray:
        return np.column_stack([self.history[f"{name}.{key}"] for name in self.chamber_names])

    command = property(lambda self: self._chambers("command"), doc="(steps, chambers) commanded area ratio or pressure")
    area = property(lambda self: self._chambers("area"), doc="(steps, chambers) chamber areas")
    area_ratio = property(lambda self: self._chambers("area_ratio"), doc="(steps, chambers) area / rest area")
    pressure = property(lambda self: self._chambers("pressure"), doc="(steps, chambers) chamber pressures")

    @property
    def tip_deflection(self) -> float:
        """Mean y displacement of the tip vertices at the last step."""
        return self.steps[-1].tip_dy

    @property
    def tip_rotation(self) -> float:
        """Rotation of the tip vertices at the last step, in degrees (counter-clockwise positive), the whole turn
        from rest (-375 for a finger curled clockwise past a whole turn; fem/tip.py)."""
        return self.steps[-1].tip_rotation

    @property
    def peak_pressure(self) -> float:
        """The largest |pressure| of any chamber at any step."""
        return max(abs(c.pressure) for s in self.steps for c in s.chambers.values())

    @property
    def converged(self) -> bool:
        """Whether every step's Newton solve converged."""
        return bool(all(s.converged for s in self.steps))

    def peak_step(self) -> int:
        """The step of the largest deformation: the last step whose largest vertex displacement is within 1 %
        of the run's largest (a hold at the peak, or a symmetric return, gives its latest step). A ramp
        that ends inflated gives its last step; one that inflates and deflates, its bent state."""
        largest = np.linalg.norm(self.displacements, axis=2).max(axis=1)
        return int(np.flatnonzero(largest >= 0.99 * largest.max())[-1])

    @property
    def ground_height(self) -> float | None:
        """The height of the scene's ground line (the effect that has one), or None."""
        return next((e.ground_height for e in self.scene.effects if e.ground_height is not None), None)

    def fields(self, step: int = -1) -> dict[str, np.ndarray]:
        """Per element at a step: det_F, max_stretch, stress (Cauchy, (m, 3, 3)), von_mises (fields.py)."""
        return self.mesh.fields.at(self.positions[step], *self.scene.element_material(self.mesh))

    def extremes(self) -> dict[str, dict]:
        """The range over the run of each measured column that has extremes (columns.COLUMNS: tip_dx, tip_dy, in 3D
        tip_dz, tip_rotation, in 3D tip_twist, with obstacles blocked_force) and of each chamber's (<chamber>.area,
        .area_ratio, .pressure), by history column: {"min": value, "min_step": the first step at it, "max": ...,
        "max_step": ...}. A schedule that goes out and back ends near rest; its extremes keep what it reached."""
        history = self.history
        names = [
            *(column.name for column in columns.COLUMNS if column.extremes and column.name in history),
            *(f"{name}.{key}" for name in self.chamber_names for key in ("area", "area_ratio", "pressure")),
        ]
        extremes = {}
        for column in names:
            values = history[column]
            low, high = int(np.argmin(values)), int(np.argmax(values))
            extremes[column] = {
                "min": float(values[low]),
                "min_step": int(history["step"][low]),
                "max": float(values[high]),
                "max_step": int(history["step"][high]),
            }
        return extremes
