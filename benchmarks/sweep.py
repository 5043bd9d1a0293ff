"""Design-study throughput: a 24-run study on 1 and 2 pool workers (and on a local Ray), and the
per-task overhead of Ray against the process pool's.

    python benchmarks/sweep.py [--out benchmarks/results] [--workers 2]

1. The study: the reference beam (full mesh, 35 increments), chamber height cy in 6 values from
   -0.15 to 0.15 times Young's modulus E in 4 values: 24 reference ramps. Wall time from the executor's
   start (worker processes spawned and their kernels loaded, or Ray started) to the last row written.
2. Overhead: 24 tiny runs (max area 0.05, 2 increments) on executors already warm (every worker has
   run a task); overhead per task = wall x workers / tasks - the mean time measured inside a task.
   The pool's per-task cost is pickling and a pipe; Ray's is its scheduler and object store.

Writes bench_sweep.md and bench_sweep.json (machine and date) under --out; prints the tables.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from datetime import date
from pathlib import Path

import numpy as np

from taichi_pneuma.apps.bench import markdown
from taichi_pneuma.io.output import prepare_directory, save_json, save_text
from taichi_pneuma.scene.build import reference_scene
from taichi_pneuma.study import LocalPool, RayCluster, Sweep, Task, parse_vary
from taichi_pneuma.study.sweep import machine, versions

BASE = reference_scene(0.15)
AXES = [parse_vary("cy=-0.15:0.15:6"), parse_vary("material.E=5e3:2e4:4")]
TINY = BASE.with_values({"mesh.max_area": 0.05, "schedule.increments": 2, "chambers[0].keyframes": [[2, 1.5]]})


def timed_study(executor) -> dict:
    """Run the 24-run study in a fresh directory on an executor (not yet entered)."""
    with tempfile.TemporaryDirectory() as tmp:
        sweep = Sweep(BASE, AXES, tmp)
        start = time.perf_counter()
        with executor:
            started = time.perf_counter()
            report = sweep.run(executor)
        wall = time.perf_counter() - start
    seconds = [r["seconds"] for r in report.rows]
    return {
        "runs": report.ran,
        "failed": report.failed,
        "wall_s": wall,
        "start_s": started - start,
        "runs_per_s": report.ran / wall,
        "mean_run_s": float(np.mean(seconds)),
    }


def timed_overhead(executor, workers: int, n: int = 24) -> dict:
    """n tiny runs on a warm executor: wall per task, time inside a task, overhead per task."""
    scene = TINY.to_toml()
    tasks = [Task(scene, {"chambers[0].center[1]": float(cy)}) for cy in np.linspace(-0.1, 0.1, n)]
    with executor:
        for _ in executor.run(tasks[: 4 * workers]):  # warm: workers started, kernels loaded
            pass
        start = time.perf_counter()
        rows = [row for _, row in executor.run(tasks)]
        wall = time.perf_counter() - start
    inside = float(np.mean([r["seconds"] for r in rows]))
    assert all(r["error"] is None for r in rows), [r["error"] for r in rows]
    return {
        "tasks": n,
        "wall_per_task_ms": 1e3 * wall / n,
        "inside_ms": 1e3 * inside,
        "overhead_ms": 1e3 * (wall * workers / n - inside),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default="benchmarks/results")
    parser.add_argument("--workers", type=int, default=2, help="the parallel case's workers")
    parser.add_argument("--no-ray", action="store_true", help="skip the Ray rows")
    args = parser.parse_args()
    out = prepare_directory(args.out)
    n = args.workers
    studies = {"pool, 1 worker": timed_study(LocalPool(1)), f"pool, {n} workers": timed_study(LocalPool(n))}
    overheads = {"pool": timed_overhead(LocalPool(n), n)}
    if not args.no_ray:
        studies[f"local Ray, {n} CPUs"] = timed_study(RayCluster(None, n))
        overheads["Ray"] = timed_overhead(RayCluster(None, n), n)
    one = studies["pool, 1 worker"]["wall_s"]
    study_table = markdown(
        [
            "executor",
            "runs",
            "wall (s)",
            "of which executor start (s)",
            "runs/s",
            "speedup vs 1 worker",
            "mean run (s, inside the worker)",
        ],
        [
            [
                name,
                s["runs"],
                f"{s['wall_s']:.1f}",
                f"{s['start_s']:.1f}",
                f"{s['runs_per_s']:.2f}",
                f"{one / s['wall_s']:.2f}",
                f"{s['mean_run_s']:.2f}",
            ]
            for name, s in studies.items()
        ],
    )
    overhead_table = markdown(
        [
            f"executor ({n} workers, warm)",
            "tiny tasks",
            "wall per task (ms)",
            "inside a task (ms)",
            "overhead per task (ms)",
        ],
        [
            [name, o["tasks"], f"{o['wall_per_task_ms']:.1f}", f"{o['inside_ms']:.1f}", f"{o['overhead_ms']:.1f}"]
            for name, o in overheads.items()
        ],
    )
    info = machine()
    where = f"{info['machine']}, {info['cpu']}, {info['cores']} cores, {date.today()}"
    text = (
        f"Machine: {where}\n\n24-run study (reference beam, cy x E = 6 x 4, 35 increments each):\n\n"
        f"{study_table}\nPer-task overhead:\n\n{overhead_table}"
    )
    print(text)
    save_text(Path(out) / "bench_sweep.md", text)
    save_json(
        Path(out) / "bench_sweep.json",
        {
            "machine": info,
            "date": str(date.today()),
            "versions": versions(ray=not args.no_ray),
            "studies": studies,
            "overheads": overheads,
        },
    )


if __name__ == "__main__":
    main()
