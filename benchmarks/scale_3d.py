"""Scale in 3D: time per Newton iteration and peak memory of large tetrahedral runs, each in a child process of
its own (its peak resident set size, getrusage's ru_maxrss, is that run's alone).

    python -m benchmarks.scale_3d [--cases P1,P2] [--backends amg] [--out benchmarks/results]   (repository root)

The body is the pressurised octant of the thick spherical shell 1 <= r <= 2 (benchmarks/solid.py's octant: layered
tetrahedra from arrays, no mesher; closed by its three symmetry planes, pressure 0 -> 0.05 E in 2 increments):
about 200k linear tetrahedra (P1) and 50k quadratic ones (P2). A child compiles the kernels on a tiny octant
first, then builds the mesh and its terms and runs the ramp; it reports the build time, ms per Newton iteration
and per phase, and its peak RSS, the latter also per tetrahedron above the RSS before the build (the
interpreter, Taichi, the kernels). A child that runs past --timeout is stopped and reported as such. Writes
scale_3d.md and .json with the machine and date; wall times on a shared machine: compare ratios within a run.
"""

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the sibling scripts (solid.py's octant)

CASES = {"P1": (57, 20, 1), "P2": (29, 20, 2)}  # (divisions, layers, order): 194,940 and 50,460 tetrahedra
INCREMENTS = 2


def peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # kilobytes on Linux


def child(case: str, backend: str) -> dict:
    """One run in this process (module docstring); returns its record."""
    from solid import octant, phase_ms

    from taichi_pneuma import runtime
    from taichi_pneuma.solve.newton import NewtonOptions
    from taichi_pneuma.solve.simulate import run_schedule

    runtime.init("cpu")
    divisions, layers, order = CASES[case]
    options = NewtonOptions(linear_solver=backend)
    run_schedule(octant(2, 1, order, 1).build(), options=options)  # compile the kernels
    before = peak_rss_mb()
    start = time.perf_counter()
    built = octant(divisions, layers, order, INCREMENTS).build()
    build = time.perf_counter() - start
    start = time.perf_counter()
    result = run_schedule(built, options=options)
    seconds = time.perf_counter() - start
    iterations, phases = phase_ms(result)
    peak = peak_rss_mb()
    tetrahedra = built.mesh.n_elements
    return {
        "case": case,
        "backend": backend,
        "tetrahedra": tetrahedra,
        "nodes": built.mesh.n_vertices,
        "dofs": built.model.n_dofs,
        "build_s": build,
        "ramp_s": seconds,
        "iterations": iterations,
        "converged": bool(all(s.converged for s in result.steps)),
        "ms_per_iteration": 1e3 * seconds / iterations,
        "phases_ms": phases,
        "rss_before_mb": before,
        "peak_rss_mb": peak,
        "bytes_per_tetrahedron": 1e6 * (peak - before) / tetrahedra,
        "tip": float(result.positions[-1][:, 0].max()),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cases", default=",".join(CASES))
    parser.add_argument("--backends", default="amg")
    parser.add_argument("--timeout", type=float, default=600.0, help="seconds per child run")
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results"))
    parser.add_argument("--child", nargs=2, metavar=("CASE", "BACKEND"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print(json.dumps(child(*args.child)))
        return
    from taichi_pneuma.apps.bench import PHASES, machine, markdown
    from taichi_pneuma.io.output import prepare_directory, save_json, save_text

    rows, records = [], []
    for case in args.cases.split(","):
        for backend in args.backends.split(","):
            command = [sys.executable, "-m", "benchmarks.scale_3d", "--child", case, backend]
            try:
                proc = subprocess.run(command, capture_output=True, text=True, timeout=args.timeout)
            except subprocess.TimeoutExpired:
                rows.append([case, "", "", backend, f"stopped after {args.timeout:.0f} s"] + [""] * (len(PHASES) + 4))
                continue
            if proc.returncode != 0:
                raise SystemExit(f"{case} {backend} failed:\n{proc.stderr[-2000:]}")
            r = json.loads(proc.stdout.strip().splitlines()[-1])
            records.append(r)
            print(json.dumps(r), file=sys.stderr, flush=True)
            rows.append(
                [
                    f"{case}, {r['tetrahedra']:,}",
                    f"{r['dofs']:,}",
                    f"{r['build_s']:.1f}",
                    backend,
                    r["iterations"],
                    f"{r['ms_per_iteration']:.0f}",
                    *(f"{r['phases_ms'][p]:.0f}" for p in PHASES),
                    f"{100 * (r['phases_ms']['factorize'] + r['phases_ms']['solve']) / r['ms_per_iteration']:.0f} %",
                    f"{r['peak_rss_mb']:.0f}",
                    f"{r['bytes_per_tetrahedron']:.0f}",
                    "yes" if r["converged"] else "NO",
                ]
            )
    header = [
        "tetrahedra",
        "DOFs",
        "build (s)",
        "backend",
        "Newton iterations",
        "ms / iteration",
        *(f"{p} (ms)" for p in PHASES),
        "linear solve share",
        "peak RSS (MB)",
        "bytes / tetrahedron",
        "converged",
    ]
    table = f"Machine: {machine()}\n\n" + markdown(header, rows)
    print(table)
    out = prepare_directory(args.out)
    save_text(out / "scale_3d.md", table)
    save_json(out / "scale_3d.json", {"machine": machine(), "runs": records})


if __name__ == "__main__":
    main()
