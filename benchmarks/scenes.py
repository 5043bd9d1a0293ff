"""Every shipped scene run as shipped through pneuma-inflate (--no-video, full resolution), one process each: its
dimension, mesh size, exit status, increments, Newton iterations, increment cuts, solve seconds (the ramp's wall
time) and its headline figure: the tip deflection (with the scene's length unit) and the bending angle at the end
(and at their peak for a ramp that returns; in 3D the twist too, and the blocked force where there is one), and for a
ramp that stops at its limit point the step where it stopped and the pressures there.

    python benchmarks/scenes.py [--scenes reference_beam ...] [--out benchmarks/results]
    python benchmarks/scenes.py --report benchmarks/results/scenes.json    (the table again from the runs' JSON)

A line per scene as it goes; writes scenes.json and scenes.md (machine and date in the header).
"""

from __future__ import annotations

import argparse
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

from taichi_pneuma.io.output import prepare_directory, save_json, save_text
from taichi_pneuma.scene.shipped import shipped

COMMAND = "python benchmarks/scenes.py"


def run(name: str, scratch: Path) -> dict:
    """One shipped scene through the command line: its exit status, wall time and summary (None without one)."""
    out = scratch / name
    start = time.perf_counter()
    command = [sys.executable, "-m", "taichi_pneuma.apps.inflate", "--scene", name, "--no-video", "--quiet"]
    done = subprocess.run(
        [*command, "--out", str(out)],
        capture_output=True,
        text=True,
        check=False,
    )
    seconds = time.perf_counter() - start
    path = out / f"{name}_summary.json"
    summary = json.loads(path.read_text()) if path.exists() else None
    errors = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    return {"scene": name, "exit": done.returncode, "process_seconds": seconds, "summary": summary, "errors": errors}


def shown(value: float) -> str:
    """A tip figure: 4 significant digits, round-off (below 1e-9) as 0 (a ramp back at rest)."""
    return f"{value if abs(value) > 1e-9 else 0.0:+.4g}"


def row(record: dict) -> str:
    s = record["summary"]
    if s is None:
        return f"| {record['scene']} | | | {record['exit']} | | | | | {'; '.join(record['errors'])} |"
    dim, elements = (3, s["tetrahedra"]) if "tetrahedra" in s else (2, s["triangles"])
    kind = ("quadratic " if s["element_order"] == 2 else "") + ("tetrahedra" if dim == 3 else "triangles")
    unit = "" if s["units"] is None else f" {s['units']['length']}"
    figure = f"tip dy {shown(s['tip_deflection'])}{unit} at {s['tip_at']}"
    figure += f", bending angle {s['tip_rotation_deg']:+.1f} deg"
    peak = max((s["extremes"]["tip_dy"][k] for k in ("min", "max")), key=abs)
    step = s["extremes"]["tip_dy"]["min_step" if peak == s["extremes"]["tip_dy"]["min"] else "max_step"]
    if step != s["steps"] - 1:  # a ramp that returns (pneunet_finger, pneunet_3d): its peak too
        turn = s["extremes"]["tip_rotation"]
        angle = max((turn[k] for k in ("min", "max")), key=abs)
        figure += f"; peak tip dy {shown(peak)}{unit} (step {step}), peak bending angle {angle:+.1f} deg"
    if "tip_twist_deg" in s:  # 3D: the twist about the body's axis (fiber_twist_3d's figure)
        figure += f", twist {s['tip_twist_deg']:+.1f} deg"
    if "blocked_force" in s:  # a force (per unit depth in 2D)
        figure += f", blocked force {s['blocked_force']:.4g}{'' if s['units'] is None else ' ' + s['units']['force']}"
    stopped = s.get("stopped")
    if stopped:  # the pressure with no equilibrium and the last equilibrium's (simulate.settle's words)
        where = re.search(r"no equilibrium at (.*?) after", stopped["message"])
        figure = f"stopped at step {stopped['step']} ({stopped['reason']}: {where[1] if where else ''}); {figure}"
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
            "(summary wall_seconds, without start-up and meshing), on a machine shared with other jobs: an upper "
            "bound.",
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
    parser.add_argument("--report", metavar="JSON", help="make no runs: the table of these runs' JSON")
    args = parser.parse_args()
    out = prepare_directory(args.out)
    if args.report:
        data = json.loads(Path(args.report).read_text())
        save_text(out / "scenes.md", report(data["runs"], data["machine"], data["date"]))
        return
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
