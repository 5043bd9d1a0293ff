"""What accuracy costs in time: start-up and rendering, timing breakdown, solver backends, accuracy-vs-time
study (P1 and P2), near-incompressible convergence, scaling, 3D (solid: the linear solvers; presets_3d: the 3D
presets on the shipped 3D scenes, time and error); and Taichi against Quadrants (the kernels' two
compilers).

    pneuma-bench [--sections startup,breakdown,backends,accuracy,incompressible,scaling,solid,presets_3d,compilers]
                 [--out out/bench]
    pneuma-bench --out benchmarks/results       (a clone: rewrite the tracked tables the site shows)

Every section prints a Markdown table and saves it (bench_<section>.md, .json) under --out (default
out/bench, a scratch directory), headed with the machine and date; the accuracy section also plots
error against wall time (log-log, one curve per knob) to bench_accuracy.png. Timings are wall-clock
on a possibly shared machine: compare ratios within one run.
"""

import argparse
import collections
import importlib.util
import json
import os
import platform
import re
import resource
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from datetime import date
from pathlib import Path

import numpy as np

from .. import environment, runtime, signals
from ..errors import PneumaInputError, require
from ..io.output import prepare_directory, save_json, save_text, write_atomic

SECTIONS = ("startup", "breakdown", "backends", "accuracy", "incompressible", "scaling", "solid", "presets_3d",
            "compilers")
REFERENCE_TUTORIAL_SECONDS = 25.0  # the seed pipeline (a NumPy/SciPy tutorial) on the cy = 0.15 ramp, this kind of machine
PHASES = ("gradient", "hessian", "assemble", "factorize", "solve", "line_search")


def machine() -> str:
    return f"{platform.node()}, {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, {date.today()}"


def markdown(header: list[str], rows: list[list]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def warm_up(built, options=None) -> None:
    """Compile (or load from the offline cache) this scene's kernels: one tiny increment of 1% area."""
    from ..scene.schedule import Schedule, area_ramp
    from ..solve.simulate import run_schedule

    run_schedule(built, Schedule(1, (area_ramp(1.01, 2),)), options)


def timed_ramp(max_area=0.0012, steps=36, growth=3.5, options=None, cy=0.15, **scene):
    """Build, warm the kernels up on a tiny ramp, then time the ramp; return (built, result, seconds).
    scene: further reference_scene arguments (order, refinements, nu)."""
    from ..scene.build import reference_scene
    from ..solve.simulate import run_schedule

    built = reference_scene(cy, growth=growth, steps=steps, max_area=max_area, **scene).build()
    warm_up(built, options)
    start = time.perf_counter()
    result = run_schedule(built, options=options)
    return built, result, time.perf_counter() - start


MAIN_COMMAND = ("--cy", "0.15")
FIRST_INCREMENT = re.compile(r"step\s+1/")


def main_command_process(cache_dir: str, out: str, flags: tuple = ()) -> tuple[float, float, dict | None]:
    """Run the main command (with flags) in a fresh process with Taichi's offline kernel cache in cache_dir;
    return (seconds until its first increment's line is printed, seconds until the process exits, its
    summary JSON), the summary None when it exits with an error (a renderer that is unavailable)."""
    from .. import backend

    env = {**os.environ, backend.environment_name("cache"): cache_dir, "PYTHONUNBUFFERED": "1"}
    command = [sys.executable, "-m", "taichi_pneuma.apps.inflate", *MAIN_COMMAND, *flags, "--out", out]
    start = time.perf_counter()
    first = float("nan")
    with subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, env=env) as proc:
        for line in proc.stdout:
            if first != first and FIRST_INCREMENT.search(line):
                first = time.perf_counter() - start
    whole = time.perf_counter() - start
    if proc.returncode != 0:
        return first, whole, None
    return first, whole, json.loads((Path(out) / "inflate_cy+0.15_summary.json").read_text())


def first_versus_typical(result) -> tuple[float, float]:
    """(seconds of increments 1 and 2, median seconds of two increments over the rest of the ramp)."""
    seconds = result.history["seconds"]
    return float(seconds[1:3].sum()), 2.0 * float(np.median(seconds[3:]))


# the main command's processes: label, flags, kernel cache (the first run fills the empty one)
PROCESSES = (("`--no-video`, empty kernel cache", ("--no-video",)), ("`--no-video`, warm kernel cache", ("--no-video",)),
             ("with its video (renderer auto: ti.GUI), warm", ()),
             ("with its video, `--renderer ggui` (GGUI on Vulkan), warm", ("--renderer", "ggui")))


def startup() -> tuple[str, dict]:
    """Kernel compilation at start-up, and rendering. The main command's whole process, and its time to the
    first increment, from an empty kernel cache (as on a fresh machine) and then from the cache it left,
    without and with its video (each renderer), against the seed pipeline's 25 s for the same ramp (a NumPy/SciPy tutorial); per
    renderer, rendering per frame against solving per step in the same process; and, in this process,
    three scenes in turn that differ in mesh size, E, nu, k and number of chambers: their build time and
    their first two increments against two typical ones."""
    from ..api import load_scene
    from ..scene.build import reference_scene
    from ..solve.simulate import run_schedule

    rows, render_rows, data = [], [], {"process": {}, "rendering": {}, "scenes": []}
    with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as out:
        for label, flags in PROCESSES:
            first, whole, summary = main_command_process(cache, out, flags)
            data["process"][label] = {"first_increment_s": first, "whole_s": whole, "ok": summary is not None}
            if summary is None:
                rows.append([f"main command {label}", "unavailable", "", ""])
                continue
            rows.append([f"main command {label}", f"{whole:.2f}", f"{first:.2f}",
                         f"{REFERENCE_TUTORIAL_SECONDS / whole:.1f}x faster"])
            if "renderer" in summary:
                frame_ms, step_ms = summary["render_ms_per_frame"], 1e3 * summary["solve_seconds_per_step"]
                data["rendering"][summary["renderer"]] = {"ms_per_frame": frame_ms, "solve_ms_per_step": step_ms,
                                                          "whole_s": whole}
                render_rows.append([summary["renderer"], f"{frame_ms:.1f}", f"{step_ms:.1f}",
                                    f"{frame_ms / step_ms:.2f}", f"{whole:.2f}"])
    table = markdown(["whole process", "s", "to first increment (s)", "against the seed pipeline's 25 s for this ramp"],
                     rows)
    table += "\n" + markdown(["renderer (960x384 frames, coloured by stretch)", "render ms / frame",
                              "solve ms / step (same process)", "frame / step", "whole process (s)"], render_rows)
    scenes = [("reference cy=+0.15 (first in process)", lambda: reference_scene(0.15)),
              ("cy=+0.10, max area 0.002, E 2e4, nu 0.4, k 2e5",
               lambda: reference_scene(0.10, E=2e4, nu=0.4, k=2e5, max_area=0.002)),
              ("bidirectional.toml (2 chambers)", lambda: load_scene("bidirectional"))]
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
    from ..scene.build import reference_scene
    from ..solve.simulate import run_schedule

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
    iterations = int(result.history["iterations"].sum())
    increments = len(result.steps) - 1
    rows = [["mesh + terms (Triangle, fields)", f"{1e3 * build_seconds:.0f}", "once"],
            ["first solve: kernel compile / cache load", f"{1e3 * first_call:.0f}", "once per process"]]
    rows += [[f"ramp: {p}", f"{1e3 * phases[p]:.0f}", f"{1e3 * phases[p] / iterations:.2f} ms/iteration"] for p in PHASES]
    other = ramp_seconds - sum(phases.values())
    rows += [["ramp: other (history, predictor, Python)", f"{1e3 * other:.0f}", ""],
             ["**ramp total (35 increments)**", f"**{1e3 * ramp_seconds:.0f}**",
              f"{increments / ramp_seconds:.0f} increments/s, {iterations} Newton iterations "
              f"({iterations / increments:.1f} per increment), {1e3 * ramp_seconds / iterations:.1f} ms/iteration"],
             ["seed pipeline, a NumPy/SciPy tutorial (its stated figure, not measured here)", f"{1e3 * REFERENCE_TUTORIAL_SECONDS:.0f}",
              f"{REFERENCE_TUTORIAL_SECONDS / ramp_seconds:.0f}x slower than this ramp"]]
    data = {"build_s": build_seconds, "first_call_s": first_call, "ramp_s": ramp_seconds, "phases_s": dict(phases),
            "iterations": iterations, "increments_per_s": increments / ramp_seconds,
            "tip_deflection": result.tip_deflection, "peak_pressure": result.peak_pressure}
    return markdown(["part", "ms", "note"], rows), data


def backends() -> tuple[str, dict]:
    """Each backend on the same matrices (the final reference state), then each on the whole ramp."""
    from ..solve.linsolve import BACKENDS, FixedPattern, make_backend
    from ..solve.newton import NewtonOptions

    built, result, _ = timed_ramp()
    model = built.model
    model.set_displacements(result.positions[-1] - built.mesh.vertices)
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


MESHES = {1: (0.005, 0.0025, 0.0012, 0.0006, 0.0003, 0.00015), 2: (0.02, 0.01, 0.005, 0.0025, 0.0012)}
STUDY_NU = (0.45, 0.499)


def converged_tip(poisson_ratio: float, levels: int = 3) -> dict:
    """The reference: P2 on the reference mesh (max area 0.0012) refined uniformly 0 .. levels-1 times, with
    10 increments (the area-controlled equilibrium does not depend on the path: see the knobs below).
    Returns the tips per level, the observed order p = log2(|f0 - f1| / |f1 - f2|) and the finest tip."""
    tips, nodes = [], []
    for level in range(levels):
        built, result, _ = timed_ramp(steps=11, order=2, refinements=level, nu=poisson_ratio)
        tips.append(result.tip_deflection)
        nodes.append(built.mesh.n_vertices)
        print(f"  reference nu={poisson_ratio}: level {level}, {nodes[-1]} nodes, tip {tips[-1]:+.6f}",
              file=sys.stderr, flush=True)
    order = float(np.log2(abs(tips[0] - tips[1]) / abs(tips[1] - tips[2])))
    return {"tips": tips, "nodes": nodes, "observed_order": order, "tip": tips[-1],
            "remaining_error_estimate": abs(tips[2] - tips[1]) / (2 ** order - 1) / abs(tips[-1])}


def accuracy(out: Path) -> tuple[str, dict]:
    """What accuracy costs: linear (P1) and quadratic (P2) triangles at several mesh densities, nu = 0.45
    and 0.499, error of the tip deflection against a converged P2 reference (converged_tip) and wall time
    of the 35-increment ramp; then the Newton tolerance and the number of increments on the default P1
    mesh, against the same mesh solved tightly (tol 1e-9, 100 increments). Plots error against time."""
    from ..solve.newton import NewtonOptions

    rows, data = [], {"elements": collections.defaultdict(list), "references": {}}
    for nu in STUDY_NU:
        reference = converged_tip(nu)
        data["references"][nu] = reference
        for order, areas in MESHES.items():
            for max_area in areas:
                built, result, seconds = timed_ramp(max_area=max_area, order=order, nu=nu)
                error = abs(result.tip_deflection / reference["tip"] - 1)
                data["elements"][f"P{order}, nu = {nu}"].append(
                    {"value": max_area, "nodes": built.mesh.n_vertices, "seconds": seconds, "tip": error})
                rows.append([f"P{order}, nu = {nu}", f"{max_area:g}", built.mesh.n_vertices, f"{1e3 * seconds:.0f}",
                             f"{result.tip_deflection:+.5f}", f"{100 * error:.2f} %"])
    table = markdown(["elements", "max area", "nodes", "ramp (ms)", "tip dy", "tip error"], rows)
    table += "\n" + markdown(["nu", "P2 reference tips, levels 0 / 1 / 2 (nodes)", "observed order",
                              "estimated error of the finest"],
                             [[nu, " / ".join(f"{t:+.5f} ({n})" for t, n in zip(r["tips"], r["nodes"])),
                               f"{r['observed_order']:.2f}", f"{100 * r['remaining_error_estimate']:.3f} %"]
                              for nu, r in data["references"].items()])
    knobs = {"Newton tolerance": [(t, dict(options=NewtonOptions(tol=t))) for t in (1e-2, 1e-4, 1e-6, 1e-9)],
             "ramp increments": [(n, dict(steps=n + 1)) for n in (5, 10, 35, 100)]}
    tight = timed_ramp(steps=101, options=NewtonOptions(tol=1e-9))[1].tip_deflection
    rows = []
    for knob, runs in knobs.items():
        for value, kwargs in runs:
            _, result, seconds = timed_ramp(**kwargs)
            rows.append([knob, f"{value:g}", f"{1e3 * seconds:.0f}", f"{abs(result.tip_deflection / tight - 1):.1e}"])
    table += "\n" + markdown(["knob (P1, max area 0.0012)", "value", "ramp (ms)", "tip error vs tight solve"], rows)
    plot_accuracy(data["elements"], out / "bench_accuracy.png")
    return table, {"elements": dict(data["elements"]), "references": data["references"]}


LOCKING_NU = (0.45, 0.49, 0.499, 0.4999)
LOCKING_BASE = {1: 0.005, 2: 0.02}


def incompressible() -> tuple[str, dict]:
    """Near incompressibility: the tip deflection of P1 (base max area 0.005) and P2 (base 0.02) meshes
    refined uniformly 0, 1, 2 times (10 increments to 3.5x), at nu = 0.45 ... 0.4999, with the observed
    order p = log2(|f0 - f1| / |f1 - f2|) and the change between the two finest levels."""
    rows, data = [], []
    for nu in LOCKING_NU:
        for order, max_area in LOCKING_BASE.items():
            runs = [timed_ramp(max_area=max_area, steps=11, order=order, refinements=level, nu=nu)
                    for level in range(3)]
            tips = [result.tip_deflection for _, result, _ in runs]
            nodes = [built.mesh.n_vertices for built, _, _ in runs]
            p = float(np.log2(abs(tips[0] - tips[1]) / abs(tips[1] - tips[2])))
            record = {"nu": nu, "order": order, "nodes": nodes, "tips": tips, "observed_order": p,
                      "last_change": abs(tips[2] / tips[1] - 1), "seconds": [s for _, _, s in runs]}
            data.append(record)
            print(f"  incompressible: {record}", file=sys.stderr, flush=True)
            rows.append([nu, f"P{order}", " / ".join(f"{t:+.4f} ({n})" for t, n in zip(tips, nodes)), f"{p:.2f}",
                         f"{100 * record['last_change']:.2f} %"])
    header = ["nu", "elements", "tip dy, levels 0 / 1 / 2 (nodes)", "observed order", "change level 1 -> 2"]
    return markdown(header, rows), {"runs": data}


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
        ax.loglog(times, errors, "o-" if knob.startswith("P2") else "s--", label=knob)  # points labelled by max area
        for r, t, e in zip(runs, times, errors):
            ax.annotate(f"{r['value']:g}", (t, e), textcoords="offset points", xytext=(4, 3), fontsize=7)
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.axhline(0.01, color="grey", lw=0.8, ls="--")
    ax.set_xlabel("wall time of the 35-increment ramp (s)")
    ax.set_ylabel("relative tip-deflection error")
    ax.set_title("Tip error versus time: linear and quadratic triangles (cy = +0.15, CPU)")
    ax.legend()
    fig.tight_layout()
    write_atomic(path, lambda tmp: fig.savefig(tmp, format="png"))
    plt.close(fig)


def scaling() -> tuple[str, dict]:
    """Time per Newton iteration and per increment from ~500 to ~100k vertices (3 increments to 1.5x)."""
    rows, data = [], []
    for max_area in (0.005, 0.0012, 0.0003, 0.0001, 0.00003, 0.00002):
        built, result, seconds = timed_ramp(max_area=max_area, steps=4, growth=1.5)
        iterations = int(result.history["iterations"].sum())
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


def phase_ms(result) -> tuple[int, dict[str, float]]:
    """(the Newton iterations of a run, each phase's ms per iteration)."""
    phases = collections.Counter()
    for solve in result.solves:
        phases.update(solve.phase_seconds)
    iterations = int(result.history["iterations"].sum())
    return iterations, {p: 1e3 * phases[p] / iterations for p in PHASES}


@dataclass(frozen=True)
class Meshed:
    """A scene geometry already meshed (a tetrahedral Mesh and its one chamber), for timing 3D solves."""

    ready: object
    chambers: tuple = (("cavity", None),)

    def mesh(self):
        return self.ready


def octant(divisions: int, layers: int, order: int, increments: int = 3) -> "Scene":
    """A pressurised octant of the thick spherical shell 1 <= r <= 2 (layered.py: 3 divisions^2 layers
    tetrahedra), closed by its three symmetry planes; pressure 0 -> 0.05 E in `increments` increments."""
    from ..fem.supports import Roller
    from ..fem.layered import spherical_shell_octant
    from ..fem.tetmesh import tet_mesh
    from ..scene.build import ChamberControl, Material, Scene
    from ..scene.schedule import ChamberSchedule

    vertices, tets, wall = spherical_shell_octant(1.0, 2.0, divisions, layers)
    mesh = tet_mesh(vertices, tets, {"cavity": wall}, order=order, clamp=None,
                    rollers=tuple(Roller(tuple(n), (0.0, 0.0, 0.0)) for n in np.eye(3)))
    return Scene(Meshed(mesh), (ChamberControl(ChamberSchedule("pressure", ((increments, 500.0),))),), increments,
                 Material(1e4, 0.45))


SOLID_MESHES = (("P1", 8, 4, 1), ("P1", 16, 6, 1), ("P1", 24, 12, 1), ("P2", 12, 6, 2))
SOLID_BACKENDS = ("taichi", "cholespy", "cholmod", "amg")


def solid() -> tuple[str, dict]:
    """3D: time per Newton iteration and its parts (the linear solve's share) on octants of growing size, linear
    and quadratic tetrahedra, Taichi's LLT, CHOLMOD and CG with multigrid (where auto's switch to it comes from);
    the elastic Hessian with the analytic eigensystem against the Jacobi one."""
    from ..materials import StableNeoHookean
    from ..solve.newton import NewtonOptions
    from ..scene.schedule import ChamberSchedule, Schedule
    from ..solve.simulate import run_schedule
    from ..terms import Elasticity

    class JacobiNeoHookean(StableNeoHookean):
        """Stable neo-Hookean without its analytic eigensystem: the generic Jacobi path (timing only)."""

        analytic_dims = ()

    rows, data = [], []
    for label, divisions, layers, order in SOLID_MESHES:
        built = octant(divisions, layers, order).build()
        mesh = built.mesh
        for backend in SOLID_BACKENDS:
            options = NewtonOptions(linear_solver=backend)
            run_schedule(built, Schedule(1, (ChamberSchedule("pressure", ((1, 5.0),)),)), options)  # compile, analyse
            start = time.perf_counter()
            result = run_schedule(built, options=options)
            seconds = time.perf_counter() - start
            iterations, per = phase_ms(result)
            linear = per["factorize"] + per["solve"]
            record = {"elements": f"{label} tetrahedra", "tetrahedra": mesh.n_elements, "dofs": 3 * mesh.n_vertices,
                      "backend": backend, "iterations": iterations, "ms_per_iteration": 1e3 * seconds / iterations,
                      "phases_ms": per, "linear_solve_share": linear / (1e3 * seconds / iterations),
                      "tip": float(result.positions[-1][:, 0].max())}
            data.append(record)
            rows.append([f"{label}, {mesh.n_elements}", 3 * mesh.n_vertices, backend, iterations,
                         f"{record['ms_per_iteration']:.0f}", *(f"{per[p]:.1f}" for p in PHASES),
                         f"{100 * record['linear_solve_share']:.0f} %", f"{record['tip']:.6f}"])
            print(f"  solid: {record}", file=sys.stderr, flush=True)
    table = markdown(["tetrahedra", "DOFs", "backend", "iterations", "ms / iteration", *(f"{p} (ms)" for p in PHASES),
                      "linear solve share", "max x (pole)"], rows)
    eigen_rows = []
    for label, divisions, layers, order in (("P1", 24, 12, 1), ("P2", 12, 6, 2)):
        built = octant(divisions, layers, order).build()
        elastic = built.elastic
        times = {}
        for name, law in (("analytic", StableNeoHookean), ("Jacobi", JacobiNeoHookean)):
            term = Elasticity(built.model.config, built.mesh.elements, law, elastic.parameters)
            term.hessian_values(True)
            start = time.perf_counter()
            for _ in range(5):
                term.hessian_values(True)
            times[name] = (time.perf_counter() - start) / 5
        n = built.mesh.n_elements
        eigen_rows.append([f"{label}, {n}", *(f"{1e3 * t:.1f} ({1e6 * t / n:.1f} us/element)" for t in times.values()),
                           f"{times['Jacobi'] / times['analytic']:.1f}x"])
    table += "\nThe projected elastic Hessian, analytic eigensystem against Jacobi on the 9 x 9 d2psi/dF2:\n\n"
    table += markdown(["tetrahedra", "analytic (ms)", "Jacobi (ms)", "ratio"], eigen_rows)
    return table, {"runs": data}


# the shipped 3D scenes and the presets run on each (the PneuNet's accurate preset takes about an hour on 2 cores)
PRESET_SCENES_3D = {"beam_3d_ellipsoid": ("draft", "default", "high", "accurate"),
                    "pneunet_3d": ("draft", "default", "high")}
# the converged peak tip deflection (the largest |mean y displacement| of the tip face over the run), for the
# presets' errors, each from quadratic meshes refined towards it (beam_3d_ellipsoid: docs/solid.md, "3D presets";
# pneunet_3d: docs/3d.md, its near-chamber size down to 0.07)
CONVERGED_TIP_3D = {"beam_3d_ellipsoid": -0.1974, "pneunet_3d": -1.100}


def presets_3d() -> tuple[str, dict]:
    """The 3D presets on the shipped 3D scenes: for each scene and --quality, the main command's whole process
    (pneuma-inflate --scene S --quality Q --no-video, a warm kernel cache) timed, with its DOFs, Newton iterations
    (and chord steps: no new Hessian), the linear solver auto chose, the seconds per phase, and the peak tip
    deflection's error against the converged one (CONVERGED_TIP_3D)."""
    rows, data = [], []
    phases = ("hessian", "assemble", "factorize", "solve", "gradient", "line_search")
    for name, qualities in PRESET_SCENES_3D.items():
        for quality in qualities:
            with tempfile.TemporaryDirectory() as out:
                command = [sys.executable, "-m", "taichi_pneuma.apps.inflate", "--scene", name, "--quality", quality,
                           "--no-video", "--quiet", "--out", out]
                start = time.perf_counter()
                proc = subprocess.run(command, capture_output=True, text=True)
                whole = time.perf_counter() - start
                require(proc.returncode == 0, f"{' '.join(command[1:])} failed: {proc.stderr[-300:]}")
                summary = json.loads(next(Path(out).glob("*_summary.json")).read_text())
            tip = summary["extremes"]["tip_dy"]
            peak = tip["min"] if abs(tip["min"]) >= abs(tip["max"]) else tip["max"]
            converged = CONVERGED_TIP_3D[name]
            error = None if converged is None else abs(peak / converged - 1)
            newton = summary["newton"]
            record = {"scene": name, "quality": quality, "dofs": 3 * summary["vertices"],
                      "order": summary["element_order"], "iterations": summary["newton_iterations_total"],
                      "chord_steps": newton["chord_steps"], "linear_solver": newton["linear_solver"],
                      "phase_seconds": newton["phase_seconds"], "ramp_s": summary["wall_seconds"], "whole_s": whole,
                      "peak_tip": peak, "error": error}
            data.append(record)
            print(f"  presets_3d: {record}", file=sys.stderr, flush=True)
            rows.append([name, quality, f"{record['dofs']:,}", record["order"],
                         f"{record['iterations']} ({record['chord_steps']})", record["linear_solver"],
                         *(f"{newton['phase_seconds'].get(p, 0.0):.1f}" for p in phases), f"{record['ramp_s']:.1f}",
                         f"{whole:.1f}", f"{peak:.5f}", "" if error is None else f"{100 * error:.2f} %"])
    header = ["scene", "quality", "DOFs", "order", "Newton iterations (chord)", "solver",
              *(f"{p} (s)" for p in phases), "ramp (s)", "whole process (s)", "peak tip dy", "error"]
    return markdown(header, rows), {"runs": data, "converged_tip": CONVERGED_TIP_3D}


def compilers() -> tuple[str, dict]:
    """Taichi against Quadrants in one run: for each one installed, in child processes with PNEUMA_BACKEND set,
    the startup section (the main command from an empty and a warm kernel cache) and the breakdown section twice
    (the second's first solve loads every kernel from the warm cache): the first calls of the kernels and the ramp."""
    from .. import backend

    empty, warm = (label for label, _ in PROCESSES[:2])  # the main command --no-video, empty and warm cache
    rows, data = [], {}
    for name in backend.INSTALL:
        if importlib.util.find_spec(name) is None:
            rows.append([name, "not installed"] + [""] * 7)
            continue
        sections = {}
        with tempfile.TemporaryDirectory() as out:
            for section in ("breakdown", "breakdown", "startup"):
                command = [sys.executable, "-m", "taichi_pneuma.apps.bench", "--sections", section, "--out", out]
                proc = subprocess.run(command, env={**os.environ, backend.CHOICE_VARIABLE: name}, capture_output=True,
                                      text=True)
                require(proc.returncode == 0, f"bench --sections {section} on {name} failed: {proc.stderr[-300:]}")
                sections[section] = json.loads((Path(out) / f"bench_{section}.json").read_text())
        process, ramp = sections["startup"]["data"]["process"], sections["breakdown"]["data"]
        data[name] = {"version": sections["breakdown"]["backend"], "startup": sections["startup"]["data"],
                      "breakdown": ramp}
        rows.append([data[name]["version"], f"{process[empty]['whole_s']:.2f}",
                     f"{process[warm]['whole_s']:.2f}",
                     f"{process[warm]['first_increment_s']:.2f}", f"{1e3 * ramp['first_call_s']:.0f}",
                     f"{1e3 * ramp['ramp_s']:.0f}", ramp["iterations"], f"{1e3 * ramp['ramp_s'] / ramp['iterations']:.1f}",
                     f"{ramp['tip_deflection']:.15f}"])
    header = ["compiler", "main command, empty cache (s)", "warm cache (s)", "warm: to first increment (s)",
              "first solve, warm cache (ms)", "reference ramp (ms)", "Newton iterations", "ms/iteration", "tip dy"]
    return markdown(header, rows), data
def parser():
    from .cli import app_parser

    p = app_parser("pneuma-bench", __doc__)
    p.add_argument("--sections", default=",".join(SECTIONS), help=f"comma-separated, from {', '.join(SECTIONS)}")
    p.add_argument("--out", default="out/bench",
                   help="directory for the tables, JSON and plot (benchmarks/results: the tracked ones of a clone)")
    p.add_argument("--arch", default="cpu", choices=sorted(runtime.ARCHES), help="Taichi backend")
    return p


def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    try:
        with signals.interrupting():
            environment.check_environment()
            return run(args)
    except PneumaInputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:  # Ctrl-C, SIGTERM, SIGHUP: the sections done are written
        print(f"error: interrupted ({signals.name_of(exc)})", file=sys.stderr)
        return signals.exit_code_of(exc)
    finally:
        signals.finished()


def run(args: argparse.Namespace) -> int:
    sections = [s.strip() for s in args.sections.split(",") if s.strip()]
    for s in sections:
        require(s in SECTIONS, f"--sections: {s!r} is not one of {', '.join(SECTIONS)}")
    out = prepare_directory(args.out)
    runtime.init(args.arch)
    from .. import backend

    heading = f"Machine: {machine()}, {backend.NAME} {backend.VERSION}, arch {args.arch}\n\n"
    for section in sections:
        print(f"## {section}", flush=True)
        table, data = accuracy(out) if section == "accuracy" else {"startup": startup, "breakdown": breakdown,
                                                                    "backends": backends, "incompressible": incompressible,
                                                                    "scaling": scaling, "solid": solid,
                                                                    "presets_3d": presets_3d,
                                                                    "compilers": compilers}[section]()
        print(heading + table, flush=True)
        save_text(out / f"bench_{section}.md", heading + table)
        save_json(out / f"bench_{section}.json", {"machine": machine(), "backend": f"{backend.NAME} {backend.VERSION}",
                                                  "arch": args.arch, **{"data": data}})
    return 0


if __name__ == "__main__":
    sys.exit(main())
