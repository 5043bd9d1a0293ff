"""taichi-pneuma against scikit-fem + SciPy on the same 3D ramp, in one run: the beam_3d scene (the reference
beam 3.5 x 0.8 x 0.8 with an ellipsoidal cavity, linear tetrahedra from its mesh file, volume 1 -> 2x in 10
increments), and the same discretisation written as a Python user would with scikit-fem (tests/skfem_model.py:
the law, the cavity and the clamp in skfem's weak form, Newton with scipy.sparse.linalg.spsolve).

    python benchmarks/skfem_3d.py [--scene beam_3d] [--coarse] [--repeats 2] [--out benchmarks/results]

Both solve each increment to the same criterion (|gradient| <= 1e-6 x the sum of the terms' force norms).
taichi-pneuma runs the ramp `repeats` times (the first includes compiling its kernels), scikit-fem once.
Prints and writes skfem_3d.md and .json (machine, date): seconds per ramp, Newton iterations, the ratio, where
each code's time goes, and how far apart the two tips are.
"""

import argparse
import os
import platform
import sys
import tempfile
import time
from datetime import date
from pathlib import Path

import numpy as np

from taichi_pneuma import api, runtime
from taichi_pneuma.fem.meshfile import write_mesh
from taichi_pneuma.fem.tetmesh import tet_mesh
from taichi_pneuma.io.output import prepare_directory, save_json, save_text

sys.path[:0] = [str(Path(__file__).resolve().parents[1] / "tests"), str(Path(__file__).resolve().parent)]
from skfem_model import SkfemBody  # noqa: E402

TOL = 1e-6


def taichi_ramp(scene):
    """(result, wall seconds, CPU seconds, {phase: seconds}) of one ramp, built and solved."""
    start, cpu = time.perf_counter(), time.process_time()
    result = api.simulate(scene, tol=TOL)
    seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
    phases = {}
    for solve in result.solves:
        for name, value in solve.phase_seconds.items():
            phases[name] = phases.get(name, 0.0) + value
    return result, seconds, cpu, phases


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scene", default="beam_3d")
    parser.add_argument("--repeats", type=int, default=2, help="taichi-pneuma ramps (the first compiles)")
    parser.add_argument(
        "--coarse",
        action="store_true",
        help="the scene on the ellipsoid beam meshed by gmsh at size 0.3 (accuracy_3d's level 0)",
    )
    parser.add_argument("--out", default="benchmarks/results")
    args = parser.parse_args()
    out = prepare_directory(args.out)
    runtime.init("cpu")
    scene = api.load_scene(args.scene)
    if args.coarse:
        from accuracy_3d import case_of, meshes

        vertices, tets, walls = meshes(case_of("beam"), 1)[0]
        path = write_mesh(Path(tempfile.mkdtemp()) / "coarse.msh", tet_mesh(vertices, tets, walls), ("chamber",))
        scene = scene.with_value("body.file", str(path))
    runs = []
    for repeat in range(args.repeats):
        result, seconds, cpu, phases = taichi_ramp(scene)
        runs.append(
            {
                "seconds": seconds,
                "cpu_seconds": cpu,
                "iterations": int(sum(s.iterations for s in result.solves)),
                "phases": phases,
            }
        )
        print(
            f"taichi-pneuma ramp {repeat + 1}: {seconds:.2f} s ({cpu:.2f} s CPU), "
            f"{runs[-1]['iterations']} Newton iterations, tip {result.tip_deflection:+.5f}",
            flush=True,
        )
    mesh = result.mesh
    chamber = result.built.chambers[0]
    ratios = [chamber_ratio for chamber_ratio in result.history[f"{chamber.chamber_name}.command"][1:]]
    body = SkfemBody(
        mesh.vertices,
        mesh.elements,
        mesh.chambers[0],
        mesh.pinned,
        scene.material.youngs_modulus,
        scene.material.poisson_ratio,
        chamber.k,
        scene.clamp_stiffness,
    )
    start, cpu = time.perf_counter(), time.process_time()
    theirs, iterations = body.ramp(
        ratios,
        tol=TOL,
        progress=lambda ratio, its: print(
            f"  scikit-fem: volume {ratio:.2f}x, {its} Newton iterations, {time.perf_counter() - start:.0f} s",
            flush=True,
        ),
    )
    skfem_seconds, skfem_cpu = time.perf_counter() - start, time.process_time() - cpu
    skfem_tip = float(theirs[mesh.tip, 1].mean())
    print(
        f"scikit-fem ramp: {skfem_seconds:.2f} s ({skfem_cpu:.2f} s CPU), {iterations} Newton iterations, "
        f"tip {skfem_tip:+.5f} (assembly {body.seconds['assembly']:.1f} s, spsolve {body.seconds['solve']:.1f} s)",
        flush=True,
    )
    warm = min(runs[1:] or runs, key=lambda r: r["seconds"])
    gap = float(np.abs(result.displacements[-1] - theirs).max() / np.abs(theirs).max())
    record = {
        "machine": f"{platform.node()}, {platform.machine()}, {os.cpu_count()} CPUs",
        "date": str(date.today()),
        "scene": args.scene,
        "tetrahedra": int(mesh.n_elements),
        "nodes": int(mesh.n_vertices),
        "increments": len(ratios),
        "tol": TOL,
        "taichi_pneuma": runs,
        "taichi_tip": result.tip_deflection,
        "skfem": {"seconds": skfem_seconds, "cpu_seconds": skfem_cpu, "iterations": iterations, **body.seconds},
        "skfem_tip": skfem_tip,
        "max_displacement_gap": gap,
        "ratio_warm": skfem_seconds / warm["seconds"],
        "ratio_warm_cpu": skfem_cpu / warm["cpu_seconds"],
        "ratio_cold": skfem_seconds / runs[0]["seconds"],
    }
    lines = [
        f"Machine: {record['machine']}; {record['date']}. Scene {args.scene}{' (coarse mesh)' if args.coarse else ''}: "
        f"{mesh.n_elements} linear "
        f"tetrahedra, {mesh.n_vertices} nodes, volume ramp in {len(ratios)} increments, tol {TOL:g}.",
        "",
        "| code | s / ramp | CPU s / ramp | Newton iterations | where the time goes |",
        "|---|---|---|---|---|",
    ]
    for i, run in enumerate(runs):
        top = ", ".join(f"{k} {v:.2f} s" for k, v in sorted(run["phases"].items(), key=lambda kv: -kv[1])[:4])
        lines.append(
            f"| taichi-pneuma ({'first run, compiling' if i == 0 else 'warm'}) | {run['seconds']:.2f} | "
            f"{run['cpu_seconds']:.2f} | "
            f"{run['iterations']} | {top} |"
        )
    lines.append(
        f"| scikit-fem + SciPy | {skfem_seconds:.2f} | {skfem_cpu:.2f} | {iterations} | assembly (skfem forms) "
        f"{body.seconds['assembly']:.1f} s, spsolve {body.seconds['solve']:.1f} s |"
    )
    lines += [
        "",
        f"Ratio per ramp (scikit-fem / taichi-pneuma): {record['ratio_warm']:.1f}x warm "
        f"({record['ratio_warm_cpu']:.1f}x in CPU time), {record['ratio_cold']:.1f}x against the first run.",
        f"Tips: taichi-pneuma {result.tip_deflection:+.6f}, scikit-fem {skfem_tip:+.6f}; largest nodal "
        f"displacement difference {gap:.1e} of the largest displacement.",
    ]
    text = "\n".join(lines) + "\n"
    print(text)
    stem = "skfem_3d" + ("_coarse" if args.coarse else "")
    save_text(out / f"{stem}.md", text)
    save_json(out / f"{stem}.json", record)


if __name__ == "__main__":
    main()
