"""Plane strain in 3D: the reference ramp on the 2D triangles and on the same triangles extruded through a depth
of 0.8 into tetrahedra (one layer of prisms, three tetrahedra each; the chamber a prism through the depth, rollers
on both faces normal to z), linear and quadratic, on the reference mesh refined uniformly.

    python benchmarks/plane_strain_3d.py [--levels 2] [--out benchmarks/results]

Prints a Markdown table (elements, 2D and 3D tip deflections, their gap, each one's error against the converged
2D tip -0.25826, wall times) and writes it with the machine and date to plane_strain_3d.md and .json. The 3D
scene is a mesh-file scene (fem/meshfile.write_mesh, then MeshGeometry), as a user would write it.
"""

import argparse
import platform
import tempfile
import time
from datetime import date
from pathlib import Path

from taichi_pneuma import api, runtime
from taichi_pneuma.fem.geometry import BeamGeometry, Roller
from taichi_pneuma.fem.layered import extrude
from taichi_pneuma.fem.meshfile import MeshBody, MeshGeometry, MeshSurface, write_mesh
from taichi_pneuma.fem.tetmesh import tet_mesh
from taichi_pneuma.io.output import prepare_directory, save_json, save_text
from taichi_pneuma.scene import ChamberControl, Material, Scene, reference_scene
from taichi_pneuma.solve.schedule import area_ramp

DEPTH = 0.8
CONVERGED = -0.25826  # P2, the reference mesh refined twice (docs/accuracy.md)
STEPS = 11  # the area-controlled equilibrium does not depend on the path (docs/accuracy.md)
ROLLERS = (Roller((0.0, 0.0, 1.0), (0.0, 0.0, 0.0)), Roller((0.0, 0.0, 1.0), (0.0, 0.0, DEPTH)))


def extruded_scene(level: int, order: int, folder: Path) -> Scene:
    """The reference scene's triangles (refined `level` times) extruded, as a mesh file and a scene of it; the
    chamber's stiffness k / depth gives the 3D model the 2D one's energy per unit depth."""
    planar = BeamGeometry(cy=0.15, refinements=level).mesh()
    vertices, tets, walls = extrude(planar, DEPTH)
    mesh = tet_mesh(vertices, tets, {"main": walls[0]}, rollers=ROLLERS)
    path = write_mesh(folder / f"beam_{level}.msh", mesh, ("main",))
    geometry = MeshGeometry(MeshBody(str(path)), (("main", MeshSurface("main")),), order, rollers=ROLLERS)
    return Scene(geometry, (ChamberControl(area_ramp(3.5, STEPS, 1e5 / DEPTH)),), STEPS - 1, Material(1e4, 0.45),
                 name=f"extruded_{level}_p{order}")


def timed(scene):
    start = time.perf_counter()
    result = api.simulate(scene)
    return result, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--levels", type=int, default=2, help="refinements of the reference mesh: 0 .. levels-1")
    parser.add_argument("--out", default="benchmarks/results")
    args = parser.parse_args()
    out = prepare_directory(args.out)
    runtime.init("cpu")
    rows, data = [], []
    with tempfile.TemporaryDirectory() as folder:
        for order in (1, 2):
            for level in range(args.levels):
                planar, planar_s = timed(reference_scene(steps=STEPS, order=order, refinements=level))
                solid, solid_s = timed(extruded_scene(level, order, Path(folder)))
                record = {"order": order, "level": level, "triangles": planar.mesh.n_elements,
                          "tetrahedra": solid.mesh.n_elements, "nodes_3d": solid.mesh.n_vertices,
                          "tip_2d": planar.tip_deflection, "tip_3d": solid.tip_deflection,
                          "seconds_2d": planar_s, "seconds_3d": solid_s}
                data.append(record)
                gap = abs(record["tip_3d"] - record["tip_2d"])
                rows.append([f"P{order}", level, record["triangles"], record["tetrahedra"], record["nodes_3d"],
                             f"{record['tip_2d']:+.5f}", f"{record['tip_3d']:+.5f}", f"{gap:.5f}",
                             *(f"{abs(record[k] / CONVERGED - 1):.2%}" for k in ("tip_2d", "tip_3d")),
                             f"{planar_s:.1f}", f"{solid_s:.1f}"])
                print(rows[-1], flush=True)
    header = ["elements", "refinements", "triangles", "tetrahedra", "3D nodes", "2D tip", "3D tip", "gap",
              "2D error", "3D error", "2D s", "3D s"]
    table = "| " + " | ".join(header) + " |\n|" + "---|" * len(header) + "\n"
    table += "".join("| " + " | ".join(str(c) for c in row) + " |\n" for row in rows)
    heading = f"Machine: {platform.node()}, {platform.machine()}, {date.today()}; converged 2D tip {CONVERGED}\n\n"
    print(heading + table)
    save_text(out / "plane_strain_3d.md", heading + table)
    save_json(out / "plane_strain_3d.json", {"machine": platform.node(), "date": str(date.today()), "runs": data})


if __name__ == "__main__":
    main()
