"""One evaluation of an optimisation: a design (the base scene with the trial's values set) simulated in a worker
process or on a Ray node, returned as plain data: its record (the summary and the history, which the objectives are
read from in the optimising process, study/goals.py) and its files' contents (scene TOML, summary JSON, history CSV,
history plot PNG), which the optimising process writes under --out (so a Ray node elsewhere writes nothing).
evaluate_design never raises: an invalid design or a ramp without equilibrium is the evaluation's error.
"""

from __future__ import annotations

import io
import json
import time
from contextlib import redirect_stdout

from .. import runtime
from ..errors import PneumaInputError
from ..fem import sizing
from ..solve.simulate import RampStopped
from .task import Task, one_line

FILES = ("scene.toml", "summary.json", "history.csv", "plot.png")  # an evaluation's files, in its folder


def contents(result, interrupted: bool) -> tuple[dict, dict]:
    """A run's record {"summary", "history": {column: list}} and its files' contents (FILES)."""
    summary = result.summary(interrupted)
    figure = result.plot()
    png = io.BytesIO()
    figure.savefig(png, format="png", dpi=90)
    record = {"summary": summary, "history": {k: v.tolist() for k, v in result.history.items()}}
    files = {
        "scene.toml": result.scene.to_toml(),
        "summary.json": json.dumps(summary, indent=2) + "\n",
        "history.csv": result.history_csv(),
        "plot.png": png.getvalue(),
    }
    return record, files


def evaluate_design(task: Task) -> dict:
    """Simulate the task's design (its base scene with task.values set) here; never raises. Returns {"values",
    "record" (None if it did not run), "files" ({} if none), "error" (None or one line), "seconds"}."""
    from ..api import simulate

    start = time.perf_counter()
    row: dict = {"values": dict(task.values), "record": None, "files": {}, "error": None}
    try:
        with redirect_stdout(io.StringIO()):  # ti.init prints its arch, once per worker
            runtime.init(task.options.arch, cpu_threads=1)
        scene = task.design()
        o = task.options
        sizing.check_scene(scene, o.max_triangles, o.max_increments, o.max_fibers, o.max_obstacles)
        result = simulate(
            scene, tol=o.tol, max_iterations=o.max_iterations, max_cuts=o.max_cuts, max_triangles=o.max_triangles
        )
        row["record"], row["files"] = contents(result, False)
    except RampStopped as exc:  # no equilibrium: the files of the steps done, and the error
        if exc.result.steps:
            row["record"], row["files"] = contents(exc.result, True)
        row["error"] = one_line(exc)
    except PneumaInputError as exc:
        row["error"] = one_line(exc)
    except Exception as exc:  # noqa: BLE001 -- a failing design never stops the optimisation
        row["error"] = f"{type(exc).__name__}: {one_line(exc)}"
    row["seconds"] = time.perf_counter() - start
    return row
