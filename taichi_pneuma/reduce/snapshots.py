"""Training snapshots: equilibria u_s of the full model at commands c_s spread over the scene's actuation space.

The commands are the scene's own schedule (every increment) and a Latin hypercube of K points (scipy.stats.qmc)
in the box [c_lo, c_hi] of the schedule's commands (a command the schedule holds fixed stays fixed). The schedule is
run by run_schedule; each hypercube point is solved by settle (cut-backs included) from the equilibrium already solved
whose commands are nearest to it, the distance measured in units of the box's widths. A point that finds no
equilibrium is left out and counted.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from scipy.stats import qmc

from ..scene.build import BuiltScene
from ..solve.newton import NewtonOptions, NewtonSolver
from ..solve.simulate import NoEquilibrium, run_schedule, settle


@dataclass
class Snapshots:
    """commands (S, c) and displacements (S, n d) of S equilibria; failed: hypercube points left out (no equilibrium);
    seconds: the wall time of the full solves."""

    commands: np.ndarray
    displacements: np.ndarray
    failed: int
    seconds: float


def command_box(built: BuiltScene) -> tuple[np.ndarray, np.ndarray]:
    """(c_lo, c_hi): the smallest and largest command of every kind the scene's schedule gives, its rest included."""
    schedule = built.scene.schedule
    commands = np.array([schedule.commands(i) for i in range(schedule.increments + 1)])
    return commands.min(axis=0), commands.max(axis=0)


def hypercube(low: np.ndarray, high: np.ndarray, samples: int, seed: int) -> np.ndarray:
    """`samples` points (samples, c) of a Latin hypercube in the box [low, high] (a command with low = high fixed)."""
    unit = qmc.LatinHypercube(d=len(low), seed=seed).random(samples)
    return low + unit * (high - low)


def nearest(commands: np.ndarray, target: np.ndarray, low: np.ndarray, high: np.ndarray) -> int:
    """The row of commands (S, c) nearest to target, in units of the box's widths (a fixed command not counted)."""
    width = np.where(high > low, high - low, 1.0)
    return int(np.argmin(np.linalg.norm((commands - target) / width, axis=1)))


def solve_snapshots(built: BuiltScene, samples: int, seed: int = 0, options: NewtonOptions | None = None) -> Snapshots:
    """The scene's schedule, then `samples` hypercube points in its command box, each solved by the full model (the
    module docstring). The model is left at rest commands and displacements."""
    start = time.perf_counter()
    run = run_schedule(built, options=options)
    commands = [built.scene.schedule.commands(i) for i in range(built.scene.schedule.increments + 1)]
    states = list(run.displacements.reshape(len(commands), -1))
    low, high = command_box(built)
    solver = NewtonSolver(built.model, options)
    failed = 0
    for target in hypercube(low, high, samples, seed) if samples else []:
        i = nearest(np.array(commands), target, low, high)
        built.set_commands(commands[i])
        built.model.set_displacements(states[i])
        try:
            u, *_ = settle(built, solver, commands[i], states[i].reshape(built.mesh.vertices.shape), target)
        except NoEquilibrium:
            failed += 1
            continue
        commands.append(target)
        states.append(u.ravel())
    built.set_commands(built.scene.schedule.rest_commands)
    built.model.set_displacements(np.zeros(built.model.n_dofs))
    return Snapshots(np.array(commands), np.array(states), failed, time.perf_counter() - start)
