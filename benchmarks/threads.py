"""What the second core buys, per phase: the main command (pneuma-inflate, its whole process, a warm kernel and
mesh cache) run with 1 and with 2 threads, alternated, each setting REPEATS times; per phase (the Newton solver's
hessian, assemble, factorize, solve, gradient, line_search; then the ramp's other work: the per-step checks and
records; then the process's start-up, meshing and output) the median seconds of each, and their ratio, the
speed-up.

"1 thread" is Taichi's CPU thread pool of 1 (runtime.init's cpu_threads) and 1 BLAS thread for the factorisation
(OPENBLAS_NUM_THREADS, OMP_NUM_THREADS, set before NumPy and CVXOPT load); "2 threads" is 2 of each (the default
on a 2-core machine is every core). The machine and the load average before each run are recorded: on a shared
machine a run beside another job can take half as long again, which is what a ratio of medians measured in
one alternated run sees through.

    python benchmarks/threads.py [--cases beam_high,fiber_bending_3d] [--repeats 3] [--out benchmarks/results]

Writes threads.md and threads.json (machine, date) under --out; one progress line per run.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

PHASES = ("hessian", "assemble", "factorize", "solve", "gradient", "line_search")
# name: the pneuma-inflate arguments of the case
CASES = {
    "beam_high": ["--scene", "beam_3d_ellipsoid", "--quality", "high"],
    "fiber_bending_3d": ["--scene", "fiber_bending_3d"],
}


def child(threads: int, arguments: list[str]) -> None:
    """One run in this process (started by run_once with the BLAS thread variables set): prints one JSON line."""
    start = time.perf_counter()
    from taichi_pneuma import runtime
    from taichi_pneuma.apps import inflate

    runtime.init("cpu", cpu_threads=threads)
    with tempfile.TemporaryDirectory() as out:
        code = inflate.main([*arguments, "--no-video", "--quiet", "--out", out])
        assert code == 0, f"pneuma-inflate {' '.join(arguments)} exited {code}"
        summary = json.loads(next(Path(out).glob("*_summary.json")).read_text())
    print(json.dumps({"summary": summary, "whole_s": time.perf_counter() - start}))


def run_once(threads: int, arguments: list[str]) -> dict:
    """A fresh process at this many threads: the phases' seconds, the ramp's, the whole process's."""
    env = {**os.environ, "OPENBLAS_NUM_THREADS": str(threads), "OMP_NUM_THREADS": str(threads)}
    load = os.getloadavg()[0]
    start = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, __file__, "--child", str(threads), "--", *arguments],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    whole = time.perf_counter() - start
    summary = json.loads(proc.stdout.strip().splitlines()[-1])["summary"]
    phases = summary["newton"]["phase_seconds"]
    ramp = summary["wall_seconds"]
    return {
        **{p: phases.get(p, 0.0) for p in PHASES},
        "other ramp work": ramp - sum(phases.values()),
        "start-up, meshing, output": whole - ramp,
        "whole process": whole,
        "iterations": summary["newton_iterations_total"],
        "load_before": load,
    }


def report(records: dict, machine: str, repeats: int) -> str:
    lines = [f"Machine: {machine}. Median of {repeats} runs of each setting, alternated.", ""]
    for case, runs in records.items():
        lines += [f"### {case}: pneuma-inflate {' '.join(CASES[case])}", ""]
        lines += ["| phase | 1 thread (s) | 2 threads (s) | speed-up |", "|---|---|---|---|"]
        for key in (*PHASES, "other ramp work", "start-up, meshing, output", "whole process"):
            one, two = (statistics.median(r[key] for r in runs[n]) for n in (1, 2))
            lines.append(f"| {key} | {one:.2f} | {two:.2f} | {one / two:.2f}x |" if two > 0 else f"| {key} | 0 | 0 | |")
        iterations = {n: sorted({r["iterations"] for r in runs[n]}) for n in (1, 2)}
        loads = [round(r["load_before"], 2) for n in (1, 2) for r in runs[n]]
        lines += ["", f"Newton iterations: {iterations[1]} (1 thread), {iterations[2]} (2); load averages: {loads}", ""]
    return "\n".join(lines)


def main() -> None:
    if "--child" in sys.argv:
        at = sys.argv.index("--child")
        child(int(sys.argv[at + 1]), sys.argv[sys.argv.index("--") + 1 :])
        return
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--cases", default=",".join(CASES))
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--out", default="benchmarks/results")
    args = p.parse_args()
    from taichi_pneuma.apps.bench import machine
    from taichi_pneuma.io.output import prepare_directory, save_json, save_text

    out = prepare_directory(args.out)
    records: dict = {}
    for case in args.cases.split(","):
        records[case] = {1: [], 2: []}
        run_once(2, CASES[case])  # warm the kernel and mesh caches
        for _ in range(args.repeats):
            for threads in (1, 2):
                record = run_once(threads, CASES[case])
                records[case][threads].append(record)
                print(f"{case} threads={threads}: {record}", file=sys.stderr, flush=True)
    save_json(out / "threads.json", {"machine": machine(), "records": records})
    save_text(out / "threads.md", report(records, machine(), args.repeats))
    print(report(records, machine(), args.repeats))


if __name__ == "__main__":
    main()
