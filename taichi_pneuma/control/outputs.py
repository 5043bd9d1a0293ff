"""Inverse control of anything a ramp measures: the commands at which a history column (the bending angle
tip_rotation, the twist tip_twist, the extension tip_dx, the blocked force, a contact force, a chamber's pressure ...)
takes a wanted value D, along the scene's own schedule.

The schedule's commands c(s) (piecewise linear in the step s, solve.simulate's ramp) are followed from rest, the
column m measured after every step. At the first step k where m(k) - D changes sign (or is zero), the root of
m(c(s)) = D for s in [k - 1, k] is found by SciPy's brentq, each evaluation one equilibrium solved from the state
of step k - 1 (simulate.settle, with its cut-backs): the state a ramp would reach at c(s), to the Newton tolerance,
and m read off it as the ramp reads it (simulate.step_record, an angle continued from step k - 1's: the whole turn
from rest, fem/tip.py). A column the ramp never brings to D is reported with the step that came closest; the ramp
then runs whole. A quasistatic state depends on its path only through what remembers it (none of the elastic,
pressure, fibre, sheet or frictionless contact terms do), so the root is the equilibrium of the scene at those
commands.

Only a measure of the state can be a target: every history column but the solver's (records.SOLVER_COLUMNS: step,
iterations, residual, converged, cuts, substeps, seconds), which count the solve and take no value in between.
The value m found at brentq's root is compared with D: the target is reached when |m - D| <= RTOL * max(|m(k) -
m(k - 1)|, |D|), a thousandth of the column's change over the crossing step (or of D); a column that jumps over D
inside the step (a snap-through, a contact closing) is not reached there, and the value found is reported with it;
so is one whose re-solved step k does not cross D (the nearer end's value).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from ..errors import require, require_finite
from ..scene.build import BuiltScene
from ..solve.newton import NewtonOptions, NewtonSolver
from ..solve.records import SOLVER_COLUMNS, Run
from ..solve.simulate import MAX_CUTS, RampFailed, RampInterrupted, run_schedule, settle, step_record


@dataclass
class OutputReach:
    """column, wanted: what was asked; found: whether the ramp crossed it and the value found there is within RTOL
    of it (module docstring); value: the column at the result (the closest step's when not crossed, the one found
    inside the crossing step when jumped over); step: the (fractional) step of the schedule at which it is reached
    (or that value is); commands: the chambers' commands there; run: the ramp's steps up to the crossing (all of
    them when not crossed); evaluations: the brentq evaluations (step, value); seconds: the wall time; failure: why
    the ramp stopped before its end without crossing the value (its last increment had no equilibrium), or None."""

    column: str
    wanted: float
    found: bool
    value: float
    step: float
    commands: np.ndarray
    run: Run
    evaluations: list[tuple[float, float]]
    seconds: float
    failure: str | None = None

    def summary_line(self) -> str:
        """'reached: <column> = <value> at step <s> ...' or 'unreachable: ...': not crossed (the closest step), or
        crossed by a step but not taken inside it (the value found there)."""
        if self.found:
            return f"reached: {self.column} = {self.value:.6g} at step {self.step:.4f} of the schedule"
        if self.evaluations:
            return (
                f"unreachable: {self.column} = {self.wanted:.6g} is not taken inside step {len(self.run.steps) - 1} of "
                f"the schedule, which crosses it: {self.value:.6g} found at step {self.step:.4f}, not within {RTOL:g} "
                f"of the step's change (the column jumps there, or the step re-solved does not cross it)"
            )
        if self.failure is not None:
            return (
                f"unreachable: the ramp stopped before {self.column} reached {self.wanted:.6g}; the closest it came "
                f"is {self.value:.6g} at step {self.step:g} ({self.failure})"
            )
        return (
            f"unreachable: {self.column} = {self.wanted:.6g} is not crossed by the schedule; closest {self.value:.6g} "
            f"at step {self.step:g}"
        )


RTOL = 1e-3  # the value found is within RTOL of the column's change over the crossing step (module docstring)


def crossing(values: np.ndarray, wanted: float) -> int | None:
    """The first step k >= 1 with values[k - 1] - wanted and values[k] - wanted of opposite signs (or one zero)."""
    gaps = np.asarray(values, dtype=float) - wanted
    for k in range(1, len(gaps)):
        if gaps[k - 1] * gaps[k] <= 0:
            return k
    return None


def reach_output(
    built: BuiltScene,
    column: str,
    wanted: float,
    options: NewtonOptions | None = None,
    xtol: float = 1e-6,
    progress=None,
    max_cuts: int = MAX_CUTS,
) -> OutputReach:
    """The commands along built's schedule at which history column `column` equals `wanted` (module docstring);
    a column the scene's history does not have, or one of the solver's, is refused, naming the ones it can be.
    progress(step_record, positions, contact_force), if given, is called after each step of the ramp; max_cuts: the
    cut-backs allowed per increment (simulate.settle). A ramp that stops (no equilibrium) before the column crosses
    the value is not found: the closest step done, with why."""
    started = time.perf_counter()
    wanted = require_finite(column, wanted)
    schedule = built.scene.schedule
    seen: list[float] = []

    def watch(step, positions, forces) -> None:
        row = step.row()
        measures = sorted(name for name in row if name not in SOLVER_COLUMNS)
        require(
            column in measures,
            f"output {column!r} is not a measure of this scene's state (the solver's {', '.join(SOLVER_COLUMNS)} take "
            f"no value between steps): one of {', '.join(measures)}",
        )
        seen.append(float(row[column]))
        if progress is not None:
            progress(step, positions, forces)

    def crossed() -> bool:
        return crossing(np.array(seen), wanted) is not None

    failure = None
    try:
        run = run_schedule(built, options=options, progress=watch, stop=crossed, max_cuts=max_cuts)
    except RampInterrupted as stopped:
        run = stopped.result
    except RampFailed as failed:  # no equilibrium past some step: what it reached is the answer
        if not failed.result.steps:  # not even at rest
            raise
        run, failure = failed.result, str(failed)
    values = run.history[column]
    k = crossing(values, wanted)
    if k is None:
        closest = int(np.argmin(np.abs(values - wanted)))
        return OutputReach(
            column,
            wanted,
            False,
            float(values[closest]),
            float(closest),
            schedule.commands(closest),
            run,
            [],
            time.perf_counter() - started,
            failure,
        )
    u0, c0, before = run.displacements[k - 1], schedule.commands(k - 1), run.steps[k - 1]
    solver = NewtonSolver(built.model, options)
    stretches = built.mesh.fields
    evaluations: list[tuple[float, float]] = []

    def measure(s: float) -> float:
        commands = schedule.commands(s)
        u, _, _, records, cuts = settle(built, solver, c0, u0, commands)
        built.set_commands(commands)
        built.model.set_displacements(u)
        record, _ = step_record(built, k, commands, u, records, cuts, math.nan, stretches, before)
        evaluations.append((s, float(record.row()[column])))
        return evaluations[-1][1] - wanted

    if values[k] == wanted or values[k - 1] == wanted:
        step = float(k if values[k] == wanted else k - 1)
    else:
        ends = measure(k - 1), measure(k)  # re-solved from step k - 1: they need not bracket D as the ramp's did
        if ends[0] * ends[1] > 0:
            step = float(k - 1 if abs(ends[0]) < abs(ends[1]) else k)  # the nearer end, checked below
        else:
            step = float(brentq(measure, k - 1, k, xtol=xtol))
    value = wanted + measure(step)
    return OutputReach(
        column,
        wanted,
        bool(abs(value - wanted) <= RTOL * max(abs(values[k] - values[k - 1]), abs(wanted))),
        value,
        step,
        schedule.commands(step),
        run,
        evaluations,
        time.perf_counter() - started,
    )
