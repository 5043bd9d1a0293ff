"""The reduced-order model (POD + ECSW, taichi_pneuma/reduce/) against the full model: its errors and its time per
equilibrium at held-out commands, on the reference beam, the 2D PneuNet finger (six chambers: a 6-dimensional
actuation space) and the 3D PneuNet (a coarser mesh than the shipped one, and the shipped one with --full-3d).

Per case: the snapshots (the schedule and a Latin hypercube of SAMPLES chamber commands in the schedule's range,
seed 0), each solved by the full model once; then for each basis size (an energy fraction kept, or a mode count) the
POD basis and the ECSW sampling (tolerance 1e-4) on those snapshots, and the comparison at HELD_OUT hypercube points
of seed 1: the tip displacement error as % of the body's length, the bend angle error in degrees, the full residual
of the reduced state (|g(V q)| / force scale), and the seconds per equilibrium of each model, both started from the
nearest training equilibrium (the full one by settle at the default tolerance 1e-6, the reduced one by its Newton to
|g_r| / scale <= 1e-8). BLAS runs on one thread (OPENBLAS_NUM_THREADS=1, set before NumPy loads): the reduced model's
dense r x r products are too small to share, and on a loaded machine threads make them 100x slower.

    python benchmarks/reduced.py [--full-3d] [--out benchmarks/results]

Writes reduced.md and reduced.json (machine, date) under --out; one progress line per case.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before NumPy loads (it is imported inside the functions)
os.environ.setdefault("OMP_NUM_THREADS", "1")

HELD_OUT = 6
# name: (scene, overrides, hypercube samples, basis sizes: an energy fraction (< 1) or a mode count)
CASES = {
    "reference_beam": ("reference_beam", {}, 16, (1 - 1e-6, 1 - 1e-8)),
    "pneunet_finger": ("pneunet_finger", {}, 64, (4, 8, 16, 1 - 1e-6, 1 - 1e-8)),
    "pneunet_3d_coarse": ("pneunet_3d", {"mesh.size": 0.4, "mesh.near_chambers": 0.2}, 24, (1 - 1e-6, 1 - 1e-8)),
}
FULL_3D = {"pneunet_3d": ("pneunet_3d", {}, 24, (1 - 1e-6, 1 - 1e-8))}


def run_case(scene_name: str, overrides: dict, samples: int, sizes: tuple) -> dict:
    import numpy as np

    import taichi_pneuma as tp
    from taichi_pneuma.reduce.snapshots import solve_snapshots
    from taichi_pneuma.reduce.train import train, validate

    load = os.getloadavg()[0]
    built = tp.load_scene(scene_name).with_values(overrides).build()
    snapshots = solve_snapshots(built, samples, 0)
    rows = []
    for size in sizes:
        modes, energy = (None, size) if size < 1 else (int(size), None)
        training = train(built, modes, energy, snapshots=snapshots)
        compared = validate(training, HELD_OUT, 1)
        model = training.model
        rows.append(
            {
                "basis": f"energy 1 - {1 - size:.0e}" if energy else f"{modes} modes",
                "modes": model.n_modes,
                "kept_energy": training.kept_energy,
                "elements": len(model.elements),
                "ecsw_error": training.sampling["elastic"].error,
                "pod_ecsw_seconds": training.seconds["pod"] + training.seconds["ecsw"],
                "tip_error_max": max(c.tip_error for c in compared),
                "tip_error_mean": float(np.mean([c.tip_error for c in compared])),
                "angle_error_max": max(c.angle_error for c in compared),
                "residual_max": max(c.residual for c in compared),
                "full_ms": 1000 * float(np.mean([c.full_seconds for c in compared])),
                "reduced_ms": 1000 * float(np.mean([c.reduced_seconds for c in compared])),
            }
        )
    return {
        "scene": scene_name,
        "overrides": overrides,
        "dofs": built.model.n_dofs,
        "mesh_elements": built.mesh.n_elements,
        "chambers": len(built.chambers),
        "snapshots": len(snapshots.commands),
        "failed_samples": snapshots.failed,
        "snapshot_seconds": snapshots.seconds,
        "load": load,
        "rows": rows,
    }


def markdown(results: dict, machine: dict, date: str) -> str:
    lines = [
        f"Machine: {machine['cpu']}, {machine['cores']} cores, {machine['platform']}, {date}; BLAS on one thread. "
        f"Written by benchmarks/reduced.py (its docstring says what is measured). Errors and times at {HELD_OUT} "
        "held-out commands (a Latin hypercube in the training range, seed 1); times are the mean per equilibrium, "
        "both models started from the nearest training equilibrium.",
        "",
    ]
    for name, case in results.items():
        lines += [
            f"## {name}",
            "",
            f"{case['scene']} {case['overrides'] or '(as shipped)'}: {case['dofs']} DOFs, {case['mesh_elements']} "
            f"elements, {case['chambers']} chambers; {case['snapshots']} training equilibria ({case['failed_samples']} "
            f"hypercube points found none) solved in {case['snapshot_seconds']:.1f} s (load {case['load']:.1f}).",
            "",
            "| basis | modes | kept energy | ECSW elements | ECSW fit | POD + ECSW s | tip error max (mean), "
            "% length | angle error max, deg | full residual max | full ms | reduced ms | speed-up |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|",
        ]
        for r in case["rows"]:
            lines.append(
                f"| {r['basis']} | {r['modes']} | 1 - {1 - r['kept_energy']:.1e} | {r['elements']} of "
                f"{case['mesh_elements']} | {r['ecsw_error']:.1e} | {r['pod_ecsw_seconds']:.2f} | "
                f"{r['tip_error_max']:.3g} ({r['tip_error_mean']:.3g}) | {r['angle_error_max']:.3g} | "
                f"{r['residual_max']:.1e} | {r['full_ms']:.1f} | {r['reduced_ms']:.1f} | "
                f"{r['full_ms'] / r['reduced_ms']:.1f}x |"
            )
        lines.append("")
    return "\n".join(lines)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--full-3d", action="store_true", help="also the shipped pneunet_3d mesh (minutes)")
    p.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = p.parse_args()
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from taichi_pneuma import runtime
    from taichi_pneuma.study.sweep import machine

    runtime.init("cpu")
    results = {}
    for name, case in {**CASES, **(FULL_3D if args.full_3d else {})}.items():
        started = time.perf_counter()
        results[name] = run_case(*case)
        best = results[name]["rows"][-1]
        print(
            f"{name}: {time.perf_counter() - started:.0f} s; {best['basis']}: tip error {best['tip_error_max']:.3g} %, "
            f"{best['full_ms'] / best['reduced_ms']:.1f}x",
            flush=True,
        )
    date = datetime.date.today().isoformat()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "reduced.md").write_text(markdown(results, machine(), date))
    (out / "reduced.json").write_text(json.dumps({"machine": machine(), "date": date, "cases": results}, indent=2))
    print(f"wrote {out / 'reduced.md'}, {out / 'reduced.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
