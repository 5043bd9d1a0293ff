"""The design optimiser against a grid sweep: pneuma-optimize with at most a third of a 100-point grid's evaluations
(33) against the best design of the 10 x 10 grid of the same two variables, on the process pool and on a local Ray.

    python benchmarks/optimize_vs_grid.py [--problem 2d|3d] [--out benchmarks/results] [--workers 2] [--seeds 3]
        [--no-ray] [--refined-only]

The problems:
- 2d (cheap): the beam of benchmarks/optimize_beam.toml, its chamber's height above the axis
  cy = chambers[0].center[1] and half-height b = chambers[0].semi_axes[1] in [0.08, 0.18]; minimise the chamber
  pressure at which the tip has turned through +6 degrees, at(main.pressure, tip_rotation, 6), subject to the
  largest principal stretch then, at(max_stretch, tip_rotation, 6) <= 1.35; on two boxes, cy in [0, 0.2] and in
  [0, 0.3] (BOXES).
- 3d: the docs' worked example (docs/guide/optimize.md) on a coarser mesh, benchmarks/optimize_fiber.toml: the fibre
  actuator's chamber radius in [5, 6.5] mm and the threads' pitch in [3, 8] mm; minimise the pressure at which the
  tip has turned through -90 degrees subject to the largest stretch then <= 1.5.

The grid: 10 evenly spaced values of each variable, ends included, every design run by the same worker function
(study/design.py) and scored by the same goals (study/goals.py). The optimiser (Optimization, study/optimize.py),
seeds 0 .. --seeds - 1, 33 evaluations each: METHODS, TPE alone (on the pool) and TPE with its last 13 evaluations
refining by COBYQA (--refine 13, study/refine.py; on the pool and on a local Ray). A design is as good as the grid's
best if its feasible objective is <= the grid's best feasible objective.

Writes optimize_vs_grid.md and .json (2d) or optimize_vs_grid_3d.md and .json (3d), machine and date, under --out;
prints the table.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from datetime import date
from pathlib import Path

import numpy as np

import taichi_pneuma as tp
from taichi_pneuma.apps.bench import markdown
from taichi_pneuma.io.output import prepare_directory, save_json, save_text
from taichi_pneuma.study import LocalPool, RayCluster, Task, parse_vary
from taichi_pneuma.study.design import evaluate_design
from taichi_pneuma.study.goals import Goals, NoValue
from taichi_pneuma.study.optimize import Optimization
from taichi_pneuma.study.sweep import machine, versions

HERE = Path(__file__).resolve().parent
# each problem: its scene, its objective and constraint, its boxes (titled) of the same two variables. The 2D
# beam's two boxes: cy up to 0.2, where the best design lies on that bound (a grid samples bounds exactly), and up
# to 0.3, where designs past about cy + b = 0.4 (the chamber through the top face) fail and the best lies inside
PROBLEMS = {
    "2d": {
        "scene": HERE / "optimize_beam.toml",
        "objective": "at(main.pressure, tip_rotation, 6)",
        "constraint": "at(max_stretch, tip_rotation, 6)<=1.35",
        "boxes": {
            "cy in [0, 0.2], b in [0.08, 0.18]": ["chambers[0].center[1]=0:0.2", "chambers[0].semi_axes[1]=0.08:0.18"],
            "cy in [0, 0.3], b in [0.08, 0.18]": ["chambers[0].center[1]=0:0.3", "chambers[0].semi_axes[1]=0.08:0.18"],
        },
        "stem": "optimize_vs_grid",
    },
    "3d": {
        "scene": HERE / "optimize_fiber.toml",
        "objective": "at(chamber.pressure, tip_rotation, -90)",
        "constraint": "at(max_stretch, tip_rotation, -90)<=1.5",
        "boxes": {
            "chamber radius in [5, 6.5] mm, pitch in [3, 8] mm": [
                "chambers[0].radius=5:6.5",
                "fibers[0].path.pitch=3:8",
            ]
        },
        "stem": "optimize_vs_grid_3d",
    },
}
GRID = 10  # values per variable: 100 designs
BUDGET = 33  # the optimiser's evaluations: at most a third of the grid's
REFINE = 13  # of them, the last refining by COBYQA
METHODS = {"TPE": (0, False), f"TPE, then {REFINE} of COBYQA": (REFINE, True)}  # name: (refine, also on Ray)


def grid(base, goals: Goals, executor, variables: list[str]) -> dict:
    """Every design of the 10 x 10 grid run on the (entered) executor; the best feasible one."""
    axes = [parse_vary(v) for v in variables]
    values = [np.linspace(a.low, a.high, GRID) for a in axes]
    designs = [{axes[0].key: float(x), axes[1].key: float(y)} for x in values[0] for y in values[1]]
    scene = base.to_toml()
    start = time.perf_counter()
    scored = []
    for _, row in executor.run([Task(scene, d) for d in designs], evaluate_design):
        if row is None or row["error"] is not None:
            continue
        try:
            objectives, violations = goals.evaluate(row["record"])
        except NoValue:
            continue
        scored.append({**row["values"], "objective": objectives[0], "feasible": all(v <= 0 for v in violations)})
    feasible = [s for s in scored if s["feasible"]]
    best = min(feasible, key=lambda s: s["objective"])
    return {
        "evaluations": len(designs),
        "scored": len(scored),
        "feasible": len(feasible),
        "best": best,
        "wall_s": time.perf_counter() - start,
        "designs": scored,
    }


def optimise(base, goals: Goals, executor, variables: list[str], seed: int, refine: int, target: float) -> dict:
    """33 evaluations of TPE (seed), the last `refine` by COBYQA, on the (entered) executor in a fresh directory; the
    best feasible design and the evaluation at which the best so far first reached the grid's best (None: never)."""
    axes = [parse_vary(v) for v in variables]
    with tempfile.TemporaryDirectory() as tmp:
        optimization = Optimization(base, axes, goals, tmp, "optimize", BUDGET, "tpe", seed, refine=refine)
        start = time.perf_counter()
        report = optimization.run(executor)
        wall = time.perf_counter() - start
    reached = next(
        (i + 1 for i, r in enumerate(report.rows) if r["feasible"] and r["objective_0"] <= target + 1e-12), None
    )
    best = report.best
    return {
        "seed": seed,
        "evaluations": len(report.rows),
        "failed": sum(r["error"] is not None for r in report.rows),
        "best": None if best is None else {k: best[k] for k in (*optimization.keys, "objective_0")},
        "as_good": best is not None and best["objective_0"] <= target + 1e-12,
        "reached_at": reached,
        "wall_s": wall,
        "rows": [{k: r[k] for k in (*optimization.keys, "objective_0", "feasible", "error")} for r in report.rows],
    }


def compare(
    base, goals: Goals, variables: list[str], workers: int, seeds: int, ray: bool, methods: dict
) -> tuple[dict, list[dict]]:
    """The grid on the pool, then each method with each seed on the pool and (ray, for the methods that say so) on
    a local Ray."""
    runs = []

    def method_runs(executor, where: str, on_ray: bool) -> None:
        for method, (refine, also_ray) in methods.items():
            for seed in range(seeds if also_ray or not on_ray else 0):
                run = optimise(base, goals, executor, variables, seed, refine, target)
                runs.append({"method": method, "executor": where, **run})
                print(runs[-1], flush=True)

    with LocalPool(workers) as pool:
        reference = grid(base, goals, pool, variables)
        target = reference["best"]["objective"]
        print(f"grid: best {target:.4f} at {reference['best']} ({reference['wall_s']:.1f} s)", flush=True)
        method_runs(pool, "process pool", False)
    if ray:
        with RayCluster(None, workers) as cluster:
            method_runs(cluster, "local Ray", True)
    return reference, runs


def table(reference: dict, runs: list[dict], objective: str) -> str:
    keys = list(runs[0]["best"] or reference["best"])[:2]
    target = reference["best"]["objective"]
    rows = [
        [
            "grid 10 x 10",
            "process pool",
            "",
            str(reference["evaluations"]),
            f"{target:.4f}",
            ", ".join(f"{reference['best'][k]:.4f}" for k in keys),
            "",
            f"{reference['wall_s']:.1f}",
        ]
    ] + [
        [
            r["method"],
            r["executor"],
            str(r["seed"]),
            str(r["evaluations"]),
            "none feasible" if r["best"] is None else f"{r['best']['objective_0']:.4f}",
            "" if r["best"] is None else ", ".join(f"{r['best'][k]:.4f}" for k in keys),
            "never" if r["reached_at"] is None else str(r["reached_at"]),
            f"{r['wall_s']:.1f}",
        ]
        for r in runs
    ]
    header = ["method", "executor", "seed", "evaluations", f"best feasible {objective}", "at"]
    return markdown([*header, "evaluation reaching the grid's best", "wall (s)"], rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--problem", choices=sorted(PROBLEMS), default="2d")
    parser.add_argument("--out", default="benchmarks/results")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--no-ray", action="store_true", help="the process pool only")
    parser.add_argument("--refined-only", action="store_true", help=f"only the method of {REFINE} of COBYQA")
    args = parser.parse_args()
    problem = PROBLEMS[args.problem]
    base = tp.load_scene(problem["scene"])
    goals = Goals.parse(base, [("minimize", problem["objective"])], [problem["constraint"]])
    m = machine()
    where = f"{m['machine']}, {m['cpu']}, {m['cores']} cores, {args.workers} workers, {date.today().isoformat()}"
    sections, results = [], {}
    for title, variables in problem["boxes"].items():
        methods = {k: v for k, v in METHODS.items() if v[0] or not args.refined_only}
        reference, runs = compare(base, goals, variables, args.workers, args.seeds, not args.no_ray, methods)
        counts = "; ".join(
            f"{method}: {sum(r['as_good'] for r in mine)} of {len(mine)}"
            for method in METHODS
            if (mine := [r for r in runs if r["method"] == method])
        )
        sections.append(
            f"### {title}\n\nOptimiser runs of {BUDGET} evaluations that found a design at least as good as the "
            f"best of the {reference['evaluations']}-point grid ({reference['feasible']} of its designs feasible): "
            f"{counts}.\n\n{table(reference, runs, problem['objective'])}"
        )
        results[title] = {"variables": variables, "grid": reference, "runs": runs}
    text = (
        f"Machine: {where}\n\nMinimise {problem['objective']} subject to {problem['constraint']} over "
        f"{' and '.join(v.split('=')[0] for v in variables)} ({problem['scene'].relative_to(HERE.parent)}), "
        f"the optimiser against a 10 x 10 grid.\n\n" + "\n".join(sections)
    )
    out = prepare_directory(args.out)
    save_text(out / f"{problem['stem']}.md", text)
    save_json(out / f"{problem['stem']}.json", {"machine": m, "versions": versions(ray=not args.no_ray), **results})
    print(text)


if __name__ == "__main__":
    main()
