"""Every shipped scene run as shipped through pneuma-inflate (--no-video, full resolution), one process each: its
dimension, mesh size, exit status, increments, Newton iterations, increment cuts, solve seconds (the ramp's wall time)
and its headline figure: the tip deflection (with the scene's length unit) and the bending angle at the end, and for a
ramp that stops at its limit point the step where it stopped.

    python benchmarks/scenes.py [--scenes reference_beam ...] [--out benchmarks/results]

A line per scene as it goes; writes scenes.json and scenes.md (machine and date in the header).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from datetime import date
from pathlib import Path

from taichi_pneuma.io.output import prepare_directory, save_json, save_text
from taichi_pneuma.scene.shipped import shipped

COMMAND = "python benchmarks/scenes.py"


def run(name: str, scratch: Path) -> dict:
    """One shipped scene through the command line: its exit status, wall time and summary (None without one)."""
    out = scratch / name
    start = time.perf_counter()
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "taichi_pneuma.apps.inflate",
            "--scene",
            name,
            "--no-video",
            "--quiet",
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    seconds = time.perf_counter() - start
    path = out / f"{name}_summary.json"
    summary = json.loads(path.read_text()) if path.exists() else None
    errors = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    return {"scene": name, "exit": done.returncode, "process_seconds": seconds, "summary": summary, "errors": errors}


def row(record: dict) -> str:
    s = record["summary"]
    if s is None:
        return f"| {record['scene']} | | | {record['exit']} | | | | | {'; '.join(record['errors'])} |"
    dim, elements = (3, s["tetrahedra"]) if "tetrahedra" in s else (2, s["triangles"])
    kind = ("quadratic " if s["element_order"] == 2 else "") + ("tetrahedra" if dim == 3 else "triangles")
    unit = "" if s["units"] is None else f" {s['units']['length']}"
    figure = f"tip dy {s['tip_deflection']:+.4g}{unit} at {s['tip_at']}, bending angle {s['tip_rotation_deg']:+.1f} deg"
    stopped = s.get("stopped")
    if stopped:
        figure = f"stopped at step {stopped['step']} ({stopped['reason']}); " + figure
    return (
        f"| {record['scene']} | {dim}D | {s['vertices']} nodes, {elements} {kind} | {record['exit']} | "
        f"{s['steps'] - 1} | {s['newton_iterations_total']} | {s['increment_cuts']} | {s['wall_seconds']:.1f} | "
        f"{figure} |"
    )


def report(records: list[dict], machine: str, day: str) -> str:
    return "\n".join(
        [
            f"Machine: {machine}; {day}. Written by `{COMMAND}`: every shipped scene as shipped, "
            "`pneuma-inflate --scene NAME --no-video`, one process each.",
            "",
            "Increments: the solves after the rest state that found an equilibrium; solve s: the ramp's wall time "
            "(summary wall_seconds, without start-up and meshing).",
            "",
            "| scene | dim | mesh | exit | increments | Newton it | cuts | solve s | headline |",
            "|---|---|---|---|---|---|---|---|---|",
            *map(row, records),
            "",
        ]
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenes", nargs="+", default=shipped(), choices=shipped())
    parser.add_argument("--out", default="benchmarks/results")
    args = parser.parse_args()
    out = prepare_directory(args.out)
    machine = f"{platform.node()}, {platform.machine()}, {os.cpu_count()} CPUs"
    records = []
    with tempfile.TemporaryDirectory() as scratch:
        for name in args.scenes:
            records.append(run(name, Path(scratch)))
            print(row(records[-1]), flush=True)
            save_json(out / "scenes.json", {"machine": machine, "date": str(date.today()), "runs": records})
    save_text(out / "scenes.md", report(records, machine, str(date.today())))


if __name__ == "__main__":
    main()
