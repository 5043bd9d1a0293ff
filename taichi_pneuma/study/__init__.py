"""Design studies: one scene run many times with dotted scene keys varied over a grid or a Latin hypercube sample,
each run a task on a local process pool or on Ray, one CSV row per run (pneuma-sweep).

    from taichi_pneuma.study import LocalPool, Sweep, parse_vary
    sweep = Sweep(scene, [parse_vary("cy=-0.15:0.15:5"), parse_vary("E=1e4,2e4")], out="out", name="sweep")
    with LocalPool(workers=2) as pool:
        report = sweep.run(pool, on_row=print)

vary.py: the varied keys and the planned runs; task.py: one run; executors.py: the process pool and Ray;
table.py: the CSV, written and read back to resume; figure.py: the plot; sweep.py: the study (Sweep);
template.py: a Python file whose scene(**parameters) makes each design (an optimisation's CAD parameters).
"""

from .executors import LocalPool, RayCluster
from .figure import study_figure
from .sweep import Report, Sweep
from .task import RunOptions, Task, run_task
from .template import SceneTemplate
from .vary import Axis, check_axes, parse_vary, plan

__all__ = [
    "Axis",
    "LocalPool",
    "RayCluster",
    "Report",
    "RunOptions",
    "SceneTemplate",
    "Sweep",
    "Task",
    "check_axes",
    "parse_vary",
    "plan",
    "run_task",
    "study_figure",
]
