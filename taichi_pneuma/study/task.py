"""One run of a study: a Task is plain data (the base scene's TOML text, the values of the varied keys, the
options every run shares), so that it travels to a worker process or a Ray node; run_task runs it there and
never raises: an invalid scene, a ramp with no equilibrium or any other exception becomes the row's `error`.
"""

from __future__ import annotations

import io
import time
import tomllib
from contextlib import redirect_stdout
from dataclasses import dataclass, field

import numpy as np

from .. import limits, runtime
from ..errors import PneumaInputError
from ..fem import sizing
from ..fem.tip import COLUMNS as TIP_COLUMNS
from ..scene.scenefile import read_scene
from ..solve.newton import NewtonOptions
from ..solve.simulate import MAX_CUTS, RampStopped
from .template import SceneTemplate

MAX_ERROR = 1_000  # characters of a run's error kept in its row


@dataclass(frozen=True)
class RunOptions:
    """What every run of a study shares besides the scene: Newton's settings, the resource limits, the backend."""

    tol: float = NewtonOptions.tol
    max_iterations: int = NewtonOptions.max_iterations
    max_cuts: int = MAX_CUTS
    max_triangles: int = limits.MAX_TRIANGLES
    max_increments: int = limits.MAX_INCREMENTS
    max_fibers: int = limits.MAX_FIBERS
    max_obstacles: int = limits.MAX_OBSTACLES
    arch: str = "cpu"


@dataclass(frozen=True)
class Task:
    scene: str  # the base scene's TOML text
    values: dict  # dotted key -> value (a template's: its parameter -> value)
    options: RunOptions = field(default_factory=RunOptions)
    template: SceneTemplate | None = None  # the design is template.build(values), not the base scene edited

    def design(self):
        """The Scene of this run: the template's, or the base scene with the values set."""
        if self.template is not None:
            return self.template.build(self.values)
        return read_scene(tomllib.loads(self.scene), "scene").with_values(self.values)


def one_line(exc: BaseException) -> str:
    """The exception's message on one line, cut to MAX_ERROR characters."""
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if len(text) <= MAX_ERROR else text[: MAX_ERROR - 3] + "..."


def measures(result, names: list[str]) -> dict:
    """The row's figures of an api.Result (finished or partial); its chambers' columns are named `names`
    (the base scene's chamber names: a run that varies a chamber's name keeps the study's columns)."""
    final = result.steps[-1]
    row = {"tip_dx": float(final.tip_dx), "tip_dy": float(final.tip_dy), "tip_rotation": float(final.tip_rotation)}
    row.update({column: float(value) for column, value in zip(TIP_COLUMNS[2:], final.tip[2:])})  # 3D: tip_dz
    if final.tip_twist is not None:
        row["tip_twist"] = float(final.tip_twist)
    if final.blocked_force is not None:
        row["blocked_force"] = float(final.blocked_force)
    for i, name in enumerate(names):
        row[f"{name}.area_ratio"] = float(result.area_ratio[-1, i])
        row[f"{name}.peak_pressure"] = float(np.abs(result.pressure[:, i]).max())
    row.update(
        converged=result.converged,
        iterations=int(result.history["iterations"].sum()),
        increments=len(result.steps) - 1,
        vertices=int(result.mesh.n_vertices),
    )
    return row


def run_task(task: Task) -> dict:
    """Run one scene of a study; never raises. Returns the row: the varied values, the figures (those of
    the steps done, for a ramp that stopped), converged, seconds, and error (None, or one line)."""
    from ..api import simulate

    start = time.perf_counter()
    row = dict(task.values)
    try:
        with redirect_stdout(io.StringIO()):  # ti.init prints its arch, once per worker
            runtime.init(task.options.arch, cpu_threads=1)
        base = read_scene(tomllib.loads(task.scene), "scene")
        names = base.chamber_names
        scene = base.with_values(task.values)
        o = task.options
        sizing.check_scene(scene, o.max_triangles, o.max_increments, o.max_fibers, o.max_obstacles)
        options = task.options
        row.update(
            measures(
                simulate(
                    scene,
                    tol=options.tol,
                    max_iterations=options.max_iterations,
                    max_cuts=options.max_cuts,
                    max_triangles=options.max_triangles,
                ),
                names,
            ),
            error=None,
        )
    except RampStopped as exc:  # no equilibrium: keep the figures of the steps done
        if exc.result.steps:
            row.update(measures(exc.result, names), converged=False)
        row["error"] = one_line(exc)
    except PneumaInputError as exc:
        row["error"] = one_line(exc)
    except Exception as exc:  # noqa: BLE001 -- a failing run never stops the study
        row["error"] = f"{type(exc).__name__}: {one_line(exc)}"
    row["seconds"] = time.perf_counter() - start
    return row
