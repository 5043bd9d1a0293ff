"""Run an inflation ramp over a built scene: one warm-started Newton equilibrium per commanded area."""

from __future__ import annotations

import csv
import io
from dataclasses import asdict, dataclass

import numpy as np

from .errors import require
from .newton import NewtonOptions, NewtonSolver, SolveRecord
from .scene import BuiltScene


@dataclass
class StepRecord:
    """One increment of the ramp, as measured after its solve."""

    step: int
    target_area: float
    area: float
    area_ratio: float
    pressure: float
    tip_dx: float
    tip_dy: float
    iterations: int
    residual: float
    converged: bool
    min_det: float
    seconds: float


@dataclass
class RampResult:
    steps: list[StepRecord]
    states: np.ndarray  # (steps, n, 2) positions
    solves: list[SolveRecord]

    def column(self, name: str) -> np.ndarray:
        return np.array([getattr(s, name) for s in self.steps])

    @property
    def tip_deflection(self) -> float:
        return self.steps[-1].tip_dy

    @property
    def peak_pressure(self) -> float:
        return float(np.max(np.abs(self.column("pressure"))))

    def history_csv(self) -> str:
        buffer = io.StringIO()
        writer = csv.DictWriter(buffer, fieldnames=list(asdict(self.steps[0])))
        writer.writeheader()
        writer.writerows(asdict(s) for s in self.steps)
        return buffer.getvalue()


def area_ramp(rest_area: float, growth: float, steps: int) -> np.ndarray:
    """Commanded areas: `steps` evenly spaced values from rest_area to growth * rest_area."""
    require(growth > 0, f"growth = {growth!r} must be > 0")
    require(steps >= 2, f"steps = {steps!r} must be >= 2 (the rest state and at least one increment)")
    return np.linspace(rest_area, growth * rest_area, steps)


def run_ramp(built: BuiltScene, targets: np.ndarray, options: NewtonOptions | None = None,
             progress=None) -> RampResult:
    """Solve for equilibrium at each commanded area in turn, each solve starting from the last.

    progress, if given, is called as progress(step_record) after every increment.
    """
    solver = NewtonSolver(built.model, options)
    mesh = built.mesh
    u = np.zeros_like(mesh.vertices)
    steps, states, solves = [], [], []
    for i, target in enumerate(targets):
        built.chamber.target_area = float(target)
        u, record = solver.solve(u)
        x = mesh.vertices + u
        area = built.chamber.area()
        tip = u[mesh.tip].mean(axis=0)
        step = StepRecord(i, float(target), area, area / built.rest_area, built.chamber.pressure(),
                          float(tip[0]), float(tip[1]), record.iterations, record.residual, record.converged,
                          built.elastic.min_determinant(), record.seconds)
        steps.append(step)
        states.append(x.copy())
        solves.append(record)
        if progress is not None:
            progress(step)
    return RampResult(steps, np.array(states), solves)
