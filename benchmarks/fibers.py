"""What the tension-only cords cost per Newton iteration, on the shipped bending actuator's mesh (fiber_bending_3d:
quadratic tetrahedra, one pressure per element, a wrinkling paper sheet, two crossed 31 GPa aramid threads).

Cases, each one ramp of the scene's mesh in this process (its kernels compiled first):

- "without cords" (`fibers = []`) and "with cords" on the same ramp, short enough for both (2 increments to 4 kPa:
  without its threads the chamber balloons and finds no equilibrium past about 10.5 kPa), both as solved now;
- "with cords, sweeps refactorised" (NewtonOptions(sweep_updates=False): every branch sweep a new factorisation, as
  before solve/branch_update.py) and "with cords" on that ramp and on 2 increments to 30 kPa: old against new.

First, one factorisation of the rest state's projected Hessian with and without the cords (the same solver, the cords'
fill-in alone), and a solve with 1 and with 10 right-hand sides (what a sweep's low-rank update costs instead),
alternated, median of FACTOR_REPEATS each. Then per case: Newton iterations, chord steps (a held factorisation
reused: a cheap iteration; the model without cords takes them, the one with cords does not: solve/newton.py),
factorisations (branch sweeps' included), the Newton phases' seconds (hessian, assemble, factorize, solve, gradient,
line_search), seconds per iteration and per factorisation, and the largest distance of the final nodes from those of
the case it is compared with (old and new: the same equilibrium to the solver's tolerance). The machine is shared:
the load average before each case and the process's CPU seconds over it are recorded beside the wall time; a case's
wall seconds vary by a quarter with the load, the counts do not.

    python benchmarks/fibers.py [--only with_cords_4kpa,...] [--out benchmarks/results]

Writes fibers.md and fibers.json (machine, date) under --out; one progress line per case.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

FACTOR_REPEATS = 5
PHASES = ("hessian", "assemble", "factorize", "solve", "gradient", "line_search")
SHORT = {"chambers[0].keyframes": [[0, 0.0], [2, 4.0]], "schedule.increments": 2}
LONG = {"chambers[0].keyframes": [[0, 0.0], [2, 30.0]], "schedule.increments": 2}
# name: (scene overrides, sweep_updates, the case whose final nodes it is compared with)
CASES = {
    "without_cords_4kpa": ({**SHORT, "fibers": []}, True, None),
    "with_cords_4kpa_refactorised": (SHORT, False, None),
    "with_cords_4kpa": (SHORT, True, "with_cords_4kpa_refactorised"),
    "with_cords_30kpa_refactorised": (LONG, False, None),
    "with_cords_30kpa": (LONG, True, "with_cords_30kpa_refactorised"),
}


def factorisations() -> dict:
    """Median seconds of one factorisation with and without the cords, and of solves with 1 and 10 right-hand sides
    with the cords' factor, alternated."""
    import statistics

    import taichi_pneuma as tp
    from taichi_pneuma.limits import Budget
    from taichi_pneuma.solve.newton import NewtonSolver

    solvers = {}
    for name, overrides in (("with_cords", {}), ("without_cords", {"fibers": []})):
        solver = NewtonSolver(tp.load_scene("fiber_bending_3d").with_values(overrides).build(Budget()).model)
        solvers[name] = (solver, solver.pattern.matrix(solver.model.hessian_parts(True)))
    times: dict = {}
    rng = np.random.default_rng(0)
    for _ in range(FACTOR_REPEATS):
        for name, (solver, matrix) in solvers.items():
            start = time.perf_counter()
            solver.backend.factorize(matrix)
            times.setdefault(f"factorize_{name}_s", []).append(time.perf_counter() - start)
            if name == "with_cords":
                for k in (1, 10):
                    rhs = rng.standard_normal((matrix.shape[0], k))
                    start = time.perf_counter()
                    solver.backend.solve(rhs)
                    times.setdefault(f"solve_{k}_rhs_s", []).append(time.perf_counter() - start)
    record: dict = {key: statistics.median(values) for key, values in times.items()}
    record["backend"] = solvers["with_cords"][0].backend.name
    record["nnz"] = {name: int(matrix.nnz) for name, (_, matrix) in solvers.items()}
    return record


def run_case(overrides: dict, sweep_updates: bool) -> tuple[dict, np.ndarray]:
    """One ramp: its counts, phases and seconds, and the final node positions."""
    import taichi_pneuma as tp
    from taichi_pneuma.limits import Budget
    from taichi_pneuma.solve.newton import NewtonOptions
    from taichi_pneuma.solve.simulate import run_schedule

    built = tp.load_scene("fiber_bending_3d").with_values(overrides).build(Budget())
    model = built.model
    model.energy(), model.gradient(), model.hessian_parts(True), model.hessian_parts(False)  # compile the kernels
    load = os.getloadavg()[0]
    start, cpu = time.perf_counter(), time.process_time()
    run = run_schedule(built, options=NewtonOptions(sweep_updates=sweep_updates))
    seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
    phases = {p: float(run.newton["phase_seconds"].get(p, 0.0)) for p in PHASES}
    iterations = sum(step.iterations for step in run.steps)
    newton = sum(phases.values())
    record = {
        "dofs": model.n_dofs,
        "iterations": iterations,
        "per_increment": [step.iterations for step in run.steps[1:]],
        "cuts": sum(step.cuts for step in run.steps),
        "chord_steps": run.newton["chord_steps"],
        "factorizations": run.newton["factorizations"],
        "phase_seconds": phases,
        "newton_s": newton,
        "ramp_s": seconds,
        "ramp_cpu_s": cpu,
        "ms_per_iteration": 1e3 * newton / iterations,
        "ms_per_factorization": 1e3 * phases["factorize"] / run.newton["factorizations"],
        "factorizations_per_iteration": run.newton["factorizations"] / iterations,
        "load_before": load,
        "displacement": float(np.abs(run.positions[-1] - run.positions[0]).max()),
    }
    return record, run.positions[-1]


def report(factor: dict, records: dict, machine: str) -> str:
    from taichi_pneuma.apps.bench import markdown

    lines = [
        f"Machine: {machine}. fiber_bending_3d's mesh ({records[next(iter(records))]['dofs']} DOFs), one run each.",
        "",
        f"One factorisation ({factor['backend']}, the projected Hessian at rest, median of {FACTOR_REPEATS}, "
        f"alternated): {1e3 * factor['factorize_with_cords_s']:.0f} ms with the cords "
        f"({factor['nnz']['with_cords']} nonzeros), {1e3 * factor['factorize_without_cords_s']:.0f} ms without them "
        f"({factor['nnz']['without_cords']}): "
        f"{factor['factorize_with_cords_s'] / factor['factorize_without_cords_s']:.2f}x, the cords' fill-in. A solve "
        f"with the cords' factor: {1e3 * factor['solve_1_rhs_s']:.0f} ms with 1 right-hand side, "
        f"{1e3 * factor['solve_10_rhs_s']:.0f} ms with 10 (a sweep's update of rank 9).",
        "",
    ]
    header = [
        "case",
        "iterations (per increment)",
        "chord steps",
        "factorisations (per iteration)",
        "Newton s (ramp CPU s)",
        "ms / iteration",
        "ms / factorisation",
        *(f"{p} s" for p in PHASES),
        "load",
        "nodes moved vs. old",
    ]
    rows = []
    for name, r in records.items():
        rows.append(
            [
                name,
                f"{r['iterations']} ({', '.join(map(str, r['per_increment']))}; {r['cuts']} cuts)",
                r["chord_steps"],
                f"{r['factorizations']} ({r['factorizations_per_iteration']:.2f})",
                f"{r['newton_s']:.1f} ({r['ramp_cpu_s']:.1f})",
                f"{r['ms_per_iteration']:.0f}",
                f"{r['ms_per_factorization']:.0f}",
                *(f"{r['phase_seconds'][p]:.2f}" for p in PHASES),
                f"{r['load_before']:.1f}",
                "" if r.get("moved") is None else f"{r['moved']:.1e} of {r['displacement']:.2f} mm",
            ]
        )
    lines.append(markdown(header, rows))
    if "with_cords_4kpa" in records and "without_cords_4kpa" in records:
        w, wo = records["with_cords_4kpa"], records["without_cords_4kpa"]
        lines.append(
            f"Per Newton iteration on the 4 kPa ramp: {w['ms_per_iteration']:.0f} ms with the cords, "
            f"{wo['ms_per_iteration']:.0f} ms without them, {w['ms_per_iteration'] / wo['ms_per_iteration']:.2f}x; "
            f"one factorisation {w['ms_per_factorization']:.0f} against {wo['ms_per_factorization']:.0f} ms "
            f"({w['ms_per_factorization'] / wo['ms_per_factorization']:.2f}x: the cords' fill-in)."
        )
    for ramp in ("4kpa", "30kpa"):
        old, new = records.get(f"with_cords_{ramp}_refactorised"), records.get(f"with_cords_{ramp}")
        if old and new:
            lines.append(
                f"With the cords to {ramp[:-3]} kPa, sweeps refactorised (old) against updated (new): "
                f"{old['factorizations']} against {new['factorizations']} factorisations, "
                f"{old['newton_s']:.1f} against {new['newton_s']:.1f} s of Newton."
            )
    return "\n".join(lines) + "\n"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--only", default=",".join(CASES))
    p.add_argument("--out", default="benchmarks/results")
    args = p.parse_args()
    from taichi_pneuma import runtime
    from taichi_pneuma.apps.bench import machine
    from taichi_pneuma.io.output import prepare_directory, save_json, save_text

    runtime.ensure_initialised()
    out = prepare_directory(args.out)
    factor = factorisations()
    print(f"factorisations: {factor}", file=sys.stderr, flush=True)
    records: dict = {}
    positions: dict = {}
    for name in args.only.split(","):
        overrides, updates, against = CASES[name]
        records[name], positions[name] = run_case(overrides, updates)
        if against in positions:
            moved = positions[name] - positions[against]
            records[name]["moved"] = float(np.abs(moved).max())
        print(f"{name}: {records[name]}", file=sys.stderr, flush=True)
    save_json(out / "fibers.json", {"machine": machine(), "factorisations": factor, "records": records})
    save_text(out / "fibers.md", report(factor, records, machine()))
    print(report(factor, records, machine()))


if __name__ == "__main__":
    main()
