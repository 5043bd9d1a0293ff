"""What the tension-only cords cost per Newton iteration, on the shipped bending actuator's mesh (fiber_bending_3d:
quadratic tetrahedra, one pressure per element, a wrinkling paper sheet, two crossed 31 GPa aramid threads).

Cases, each one ramp of the scene's mesh in this process (its kernels compiled first):

- "without cords" (`fibers = []`) and "with cords" on the same ramp, short enough for both (2 increments to 4 kPa:
  without its threads the chamber balloons and finds no equilibrium past about 10.5 kPa), both as solved now;
- "with cords, sweeps refactorised" (NewtonOptions(sweep_updates=False): every branch sweep a new factorisation, as
  before solve/branch_update.py) and "with cords" on that ramp and on 2 increments to 30 kPa: old against new.

Per case: Newton iterations, chord steps (a held factorisation reused: a cheap iteration; the model without cords
takes them, the one with cords does not: solve/newton.py), factorisations (branch sweeps' included), the Newton
phases' seconds (hessian, assemble, factorize, solve, gradient, line_search), seconds per iteration and per
factorisation, and the largest distance of the final nodes from those of the case it is compared with (old and
new: the same equilibrium to the solver's tolerance). The machine is shared: the load average before each case is
recorded, and a case's seconds vary by a quarter with it; the counts do not.

    python benchmarks/fibers.py [--only with_cords_4kpa,...] [--out benchmarks/results]

Writes fibers.md and fibers.json (machine, date) under --out; one progress line per case.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

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
    start = time.perf_counter()
    run = run_schedule(built, options=NewtonOptions(sweep_updates=sweep_updates))
    seconds = time.perf_counter() - start
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
        "ms_per_iteration": 1e3 * newton / iterations,
        "ms_per_factorization": 1e3 * phases["factorize"] / run.newton["factorizations"],
        "factorizations_per_iteration": run.newton["factorizations"] / iterations,
        "load_before": load,
        "displacement": float(np.abs(run.positions[-1] - run.positions[0]).max()),
    }
    return record, run.positions[-1]


def report(records: dict, machine: str) -> str:
    from taichi_pneuma.apps.bench import markdown

    lines = [
        f"Machine: {machine}. fiber_bending_3d's mesh ({records[next(iter(records))]['dofs']} DOFs), one run each.",
        "",
    ]
    header = [
        "case",
        "iterations (per increment)",
        "chord steps",
        "factorisations (per iteration)",
        "Newton s",
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
                f"{r['newton_s']:.1f}",
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
    records: dict = {}
    positions: dict = {}
    for name in args.only.split(","):
        overrides, updates, against = CASES[name]
        records[name], positions[name] = run_case(overrides, updates)
        if against in positions:
            moved = positions[name] - positions[against]
            records[name]["moved"] = float(np.abs(moved).max())
        print(f"{name}: {records[name]}", file=sys.stderr, flush=True)
    save_json(out / "fibers.json", {"machine": machine(), "records": records})
    save_text(out / "fibers.md", report(records, machine()))
    print(report(records, machine()))


if __name__ == "__main__":
    main()
