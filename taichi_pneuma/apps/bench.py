"""What a user's run costs in time: start-up and rendering (the main command as a whole process, from an empty and a
warm kernel cache), where the time of the reference ramp goes, and the 3D presets on the shipped 3D scenes (time
and error).

    pneuma-bench [--sections startup,breakdown,presets_3d] [--out out/bench]
    pneuma-bench --out benchmarks/results       (a clone: rewrite the tracked tables the site shows)

Every section prints a Markdown table and saves it (bench_<section>.md, .json) under --out (default out/bench,
a scratch directory), headed with the machine and date. Timings are wall-clock on a possibly shared machine:
compare ratios within one run. The research measurements (accuracy, incompressible, scaling, backends, solid,
compilers) are scripts in benchmarks/ that write their tables the same way (save_section).
"""

import argparse
import collections
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from datetime import date
from pathlib import Path

import numpy as np

from .. import environment, runtime, signals
from ..errors import PneumaInputError, require
from ..io.output import prepare_directory, save_json, save_text
from .quality import ACTUATORS_3D, CONVERGED_3D

SECTIONS = ("startup", "breakdown", "presets_3d")
# sections that were pneuma-bench's and are now scripts of the repository: python benchmarks/<name>.py
MOVED = ("accuracy", "incompressible", "scaling", "backends", "solid", "compilers")
REFERENCE_TUTORIAL_SECONDS = (
    25.0  # the seed pipeline (a NumPy/SciPy tutorial) on the cy = 0.15 ramp, this kind of machine
)
PHASES = ("gradient", "hessian", "assemble", "factorize", "solve", "line_search")


def machine() -> str:
    cores = f"{os.cpu_count()} cores"
    return f"{platform.node()}, {platform.machine()}, {cores}, Python {platform.python_version()}, {date.today()}"


def markdown(header: list[str], rows: list[list]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def warm_up(built, options=None) -> None:
    """Compile (or load from the offline cache) this scene's kernels: one tiny increment of 1% area."""
    from ..scene.schedule import Schedule, area_ramp
    from ..solve.simulate import run_schedule

    run_schedule(built, Schedule(1, (area_ramp(1.01, 2),)), options)


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
        for line in proc.stdout or ():
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
PROCESSES = (
    ("`--no-video`, empty kernel cache", ("--no-video",)),
    ("`--no-video`, warm kernel cache", ("--no-video",)),
    ("with its video (renderer auto: ti.GUI), warm", ()),
    ("with its video, `--renderer ggui` (GGUI on Vulkan), warm", ("--renderer", "ggui")),
)


def startup() -> tuple[str, dict]:
    """Kernel compilation at start-up, and rendering. The main command's whole process, and its time to the
    first increment, from an empty kernel cache (as on a fresh machine) and then from the cache it left,
    without and with its video (each renderer), against the seed pipeline's 25 s for the same ramp (a NumPy/SciPy
    tutorial); per
    renderer, rendering per frame against solving per step in the same process; and, in this process,
    three scenes in turn that differ in mesh size, E, nu, k and number of chambers: their build time and
    their first two increments against two typical ones."""
    from ..api import load_scene
    from ..scene.build import reference_scene
    from ..solve.simulate import run_schedule

    rows: list[list] = []
    render_rows: list[list] = []
    processes: dict[str, dict] = {}
    rendering: dict[str, dict] = {}
    scenes_data: list[dict] = []
    data = {"process": processes, "rendering": rendering, "scenes": scenes_data}
    with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as out:
        for label, flags in PROCESSES:
            first, whole, summary = main_command_process(cache, out, flags)
            processes[label] = {"first_increment_s": first, "whole_s": whole, "ok": summary is not None}
            if summary is None:
                rows.append([f"main command {label}", "unavailable", "", ""])
                continue
            rows.append(
                [
                    f"main command {label}",
                    f"{whole:.2f}",
                    f"{first:.2f}",
                    f"{REFERENCE_TUTORIAL_SECONDS / whole:.1f}x faster",
                ]
            )
            if "renderer" in summary:
                frame_ms, step_ms = summary["render_ms_per_frame"], 1e3 * summary["solve_seconds_per_step"]
                rendering[summary["renderer"]] = {
                    "ms_per_frame": frame_ms,
                    "solve_ms_per_step": step_ms,
                    "whole_s": whole,
                }
                render_rows.append(
                    [
                        summary["renderer"],
                        f"{frame_ms:.1f}",
                        f"{step_ms:.1f}",
                        f"{frame_ms / step_ms:.2f}",
                        f"{whole:.2f}",
                    ]
                )
    table = markdown(
        ["whole process", "s", "to first increment (s)", "against the seed pipeline's 25 s for this ramp"], rows
    )
    table += "\n" + markdown(
        [
            "renderer (960x384 frames, coloured by stretch)",
            "render ms / frame",
            "solve ms / step (same process)",
            "frame / step",
            "whole process (s)",
        ],
        render_rows,
    )
    scenes = [
        ("reference cy=+0.15 (first in process)", lambda: reference_scene(0.15)),
        (
            "cy=+0.10, max area 0.002, E 2e4, nu 0.4, k 2e5",
            lambda: reference_scene(0.10, E=2e4, nu=0.4, k=2e5, max_area=0.002),
        ),
        ("bidirectional.toml (2 chambers)", lambda: load_scene("bidirectional")),
    ]
    rows = []
    for label, make in scenes:
        start = time.perf_counter()
        built = make().build()
        build_seconds = time.perf_counter() - start
        first, typical = first_versus_typical(run_schedule(built))
        scenes_data.append(
            {
                "scene": label,
                "vertices": built.mesh.n_vertices,
                "build_s": build_seconds,
                "first_two_increments_s": first,
                "two_typical_increments_s": typical,
            }
        )
        rows.append(
            [
                label,
                built.mesh.n_vertices,
                f"{1e3 * build_seconds:.0f}",
                f"{1e3 * first:.0f}",
                f"{1e3 * typical:.0f}",
                f"{first / typical:.1f}x",
            ]
        )
    table += "\n" + markdown(
        [
            "scene, in one process",
            "vertices",
            "build (ms)",
            "increments 1-2 (ms)",
            "two typical increments (ms)",
            "ratio",
        ],
        rows,
    )
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
    phases: collections.Counter[str] = collections.Counter()
    for solve in result.solves:
        phases.update(solve.phase_seconds)
    iterations = int(result.history["iterations"].sum())
    increments = len(result.steps) - 1
    rows = [
        ["mesh + terms (Triangle, fields)", f"{1e3 * build_seconds:.0f}", "once"],
        ["first solve: kernel compile / cache load", f"{1e3 * first_call:.0f}", "once per process"],
    ]
    rows += [
        [f"ramp: {p}", f"{1e3 * phases[p]:.0f}", f"{1e3 * phases[p] / iterations:.2f} ms/iteration"] for p in PHASES
    ]
    other = ramp_seconds - sum(phases.values())
    rows += [
        ["ramp: other (history, predictor, Python)", f"{1e3 * other:.0f}", ""],
        [
            "**ramp total (35 increments)**",
            f"**{1e3 * ramp_seconds:.0f}**",
            f"{increments / ramp_seconds:.0f} increments/s, {iterations} Newton iterations "
            f"({iterations / increments:.1f} per increment), {1e3 * ramp_seconds / iterations:.1f} ms/iteration",
        ],
        [
            "seed pipeline, a NumPy/SciPy tutorial (its stated figure, not measured here)",
            f"{1e3 * REFERENCE_TUTORIAL_SECONDS:.0f}",
            f"{REFERENCE_TUTORIAL_SECONDS / ramp_seconds:.0f}x slower than this ramp",
        ],
    ]
    data = {
        "build_s": build_seconds,
        "first_call_s": first_call,
        "ramp_s": ramp_seconds,
        "phases_s": dict(phases),
        "iterations": iterations,
        "increments_per_s": increments / ramp_seconds,
        "tip_deflection": result.tip_deflection,
        "peak_pressure": result.peak_pressure,
    }
    return markdown(["part", "ms", "note"], rows), data


# the shipped 3D scenes and the presets run on each ("as written": no --quality, the scene's own [mesh]; the
# PneuNet's accurate preset takes about an hour on 2 cores)
PRESET_SCENES_3D = {
    "beam_3d_ellipsoid": ("draft", "default", "high", "accurate"),
    "pneunet_3d": ("draft", "default", "high"),
    **{name: ("as written", "draft", "default", "high") for name in ACTUATORS_3D},
}


def presets_3d() -> tuple[str, dict]:
    """The 3D presets on the shipped 3D scenes: for each scene and --quality, the main command's whole process
    (pneuma-inflate --scene S --quality Q --no-video, a warm kernel cache) timed, with its DOFs, Newton iterations
    (and chord steps: no new Hessian), the linear solver auto chose, the seconds per phase, and the peak of the
    scene's measure (the larger in size of its history column's least and greatest value) against its converged
    reference (quality.CONVERGED_3D)."""
    rows, data = [], []
    phases = ("hessian", "assemble", "factorize", "solve", "gradient", "line_search")
    for name, qualities in PRESET_SCENES_3D.items():
        column, converged, _ = CONVERGED_3D[name]
        for quality in qualities:
            with tempfile.TemporaryDirectory() as out:
                preset = [] if quality == "as written" else ["--quality", quality]
                command = [
                    sys.executable,
                    "-m",
                    "taichi_pneuma.apps.inflate",
                    "--scene",
                    name,
                    *preset,
                    "--no-video",
                    "--quiet",
                    "--out",
                    out,
                ]
                start = time.perf_counter()
                proc = subprocess.run(command, capture_output=True, text=True)
                whole = time.perf_counter() - start
                written = next(Path(out).glob("*_summary.json"), None) if proc.returncode == 0 else None
                summary = None if written is None else json.loads(written.read_text())
            if summary is None:  # a preset that finds no equilibrium is a row of the table, not the end of it
                stopped = (proc.stderr.strip().splitlines() or [f"exit {proc.returncode}"])[-1]
                data.append({"scene": name, "quality": quality, "whole_s": whole, "stopped": stopped})
                print(f"  presets_3d: {name} {quality}: {stopped}", file=sys.stderr, flush=True)
                rows.append([name, quality, *[""] * (len(phases) + 5), f"{whole:.1f}", "", stopped])
                continue
            extremes = summary["extremes"][column]
            peak = extremes["min"] if abs(extremes["min"]) >= abs(extremes["max"]) else extremes["max"]
            error = abs(peak / converged - 1)
            newton = summary["newton"]
            record = {
                "scene": name,
                "quality": quality,
                "dofs": 3 * summary["vertices"],
                "order": summary["element_order"],
                "iterations": summary["newton_iterations_total"],
                "chord_steps": newton["chord_steps"],
                "linear_solver": newton["linear_solver"],
                "phase_seconds": newton["phase_seconds"],
                "ramp_s": summary["wall_seconds"],
                "whole_s": whole,
                "measure": column,
                "peak": peak,
                "error": error,
            }
            data.append(record)
            print(f"  presets_3d: {record}", file=sys.stderr, flush=True)
            rows.append(
                [
                    name,
                    quality,
                    f"{record['dofs']:,}",
                    record["order"],
                    f"{record['iterations']} ({record['chord_steps']})",
                    record["linear_solver"],
                    *(f"{newton['phase_seconds'].get(p, 0.0):.1f}" for p in phases),
                    f"{record['ramp_s']:.1f}",
                    f"{whole:.1f}",
                    f"{column} {peak:.5g}",
                    f"{100 * error:.2f} %",
                ]
            )
    header = [
        "scene",
        "quality",
        "DOFs",
        "order",
        "Newton iterations (chord)",
        "solver",
        *(f"{p} (s)" for p in phases),
        "ramp (s)",
        "whole process (s)",
        "peak",
        "error",
    ]
    return markdown(header, rows), {"runs": data, "converged": CONVERGED_3D}


def save_section(out: Path, section: str, table: str, data, arch: str) -> None:
    """Print a section's Markdown table and save it as bench_<section>.md, its data as bench_<section>.json, under
    out, headed with the machine and date, the kernels' compiler and the arch."""
    from .. import backend

    heading = f"Machine: {machine()}, {backend.NAME} {backend.VERSION}, arch {arch}\n\n"
    print(heading + table, flush=True)
    save_text(out / f"bench_{section}.md", heading + table)
    save_json(
        out / f"bench_{section}.json",
        {"machine": machine(), "backend": f"{backend.NAME} {backend.VERSION}", "arch": arch, **{"data": data}},
    )


def parser():
    from .cli import app_parser

    p = app_parser("pneuma-bench", __doc__)
    p.add_argument("--sections", default=",".join(SECTIONS), help=f"comma-separated, from {', '.join(SECTIONS)}")
    p.add_argument(
        "--out",
        default="out/bench",
        help="directory for the tables and JSON (benchmarks/results: the tracked ones of a clone)",
    )
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
        require(
            s not in MOVED,
            f"--sections: {s!r} is a script of the repository now (python benchmarks/{s}.py); "
            f"pneuma-bench's sections are {', '.join(SECTIONS)}",
        )
        require(s in SECTIONS, f"--sections: {s!r} is not one of {', '.join(SECTIONS)}")
    out = prepare_directory(args.out)
    runtime.init(args.arch)
    for section in sections:
        print(f"## {section}", flush=True)
        table, data = {"startup": startup, "breakdown": breakdown, "presets_3d": presets_3d}[section]()
        save_section(out, section, table, data, args.arch)
    return 0


if __name__ == "__main__":
    sys.exit(main())
