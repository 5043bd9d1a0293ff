"""The shipped 3D actuator scenes' accuracy and time: the bending angle (tip_rotation) of fiber_bending_3d and the
blocked force of blocked_force_3d against pressure at four mesh resolutions of linear tetrahedra and on the coarsest
with quadratic ones, the twist (tip_twist) of fiber_twist_3d at three of each, each run's wall and CPU time (on a
shared machine: the CPU time is the steadier figure), and the mesh convergence: the relative change of the final
bending angle, blocked force and twist between the two finest meshes of each order.

Each mesh is the shipped scene's with its three gmsh lengths (size, near_chambers, distance) scaled by one factor
(PLANS: 1.5 coarser, 1 the shipped sizes, then finer) and the order given (1 or 2, whatever the scene's own); the
ramps are the shipped ones.

    python benchmarks/actuators.py [--cases fiber_bending_3d ...] [--out benchmarks/results]
    python benchmarks/actuators.py --report a.json b.json ...    (one report of runs made apart)

Progress lines as it goes; actuators.json is rewritten after every run (machine, date); actuators.md at the end.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from datetime import date
from pathlib import Path

from taichi_pneuma import api, runtime
from taichi_pneuma.io.output import prepare_directory, save_json, save_text
from taichi_pneuma.solve.simulate import RampStopped

SCENES = Path(__file__).resolve().parents[1] / "taichi_pneuma" / "scenes"
# (order, mesh scale) per case: the lengths of the shipped mesh times the scale
PLANS = {
    "fiber_bending_3d": [(1, 1.5), (1, 1.0), (1, 0.75), (1, 0.6), (2, 1.5)],
    "blocked_force_3d": [(1, 1.5), (1, 1.0), (1, 0.75), (1, 0.6), (2, 1.5)],
    "fiber_twist_3d": [(1, 1.0), (1, 0.75), (1, 0.6), (2, 1.5), (2, 1.0), (2, 0.75)],
}
MEASURES = {"fiber_bending_3d": "tip_rotation", "blocked_force_3d": "blocked_force", "fiber_twist_3d": "tip_twist"}
LENGTHS = ("size", "near_chambers", "distance")


def run(name: str, order: int, scale: float) -> dict:
    """One ramp of the named scene on its mesh scaled by scale, of the given order: its measure per increment."""
    scene = api.load_scene(SCENES / f"{name}.toml")
    mesh = scene.geometry.sizes  # type: ignore[attr-defined]
    values = {f"mesh.{key}": getattr(mesh, key) * scale for key in LENGTHS}
    scene = scene.with_values({**values, "mesh.order": order})
    start, cpu = time.perf_counter(), time.process_time()
    try:
        result, stopped = api.simulate(scene), None
    except RampStopped as error:  # the steps done, and why it stopped
        result, stopped = error.result, str(error)
    seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
    history = result.history
    return {
        "case": name,
        "order": order,
        "scale": scale,
        "tetrahedra": int(result.mesh.n_elements),
        "nodes": int(result.mesh.n_vertices),
        "pressure": [float(p) for p in history[f"{result.chamber_names[0]}.pressure"]],
        "value": [float(v) for v in history[MEASURES[name]]],
        "seconds": seconds,
        "cpu_seconds": cpu,
        "iterations": int(sum(s.iterations for s in result.solves)),
        "converged": bool(result.converged),
        "stopped": stopped,
    }


def report(records: list[dict], machine: str, day: str) -> str:
    lines = [f"Machine: {machine}; {day}.", ""]
    for name in dict.fromkeys(r["case"] for r in records):
        rows = [r for r in records if r["case"] == name]
        measure = MEASURES[name]
        lines += [f"### {name}: {measure} against pressure (kPa)", ""]
        pressures = max((r["pressure"] for r in rows), key=len)
        header = " | ".join(f"{p:g}" for p in pressures[1:])
        lines += [
            f"| elements | mesh scale | tetrahedra | nodes | {header} | s | CPU s | Newton it |",
            "|---|---|---|---|" + "---|" * (len(pressures) - 1) + "---|---|---|",
        ]
        for r in rows:
            done = r["value"][1:] + [float("nan")] * (len(pressures) - len(r["value"]))
            values = " | ".join("stopped" if v != v else f"{v:.4g}" for v in done)
            lines.append(
                f"| P{r['order']} | {r['scale']:g} | {r['tetrahedra']} | {r['nodes']} | {values} | "
                f"{r['seconds']:.1f} | {r['cpu_seconds']:.1f} | {r['iterations']} |"
            )
        for order in (1, 2):
            done = sorted((r for r in rows if r["order"] == order and not r.get("stopped")), key=lambda r: -r["scale"])
            if len(done) >= 2:
                coarse, fine = done[-2], done[-1]
                changes = [abs(f / c - 1) for c, f in zip(coarse["value"][1:], fine["value"][1:])]
                lines += [
                    "",
                    f"P{order}: final {measure} {fine['value'][-1]:.4g} at mesh scale {fine['scale']:g}, "
                    f"{coarse['value'][-1]:.4g} at {coarse['scale']:g}: a relative change of {changes[-1]:.1%} between "
                    f"the two finest meshes (at most {max(changes):.1%} over the ramp).",
                ]
        lines += [f"P{r['order']} at mesh scale {r['scale']:g}: {r['stopped']}" for r in rows if r.get("stopped")]
        lines.append("")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cases", nargs="+", default=list(PLANS), choices=list(PLANS))
    parser.add_argument("--out", default="benchmarks/results")
    parser.add_argument("--report", nargs="+", metavar="JSON", help="make no runs: the report of these runs' JSON")
    args = parser.parse_args()
    out = prepare_directory(args.out)
    if args.report:
        loaded = [json.loads(Path(path).read_text()) for path in args.report]
        records = [r for data in loaded for r in data["runs"]]
        save_text(out / "actuators.md", report(records, loaded[0]["machine"], loaded[0]["date"]))
        save_json(out / "actuators.json", {**loaded[0], "runs": records})
        return
    runtime.init("cpu")
    machine = f"{platform.node()}, {platform.machine()}, {os.cpu_count()} CPUs"
    records: list[dict] = []
    for name in args.cases:
        for order, scale in PLANS[name]:
            record = run(name, order, scale)
            records.append(record)
            print(
                f"{name} P{order} scale {scale:g}: {record['tetrahedra']} tetrahedra, {record['nodes']} nodes, "
                f"final {MEASURES[name]} {record['value'][-1]:.4g}, {record['seconds']:.1f} s "
                f"({record['cpu_seconds']:.1f} s CPU), {record['iterations']} Newton iterations",
                flush=True,
            )
            save_json(out / "actuators.json", {"machine": machine, "date": str(date.today()), "runs": records})
    text = report(records, machine, str(date.today()))
    print(text)
    save_text(out / "actuators.md", text)


if __name__ == "__main__":
    main()
