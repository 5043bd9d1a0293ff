"""The design optimiser against a grid sweep: pneuma-optimize's TPE with at most a third of a 100-point grid's
evaluations (33) against the best design of the 10 x 10 grid of the same two variables, on the process pool and on a
local Ray.

    python benchmarks/optimize_vs_grid.py [--out benchmarks/results] [--workers 2] [--seeds 3] [--no-ray]

The problem (a cheap 2D one: the 3D fibre actuator of docs/optimize.md takes about a minute a design on this
machine, 100 of them more than an hour): the beam of benchmarks/optimize_beam.toml, its chamber's height above the
axis cy = chambers[0].center[1] in [0, 0.2] and half-height b = chambers[0].semi_axes[1] in [0.08, 0.18]; minimise
the chamber pressure at which the tip has turned through +6 degrees, at(main.pressure, tip_rotation, 6), subject to
the largest principal stretch at that moment at(max_stretch, tip_rotation, 6) <= 1.35. The grid: 10 evenly spaced
values of each, ends included, every design run by the same worker function (study/design.py) and scored by the
same goals (study/goals.py). The optimiser: Optimization (study/optimize.py), sampler TPE, seeds 0 .. --seeds - 1,
33 evaluations each, in batches of the executor's workers. A design is as good as the grid's best if its feasible
objective is <= the grid's best feasible objective.

Writes optimize_vs_grid.md and optimize_vs_grid.json (machine and date) under --out; prints the table.
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

SCENE = Path(__file__).resolve().parent / "optimize_beam.toml"
# two boxes of the same variables: cy up to 0.2, where the best design lies on that bound (a grid samples bounds
# exactly), and up to 0.3, where designs past cy + b = 0.4 (the chamber through the top face) fail and the best lies
# inside the box
PROBLEMS = {
    "cy in [0, 0.2]": ["chambers[0].center[1]=0:0.2", "chambers[0].semi_axes[1]=0.08:0.18"],
    "cy in [0, 0.3]": ["chambers[0].center[1]=0:0.3", "chambers[0].semi_axes[1]=0.08:0.18"],
}
OBJECTIVE = "at(main.pressure, tip_rotation, 6)"
CONSTRAINT = "at(max_stretch, tip_rotation, 6)<=1.35"
GRID = 10  # values per variable: 100 designs
BUDGET = 33  # the optimiser's evaluations: at most a third of the grid's


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
    }


def optimise(base, goals: Goals, executor, variables: list[str], seed: int, target: float) -> dict:
    """33 evaluations of TPE (seed) on the (entered) executor in a fresh directory; the best feasible design and the
    evaluation at which the best so far first reached the grid's best (None: never)."""
    axes = [parse_vary(v) for v in variables]
    with tempfile.TemporaryDirectory() as tmp:
        optimization = Optimization(base, axes, goals, tmp, "optimize", BUDGET, "tpe", seed)
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
    }


def compare(base, goals: Goals, variables: list[str], workers: int, seeds: int, ray: bool) -> tuple[dict, list[dict]]:
    """The grid on the pool, then TPE with each seed on the pool and (ray) on a local Ray."""
    with LocalPool(workers) as pool:
        reference = grid(base, goals, pool, variables)
        target = reference["best"]["objective"]
        print(f"grid: best {target:.4f} at {reference['best']} ({reference['wall_s']:.1f} s)", flush=True)
        runs = [{"executor": "process pool", **optimise(base, goals, pool, variables, s, target)} for s in range(seeds)]
    if ray:
        with RayCluster(None, workers) as cluster:
            runs += [
                {"executor": "local Ray", **optimise(base, goals, cluster, variables, s, target)} for s in range(seeds)
            ]
    for run in runs:
        print(run, flush=True)
    return reference, runs


def table(reference: dict, runs: list[dict]) -> str:
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
            "TPE",
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
    header = ["method", "executor", "seed", "evaluations", "best feasible pressure", "at (cy, b)"]
    return markdown([*header, "evaluation reaching the grid's best", "wall (s)"], rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="benchmarks/results")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--no-ray", action="store_true", help="the process pool only")
    args = parser.parse_args()
    base = tp.load_scene(SCENE)
    goals = Goals.parse(base, [("minimize", OBJECTIVE)], [CONSTRAINT])
    m = machine()
    where = f"{m['machine']}, {m['cpu']}, {m['cores']} cores, {args.workers} workers, {date.today().isoformat()}"
    sections, results = [], {}
    for title, variables in PROBLEMS.items():
        reference, runs = compare(base, goals, variables, args.workers, args.seeds, not args.no_ray)
        good = sum(r["as_good"] for r in runs)
        sections.append(
            f"### {title}, b in [0.08, 0.18]\n\n{good} of {len(runs)} optimiser runs of {BUDGET} evaluations found "
            f"a design at least as good as the best of the {reference['evaluations']}-point grid "
            f"({reference['feasible']} of its designs feasible).\n\n{table(reference, runs)}"
        )
        results[title] = {"variables": variables, "grid": reference, "runs": runs}
    text = (
        f"Machine: {where}\n\nMinimise {OBJECTIVE} subject to {CONSTRAINT} over cy = chambers[0].center[1] and "
        f"b = chambers[0].semi_axes[1] (benchmarks/optimize_beam.toml, 2D), TPE against a 10 x 10 grid.\n\n"
        + "\n".join(sections)
    )
    out = prepare_directory(args.out)
    save_text(out / "optimize_vs_grid.md", text)
    save_json(out / "optimize_vs_grid.json", {"machine": m, "versions": versions(ray=not args.no_ray), **results})
    print(text)


if __name__ == "__main__":
    main()
