"""What accuracy costs in time: start-up, timing breakdown, solver backends, accuracy-vs-time study, scaling.

    python -m taichi_pneuma.apps.bench [--sections startup,breakdown,backends,accuracy,scaling] [--out benchmarks/results]

Every section prints a Markdown table and saves it (bench_<section>.md, .json) under --out, headed
with the machine and date; the accuracy section also plots error against wall time (log-log, one
curve per knob) to bench_accuracy.png when matplotlib is installed (`pip install .[bench]`).
Timings are wall-clock on a possibly shared machine: compare ratios within one run.
"""

import argparse
import collections
import os
import platform
import re
import resource
import subprocess
import sys
import tempfile
import time
from datetime import date
from pathlib import Path

import numpy as np

from .. import runtime
from ..errors import PneumaInputError, require
from ..linsolve import BACKENDS, FixedPattern, make_backend
from ..newton import NewtonOptions
from ..output import prepare_directory, save_json, save_text, write_atomic
from ..scene import reference_scene
from ..scenefile import load_scene
from ..schedule import Schedule, area_ramp
from ..simulate import run_schedule

SECTIONS = ("startup", "breakdown", "backends", "accuracy", "scaling")
REFERENCE_TUTORIAL_SECONDS = 25.0  # SPEC.md: the NumPy/SciPy tutorial's cy = 0.15 ramp on this kind of machine
PHASES = ("gradient", "hessian", "assemble", "factorize", "solve", "line_search")


def machine() -> str:
    return f"{platform.node()}, {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, {date.today()}"


def markdown(header: list[str], rows: list[list]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def warm_up(built, options=None) -> None:
    """Compile (or load from the offline cache) this scene's kernels: one tiny increment of 1% area."""
    run_schedule(built, Schedule(1, (area_ramp(1.01, 2),)), options)


def timed_ramp(max_area=0.0012, steps=36, growth=3.5, options=None, cy=0.15):
    """Build, warm the kernels up on a tiny ramp, then time the ramp; return (built, result, seconds)."""
    built = reference_scene(cy, growth=growth, steps=steps, max_area=max_area).build()
    warm_up(built, options)
    start = time.perf_counter()
    result = run_schedule(built, options=options)
    return built, result, time.perf_counter() - start


MAIN_COMMAND = ("--cy", "0.15", "--no-video")
FIRST_INCREMENT = re.compile(r"step\s+1/")
SCENES_DIR = Path(__file__).resolve().parents[2] / "assets" / "scenes"


def main_command_process(cache_dir: str, out: str) -> tuple[float, float]:
    """Run the main command (--no-video) in a fresh process with Taichi's offline kernel cache in cache_dir;
    return (seconds until its first increment's line is printed, seconds until the process exits)."""
    env = {**os.environ, "TI_OFFLINE_CACHE_FILE_PATH": cache_dir, "PYTHONUNBUFFERED": "1"}
    command = [sys.executable, "-m", "taichi_pneuma.apps.inflate", *MAIN_COMMAND, "--out", out]
    start = time.perf_counter()
    first = float("nan")
    with subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, env=env) as proc:
        for line in proc.stdout:
            if first != first and FIRST_INCREMENT.search(line):
                first = time.perf_counter() - start
    require(proc.returncode == 0, f"the main command exited with {proc.returncode}")
    return first, time.perf_counter() - start


def first_versus_typical(result) -> tuple[float, float]:
    """(seconds of increments 1 and 2, median seconds of two increments over the rest of the ramp)."""
    seconds = result.column("seconds")
    return float(seconds[1:3].sum()), 2.0 * float(np.median(seconds[3:]))


def startup() -> tuple[str, dict]:
    """Kernel compilation at start-up. The main command's whole process, and its time to the first
    increment, from an empty kernel cache (as on a fresh machine) and then from the cache it left; and,
    in this process, three scenes in turn that differ in mesh size, E, nu, k and number of chambers:
    their build time and their first two increments against two typical ones."""
    rows, data = [], {"process": {}, "scenes": []}
    with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as out:
        for label in ("empty kernel cache", "warm kernel cache"):
            first, whole = main_command_process(cache, out)
            data["process"][label] = {"first_increment_s": first, "whole_s": whole}
            rows.append([f"main command `{' '.join(MAIN_COMMAND)}`, {label}", f"{whole:.2f}", f"{first:.2f}",
                         f"{REFERENCE_TUTORIAL_SECONDS / whole:.1f}x faster than the tutorial's ramp alone"])
    table = markdown(["whole process", "s", "to first increment (s)", "against SPEC.md's 25 s reference"], rows)
    scenes = [("reference cy=+0.15 (first in process)", lambda: reference_scene(0.15)),
              ("cy=+0.10, max area 0.002, E 2e4, nu 0.4, k 2e5",
               lambda: reference_scene(0.10, youngs_modulus=2e4, poisson_ratio=0.4, chamber_stiffness=2e5,
                                       max_area=0.002)),
              ("bidirectional.toml (2 chambers)", lambda: load_scene(SCENES_DIR / "bidirectional.toml"))]
    rows = []
    for label, make in scenes:
        start = time.perf_counter()
        built = make().build()
        build_seconds = time.perf_counter() - start
        first, typical = first_versus_typical(run_schedule(built))
        data["scenes"].append({"scene": label, "vertices": built.mesh.n_vertices, "build_s": build_seconds,
                               "first_two_increments_s": first, "two_typical_increments_s": typical})
        rows.append([label, built.mesh.n_vertices, f"{1e3 * build_seconds:.0f}", f"{1e3 * first:.0f}",
                     f"{1e3 * typical:.0f}", f"{first / typical:.1f}x"])
    table += "\n" + markdown(["scene, in one process", "vertices", "build (ms)", "increments 1-2 (ms)",
                               "two typical increments (ms)", "ratio"], rows)
    return table, data


def breakdown() -> tuple[str, dict]:
    """Where the time of one reference ramp goes, with the one-off kernel compile/load separately."""
    start = time.perf_counter()
    built = reference_scene(0.15).build()
    build_seconds = time.perf_counter() - start
    start = time.perf_counter()
    warm_up(built)
    first_call = time.perf_counter() - start
    start = time.perf_counter()
    result = run_schedule(built)
    ramp_seconds = time.perf_counter() - start
    phases = collections.Counter()
    for solve in result.solves:
        phases.update(solve.phase_seconds)
    iterations = int(result.column("iterations").sum())
    increments = len(result.steps) - 1
    rows = [["mesh + terms (Triangle, fields)", f"{1e3 * build_seconds:.0f}", "once"],
            ["first solve: kernel compile / cache load", f"{1e3 * first_call:.0f}", "once per process"]]
    rows += [[f"ramp: {p}", f"{1e3 * phases[p]:.0f}", f"{1e3 * phases[p] / iterations:.2f} ms/iteration"] for p in PHASES]
    other = ramp_seconds - sum(phases.values())
    rows += [["ramp: other (history, predictor, Python)", f"{1e3 * other:.0f}", ""],
             ["**ramp total (35 increments)**", f"**{1e3 * ramp_seconds:.0f}**",
              f"{increments / ramp_seconds:.0f} increments/s, {iterations} Newton iterations "
              f"({iterations / increments:.1f} per increment), {1e3 * ramp_seconds / iterations:.1f} ms/iteration"],
             ["reference tutorial (SPEC.md figure, not measured here)", f"{1e3 * REFERENCE_TUTORIAL_SECONDS:.0f}",
              f"{REFERENCE_TUTORIAL_SECONDS / ramp_seconds:.0f}x slower than this ramp"]]
    data = {"build_s": build_seconds, "first_call_s": first_call, "ramp_s": ramp_seconds, "phases_s": dict(phases),
            "iterations": iterations, "increments_per_s": increments / ramp_seconds,
            "tip_deflection": result.tip_deflection, "peak_pressure": result.peak_pressure}
    return markdown(["part", "ms", "note"], rows), data


def backends() -> tuple[str, dict]:
    """Each backend on the same matrices (the final reference state), then each on the whole ramp."""
    built, result, _ = timed_ramp()
    model = built.model
    model.set_displacements(result.states[-1] - built.mesh.vertices)
    rows_, cols_ = model.hessian_pattern()
    matrix = FixedPattern(rows_, cols_, model.n_dofs).matrix(model.hessian_values(psd_only=True))
    rhs = np.random.default_rng(0).standard_normal(model.n_dofs)
    rows, data = [], {}
    for name in BACKENDS:
        backend = make_backend(name)
        backend.factorize(matrix)
        start = time.perf_counter()
        for _ in range(20):
            backend.factorize(matrix)
        factorize = (time.perf_counter() - start) / 20
        start = time.perf_counter()
        for _ in range(20):
            backend.solve(rhs)
        solve = (time.perf_counter() - start) / 20
        _, ramp, seconds = timed_ramp(options=NewtonOptions(linear_solver=name))
        data[name] = {"factorize_ms": 1e3 * factorize, "solve_ms": 1e3 * solve, "ramp_s": seconds,
                      "tip_deflection": ramp.tip_deflection}
        rows.append([name, f"{1e3 * factorize:.2f}", f"{1e3 * solve:.3f}", f"{seconds:.2f}",
                     f"{ramp.tip_deflection:+.5f}"])
    header = ["backend", "factorise (ms)", "solve (ms)", "reference ramp (s)", "tip dy"]
    return f"matrix: {matrix.shape[0]} DOFs, {matrix.nnz} non-zeros\n\n" + markdown(header, rows), data


def accuracy(out: Path) -> tuple[str, dict]:
    """Error in tip deflection, final area and peak pressure against a converged reference, and wall time,
    for each knob in turn (the others at their defaults). Mesh errors are measured against the finest mesh;
    tolerance and increment errors against the default mesh solved tightly (tol 1e-9, 100 increments).
    (1e-10 is below what float64 attains here: the rest state of the finest mesh already has a residual
    of ~2e-10.)"""
    knobs = {
        "max triangle area": [("mesh", a, dict(max_area=a)) for a in (0.01, 0.005, 0.0025, 0.0012, 0.0006, 0.0003)],
        "Newton tolerance": [("tol", t, dict(options=NewtonOptions(tol=t))) for t in (1e-2, 1e-3, 1e-4, 1e-6, 1e-8, 1e-9)],
        "ramp increments": [("steps", n, dict(steps=n + 1)) for n in (5, 10, 20, 35, 50, 100)],
    }
    references = {"mesh": timed_ramp(max_area=0.00015, options=NewtonOptions(tol=1e-9))[1],
                  "tight": timed_ramp(steps=101, options=NewtonOptions(tol=1e-9))[1]}
    rows, data = [], collections.defaultdict(list)
    for knob, runs in knobs.items():
        for kind, value, kwargs in runs:
            _, result, seconds = timed_ramp(**kwargs)
            reference = references["mesh" if kind == "mesh" else "tight"]
            errors = {
                "tip": abs(result.tip_deflection / reference.tip_deflection - 1),
                "area": abs(result.column("main.area")[-1] / reference.column("main.area")[-1] - 1),
                "pressure": abs(result.peak_pressure / reference.peak_pressure - 1),
            }
            data[knob].append({"value": value, "seconds": seconds, **errors})
            rows.append([knob, f"{value:g}", f"{1e3 * seconds:.0f}", f"{errors['tip']:.1e}", f"{errors['area']:.1e}",
                         f"{errors['pressure']:.1e}"])
    table = markdown(["knob", "value", "ramp (ms)", "tip error", "area error", "peak p error"], rows)
    plot_accuracy(data, out / "bench_accuracy.png")
    return table, dict(data)


def plot_accuracy(data: dict, path: Path) -> None:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        import matplotlib.ticker
    except ImportError:
        print("matplotlib is not installed (pip install .[bench]): no accuracy plot", file=sys.stderr)
        return
    fig, ax = plt.subplots(figsize=(6.4, 4.2), dpi=100)
    for knob, runs in data.items():
        times, errors = [r["seconds"] for r in runs], [max(r["tip"], 1e-12) for r in runs]
        ax.loglog(times, errors, "o-", label=knob)  # in knob order, each point labelled with its value
        for r, t, e in zip(runs, times, errors):
            ax.annotate(f"{r['value']:g}", (t, e), textcoords="offset points", xytext=(4, 3), fontsize=7)
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.axhline(0.01, color="grey", lw=0.8, ls="--")
    ax.set_xlabel("wall time of the 35-increment ramp (s)")
    ax.set_ylabel("relative tip-deflection error")
    ax.set_title("Accuracy versus time (cy = +0.15, CPU)")
    ax.legend()
    fig.tight_layout()
    write_atomic(path, lambda tmp: fig.savefig(tmp, format="png"))
    plt.close(fig)


def scaling() -> tuple[str, dict]:
    """Time per Newton iteration and per increment from ~500 to ~100k vertices (3 increments to 1.5x)."""
    rows, data = [], []
    for max_area in (0.005, 0.0012, 0.0003, 0.0001, 0.00003, 0.00002):
        built, result, seconds = timed_ramp(max_area=max_area, steps=4, growth=1.5)
        iterations = int(result.column("iterations").sum())
        record = {"vertices": built.mesh.n_vertices, "ms_per_iteration": 1e3 * seconds / iterations,
                  "ms_per_increment": 1e3 * seconds / 3, "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}
        data.append(record)
        rows.append([record["vertices"], f"{record['ms_per_iteration']:.1f}", f"{record['ms_per_increment']:.0f}",
                     f"{record['peak_rss_mb']:.0f}"])
        print(f"  scaling: {record}", file=sys.stderr, flush=True)
    n = np.log([r["vertices"] for r in data])
    exponent = np.polyfit(n, np.log([r["ms_per_iteration"] for r in data]), 1)[0]
    table = markdown(["vertices", "ms / Newton iteration", "ms / increment", "peak RSS (MB)"], rows)
    return table + f"\nfitted: time per iteration ~ vertices^{exponent:.2f}\n", {"runs": data, "exponent": exponent}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m taichi_pneuma.apps.bench", description=__doc__.split("\n")[0])
    parser.add_argument("--sections", default=",".join(SECTIONS), help=f"comma-separated, from {', '.join(SECTIONS)}")
    parser.add_argument("--out", default="benchmarks/results", help="directory for the tables, JSON and plot")
    parser.add_argument("--arch", default="cpu", choices=sorted(runtime.ARCHES), help="Taichi backend")
    args = parser.parse_args(argv)
    try:
        sections = [s.strip() for s in args.sections.split(",") if s.strip()]
        for s in sections:
            require(s in SECTIONS, f"--sections: {s!r} is not one of {', '.join(SECTIONS)}")
        out = prepare_directory(args.out)
    except PneumaInputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    runtime.init(args.arch)
    heading = f"Machine: {machine()}, Taichi arch {args.arch}\n\n"
    for section in sections:
        print(f"## {section}", flush=True)
        table, data = accuracy(out) if section == "accuracy" else {"startup": startup, "breakdown": breakdown,
                                                                    "backends": backends, "scaling": scaling}[section]()
        print(heading + table, flush=True)
        save_text(out / f"bench_{section}.md", heading + table)
        save_json(out / f"bench_{section}.json", {"machine": machine(), "arch": args.arch, **{"data": data}})
    return 0


if __name__ == "__main__":
    sys.exit(main())
