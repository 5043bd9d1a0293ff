"""What accuracy costs in 3D: linear against quadratic tetrahedra on nested refinements of a gmsh mesh, against a
converged reference, at nu = 0.45 and 0.499, for two bodies:

    beam     the reference beam in 3D: the clamped 3.5 x 0.8 x 0.8 box with the ellipsoidal chamber of semi-axes
             (0.85, 0.22, 0.25) at (0, 0.15, 0), volume 1 -> 2x
    pneunet  the PneuNet finger (fem/pneunet.py defaults, its bottom layer five times stiffer), its six chambers
             driven together, volume 1 -> 1.5x

Level 0 is gmsh's mesh of the solid (fem/gmsh_mesher.py) at size SIZE; level l + 1 splits every tetrahedron of
level l in eight at its edge midpoints (and every wall triangle in four; a curved chamber wall keeps level 0's
facets: the study measures the elements' error on one geometry, the mesh's own; moving the new wall nodes onto
the ellipsoid turns tetrahedra inside out at this size), so the quadratic tetrahedra of level l have exactly the
nodes of the linear ones of level l + 1. Every ramp has INCREMENTS increments (the volume-controlled equilibrium
does not depend on the path). Per run: tip deflection (mean y displacement of the right face), chamber pressure at
the final volume, wall and CPU time (the process's, all threads: the steadier figure on a shared machine) and
Newton iterations; every run's error against the reference: the Richardson extrapolation
of the quadratic runs on three nested levels, else of the linear ones (with their observed order; where they
converge monotonically), else the finest quadratic run.

    python benchmarks/accuracy_3d.py [--cases beam pneunet] [--nu 0.45 0.499] [--runs 1:0 2:0 ...] [--out DIR]
    python benchmarks/accuracy_3d.py --report a.json b.json ...    (one report of runs made apart)

Progress lines as it goes; accuracy_3d.json is rewritten after every run (machine, date); accuracy_3d.md at the end.
"""

from __future__ import annotations

import argparse
import json
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
from taichi_pneuma.fem.supports import PointSet
from taichi_pneuma.fem.tetmesh import tet_mesh
from taichi_pneuma.io.output import prepare_directory, save_json, save_text
from taichi_pneuma.scene.build import ChamberControl, Material, Region, Scene
from taichi_pneuma.scene.schedule import area_ramp

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from solid_meshes import MeshOf  # noqa: E402

E, STIFFNESS, INCREMENTS = 1e4, 1e6, 5
# gmsh's MeshAdapt surface algorithm, no curvature sizing: the study's level 0 meshes (the beam's 802 tetrahedra),
# pinned: mesh_solid's own choice (fem/gmsh_mesher.py SURFACE_MESHERS) may change, the study's meshes must not
STUDY_MESHER = ((1, 0),)
# (order, level) per case: linear tetrahedra on three levels where affordable, quadratic ones on the first one or two
PLANS = {"beam": [(1, 0), (1, 1), (1, 2), (2, 0), (2, 1)], "pneunet": [(1, 0), (1, 1), (2, 0)]}
# tetrahedron corners of the eight children of a split tetrahedron: corners 0-3, edge midpoints 4-9 in the order
# (01, 02, 03, 12, 13, 23); four corner tetrahedra, the inner octahedron cut along its 02-13 diagonal
EDGES = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))
CHILDREN = np.array(
    [[0, 4, 5, 6], [4, 1, 7, 8], [5, 7, 2, 9], [6, 8, 9, 3], [5, 8, 4, 6], [5, 8, 6, 9], [5, 8, 9, 7], [5, 8, 7, 4]]
)
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
    solid = mesh_solid(case.solid, MeshSizes(case.size), surface_meshers=STUDY_MESHER)
    level = (solid.vertices, solid.tets, dict(solid.chambers))
    out = [level]
    for _ in range(1, levels):
        level = split(*level)
        out.append(level)
    return out


def scene_of(case: Case, level, order: int, nu: float) -> Scene:
    vertices, tets, walls = level
    mesh = tet_mesh(vertices, tets, walls, order=order, clamp=PointSet("left"))
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
    return {
        "tetrahedra": int(mesh.n_elements),
        "nodes": int(mesh.n_vertices),
        "dofs": 3 * int(mesh.n_vertices),
        "tip": float(result.tip_deflection),
        "pressure": float(np.mean(pressures)),
        "seconds": seconds,
        "cpu_seconds": cpu,
        "iterations": int(sum(s.iterations for s in result.solves)),
        "converged": bool(result.converged),
    }


def richardson(values: list[float]) -> tuple[float, float]:
    """(extrapolated value, observed order) from the last three of a nested sequence (h halved each time):
    p = log2((v0 - v1) / (v1 - v2)), v = v2 + (v2 - v1) / (2^p - 1); (NaN, NaN) unless the differences shrink
    monotonically."""
    v0, v1, v2 = values[-3:]
    if not 0 < (v1 - v2) / (v0 - v1) < 1:
        return float("nan"), float("nan")
    order = float(np.log2((v0 - v1) / (v1 - v2)))
    return v2 + (v2 - v1) / (2**order - 1), order


def extrapolations(rows: list[dict], key: str) -> list[tuple[float, str]]:
    """The Richardson extrapolations of a quantity, quadratic then linear elements, from each order's last three
    nested levels where they converge monotonically: (value, how it was made)."""
    out = []
    for order in (2, 1):
        values = [r[key] for r in rows if r["order"] == order]
        if len(values) >= 3:
            value, rate = richardson(values)
            if np.isfinite(value):
                out.append(
                    (
                        value,
                        f"Richardson of P{order} levels {len(values) - 3}-{len(values) - 1}, observed order {rate:.2f}",
                    )
                )
    return out


def reference(rows: list[dict], key: str) -> tuple[float, str]:
    """The reference value of a quantity: the first of its extrapolations (quadratic elements before linear
    ones), else the run of the highest order with the most DOFs."""
    found = extrapolations(rows, key)
    if found:
        return found[0]
    finest = max(rows, key=lambda r: (r["order"], r["dofs"]))
    return finest[key], f"P{finest['order']} level {finest['level']}"


def heading(machine: str, day: str) -> str:
    return f"Machine: {machine}; {day}; {INCREMENTS} increments per ramp.\n\n"


def report(records: list[dict]) -> str:
    lines = []
    for case, nu in dict.fromkeys((r["case"], r["nu"]) for r in records):
        rows = sorted(
            (r for r in records if r["case"] == case and r["nu"] == nu), key=lambda r: (r["order"], r["level"])
        )
        tip, tip_from = reference(rows, "tip")
        pressure, pressure_from = reference(rows, "pressure")
        others = [
            f"{key} {value:.5g} ({how})"
            for key in ("tip", "pressure")  # reference() takes the first
            for value, how in extrapolations(rows, key)[1:]
        ]
        lines += [
            f"### {case}, nu = {nu}",
            "",
            f"Reference tip {tip:+.5f} ({tip_from}); pressure {pressure:.1f} ({pressure_from}).",
            *([f"Not taken: {'; '.join(others)}."] if others else []),
            "",
            "| elements | level | tetrahedra | DOFs | tip | tip error | pressure | pressure error | s | CPU s | "
            "Newton it |",
            "|---|---|---|---|---|---|---|---|---|---|---|",
        ]
        for r in rows:
            lines.append(
                f"| P{r['order']} | {r['level']} | {r['tetrahedra']} | {r['dofs']} | {r['tip']:+.5f} | "
                f"{abs(r['tip'] / tip - 1):.2%} | {r['pressure']:.1f} | {abs(r['pressure'] / pressure - 1):.2%} | "
                f"{r['seconds']:.1f} | {r['cpu_seconds']:.1f} | {r['iterations']} |"
            )
        lines.append("")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cases", nargs="+", default=["beam", "pneunet"], choices=["beam", "pneunet"])
    parser.add_argument("--nu", nargs="+", type=float, default=[0.45, 0.499])
    parser.add_argument(
        "--runs",
        nargs="+",
        default=None,
        metavar="ORDER:LEVEL",
        help="the runs to make (default: each case's plan, PLANS)",
    )
    parser.add_argument(
        "--report",
        nargs="+",
        default=None,
        metavar="JSON",
        help="make no runs: write accuracy_3d.md of the runs in these accuracy_3d.json files",
    )
    parser.add_argument("--out", default="benchmarks/results")
    args = parser.parse_args()
    out = prepare_directory(args.out)
    if args.report:
        loaded = [json.loads(Path(path).read_text()) for path in args.report]
        records = [r for data in loaded for r in data["runs"]]
        save_text(out / "accuracy_3d.md", heading(loaded[0]["machine"], loaded[0]["date"]) + report(records))
        save_json(out / "accuracy_3d.json", {**loaded[0], "runs": records})
        return
    runtime.init("cpu")
    machine = f"{platform.node()}, {platform.machine()}, {os.cpu_count()} CPUs"
    records = []
    for name in args.cases:
        case = case_of(name)
        plan = PLANS[name] if args.runs is None else [tuple(int(k) for k in run.split(":")) for run in args.runs]
        levels = meshes(case, 1 + max(level + order - 1 for order, level in plan))
        for nu in args.nu:
            for order, level in plan:
                record = {"case": name, "nu": nu, "order": order, "level": level, **run(case, levels[level], order, nu)}
                records.append(record)
                print(
                    f"{name} nu={nu} P{order} level {level}: {record['tetrahedra']} tetrahedra, {record['dofs']} "
                    f"DOFs, tip {record['tip']:+.5f}, pressure {record['pressure']:.1f}, "
                    f"{record['seconds']:.1f} s ({record['cpu_seconds']:.1f} s CPU), "
                    f"{record['iterations']} Newton iterations",
                    flush=True,
                )
                save_json(
                    out / "accuracy_3d.json",
                    {"machine": machine, "date": str(date.today()), "increments": INCREMENTS, "runs": records},
                )
    text = heading(machine, str(date.today())) + report(records)
    print(text)
    save_text(out / "accuracy_3d.md", text)


if __name__ == "__main__":
    main()
