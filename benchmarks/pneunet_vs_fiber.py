"""A PneuNet against the fibre-reinforced bending actuator, measured alike: the bending angle (tip_rotation), the tip's
extension (tip_dx) and the largest principal stretch against pressure, each on two or three meshes (the mesh check).

The fibre-reinforced actuator is the shipped fiber_bending_3d scene: an Elastosil M4601 body 100 mm long of half-round
section (radius 8 mm, 10 mm tall, 16 mm wide) with a half-round chamber (radius 6 mm: 2 mm walls, 3 mm end caps), a
crossed aramid helix and a 0.1 mm paper sheet on its flat bottom (after Polygerinos et al. 2015).

The PneuNet is the pneunet generator's body (shape = "pneunet", as pneunet_3d.toml; the scene is PNEUNET below, not a
shipped one) in the proportions of the classic PneuNet (Mosadegh et al. 2014): a row
of a dozen box chambers, each taller than it is long and nearly as wide as the body, in a block of the same silicone,
separated by thin walls, over a base with a paper strain-limiting sheet. Scaled to this length and to the fibre
actuator's cross-section, with every wall as thick as the fibre actuator's (the dimensions are this project's choice,
not the papers'): a body 100 mm long, 16 mm wide and 12 mm tall; 12 chambers 6 mm long, 8 mm tall and 12 mm wide
(edges rounded to 1 mm), 2 mm walls between them, above them and beside them, 3 mm end caps, a 2 mm base under them
(as under the fibre actuator's chamber) and the same 0.1 mm paper sheet ([[layers]], side = "bottom") on the base's
bottom face; the generator's stiffer "layer" is not used (layer = 0). The chambers are sealed from each other and
pressurised together (a real PneuNet joins them by a channel; a common pressure is the same load).

Both are clamped at x = left end, meshed alike (linear tetrahedra, the shipped fibre actuator's gmsh lengths: 4 mm in
the bulk, 2 mm within 2 mm of the chambers, times a mesh scale) and ramped alike: 8 increments of 15 kPa to 120 kPa.
Linear tetrahedra lock in this nearly incompressible rubber: both bend too little by some percent (for the fibre
actuator about 15 %, benchmarks/results/actuators.md). The PneuNet, all of whose rubber is 2 mm walls, locks more: its
angle at 120 kPa grew by 17 % and then 24 % from mesh scale 1 to 0.75 to 0.6 (2026-12-02), not yet converging, so its
figures are lower bounds; the same element order and sizes keep the comparison like for like, not converged.

    python benchmarks/pneunet_vs_fiber.py [--coarse] [--out benchmarks/results]

Mesh scales (PLANS): 1 and 0.75 for the fibre actuator, 1, 0.75 and 0.6 for the PneuNet; --coarse: 1.5 and 1 for
both (a quick look). Writes pneunet_vs_fiber.json (machine, date,
every run's columns), pneunet_vs_fiber.md (the tables, the mesh check) and pneunet_vs_fiber.png (the bending angle
against pressure, and the two bent shapes at the last pressure on the finer mesh).
"""

from __future__ import annotations

import argparse
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
from taichi_pneuma.io.output import prepare_directory, save_json, save_text  # noqa: E402
from taichi_pneuma.render.drawing import draw_surface  # noqa: E402
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
near_chambers = 2.0
distance = 2.0
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
# mesh scales per case: the PneuNet's bending angle converges more slowly (all its rubber is 2 mm walls): a third mesh
PLANS = {"fiber_bending_3d": (1.0, 0.75), "pneunet": (1.0, 0.75, 0.6)}
COARSE = {"fiber_bending_3d": (1.5, 1.0), "pneunet": (1.5, 1.0)}
LENGTHS = ("size", "near_chambers", "distance")
COLUMNS = ("tip_rotation", "tip_dx", "max_stretch")
LABELS = {"fiber_bending_3d": "fibre-reinforced (fiber_bending_3d)", "pneunet": "PneuNet (12 chambers)"}


def scene_of(case: str, scale: float):
    """The case's scene with its gmsh lengths times scale."""
    if case == "pneunet":
        scene = read_scene(tomllib.loads(PNEUNET), "pneunet_vs_fiber")
    else:
        scene = api.load_scene(SCENES / f"{case}.toml")
    mesh = scene.geometry.sizes  # type: ignore[attr-defined]
    return scene.with_values({f"mesh.{key}": getattr(mesh, key) * scale for key in LENGTHS})


def run(case: str, scale: float):
    """One ramp: its record (columns per increment, the place of the largest stretch, times) and its Result."""
    scene = scene_of(case, scale)
    start, cpu = time.perf_counter(), time.process_time()
    try:
        result, stopped = api.simulate(scene), None
    except RampStopped as error:  # the steps done, and why it stopped
        result, stopped = error.result, str(error)
    seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
    history, mesh = result.history, result.mesh
    worst = int(np.argmax(result.fields()["max_stretch"]))
    return {
        "case": case,
        "scale": scale,
        "tetrahedra": int(mesh.n_elements),
        "nodes": int(mesh.n_vertices),
        "pressure": [float(p) for p in history[f"{result.chamber_names[0]}.pressure"]],
        **{column: [float(v) for v in history[column]] for column in COLUMNS},
        "max_stretch_at": [round(float(v), 2) for v in mesh.vertices[mesh.elements[worst, :4]].mean(axis=0)],
        "seconds": seconds,
        "cpu_seconds": cpu,
        "iterations": int(sum(s.iterations for s in result.solves)),
        "stopped": stopped,
    }, result


def at(record: dict, pressure: float) -> float:
    """The bending angle at a pressure of the ramp (NaN past where it stopped)."""
    hits = [a for p, a in zip(record["pressure"], record["tip_rotation"]) if abs(p - pressure) < 1e-9]
    return hits[0] if hits else float("nan")


def report(records: list[dict], machine: str, day: str) -> str:
    lines = [f"Machine: {machine}; {day}.", "", "Written by `python benchmarks/pneunet_vs_fiber.py`.", ""]
    for case in dict.fromkeys(r["case"] for r in records):
        rows = sorted((r for r in records if r["case"] == case), key=lambda r: -r["scale"])
        lines += [f"### {LABELS[case]}", ""]
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
                f"{r['iterations']} Newton iterations; largest stretch {max(r['max_stretch']):.3g} at the end, in the "
                f"element around (x, y, z) = {tuple(r['max_stretch_at'])} mm (rest)"
                + (f"; stopped: {r['stopped']}" if r["stopped"] else "")
            )
        if len(rows) >= 2:
            coarse, fine = rows[-2], rows[-1]
            changes = [abs(f / c - 1) for c, f in zip(coarse["tip_rotation"][1:], fine["tip_rotation"][1:])]
            lines.append(
                f"- mesh check: final angle {fine['tip_rotation'][-1]:.4g} deg at mesh scale {fine['scale']:g}, "
                f"{coarse['tip_rotation'][-1]:.4g} at {coarse['scale']:g}: {changes[-1]:.1%} apart "
                f"(at most {max(changes):.1%} over the ramp)"
            )
        fine = rows[-1]
        first = fine["pressure"][1]
        lines.append(
            f"- on the finer mesh: {fine['tip_rotation'][1] / first:.3g} deg/kPa at {first:g} kPa; "
            + ", ".join(f"{at(fine, p):.3g} deg at {p:g} kPa" for p in (30.0, 60.0, 120.0))
        )
        lines.append("")
    return "\n".join(lines)


def picture(records: list[dict], results: dict, path: Path) -> None:
    """The bending angle against pressure (finer mesh solid, coarser dashed) and the bent shapes at the end."""
    fig = plt.figure(figsize=(12, 4), layout="constrained")
    ax = fig.add_subplot(1, 3, 1)
    for colour, case in zip(("tab:blue", "tab:orange"), dict.fromkeys(r["case"] for r in records)):
        rows = sorted((r for r in records if r["case"] == case), key=lambda r: -r["scale"])
        for r in rows:
            fine = r is rows[-1]
            ax.plot(
                r["pressure"],
                -np.array(r["tip_rotation"]),
                "o-" if fine else "--",
                color=colour,
                alpha=1.0 if fine else 0.6,
                label=f"{LABELS[case]}, mesh scale {r['scale']:g}",
            )
    ax.set(xlabel="pressure p [kPa]", ylabel="bending angle [deg]", title="Bending angle against pressure")
    ax.grid(alpha=0.3)
    ax.legend(fontsize="x-small")
    for i, (case, result) in enumerate(results.items()):
        mesh = result.mesh
        outer = mesh.surface[np.isin(mesh.surface[:, :3], mesh.boundary).all(axis=1)]  # chamber walls left out
        shape = fig.add_subplot(1, 3, 2 + i, projection="3d")
        draw_surface(shape, result.positions[-1], outer)
        shape.view_init(elev=10, azim=-80)
        shape.set_title(f"{LABELS[case]}\nat {result.pressure[-1, 0]:.0f} kPa: {result.tip_rotation:.1f} deg")
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--coarse", action="store_true", help="mesh scales 1.5 and 1 (COARSE) instead of PLANS")
    parser.add_argument("--out", default="benchmarks/results")
    args = parser.parse_args()
    out = prepare_directory(args.out)
    runtime.init("cpu")
    machine = f"{platform.node()}, {platform.machine()}, {os.cpu_count()} CPUs"
    plans = COARSE if args.coarse else PLANS
    records: list[dict] = []
    results = {}
    for case, scales in plans.items():
        for scale in scales:
            record, results[case] = run(case, scale)  # the finer mesh's result kept for the picture
            records.append(record)
            print(
                f"{case} scale {scale:g}: {record['tetrahedra']} tetrahedra, final angle "
                f"{record['tip_rotation'][-1]:.4g} deg, {record['seconds']:.1f} s ({record['cpu_seconds']:.1f} s CPU)",
                flush=True,
            )
            save_json(out / "pneunet_vs_fiber.json", {"machine": machine, "date": str(date.today()), "runs": records})
    text = report(records, machine, str(date.today()))
    print(text)
    save_text(out / "pneunet_vs_fiber.md", text)
    picture(records, results, out / "pneunet_vs_fiber.png")


if __name__ == "__main__":
    main()
