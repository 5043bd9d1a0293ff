"""Inverse control with and without a reduced model (pneuma-reach --reduced, control/reduced.py): the wall time of
the same targets reached by the full Reacher and by the ReducedReacher (reduced search, then the full polish), and
whether the two answers agree.

Per case: a reduced model trained once (its time reported apart, not in the ratio: it is made once per scene), then
in one process, kernels compiled, each Reacher made (its first equilibrium at the box centre solved, as pneuma-reach
does) and the targets followed in order, each from the pose the last one reached. The time of each is that of the
Reacher's making and of all its reaches, the least of 3 runs of each (the two alternating: the machine is shared and
loaded; one run on the unreachable target). The targets: pneunet_finger's shipped trajectory
(pneunet_finger_targets.csv); on pneunet_3d (a coarse mesh) the tip points of the full model at 3 Latin hypercube
commands (seed 2) in the training box, and the unreachable tip (1.9, -0.9) (z free), where the full Reacher
restarts. The answers: the largest distance between the two final tip points over the targets, as a fraction of the
body length (the Reachers' tolerance is 1e-3 of it), and the largest command difference as a fraction of the box.
BLAS on one thread, as in benchmarks/reduced.py.

    python benchmarks/reach_reduced.py [--3d] [--out benchmarks/results]

Writes reach_reduced.md and reach_reduced.json (machine, date) under --out; one progress line per case.
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

# name: (scene, overrides, hypercube samples, POD energy kept, targets: a shipped CSV, a count of hypercube tips or
# the tip points themselves, runs of each Reacher)
COARSE_3D = {"mesh.size": 0.4, "mesh.near_chambers": 0.2}
CASES = {"pneunet_finger": ("pneunet_finger", {}, 64, 1 - 1e-8, "pneunet_finger_targets.csv", 3)}
CASES_3D = {
    "pneunet_3d_coarse": ("pneunet_3d", COARSE_3D, 24, 1 - 1e-8, 3, 3),
    "pneunet_3d_coarse, unreachable": ("pneunet_3d", COARSE_3D, 24, 1 - 1e-8, ((1.9, -0.9),), 1),
}
TRAINED: dict = {}  # (scene, overrides, samples, energy) -> (built, model, training seconds): a model per scene


def targets_for(built, model, targets):
    """The shipped CSV's targets, the full model's tip points at `targets` hypercube commands (seed 2), or the tip
    points given."""
    from taichi_pneuma.control.inverse import Reacher
    from taichi_pneuma.reduce.snapshots import hypercube
    from taichi_pneuma.scene.shipped import find
    from taichi_pneuma.scene.targets import Target, read_targets_csv

    if isinstance(targets, str):
        return read_targets_csv(find(targets, ".csv", "targets file"))
    if isinstance(targets, tuple):
        return [Target(tip, None, (1.0, 1.0, 1.0)) for tip in targets]
    low, high = model.training[0].min(axis=0), model.training[0].max(axis=0)
    reacher = Reacher(built, start=(low + high) / 2)
    return [Target(tuple(reacher.settle(c).tip), None, (1.0, 1.0, 1.0)) for c in hypercube(low, high, targets, 2)]


def timed_follow(make, targets):
    started = time.perf_counter()
    reacher = make()
    made = time.perf_counter() - started
    results = reacher.follow(targets)
    return reacher, results, made, time.perf_counter() - started


def run_case(scene_name: str, overrides: dict, samples: int, energy: float, targets, repeat: int) -> dict:
    import numpy as np

    import taichi_pneuma as tp
    from taichi_pneuma.control.inverse import Reacher
    from taichi_pneuma.control.reduced import ReducedReacher
    from taichi_pneuma.reduce.train import train

    load = os.getloadavg()[0]
    key = (scene_name, tuple(overrides.items()), samples, energy)
    if key not in TRAINED:
        built = tp.load_scene(scene_name).with_values(overrides).build()
        started = time.perf_counter()
        TRAINED[key] = built, train(built, energy=energy, samples=samples).model, time.perf_counter() - started
    built, model, train_seconds = TRAINED[key]
    wanted = targets_for(built, model, targets)
    runs = [
        (timed_follow(lambda: Reacher(built), wanted), timed_follow(lambda: ReducedReacher(model), wanted))
        for _ in range(repeat)
    ]
    full, full_results, full_made, full_seconds = min((run[0] for run in runs), key=lambda r: r[3])
    reduced, reduced_results, reduced_made, reduced_seconds = min((run[1] for run in runs), key=lambda r: r[3])
    phases = [r.reduced for r in reduced_results]
    span = full.hi - full.lo
    return {
        "scene": scene_name,
        "overrides": overrides,
        "dofs": built.model.n_dofs,
        "chambers": len(built.chambers),
        "modes": model.n_modes,
        "elements": f"{len(model.elements)} of {built.mesh.n_elements}",
        "train_seconds": train_seconds,
        "targets": len(wanted),
        "load": load,
        "full_seconds": full_seconds,
        "full_start_seconds": full_made,
        "full_seconds_all": [run[0][3] for run in runs],
        "full_solves": sum(r.forward_solves for r in full_results),
        "full_reached": sum(r.reached for r in full_results),
        "reduced_seconds": reduced_seconds,
        "reduced_start_seconds": reduced_made,
        "reduced_seconds_all": [run[1][3] for run in runs],
        "reduced_search_seconds": sum(p.seconds for p in phases),
        "reduced_solves": sum(p.result.forward_solves for p in phases),
        "polish_seconds": sum(p.polish_seconds for p in phases),
        "polish_solves": sum(r.forward_solves for r in reduced_results),
        "reduced_reached": sum(r.reached for r in reduced_results),
        "indicator_max": max(p.indicator.residual for p in phases),
        "outside": sum(not p.indicator.inside for p in phases),
        "tip_difference": max(
            float(np.linalg.norm(a.pose.tip - b.pose.tip)) for a, b in zip(full_results, reduced_results)
        )
        / full.length,
        "command_difference": max(
            float(np.max(np.abs(a.pose.commands - b.pose.commands) / span))
            for a, b in zip(full_results, reduced_results)
        ),
    }


def markdown(results: dict, machine: dict, date: str) -> str:
    lines = [
        f"Machine: {machine['cpu']}, {machine['cores']} cores, {machine['platform']}, {date}; BLAS on one thread. "
        "Written by benchmarks/reach_reduced.py (its docstring says what is measured): the same targets followed by "
        "the full Reacher and by the ReducedReacher (the reduced search, then the full polish), in one process, "
        "kernels compiled; each time includes making the Reacher (its first equilibrium, at the box centre).",
        "",
        "| case | DOFs | chambers | modes | ECSW elements | training s | targets | full s (start) | full solves | "
        "reduced s (start) | reduced search s (solves) | polish s (full solves) | speed-up | "
        "speed-up per target, start excluded | reached full / reduced | "
        "tip difference / length | command difference / box | indicator max | outside box |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, c in results.items():
        per_target = (c["full_seconds"] - c["full_start_seconds"]) / (c["reduced_seconds"] - c["reduced_start_seconds"])
        lines.append(
            f"| {name} | {c['dofs']} | {c['chambers']} | {c['modes']} | {c['elements']} | {c['train_seconds']:.1f} | "
            f"{c['targets']} | {c['full_seconds']:.2f} ({c['full_start_seconds']:.2f}) | {c['full_solves']} | "
            f"{c['reduced_seconds']:.2f} ({c['reduced_start_seconds']:.2f}) | {c['reduced_search_seconds']:.2f} "
            f"({c['reduced_solves']}) | {c['polish_seconds']:.2f} ({c['polish_solves']}) | "
            f"{c['full_seconds'] / c['reduced_seconds']:.1f}x | {per_target:.1f}x | "
            f"{c['full_reached']} / {c['reduced_reached']} | "
            f"{c['tip_difference']:.1e} | {c['command_difference']:.1e} | {c['indicator_max']:.1e} | {c['outside']} |"
        )
    return "\n".join(lines) + "\n"


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--3d", dest="three_d", action="store_true", help="also pneunet_3d on a coarse mesh (minutes)")
    p.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = p.parse_args()
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from taichi_pneuma import runtime
    from taichi_pneuma.study.sweep import machine

    runtime.init("cpu")
    results = {}
    for name, case in {**CASES, **(CASES_3D if args.three_d else {})}.items():
        started = time.perf_counter()
        results[name] = c = run_case(*case)
        print(
            f"{name}: {time.perf_counter() - started:.0f} s; full {c['full_seconds']:.2f} s, reduced "
            f"{c['reduced_seconds']:.2f} s ({c['full_seconds'] / c['reduced_seconds']:.1f}x)",
            flush=True,
        )
    date = datetime.date.today().isoformat()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "reach_reduced.md").write_text(markdown(results, machine(), date))
    record = {"machine": machine(), "date": date, "cases": results}
    (out / "reach_reduced.json").write_text(json.dumps(record, indent=2))
    print(f"wrote {out / 'reach_reduced.md'}, {out / 'reach_reduced.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
