"""What accuracy costs in 3D: linear against quadratic tetrahedra on nested refinements of a gmsh mesh, against
the finest run as the reference, at nu = 0.45 and 0.499, for two bodies:

    beam     the reference beam in 3D: the clamped 3.5 x 0.8 x 0.8 box with the ellipsoidal chamber of semi-axes
             (0.85, 0.22, 0.25) at (0, 0.15, 0), volume 1 -> 2x
    pneunet  the PneuNet finger (fem/pneunet.py defaults, its bottom layer five times stiffer), its six chambers
             driven together, volume 1 -> 1.5x

Level 0 is gmsh's mesh of the solid (fem/gmsh_mesher.py) at size SIZE; level l + 1 splits every tetrahedron of
level l in eight at its edge midpoints (and every wall triangle in four; a curved chamber wall keeps level 0's
facets: the study measures the elements' error on one geometry, the mesh's own), so the quadratic tetrahedra of level l have exactly the nodes of the linear ones
of level l + 1. Per run: tip deflection (mean y displacement of the right face), chamber pressure at the final
volume, wall and CPU time (the process's, all threads: the steadier figure on a shared machine) and
Newton iterations; per element order the observed order of convergence of the tip from
three nested levels, p = log2((t0 - t1) / (t1 - t2)), and every run's error against the reference (the
finest quadratic run, listed with its own estimated error |t_fine - t_coarse| / (2^2 - 1)).

    python benchmarks/accuracy_3d.py [--cases beam pneunet] [--nu 0.45 0.499] [--out benchmarks/results]

Progress lines as it goes; accuracy_3d.json is rewritten after every run (machine, date); accuracy_3d.md at the end.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from dataclasses import dataclass
from datetime import date
from pathlib import Path

import numpy as np

from taichi_pneuma import api, runtime
from taichi_pneuma.fem.gmsh_mesher import MeshSizes, Solid, mesh_solid
from taichi_pneuma.fem.pneunet import PneuNet
from taichi_pneuma.fem.solids import Box, Ellipsoid
from taichi_pneuma.fem.tetmesh import tet_mesh
from taichi_pneuma.io.output import prepare_directory, save_json, save_text
from taichi_pneuma.scene import ChamberControl, Material, Region, Scene
from taichi_pneuma.solve.schedule import area_ramp

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from solid_meshes import MeshOf  # noqa: E402

E, STIFFNESS, INCREMENTS = 1e4, 1e6, 5
# tetrahedron corners of the eight children of a split tetrahedron: corners 0-3, edge midpoints 4-9 in the order
# (01, 02, 03, 12, 13, 23); four corner tetrahedra, the inner octahedron cut along its 02-13 diagonal
EDGES = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))
CHILDREN = np.array([[0, 4, 5, 6], [4, 1, 7, 8], [5, 7, 2, 9], [6, 8, 9, 3],
                     [5, 8, 4, 6], [5, 8, 6, 9], [5, 8, 9, 7], [5, 8, 7, 4]])
FACE_CHILDREN = np.array([[0, 3, 5], [3, 1, 4], [5, 4, 2], [3, 4, 5]])  # corners 0-2, midpoints (01, 12, 20) 3-5


@dataclass(frozen=True)
class Case:
    name: str
    solid: object
    size: float
    growth: float
    layer: tuple | None = None  # a stiffer region's box (x0, y0, z0, x1, y1, z1) and its E


BEAM_CHAMBER = ((0.0, 0.15, 0.0), (0.85, 0.22, 0.25))


def case_of(name: str) -> Case:
    if name == "beam":
        solid = Solid(Box((0.0, 0.0, 0.0), (3.5, 0.8, 0.8)), (("main", Ellipsoid(*BEAM_CHAMBER)),))
        return Case("beam", solid, 0.3, 2.0)
    finger = PneuNet()
    length, height, width = finger.size
    layer = (-length, -height / 2 - 1e-9, -width, length, -height / 2 + finger.layer + 1e-9, width)
    return Case("pneunet", finger.solid(), 0.3, 1.5, layer=(layer, 5 * E))


def split(vertices, tets, walls):
    """One nested refinement: every tetrahedron into eight, every wall triangle into four (their new nodes at
    the edge midpoints: a curved wall keeps the facets of the level it is split from)."""
    n = len(vertices)
    pairs = np.sort(tets[:, EDGES].reshape(-1, 2), axis=1)
    keys, inverse = np.unique(pairs[:, 0] * n + pairs[:, 1], return_inverse=True)
    points = np.vstack([vertices, 0.5 * (vertices[keys // n] + vertices[keys % n])])
    fine = np.column_stack([tets, n + inverse.reshape(-1, 6)])[:, CHILDREN].reshape(-1, 4)
    fine_walls = {}
    for name, faces in walls.items():
        sides = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
        middles = n + np.searchsorted(keys, sides[:, 0] * n + sides[:, 1]).reshape(-1, 3)
        fine_walls[name] = np.column_stack([faces, middles])[:, FACE_CHILDREN].reshape(-1, 3)
    return points, fine, fine_walls


def meshes(case: Case, levels: int):
    """The level 0 .. levels - 1 meshes' arrays: (vertices, tets, walls)."""
    import gmsh

    # gmsh's default surface algorithm leaves the ellipsoid's wall unmeshed at these sizes; MeshAdapt meshes it
    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("Mesh.Algorithm", 1)
    try:
        solid = mesh_solid(case.solid, MeshSizes(case.size))
    finally:
        gmsh.finalize()
    level = (solid.vertices, solid.tets, dict(solid.chambers))
    out = [level]
    for _ in range(1, levels):
        level = split(*level)
        out.append(level)
    return out


def scene_of(case: Case, level, order: int, nu: float) -> Scene:
    vertices, tets, walls = level
    mesh = tet_mesh(vertices, tets, walls, order=order)
    names = tuple(walls)
    controls = tuple(ChamberControl(area_ramp(case.growth, INCREMENTS + 1, STIFFNESS)) for _ in names)
    regions = () if case.layer is None else (Region(case.layer[0], Material(case.layer[1], nu)),)
    return Scene(MeshOf(mesh, names), controls, INCREMENTS, Material(E, nu), regions, name=f"{case.name}_p{order}")


def run(case: Case, level, order: int, nu: float) -> dict:
    start, cpu = time.perf_counter(), time.process_time()
    result = api.simulate(scene_of(case, level, order, nu))
    seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
    mesh = result.mesh
    pressures = [result.history[f"{name}.pressure"][-1] for name in result.chamber_names]
    return {"tetrahedra": int(mesh.n_elements), "nodes": int(mesh.n_vertices), "dofs": 3 * int(mesh.n_vertices),
            "tip": float(result.tip_deflection), "pressure": float(np.mean(pressures)), "seconds": seconds,
            "cpu_seconds": cpu, "iterations": int(sum(s.iterations for s in result.solves)), "converged": bool(result.converged)}


def observed_order(tips: list[float]) -> float:
    """log2 of the ratio of successive differences over three nested levels (NaN if they do not shrink)."""
    a, b = tips[-3] - tips[-2], tips[-2] - tips[-1]
    return float(np.log2(a / b)) if a * b > 0 else float("nan")


def report(records: list[dict]) -> str:
    lines = []
    for (case, nu) in dict.fromkeys((r["case"], r["nu"]) for r in records):
        rows = [r for r in records if r["case"] == case and r["nu"] == nu]
        quadratic = [r for r in rows if r["order"] == 2]
        reference = max(quadratic or rows, key=lambda r: r["nodes"])
        same = [r for r in quadratic if r is not reference]
        estimate = abs(reference["tip"] - same[-1]["tip"]) / 3 if same else float("nan")
        lines += [f"### {case}, nu = {nu}", "",
                  f"Reference: P{reference['order']} level {reference['level']}, tip {reference['tip']:+.5f} "
                  f"(estimated error {estimate:.1e}), pressure {reference['pressure']:.1f}.", "",
                  "| elements | level | tetrahedra | DOFs | tip | tip error | pressure | pressure error | s | "
                  "Newton it |", "|---|---|---|---|---|---|---|---|---|---|"]
        for r in rows:
            tip_error = abs(r["tip"] / reference["tip"] - 1)
            pressure_error = abs(r["pressure"] / reference["pressure"] - 1)
            lines.append(f"| P{r['order']} | {r['level']} | {r['tetrahedra']} | {r['dofs']} | {r['tip']:+.5f} | "
                         f"{tip_error:.2%} | {r['pressure']:.1f} | {pressure_error:.2%} | {r['seconds']:.1f} | "
                         f"{r['iterations']} |")
        for order in (1, 2):
            tips = [r["tip"] for r in rows if r["order"] == order]
            if len(tips) >= 3:
                lines.append(f"\nObserved order of the P{order} tip over its last three levels: "
                             f"{observed_order(tips):.2f}")
        lines.append("")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cases", nargs="+", default=["beam", "pneunet"], choices=["beam", "pneunet"])
    parser.add_argument("--nu", nargs="+", type=float, default=[0.45, 0.499])
    parser.add_argument("--out", default="benchmarks/results")
    args = parser.parse_args()
    out = prepare_directory(args.out)
    runtime.init("cpu")
    machine = f"{platform.node()}, {platform.machine()}, {os.cpu_count()} CPUs"
    # (order, level) per case: the linear tetrahedra on three levels where affordable, the quadratic on two
    plans = {"beam": [(1, 0), (1, 1), (1, 2), (2, 0), (2, 1)], "pneunet": [(1, 0), (1, 1), (2, 0)]}
    records = []
    for name in args.cases:
        case = case_of(name)
        levels = meshes(case, 1 + max(level + order - 1 for order, level in plans[name]))
        for nu in args.nu:
            for order, level in plans[name]:
                record = {"case": name, "nu": nu, "order": order, "level": level,
                          **run(case, levels[level], order, nu)}
                records.append(record)
                print(f"{name} nu={nu} P{order} level {level}: {record['tetrahedra']} tetrahedra, {record['dofs']} "
                      f"DOFs, tip {record['tip']:+.5f}, pressure {record['pressure']:.1f}, "
                      f"{record['seconds']:.1f} s ({record['cpu_seconds']:.1f} s CPU), {record['iterations']} Newton iterations",
                      flush=True)
                save_json(out / "accuracy_3d.json", {"machine": machine, "date": str(date.today()),
                                                     "increments": INCREMENTS, "runs": records})
    text = f"Machine: {machine}; {date.today()}; {INCREMENTS} increments per ramp.\n\n" + report(records)
    print(text)
    save_text(out / "accuracy_3d.md", text)


if __name__ == "__main__":
    main()
