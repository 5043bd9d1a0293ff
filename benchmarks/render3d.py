"""3D meshing and rendering costs: the PneuNet meshed by gmsh, and ms per frame of both 3D views.

    python -m benchmarks.render3d [--frames 8] [--out benchmarks/results]      (from the repository root)

Meshing: PneuNet() at the sizes below, wall time of mesh_solid (OpenCASCADE geometry, fragment, gmsh's
Delaunay, reading the arrays back), tetrahedra, surface triangles, and the estimate mesh_solid checks.
Rendering: the PneuNet's surface (outer faces and chamber walls) bent by an analytic displacement over
`frames` steps, drawn at 960 x 540 (trace panel and colour bar included) by the NumPy rasteriser and by
GGUI's scene (lavapipe on a CPU-only machine); ms per frame after one warm-up frame, wall-clock and
CPU time of the process (all its threads: lavapipe's included), the latter steadier on a shared machine. With a display
(DISPLAY set; e.g. Xvfb), the interactive window's redraw rate on the coarse PneuNet (six sliders, the
camera spinning, no solve). Wall times on a shared machine: compare ratios within one run.
"""

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np

from taichi_pneuma import runtime
from taichi_pneuma.apps.bench import machine
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.pneunet import PneuNet
from taichi_pneuma.fem.gmsh_mesher import MeshSizes, estimate_tets, mesh_solid
from taichi_pneuma.render.frames3d import FrameRenderer3D, Track3D
from taichi_pneuma.render.interactive3d import Slider, explore_3d

MESH_SIZES = {"coarse (interactive)": MeshSizes(0.3), "scene default": MeshSizes(0.1),
              "fine": MeshSizes(0.05)}
RENDER_SIZES = {"~2k faces": MeshSizes(0.25), "~20k faces": MeshSizes(0.05)}


def bent(rest: np.ndarray, steps: int) -> np.ndarray:
    """The body curled down about z by curvatures up to 0.45, its left end (x = -2) fixed."""
    states = [rest.copy()]
    for kappa in np.linspace(0, 0.45, steps)[1:]:
        s, r = rest[:, 0] + 2, 1 / kappa + rest[:, 1]
        states.append(np.column_stack([-2 + r * np.sin(kappa * s), r * np.cos(kappa * s) - 1 / kappa, rest[:, 2]]))
    return np.array(states)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--frames", type=int, default=8)
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results"))
    args = parser.parse_args()
    runtime.init("cpu")
    solid, data = PneuNet().solid(), {"meshing": [], "rendering": []}
    for label, sizes in MESH_SIZES.items():
        start = time.perf_counter()
        mesh = mesh_solid(solid, sizes)
        seconds = time.perf_counter() - start
        faces = len(mesh.boundary) + sum(len(w) for w in mesh.chambers.values())
        data["meshing"].append({"mesh": label, "size": sizes.size, "seconds": seconds, "tets": len(mesh.tets),
                                "nodes": len(mesh.vertices), "surface_triangles": faces,
                                "estimate": estimate_tets(solid, sizes)})
        print(data["meshing"][-1], flush=True)
    for label, sizes in RENDER_SIZES.items():
        mesh = mesh_solid(solid, sizes)
        positions = bent(mesh.vertices, args.frames)
        track = Track3D(positions, mesh.boundary, tuple(mesh.chambers.values()),
                        color=np.linalg.norm(positions - mesh.vertices, axis=2), color_label="|u|",
                        captions=tuple((f"step {i}",) for i in range(args.frames)),
                        trace=(("curvature", np.linspace(0, 0.45, args.frames)),))
        faces = len(mesh.boundary) + sum(len(w) for w in mesh.chambers.values())
        for backend in ("numpy", "ggui"):
            try:
                renderer = FrameRenderer3D(track, 960, 540, backend=backend, log=lambda _: None)
            except PneumaInputError as exc:
                print(f"{backend}: {exc}")
                continue
            try:
                renderer.frame(0)
                start, cpu = time.perf_counter(), time.process_time()
                for i in range(args.frames):
                    renderer.frame(i)
                ms = 1e3 * (time.perf_counter() - start) / args.frames
                cpu_ms = 1e3 * (time.process_time() - cpu) / args.frames
            finally:
                renderer.canvas.close()
            data["rendering"].append({"mesh": label, "surface_triangles": faces, "drawn_triangles": len(renderer.kept)
                                      + len(renderer.walls), "view": renderer.canvas.name, "ms_per_frame": ms,
                                      "cpu_ms_per_frame": cpu_ms})
            print(data["rendering"][-1], flush=True)
    if os.environ.get("DISPLAY"):
        mesh = mesh_solid(solid, MESH_SIZES["coarse (interactive)"])
        states = bent(mesh.vertices, 11)
        summary = explore_3d(lambda q: (states[int(round(10 * q[0]))], [f"c1 = {q[0]:.2f}"]),
                             [Slider(name, 0.0, 1.0, 0.0) for name in mesh.chambers], mesh.vertices, mesh.boundary,
                             tuple(mesh.chambers.values()), size=(960, 640), spin=2.0, max_frames=60)
        data["interactive"] = {"tets": len(mesh.tets), "frames_per_second": summary["fps"]}
        print(data["interactive"], flush=True)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "render3d.json").write_text(json.dumps({"machine": machine(), "data": data}, indent=2))
    lines = [f"Machine: {machine()}", "", "| PneuNet mesh | size | tetrahedra | nodes | surface triangles | "
             "estimate | meshing (s) |", "|---|---|---|---|---|---|---|"]
    lines += [f"| {r['mesh']} | {r['size']:g} | {r['tets']} | {r['nodes']} | {r['surface_triangles']} | "
              f"{r['estimate']:.0f} | {r['seconds']:.2f} |" for r in data["meshing"]]
    lines += ["", "| surface | triangles (drawn after the section) | view | ms / frame (960 x 540) | CPU ms / frame |",
              "|---|---|---|---|---|"]
    lines += [f"| {r['mesh']} | {r['surface_triangles']} ({r['drawn_triangles']}) | {r['view']} | "
              f"{r['ms_per_frame']:.0f} | {r['cpu_ms_per_frame']:.0f} |" for r in data["rendering"]]
    if "interactive" in data:
        lines += ["", f"Interactive window (960 x 640, coarse PneuNet of {data['interactive']['tets']} tetrahedra, "
                      f"no solve): {data['interactive']['frames_per_second']:.0f} frames/s"]
    (args.out / "render3d.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
