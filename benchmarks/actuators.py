"""The shipped 3D actuator scenes' converged references, and what each discretisation costs to approach them: the
bending angle (tip_rotation) of fiber_bending_3d, the blocked force of blocked_force_3d and the twist (tip_twist) of
fiber_twist_3d against pressure, on meshes refined by one factor, of linear tetrahedra (P1), quadratic ones (P2)
and quadratic ones with one pressure per element (P2/P0: mesh.volumetric = "mixed"); each run's wall and CPU time
(on a shared machine: the CPU time is the steadier figure) and Newton iterations.

Each mesh is the shipped scene's with its three gmsh lengths (size, near_chambers, distance) scaled by one factor
(PLANS: 1.5 coarser, 1 the shipped sizes, then finer); the ramps are the shipped ones. The reference of a scene is
found by Richardson extrapolation of each discretisation refined on three meshes or more: with the mesh size
h = (number of tetrahedra)^(-1/3) and the final value f(h) = f0 + C h^p on the three finest, the observed order p
and the extrapolated f0; its uncertainty is the grid convergence index's, 1.25 |f0 - f(finest)| (Roache). Where the
three oscillate, the mean of the two finest, its uncertainty the largest distance of the three from it; where they
converge faster than any order up to 8 fits, the finest value, its uncertainty the last change. The
reference is the mean of the quadratic discretisations' f0 (P2, P2/P0), its uncertainty the larger of theirs and
half their spread; P1's extrapolation is shown beside it.

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

import numpy as np
from scipy.optimize import brentq

from taichi_pneuma import api, runtime
from taichi_pneuma.apps.quality import mesh_values
from taichi_pneuma.io.output import prepare_directory, save_json, save_text
from taichi_pneuma.solve.simulate import RampStopped

SCENES = Path(__file__).resolve().parents[1] / "taichi_pneuma" / "scenes"
# (elements, mesh scale) per case: P1, P2 or P2/P0 on the lengths of the shipped mesh times the scale
PLANS = {
    name: [("P1", 1.0), ("P1", 0.75), ("P1", 0.6), ("P2", 1.5), ("P2", 1.0), ("P2", 0.75)]
    + [("P2/P0", 1.5), ("P2/P0", 1.0), ("P2/P0", 0.75)]
    for name in ("fiber_bending_3d", "blocked_force_3d", "fiber_twist_3d")
}
ELEMENTS = {"P1": (1, "element"), "P2": (2, "element"), "P2/P0": (2, "mixed")}  # mesh.order, mesh.volumetric
MEASURES = {"fiber_bending_3d": "tip_rotation", "blocked_force_3d": "blocked_force", "fiber_twist_3d": "tip_twist"}


def run(name: str, elements: str, scale: float) -> dict:
    """One ramp of the named scene on its mesh scaled by scale, of these elements (ELEMENTS): its measure per
    increment."""
    scene = api.load_scene(SCENES / f"{name}.toml")
    mesh = scene.geometry.mesh_sizes  # type: ignore[attr-defined]
    values = mesh_values(scene.geometry, mesh.size * scale, mesh.near * scale, mesh.grading * scale)
    order, volumetric = ELEMENTS[elements]
    scene = scene.with_values({**values, "mesh.order": order, "mesh.volumetric": volumetric})
    start, cpu = time.perf_counter(), time.process_time()
    try:
        result, stopped = api.simulate(scene), None
    except RampStopped as error:  # the steps done, and why it stopped
        result, stopped = error.result, str(error)
    seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
    history = result.history
    return {
        "case": name,
        "elements": elements,
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


def extrapolated(runs: list[dict]) -> dict | None:
    """Richardson extrapolation of the final values of the three finest runs (module docstring): {"order" p,
    "value" f0, "uncertainty" 1.25 |f0 - f(finest)|}; where they oscillate, the mean of the two finest and the
    largest distance of the three from it, and where no order in (0.2, 8) fits, the finest value and its last change
    (order None both); None with fewer than three runs."""
    done = sorted((r for r in runs if not r.get("stopped")), key=lambda r: r["tetrahedra"])[-3:]
    if len(done) < 3:
        return None
    h = np.array([r["tetrahedra"] ** (-1 / 3) for r in done])  # coarse to fine
    f = np.array([r["value"][-1] for r in done])
    if (f[1] - f[0]) * (f[2] - f[1]) <= 0:  # oscillating: no order to observe; the band of the three finest
        middle = (f[1] + f[2]) / 2
        return {"order": None, "value": middle, "uncertainty": float(np.abs(f - middle).max())}

    def mismatch(p):
        return (f[0] - f[1]) / (f[1] - f[2]) - (h[0] ** p - h[1] ** p) / (h[1] ** p - h[2] ** p)

    try:
        p = brentq(mismatch, 0.2, 8.0)
    except ValueError:  # faster than order 8 (or slower than 0.2): the finest value, the last change its uncertainty
        return {"order": None, "value": f[2], "uncertainty": abs(f[2] - f[1])}
    c = (f[1] - f[2]) / (h[1] ** p - h[2] ** p)
    f0 = f[2] - c * h[2] ** p
    return {"order": p, "value": f0, "uncertainty": 1.25 * abs(f0 - f[2])}


def reference(rows: list[dict]) -> dict | None:
    """The scene's reference from its discretisations' extrapolations (module docstring), each one's given."""
    each = {e: extrapolated([r for r in rows if r["elements"] == e]) for e in ("P2", "P2/P0")}
    found = {e: x for e, x in each.items() if x is not None}
    if not found:
        return None
    values = [x["value"] for x in found.values()]
    spread = (max(values) - min(values)) / 2
    return {
        "value": float(np.mean(values)),
        "uncertainty": max(spread, *(x["uncertainty"] for x in found.values())),
        "by_elements": found,
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
                f"| {r['elements']} | {r['scale']:g} | {r['tetrahedra']} | {r['nodes']} | {values} | "
                f"{r['seconds']:.1f} | {r['cpu_seconds']:.1f} | {r['iterations']} |"
            )
        found = reference(rows)
        lines.append("")
        if found is None:
            lines.append("No discretisation converged monotonically on three meshes: no reference.")
        else:
            for elements, x in {
                "P1": extrapolated([r for r in rows if r["elements"] == "P1"]),
                **found["by_elements"],
            }.items():
                if x is None:
                    continue
                how = "extrapolated" if x["order"] is not None else "the two finest meshes' mean or the finest's"
                order = "" if x["order"] is None else f" (observed order {x['order']:.2f})"
                lines.append(f"- {elements}: {how} final {measure} {x['value']:.4g} +- {x['uncertainty']:.2g}{order}")
            lines.append(
                f"- reference: **{found['value']:.4g} +- {found['uncertainty']:.2g}** "
                f"({found['uncertainty'] / abs(found['value']):.1%})"
            )
            lines += [
                f"- {r['elements']} at mesh scale {r['scale']:g}: {r['value'][-1] / found['value'] - 1:+.1%} "
                f"in {r['seconds']:.1f} s"
                for r in rows
                if not r.get("stopped")
            ]
        lines += [f"{r['elements']} at mesh scale {r['scale']:g}: {r['stopped']}" for r in rows if r.get("stopped")]
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
        for elements, scale in PLANS[name]:
            record = run(name, elements, scale)
            records.append(record)
            print(
                f"{name} {elements} scale {scale:g}: {record['tetrahedra']} tetrahedra, {record['nodes']} nodes, "
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
