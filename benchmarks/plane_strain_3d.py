"""Plane strain in 3D: the reference ramp on the 2D triangles and on the same triangles extruded through a depth
of 0.8 into tetrahedra (one layer of prisms, three tetrahedra each; the chamber a prism through the depth, rollers
on both faces normal to z), linear and quadratic, on the reference mesh refined uniformly.

    python benchmarks/plane_strain_3d.py [--levels 3] [--quadratic-levels 1] [--out benchmarks/results]

Prints a Markdown table (elements, 2D and 3D tip deflections, their gap, each one's error against the converged
2D tip -0.25826, wall times) and writes it with the machine and date to plane_strain_3d.md and .json
(plane_strain_3d_a<max area>.md where level 0 is not the reference mesh). The 3D
scene is a mesh-file scene (fem/meshfile.write_mesh, then MeshGeometry), as a user would write it.

The converged 3D value: Richardson extrapolation of the tips t0, t1, t2 on three nested levels (h halved each
time) of one element order, with their observed order p = log2((t0 - t1) / (t1 - t2)):
t = t2 + (t2 - t1) / (2^p - 1); the same for the 2D tips checks the extrapolation against the converged 2D value.
"""

import argparse
import math
import platform
import tempfile
import time
from datetime import date
from pathlib import Path

from taichi_pneuma import api, runtime
from taichi_pneuma.fem.layered import extrude
from taichi_pneuma.fem.meshfile import MeshBody, MeshGeometry, MeshSurface, write_mesh
from taichi_pneuma.fem.planar import BeamGeometry
from taichi_pneuma.fem.supports import PointSet, Roller
from taichi_pneuma.fem.tetmesh import tet_mesh
from taichi_pneuma.io.output import prepare_directory, save_json, save_text
from taichi_pneuma.scene.build import ChamberControl, Material, Scene, reference_scene
from taichi_pneuma.scene.schedule import area_ramp

DEPTH = 0.8
CONVERGED = -0.25826  # P2, the reference mesh refined twice (docs/accuracy.md)
STEPS = 11  # the area-controlled equilibrium does not depend on the path (docs/accuracy.md)
ROLLERS = (Roller((0.0, 0.0, 1.0), (0.0, 0.0, 0.0)), Roller((0.0, 0.0, 1.0), (0.0, 0.0, DEPTH)))


def extruded_scene(level: int, order: int, folder: Path, max_area: float) -> Scene:
    """The reference scene's triangles (Triangle's mesh of max_area, refined `level` times) extruded, as a mesh
    file and a scene of it; the chamber's stiffness k / depth gives the 3D model the 2D one's energy per unit
    depth."""
    planar = BeamGeometry(cy=0.15, max_area=max_area, refinements=level).mesh()
    vertices, tets, walls = extrude(planar, DEPTH)
    mesh = tet_mesh(vertices, tets, {"main": walls[0]}, rollers=ROLLERS)
    path = write_mesh(folder / f"beam_{level}.msh", mesh, ("main",))
    geometry = MeshGeometry(
        MeshBody(str(path)), (("main", MeshSurface("main")),), order, PointSet("left"), rollers=ROLLERS
    )
    return Scene(
        geometry,
        (ChamberControl(area_ramp(3.5, STEPS, 1e5 / DEPTH)),),
        STEPS - 1,
        Material(1e4, 0.45),
        name=f"extruded_{level}_p{order}",
    )


def richardson(tips: list[float]) -> tuple[float, float]:
    """(extrapolated value, observed order) of the last three tips of a nested refinement sequence (NaN, NaN
    unless the differences shrink monotonically)."""
    t0, t1, t2 = tips[-3:]
    if not 0 < (t1 - t2) / (t0 - t1) < 1:
        return math.nan, math.nan
    order = math.log2((t0 - t1) / (t1 - t2))
    return t2 + (t2 - t1) / (2**order - 1), order


def timed(scene):
    start = time.perf_counter()
    result = api.simulate(scene)
    return result, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "--levels", type=int, default=3, help="linear elements: refinements of the reference mesh, 0 .. levels-1"
    )
    parser.add_argument("--quadratic-levels", type=int, default=1, help="the same for quadratic elements")
    parser.add_argument(
        "--max-area",
        type=float,
        default=BeamGeometry.max_area,
        help="Triangle's max area of level 0 (the chamber's 128-gon, hence the converged tip, whatever it is)",
    )
    parser.add_argument("--out", default="benchmarks/results")
    args = parser.parse_args()
    out = prepare_directory(args.out)
    runtime.init("cpu")
    rows, data = [], []
    with tempfile.TemporaryDirectory() as folder:
        for order, levels in ((1, args.levels), (2, args.quadratic_levels)):
            for level in range(levels):
                planar, planar_s = timed(
                    reference_scene(steps=STEPS, order=order, refinements=level, max_area=args.max_area)
                )
                solid, solid_s = timed(extruded_scene(level, order, Path(folder), args.max_area))
                record = {
                    "order": order,
                    "level": level,
                    "triangles": planar.mesh.n_elements,
                    "tetrahedra": solid.mesh.n_elements,
                    "nodes_3d": solid.mesh.n_vertices,
                    "tip_2d": planar.tip_deflection,
                    "tip_3d": solid.tip_deflection,
                    "seconds_2d": planar_s,
                    "seconds_3d": solid_s,
                }
                data.append(record)
                gap = abs(record["tip_3d"] - record["tip_2d"])
                rows.append(
                    [
                        f"P{order}",
                        level,
                        record["triangles"],
                        record["tetrahedra"],
                        record["nodes_3d"],
                        f"{record['tip_2d']:+.5f}",
                        f"{record['tip_3d']:+.5f}",
                        f"{gap:.5f}",
                        *(f"{abs(record[k] / CONVERGED - 1):.2%}" for k in ("tip_2d", "tip_3d")),
                        f"{planar_s:.1f}",
                        f"{solid_s:.1f}",
                    ]
                )
                print(rows[-1], flush=True)
    header = [
        "elements",
        "refinements",
        "triangles",
        "tetrahedra",
        "3D nodes",
        "2D tip",
        "3D tip",
        "gap",
        "2D error",
        "3D error",
        "2D s",
        "3D s",
    ]
    table = "| " + " | ".join(header) + " |\n|" + "---|" * len(header) + "\n"
    table += "".join("| " + " | ".join(str(c) for c in row) + " |\n" for row in rows)
    heading = (
        f"Machine: {platform.node()}, {platform.machine()}, {date.today()}; level 0: max area {args.max_area:g}; "
        f"converged 2D tip {CONVERGED}\n\n"
    )
    extrapolated, notes = {}, ""
    for order in (1, 2):
        for dim in ("2d", "3d"):
            tips = [r[f"tip_{dim}"] for r in data if r["order"] == order]
            if len(tips) >= 3:
                value, observed = richardson(tips)
                extrapolated[f"p{order}_{dim}"] = {"tip": value, "order": observed}
                notes += (
                    f"\nRichardson, P{order} {dim.upper()} levels {len(tips) - 3}-{len(tips) - 1}: converged tip "
                    f"{value:+.5f} (observed order {observed:.2f}), {abs(value / CONVERGED - 1):.2%} from the "
                    f"converged 2D {CONVERGED}"
                )
    print(heading + table + notes)
    stem = "plane_strain_3d" + ("" if args.max_area == BeamGeometry.max_area else f"_a{args.max_area:g}")
    save_text(out / f"{stem}.md", heading + table + notes + "\n")
    save_json(
        out / f"{stem}.json",
        {
            "machine": platform.node(),
            "date": str(date.today()),
            "max_area": args.max_area,
            "runs": data,
            "extrapolated": extrapolated,
        },
    )


if __name__ == "__main__":
    main()
