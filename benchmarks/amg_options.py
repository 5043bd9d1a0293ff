"""pyamg's options for the multigrid preconditioner of CG (solve/linsolve.py AmgConjugateGradient) on the
Hessians of quadratic tetrahedra: the 3D reference beam of accuracy_3d.py (nested level 1 by default: 6,416
quadratic tetrahedra, 32,064 DOFs, nu = 0.45), its first Newton iterations recorded as they are solved
(matrix, right-hand side, the chamber's rank-1 part), then each recorded system solved again by CG with a
hierarchy of each option set, to the relative residual 1e-2 (Newton's largest forcing term), at most 300
iterations. Per system and option set: the hierarchy's levels and operator complexity, set-up seconds, CG
iterations and seconds.

    python benchmarks/amg_options.py [--level 1] [--systems 8] [--out benchmarks/results]

Writes amg_options.md and .json (machine, date).
"""

import argparse
import itertools
import os
import platform
import sys
import time
from datetime import date
from pathlib import Path

import numpy as np
import scipy.sparse.linalg as spla

from taichi_pneuma import runtime
from taichi_pneuma.io.output import prepare_directory, save_json, save_text
from taichi_pneuma.solve import linsolve
from taichi_pneuma.solve.newton import NewtonOptions
from taichi_pneuma.solve.simulate import RampInterrupted, run_schedule

sys.path.insert(0, str(Path(__file__).resolve().parent))
from accuracy_3d import case_of, meshes, scene_of  # noqa: E402

RTOL, MAX_ITERATIONS = 1e-2, 300
STRONG = ("symmetric", {"theta": 0.08})
OPTION_SETS = {
    "pyamg's defaults": {},
    "strength 0.08": {"strength": STRONG},
    "energy smoothing": {"smooth": "energy"},
    "strength 0.04, energy": {"strength": ("symmetric", {"theta": 0.04}), "smooth": "energy"},
    "strength 0.08, energy (used)": {"strength": STRONG, "smooth": "energy"},
    "strength 0.15, energy": {"strength": ("symmetric", {"theta": 0.15}), "smooth": "energy"},
}


def recorded_systems(level: int, count: int) -> tuple[list[dict], np.ndarray, int]:
    """The first `count` systems CG is given in a ramp of the quadratic beam on nested level `level`, the
    nodes at rest and the DOFs."""
    systems = []
    solve = linsolve.AmgConjugateGradient.solve

    def recording(backend, rhs, low_rank=(), rtol=None):
        if len(systems) < count:
            systems.append({"matrix": backend._matrix, "rhs": rhs.copy(), "low_rank": low_rank})
        return solve(backend, rhs, low_rank, rtol)

    case = case_of("beam")
    built = scene_of(case, meshes(case, level + 1)[level], 2, 0.45).build()
    linsolve.AmgConjugateGradient.solve = recording
    try:
        run_schedule(built, options=NewtonOptions(linear_solver="amg"), stop=lambda: len(systems) >= count)
    except RampInterrupted:
        pass
    finally:
        linsolve.AmgConjugateGradient.solve = solve
    return systems, built.model.config.rest, built.model.n_dofs


def cg_run(system: dict, options: dict, modes: np.ndarray) -> dict:
    import pyamg

    matrix, rhs = system["matrix"], system["rhs"]

    def apply(x):
        y = matrix @ x
        for dofs, u, c in system["low_rank"]:
            y[dofs] += c * float(u @ x[dofs]) * u
        return y

    start = time.perf_counter()
    hierarchy = pyamg.smoothed_aggregation_solver(
        matrix.tobsr(blocksize=(3, 3)), B=modes, symmetry="hermitian", **options
    )
    setup = time.perf_counter() - start
    count = itertools.count()
    start = time.perf_counter()
    _, info = spla.cg(
        spla.LinearOperator(matrix.shape, matvec=apply),
        rhs,
        rtol=RTOL,
        maxiter=MAX_ITERATIONS,
        M=hierarchy.aspreconditioner(cycle="V"),
        callback=lambda _: next(count),
    )
    return {
        "levels": len(hierarchy.levels),
        "complexity": hierarchy.operator_complexity(),
        "setup_seconds": setup,
        "iterations": next(count),
        "converged": info == 0,
        "cg_seconds": time.perf_counter() - start,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--level", type=int, default=1, help="the nested level of accuracy_3d's beam")
    parser.add_argument("--systems", type=int, default=8, help="the ramp's first systems to record")
    parser.add_argument("--out", default="benchmarks/results")
    args = parser.parse_args()
    out = prepare_directory(args.out)
    runtime.init("cpu")
    systems, rest, dofs = recorded_systems(args.level, args.systems)
    modes = linsolve.rigid_body_modes(rest)
    rows = []
    for k, system in enumerate(systems):
        for name, options in OPTION_SETS.items():
            rows.append({"system": k, "options": name, **cg_run(system, options, modes)})
            r = rows[-1]
            print(
                f"system {k}, {name}: {r['levels']} levels, complexity {r['complexity']:.2f}, set-up "
                f"{r['setup_seconds']:.1f} s, {r['iterations']} CG iterations{'' if r['converged'] else ' (failed)'}, "
                f"{r['cg_seconds']:.1f} s",
                flush=True,
            )
    machine = f"{platform.node()}, {platform.machine()}, {os.cpu_count()} CPUs"
    lines = [
        f"Machine: {machine}; {date.today()}. The quadratic beam, nested level {args.level}: {dofs} DOFs; "
        f"CG to a relative residual of {RTOL:g}, at most {MAX_ITERATIONS} iterations.",
        "",
        "| options | " + " | ".join(f"system {k}" for k in range(len(systems))) + " | levels | complexity |",
        "|---|" + "---|" * (len(systems) + 2),
    ]
    for name in OPTION_SETS:
        mine = [r for r in rows if r["options"] == name]
        cells = [f"{r['iterations']}" + ("" if r["converged"] else " (failed)") for r in mine]
        lines.append(f"| {name} | " + " | ".join(cells) + f" | {mine[-1]['levels']} | {mine[-1]['complexity']:.2f} |")
    text = "\n".join(lines) + "\n\nCells: CG iterations.\n"
    print(text)
    save_text(out / "amg_options.md", text)
    save_json(
        out / "amg_options.json",
        {"machine": machine, "date": str(date.today()), "level": args.level, "dofs": dofs, "rtol": RTOL, "runs": rows},
    )


if __name__ == "__main__":
    main()
