"""CAD files in: the shipped STEP actuator and STL PneuNet against the parametric scenes they were made from.

Cases, each the parametric scene and the same scene with its body and chambers read from the CAD file instead (the
geometry replaced, every other key as shipped):

- fiber_bending_3d against its STEP (taichi_pneuma/scenes/fiber_actuator.step, drawn by build123d:
  examples/cad_fiber_actuator_step.py): the tip rotation at 120 kPa;
- fiber_bending_3d against the STL of the same actuator's rubber (fiber_actuator.stl, exported by build123d beside
  the STEP, triangulated to 0.05 mm), meshed at 4 mm near the chamber;
- pneunet_3d against its STL (taichi_pneuma/scenes/pneunet.stl, the generator's solid triangulated at 0.08:
  examples/cad_pneunet_stl.py), its bottom layer a box region (an STL has no regions), meshed at 0.08 near the
  chambers (the STL's facets; the parametric scene's 0.12 chords a 0.08 corner radius once), ramped to its peak (900,
  10 increments): the tip's y there.

Per geometry: the import and meshing time with the mesh cache off (a fresh import; the least of 3), the tetrahedra and
nodes, the mesh quality (the normalised volume 6 sqrt(2) V / l_rms^3 of each linear tetrahedron of corners: 1 for
the regular one; its minimum and 1st percentile), the enclosed rubber volume, and the answer, with its difference
from the parametric scene's and from the converged answer, each as a fraction of the scene's measured
mesh-convergence error (docs/3d.md: fiber_bending_3d
-154.1 +- 2.7 degrees; pneunet_3d's shipped mesh 2.0 % from its converged tip).

    python benchmarks/cad_import.py [--out benchmarks/results]

Writes cad_import.md and cad_import.json (machine, date) under --out; one progress line per run.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time

import numpy as np

os.environ["PNEUMA_CACHE_DIR"] = "off"  # every import and mesh made afresh
REPEATS = 3
LAYER_BOX = (-2.1, -0.41, -0.5, 2.1, -0.25, 0.5)  # pneunet_3d's bottom layer, y in [-0.4, -0.25]
STL_NEAR = 0.08  # the STL's own facets' size: edges near the chambers as fine (pneunet_stl.toml's near_chambers)
PNEUNET_PEAK = {"schedule.increments": 10, **{f"chambers[{k}].keyframes": [[0, 0.0], [10, 900.0]] for k in range(6)}}


def step_geometry(scene):
    from taichi_pneuma.fem.cad import StepPart
    from taichi_pneuma.scene.shipped import find

    path = str(find("fiber_actuator", ".step", "CAD file"))
    metre = scene.units.metre
    return dataclasses.replace(
        scene.geometry,
        body=StepPart(path, "body", metre),
        chambers=(("chamber", StepPart(path, "chamber", metre)),),
    )


def fiber_stl_geometry(scene):
    """fiber_bending_3d's body and chamber as the STL of its rubber (fiber_actuator.stl, triangulated to 0.05 mm by
    build123d), meshed at the scene's 5 mm, 4 mm near the chamber (its 2 mm walls' through_wall = 0.5)."""
    from taichi_pneuma.fem.gmsh_mesher import MeshSizes
    from taichi_pneuma.fem.surface_import import Cavity, SurfaceBody, SurfaceGeometry
    from taichi_pneuma.scene.shipped import find

    g = scene.geometry
    body = SurfaceBody(str(find("fiber_actuator", ".stl", "surface file")), 1.0)
    chamber = (("chamber", Cavity((50.0, 4.0, 0.0))),)
    return SurfaceGeometry(body, chamber, MeshSizes(5.0, 4.0, 4.0), g.order, g.clamp, g.tip)


def stl_scene(scene):
    from taichi_pneuma.fem.surface_import import Cavity, SurfaceBody, SurfaceGeometry
    from taichi_pneuma.scene.shipped import find

    g = scene.geometry
    chambers = tuple((f"c{k + 1}", Cavity((-1.25 + 0.5 * k, 0.1, 0.0))) for k in range(6))
    sizes = dataclasses.replace(g.sizes, near_chambers=STL_NEAR)
    geometry = SurfaceGeometry(
        SurfaceBody(str(find("pneunet", ".stl", "surface file")), 1.0), chambers, sizes, g.order, g.clamp, g.tip
    )
    regions = tuple(dataclasses.replace(r, box=LAYER_BOX, group=None) for r in scene.regions)
    return dataclasses.replace(scene, geometry=geometry, regions=regions)


def normalised_volumes(x: np.ndarray) -> np.ndarray:
    """6 sqrt(2) V / l_rms^3 of each tetrahedron of corners x (t, 4, 3): 1 for the regular one, 0 for a flat one."""
    volume = np.abs(np.linalg.det(x[:, 1:] - x[:, :1])) / 6
    pairs = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    rms = np.sqrt(np.mean([np.sum((x[:, a] - x[:, b]) ** 2, axis=1) for a, b in pairs], axis=0))
    return 6 * np.sqrt(2) * volume / rms**3


def quality(mesh) -> tuple[float, float]:
    """(minimum, 1st percentile) of the normalised volumes of the corner tetrahedra."""
    q = normalised_volumes(mesh.vertices[mesh.elements[:, :4]])
    return float(q.min()), float(np.percentile(q, 1))


def measure_geometry(geometry) -> dict:
    """Meshing time (least of REPEATS, cache off), counts, quality, volume."""
    seconds = []
    for _ in range(REPEATS):
        started = time.perf_counter()
        mesh = geometry.mesh()
        seconds.append(time.perf_counter() - started)
    q_min, q_1 = quality(mesh)
    return {
        "mesh_s": min(seconds),
        "tetrahedra": mesh.n_elements,
        "nodes": mesh.n_vertices,
        "quality_min": q_min,
        "quality_p1": q_1,
        "volume": mesh.measure,
    }


def answer(scene, column: str) -> float:
    from taichi_pneuma.api import simulate

    result = simulate(scene)
    values = result.history[column]
    return float(values[np.argmax(np.abs(values))])


def run_case(name: str, parametric, imported, column: str, converged: float, error: float) -> dict:
    rows = {}
    for label, scene in (("parametric", parametric), ("CAD file", imported)):
        started = time.perf_counter()
        rows[label] = {**measure_geometry(scene.geometry), column: answer(scene, column)}
        print(f"{name}, {label}: {time.perf_counter() - started:.0f} s; {rows[label]}", flush=True)
    difference = rows["CAD file"][column] - rows["parametric"][column]
    return {"column": column, "converged": converged, "error": error, "rows": rows, "difference": difference}


def markdown(results: dict, machine: str, day: str) -> str:
    lines = [
        f"Machine: {machine}. Written by `python benchmarks/cad_import.py` (its docstring says what is "
        "measured); the mesh cache off.",
        "",
        "| scene | geometry | mesh s | tetrahedra | nodes | quality min | quality 1 % | rubber volume | answer | "
        "from the parametric / convergence error | from the converged / convergence error |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, r in results.items():
        for label, row in r["rows"].items():
            share = f"{abs(r['difference']) / r['error']:.2f}" if label == "CAD file" else ""
            converged = abs(row[r["column"]] - r["converged"]) / r["error"]
            lines.append(
                f"| {name} | {label} | {row['mesh_s']:.2f} | {row['tetrahedra']} | {row['nodes']} | "
                f"{row['quality_min']:.3f} | {row['quality_p1']:.3f} | {row['volume']:.6g} | "
                f"{r['column']} {row[r['column']]:.4g} | {share} | {converged:.2f} |"
            )
    return "\n".join(lines) + "\n"


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default="benchmarks/results")
    args = p.parse_args()
    from taichi_pneuma import runtime
    from taichi_pneuma.api import load_scene
    from taichi_pneuma.apps.bench import machine
    from taichi_pneuma.io.output import prepare_directory, save_json, save_text

    runtime.ensure_initialised()
    fiber = load_scene("fiber_bending_3d")
    pneunet = load_scene("pneunet_3d").with_values(PNEUNET_PEAK)
    results = {
        "fiber_bending_3d / STEP": run_case(
            "fiber_bending_3d",
            fiber,
            dataclasses.replace(fiber, geometry=step_geometry(fiber)),
            "tip_rotation",
            -154.1,
            2.7,
        ),
        "fiber_bending_3d / STL": run_case(
            "fiber_bending_3d",
            fiber,
            dataclasses.replace(fiber, geometry=fiber_stl_geometry(fiber)),
            "tip_rotation",
            -154.1,
            2.7,
        ),
        "pneunet_3d / STL": run_case("pneunet_3d", pneunet, stl_scene(pneunet), "tip_dy", -1.100, 0.02 * 1.100),
    }
    out = prepare_directory(args.out)
    day = time.strftime("%Y-%m-%d")
    save_json(out / "cad_import.json", {"machine": machine(), "date": day, "cases": results})
    save_text(out / "cad_import.md", markdown(results, machine(), day))
    print(f"wrote {out / 'cad_import.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
