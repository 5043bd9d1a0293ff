"""Run an inflation ramp over a built scene: one warm-started Newton equilibrium per commanded area."""

from __future__ import annotations

import csv
import io
import time
from dataclasses import asdict, dataclass, fields

import numpy as np

from .errors import require, require_finite
from .newton import NewtonOptions, NewtonSolver, SolveRecord
from .scene import BuiltScene

MAX_CUTS = 8


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
    cuts: int
    substeps: int
    min_det: float
    seconds: float


@dataclass
class RampResult:
    steps: list[StepRecord]
    states: np.ndarray  # (steps, n, 2) positions
    solves: list[SolveRecord]

    def column(self, name: str) -> np.ndarray:
        return np.array([getattr(s, name) for s in self.steps], dtype=float)

    @property
    def tip_deflection(self) -> float:
        return self.steps[-1].tip_dy

    @property
    def peak_pressure(self) -> float:
        return float(np.max(np.abs(self.column("pressure"))))

    def history_csv(self) -> str:
        buffer = io.StringIO()
        writer = csv.DictWriter(buffer, fieldnames=[f.name for f in fields(StepRecord)])
        writer.writeheader()
        writer.writerows(asdict(s) for s in self.steps)
        return buffer.getvalue()


def area_ramp(rest_area: float, growth: float, steps: int) -> np.ndarray:
    """Commanded areas: `steps` evenly spaced values from rest_area to growth * rest_area."""
    require(require_finite("growth", growth) > 0, f"growth = {growth!r} must be > 0")
    require(isinstance(steps, (int, np.integer)) and steps >= 2,
            f"steps = {steps!r} must be an integer >= 2 (the rest state and at least one increment)")
    return np.linspace(rest_area, growth * rest_area, steps)


def predict(built: BuiltScene, previous, current, value: float) -> np.ndarray:
    """Initial guess for the equilibrium at commanded `value`: linear extrapolation through the last two
    equilibria (a, u), u_guess = u1 + (u1 - u0) (value - a1) / (a1 - a0), unless that inverts a triangle
    (then the last equilibrium u1)."""
    a1, u1 = current
    if previous is None or previous[0] == a1:
        return u1
    a0, u0 = previous
    guess = u1 + (u1 - u0) * ((value - a1) / (a1 - a0))
    built.model.set_displacements(guess)
    return guess if built.elastic.min_determinant() > 0 else u1


class RampFailed(RuntimeError):
    """An increment found no equilibrium even after cutting it back; `partial` holds the steps done."""

    def __init__(self, message: str, partial: RampResult):
        super().__init__(message)
        self.partial = partial


def run_ramp(built: BuiltScene, targets: np.ndarray, options: NewtonOptions | None = None,
             progress=None, max_cuts: int = MAX_CUTS) -> RampResult:
    """Solve for equilibrium at each commanded area in turn, each solve starting from the last.

    An increment whose Newton solve does not converge is cut back: the remaining change of the
    commanded area is halved and the smaller sub-increment solved from the last equilibrium, as
    often as max_cuts times per increment; every cut is counted in the history. If it still fails,
    RampFailed names the step, the commanded area and the residual, and carries the steps done.
    progress, if given, is called as progress(step_record) after every increment.
    """
    solver = NewtonSolver(built.model, options)
    mesh = built.mesh
    u = np.zeros_like(mesh.vertices)
    steps, states, solves = [], [], []
    reached = float(targets[0])
    previous = None  # (commanded value, u) of the equilibrium before the last one, for the predictor
    for i, target in enumerate(targets):
        start = time.perf_counter()
        records: list[SolveRecord] = []
        increment, cuts = float(target) - reached, 0
        while True:
            trial = float(target) if abs(float(target) - reached) <= abs(increment) else reached + increment
            built.chamber.target_area = trial
            u_trial, record = solver.solve(predict(built, previous, (reached, u), trial))
            records.append(record)
            if record.converged:
                previous = (reached, u)
                u, reached = u_trial, trial
                if trial == float(target):
                    break
            elif cuts < max_cuts:
                cuts += 1
                increment /= 2
            else:
                built.model.set_displacements(u)
                raise RampFailed(
                    f"step {i}: no equilibrium at commanded area {trial:.6g} ({trial / built.rest_area:.4g} x rest) "
                    f"after {cuts} cuts; residual {record.residual:.2e} ({record.message})",
                    RampResult(steps, np.array(states).reshape(-1, *mesh.vertices.shape), solves))
        built.model.set_displacements(u)
        area = built.chamber.area()
        tip = u[mesh.tip].mean(axis=0)
        final = records[-1]
        step = StepRecord(i, float(target), area, area / built.rest_area, built.chamber.pressure(),
                          float(tip[0]), float(tip[1]), sum(r.iterations for r in records), final.residual,
                          final.converged, cuts, len(records) - cuts, built.elastic.min_determinant(),
                          time.perf_counter() - start)
        steps.append(step)
        states.append(mesh.vertices + u)
        solves.append(final)
        if progress is not None:
            progress(step)
    return RampResult(steps, np.array(states), solves)
