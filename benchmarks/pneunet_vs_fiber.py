"""A PneuNet against the fibre-reinforced bending actuator, measured alike: the bending angle (tip_rotation), the tip's
extension (tip_dx) and the largest principal stretch against pressure, each on two or three meshes (the mesh check).

The fibre-reinforced actuator is the shipped fiber_bending_3d scene: an Elastosil M4601 body 100 mm long of half-round
section (radius 8 mm, 10 mm tall, 16 mm wide) with a half-round chamber (radius 6 mm: 2 mm walls, 3 mm end caps), a
crossed aramid helix and a 0.1 mm paper sheet on its flat bottom (after Polygerinos et al. 2015).

The PneuNet is the pneunet generator's body (shape = "pneunet", as pneunet_3d.toml; the scene is PNEUNET below, not a
shipped one) in the proportions of the classic PneuNet (Mosadegh et al. 2014): a row of a dozen box chambers, each
taller than it is long and nearly as wide as the body, in a block of the same silicone, separated by thin walls, over
a base with a paper strain-limiting sheet. Scaled to this length and to the fibre actuator's cross-section, with every
wall as thick as the fibre actuator's (the dimensions are this project's choice, not the papers'): a body 100 mm long,
16 mm wide and 12 mm tall; 12 chambers 6 mm long, 8 mm tall and 12 mm wide (edges rounded to 1 mm), 2 mm walls between
them, above them and beside them, 3 mm end caps, a 2 mm base under them (as under the fibre actuator's chamber) and
the same 0.1 mm paper sheet ([[layers]], side = "bottom") on the base's bottom face; the generator's stiffer "layer"
is not used (layer = 0). The chambers are sealed from each other and pressurised together (a real PneuNet joins them
by a channel; a common pressure is the same load).

Both are clamped at their left end, meshed alike (PNEUNET's gmsh lengths: 4 mm in the bulk, 3 mm within 3 mm of the
chambers, times a mesh scale) and ramped alike: 8 increments of 15 kPa to 120 kPa, or to where a
ramp stops. Linear tetrahedra (P1) lock in this nearly incompressible rubber: the fibre actuator's converge about a
quarter short (benchmarks/results/actuators.md), and the PneuNet's, all of whose rubber is 2 mm walls, lock far more,
so both are run on quadratic tetrahedra with one pressure per element (P2/P0, mesh.volumetric = "mixed", as
fiber_bending_3d ships) on two meshes: the P2/P0 figures are the comparison, the P1 ones show how far linear elements
are off. The fibre actuator's P2/P0 angle at 120 kPa is within its converged reference's uncertainty at mesh scale 1
(-154.1 +- 2.7 deg: benchmarks/actuators.py).

    python benchmarks/pneunet_vs_fiber.py [--coarse] [--resume] [--out benchmarks/results]

PLANS: P1 at mesh scales 1 and 0.75 (the PneuNet also 0.6) and P2/P0 at 1.5 and 1; --coarse: P1 at 1.5 and 1 only
(a quick look); --resume: the runs already in the output JSON are kept, not run again. Writes pneunet_vs_fiber.json
(machine, date, every run's columns), pneunet_vs_fiber.md (the tables, the mesh checks) and pneunet_vs_fiber.png (the
bending angle against pressure, and the bent shapes at the end of the last runs made).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
import tomllib
from datetime import date
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from taichi_pneuma import api, runtime  # noqa: E402
from taichi_pneuma.apps.quality import mesh_values  # noqa: E402
from taichi_pneuma.io.output import prepare_directory, save_json, save_text  # noqa: E402
from taichi_pneuma.render.drawing import draw_surface  # noqa: E402
from taichi_pneuma.result import Result  # noqa: E402
from taichi_pneuma.scene.scenefile import read_scene  # noqa: E402
from taichi_pneuma.solve.simulate import RampStopped  # noqa: E402

SCENES = Path(__file__).resolve().parents[1] / "taichi_pneuma" / "scenes"
CHAMBERS = 12
PRESSURE, INCREMENTS = 120.0, 8  # kPa, as fiber_bending_3d
CHAMBER = """
[[chambers]]
name = "c{i}"
shape = "mesh_surface"
group = "c{i}"
control = "pressure"
keyframes = [[0, 0.0], [{increments}, {pressure}]]
"""
PNEUNET = f"""
name = "pneunet_vs_fiber"
units = "mm-kPa"

[body]
shape = "pneunet"
chambers = {CHAMBERS}
chamber_length = 6.0
chamber_height = 8.0
chamber_width = 12.0
radius = 1.0
gap = 2.0
wall = 2.0
end = 3.0
base = 2.0
layer = 0.0

[mesh]
size = 4.0
near_chambers = 3.0
distance = 3.0
order = 1

[material]
preset = "elastosil_m4601"

[clamp]
side = "left"

[[layers]]
name = "sheet"
side = "bottom"
E = 6.5e6
nu = 0.2
thickness = 0.1

[schedule]
increments = {INCREMENTS}
""" + "".join(CHAMBER.format(i=i, increments=INCREMENTS, pressure=PRESSURE) for i in range(1, CHAMBERS + 1))
# (elements, mesh scale) per case: linear tetrahedra lock (the PneuNet's, all 2 mm walls, badly: a third mesh); the
# comparison is on quadratic ones with one pressure per element (P2/P0), as fiber_bending_3d ships
PLANS = {
    "fiber_bending_3d": [("P1", 1.0), ("P1", 0.75), ("P2/P0", 1.5), ("P2/P0", 1.0)],
    "pneunet": [("P1", 1.0), ("P1", 0.75), ("P1", 0.6), ("P2/P0", 1.5), ("P2/P0", 1.0)],
}
COARSE = {case: [("P1", 1.5), ("P1", 1.0)] for case in PLANS}
ELEMENTS = {"P1": (1, "element"), "P2/P0": (2, "mixed")}  # mesh.order, mesh.volumetric
COLUMNS = ("tip_rotation", "tip_dx", "max_stretch")
WORDS = {"P1": "linear tetrahedra", "P2/P0": "quadratic tetrahedra, one pressure per element"}
LABELS = {"fiber_bending_3d": "fibre-reinforced (fiber_bending_3d)", "pneunet": "PneuNet (12 chambers)"}


def scene_of(case: str, elements: str, scale: float):
    """The case's scene with its gmsh lengths times scale, of the given elements (ELEMENTS)."""
    if case == "pneunet":
        scene = read_scene(tomllib.loads(PNEUNET), "pneunet_vs_fiber")
    else:
        scene = api.load_scene(SCENES / f"{case}.toml")
    mesh = read_scene(tomllib.loads(PNEUNET), "pneunet_vs_fiber").geometry.sizes  # type: ignore[attr-defined]
    order, volumetric = ELEMENTS[elements]
    lengths = mesh_values(scene.geometry, mesh.size * scale, mesh.near * scale, mesh.grading * scale)
    return scene.with_values({**lengths, "mesh.order": order, "mesh.volumetric": volumetric})


def run(case: str, elements: str, scale: float):
    """One ramp: its record (columns per increment, the place of the largest stretch, times) and its Result."""
    scene = scene_of(case, elements, scale)
    start, cpu = time.perf_counter(), time.process_time()
    try:
        result, stopped = api.simulate(scene), None
    except RampStopped as error:  # the steps done, and why it stopped
        result, stopped = Result.of(error.result), str(error)
    seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
    history, mesh = result.history, result.mesh
    worst = int(np.argmax(result.fields()["max_stretch"]))
    return {
        "case": case,
        "elements": elements,
        "scale": scale,
        "tetrahedra": int(mesh.n_elements),
        "nodes": int(mesh.n_vertices),
        "pressure": [float(p) for p in history[f"{result.chamber_names[0]}.pressure"]],
        **{column: [float(v) for v in history[column]] for column in COLUMNS},
        "max_stretch_at": [round(float(v), 2) for v in mesh.vertices[mesh.elements[worst, :4]].mean(axis=0)],
        "max_stretch_step": int(np.argmax(history["max_stretch"])),
        "seconds": seconds,
        "cpu_seconds": cpu,
        "iterations": int(sum(s.iterations for s in result.solves)),
        "stopped": stopped,
    }, result


def at(record: dict, pressure: float) -> float:
    """The bending angle at a pressure of the ramp (NaN past where it stopped)."""
    hits = [a for p, a in zip(record["pressure"], record["tip_rotation"]) if abs(p - pressure) < 1e-9]
    return hits[0] if hits else float("nan")


def groups(records: list[dict]) -> dict:
    """The runs by (case, elements), coarsest mesh first."""
    keys = dict.fromkeys((r["case"], r["elements"]) for r in records)
    return {
        key: sorted((r for r in records if (r["case"], r["elements"]) == key), key=lambda r: -r["scale"])
        for key in keys
    }


def report(records: list[dict], machine: str, day: str) -> str:
    lines = [f"Machine: {machine}; {day}.", "", "Written by `python benchmarks/pneunet_vs_fiber.py`.", ""]
    for (case, elements), rows in groups(records).items():
        lines += [f"### {LABELS[case]}, {elements} ({WORDS[elements]})", ""]
        pressures = max((r["pressure"] for r in rows), key=len)[1:]
        lines += [
            f"| mesh scale | tetrahedra | nodes | measure | {' | '.join(f'{p:g} kPa' for p in pressures)} |",
            "|---|---|---|---|" + "---|" * len(pressures),
        ]
        for r in rows:
            for column in COLUMNS:
                done = r[column][1:] + [float("nan")] * (len(pressures) + 1 - len(r[column]))
                values = " | ".join("stopped" if v != v else f"{v:.4g}" for v in done)
                lines.append(f"| {r['scale']:g} | {r['tetrahedra']} | {r['nodes']} | {column} | {values} |")
        lines.append("")
        for r in rows:
            lines.append(
                f"- mesh scale {r['scale']:g}: {r['seconds']:.0f} s ({r['cpu_seconds']:.0f} s CPU), "
                f"{r['iterations']} Newton iterations; largest stretch {max(r['max_stretch']):.3g} at "
                f"{r['pressure'][r['max_stretch_step']]:g} kPa, in the element around (x, y, z) = "
                f"{tuple(r['max_stretch_at'])} mm (rest) at the last step"
                + (f"; stopped: {r['stopped']}" if r["stopped"] else "")
            )
        if len(rows) >= 2:
            coarse, fine = rows[-2], rows[-1]
            both = min(len(coarse["tip_rotation"]), len(fine["tip_rotation"])) - 1
            changes = [abs(f / c - 1) for c, f in zip(coarse["tip_rotation"][1:], fine["tip_rotation"][1:])]
            lines.append(
                f"- mesh check at {fine['pressure'][both]:g} kPa: angle {fine['tip_rotation'][both]:.4g} deg at mesh "
                f"scale {fine['scale']:g}, {coarse['tip_rotation'][both]:.4g} at {coarse['scale']:g}: "
                f"{changes[-1]:.1%} apart (at most {max(changes):.1%} over the ramp)"
            )
        fine = rows[-1]
        first = fine["pressure"][1]
        lines.append(
            f"- on the finest mesh: {fine['tip_rotation'][1] / first:.3g} deg/kPa at {first:g} kPa; "
            + ", ".join(
                f"{at(fine, p):.3g} deg at {p:g} kPa" if at(fine, p) == at(fine, p) else f"stopped before {p:g} kPa"
                for p in (30.0, 60.0, 90.0, 120.0)
            )
        )
        lines.append("")
    return "\n".join(lines)


def picture(records: list[dict], results: dict, path: Path) -> None:
    """The bending angle against pressure (P1 dashed, P2/P0 solid, the finest of each with markers) and the bent
    shapes at the end of the finest runs of the highest order made here (results: case -> Result)."""
    fig = plt.figure(figsize=(13, 4.2), layout="constrained")
    ax = fig.add_subplot(1, 3, 1)
    colours = {"fiber_bending_3d": "tab:blue", "pneunet": "tab:orange"}
    for (case, elements), rows in groups(records).items():
        for r in rows:
            fine = r is rows[-1]
            ax.plot(
                r["pressure"],
                -np.array(r["tip_rotation"]),
                ("o" if fine else "") + ("--" if elements == "P1" else "-"),
                color=colours[case],
                alpha=1.0 if fine else 0.45,
                label=f"{LABELS[case]}, {elements}, mesh scale {r['scale']:g}",
            )
    ax.set(xlabel="pressure p [kPa]", ylabel="bending angle [deg]", title="Bending angle against pressure")
    ax.grid(alpha=0.3)
    ax.legend(fontsize="xx-small")
    for i, (case, result) in enumerate(results.items()):
        mesh = result.mesh
        outer = mesh.surface[np.isin(mesh.surface[:, :3], mesh.boundary).all(axis=1)]  # chamber walls left out
        shape = fig.add_subplot(1, 3, 2 + i, projection="3d")
        draw_surface(shape, result.positions[-1], outer)
        shape.view_init(elev=10, azim=-80)
        elements, bent = "P1" if mesh.order == 1 else "P2/P0", -result.tip_rotation
        shape.set_title(f"{LABELS[case]}, {elements}\nat {result.pressure[-1, 0]:.0f} kPa: bent {bent:.1f} deg")
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--coarse", action="store_true", help="linear tetrahedra at mesh scales 1.5 and 1 only")
    parser.add_argument("--resume", action="store_true", help="keep the runs already in the output JSON")
    parser.add_argument("--out", default="benchmarks/results")
    args = parser.parse_args()
    out = prepare_directory(args.out)
    runtime.init("cpu")
    machine = f"{platform.node()}, {platform.machine()}, {os.cpu_count()} CPUs"
    saved = out / "pneunet_vs_fiber.json"
    records: list[dict] = json.loads(saved.read_text())["runs"] if args.resume and saved.exists() else []
    results = {}
    for case, plan in (COARSE if args.coarse else PLANS).items():
        for elements, scale in plan:
            if any((r["case"], r["elements"], r["scale"]) == (case, elements, scale) for r in records):
                continue
            record, results[case] = run(case, elements, scale)  # the last (finest, P2/P0) kept for the picture
            records.append(record)
            print(
                f"{case} {elements} scale {scale:g}: {record['tetrahedra']} tetrahedra, final angle "
                f"{record['tip_rotation'][-1]:.4g} deg at {record['pressure'][-1]:g} kPa, {record['seconds']:.1f} s "
                f"({record['cpu_seconds']:.1f} s CPU)",
                flush=True,
            )
            save_json(saved, {"machine": machine, "date": str(date.today()), "runs": records})
    text = report(records, machine, str(date.today()))
    print(text)
    save_text(out / "pneunet_vs_fiber.md", text)
    picture(records, results, out / "pneunet_vs_fiber.png")


if __name__ == "__main__":
    main()
