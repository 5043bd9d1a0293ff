"""Training snapshots: equilibria u_s of the full model at commands c_s spread over the scene's actuation space.

The commands are the scene's own schedule (every increment) and a Latin hypercube of K points (scipy.stats.qmc)
in the box [c_lo, c_hi] of the schedule's commands (a command the schedule holds fixed stays fixed). The schedule is
run by run_schedule; each hypercube point is solved by settle (cut-backs included) from the equilibrium already solved
whose commands are nearest to it, the distance measured in units of the box's widths. A point that finds no
equilibrium is left out and counted.

Given an executor (study/executors.py: a process pool on this machine or a Ray cluster, whose run(tasks, function)
yields (index, row) and capacity() says how many run at once), the hypercube points are split into one chunk per
worker, each a PointsTask of plain data (the scene's TOML, the schedule's equilibria, its points, Newton's settings)
that solve_points solves in a worker from the same scene built there (the same mesh: the scene's TOML fixes it),
each point from the nearest equilibrium known to that worker. The schedule itself is a ramp, solved here first.
"""

from __future__ import annotations

import io
import time
import tomllib
from contextlib import redirect_stdout
from dataclasses import dataclass

import numpy as np
from scipy.stats import qmc

from ..errors import require
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


def solve_from(built: BuiltScene, solver: NewtonSolver, commands: list, states: list, targets: np.ndarray) -> int:
    """Solve each target commands (k, c) from the nearest of the equilibria (commands, states: lists, extended with
    each point solved); return how many found none. The model is left at rest commands and displacements."""
    low, high = command_box(built)
    failed = 0
    for target in targets:
        i = nearest(np.array(commands), target, low, high)
        built.set_commands(commands[i])
        built.model.set_displacements(states[i])
        try:
            u, *_ = settle(built, solver, commands[i], states[i].reshape(built.mesh.vertices.shape), target)
        except NoEquilibrium:
            failed += 1
            continue
        commands.append(np.asarray(target))
        states.append(u.ravel())
    built.set_commands(built.scene.schedule.rest_commands)
    built.model.set_displacements(np.zeros(built.model.n_dofs))
    return failed


@dataclass(frozen=True)
class PointsTask:
    """One worker's hypercube points (module docstring): plain data for a worker process or a Ray node."""

    scene: str  # the scene's TOML text
    commands: np.ndarray  # (S, c) the schedule's commands
    states: np.ndarray  # (S, n d) its equilibria
    targets: np.ndarray  # (k, c) the points
    options: NewtonOptions | None
    arch: str = "cpu"


def solve_points(task: PointsTask) -> dict:
    """Build the task's scene in this process and solve its points (solve_from); never raises. Returns {"commands"
    (k', c) and "states" (k', n d) of the points solved, "failed": how many found none, "error": None or why the
    chunk could not run}."""
    from .. import runtime
    from ..scene.scenefile import read_scene

    try:
        with redirect_stdout(io.StringIO()):  # ti.init prints its arch, once per worker
            runtime.init(task.arch, cpu_threads=1)
        built = read_scene(tomllib.loads(task.scene), "scene").build()
        require(
            built.model.n_dofs == task.states.shape[1],
            f"the worker's mesh has {built.model.n_dofs} DOFs, the scene's {task.states.shape[1]}",
        )
        commands, states = list(task.commands), list(task.states)
        failed = solve_from(built, NewtonSolver(built.model, task.options), commands, states, task.targets)
    except Exception as exc:  # noqa: BLE001 -- a worker's failure becomes its row's error, as a study run's
        return {"commands": None, "states": None, "failed": len(task.targets), "error": f"{type(exc).__name__}: {exc}"}
    n = len(task.commands)
    return {"commands": np.array(commands[n:]), "states": np.array(states[n:]), "failed": failed, "error": None}


def solve_snapshots(
    built: BuiltScene, samples: int, seed: int = 0, options: NewtonOptions | None = None, executor=None
) -> Snapshots:
    """The scene's schedule, then `samples` hypercube points in its command box, each solved by the full model (the
    module docstring): here, or on the executor's workers. The model is left at rest commands and displacements."""
    start = time.perf_counter()
    run = run_schedule(built, options=options)
    commands = [built.scene.schedule.commands(i) for i in range(built.scene.schedule.increments + 1)]
    states = list(run.displacements.reshape(len(commands), -1))
    targets = hypercube(*command_box(built), samples, seed) if samples else np.zeros((0, len(commands[0])))
    if executor is None or not len(targets):
        failed = solve_from(built, NewtonSolver(built.model, options), commands, states, targets)
        return Snapshots(np.array(commands), np.array(states), failed, time.perf_counter() - start)
    chunks = [chunk for chunk in np.array_split(targets, executor.capacity()) if len(chunk)]
    text = built.scene.to_toml()
    tasks = [PointsTask(text, np.array(commands), np.array(states), chunk, options) for chunk in chunks]
    failed = 0
    for _, row in executor.run(tasks, solve_points):
        if row is None or row["error"] is not None:
            why = "its process died" if row is None else row["error"]
            raise NoEquilibrium(f"training stopped: a worker solving hypercube points failed: {why}")
        failed += row["failed"]
        commands += list(row["commands"])
        states += list(row["states"])
    return Snapshots(np.array(commands), np.array(states), failed, time.perf_counter() - start)
