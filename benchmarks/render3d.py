"""3D meshing and rendering costs: the PneuNet meshed by gmsh, and ms per frame of both 3D views.

    python -m benchmarks.render3d [--frames 8] [--live-frames 30] [--only-live] [--out benchmarks/results]  (repository root)

Meshing: PneuNet() at the sizes below, wall time of mesh_solid (OpenCASCADE geometry, fragment, gmsh's
Delaunay, reading the arrays back), tetrahedra, surface triangles, and the estimate mesh_solid checks.
Rendering: the PneuNet's surface (outer faces and chamber walls) bent by an analytic displacement over
`frames` steps, drawn at 960 x 540 (trace panel and colour bar included) by the NumPy rasteriser and by
GGUI's scene (lavapipe on a CPU-only machine); ms per frame after one warm-up frame, wall-clock and
CPU time of the process (all its threads: lavapipe's included), the latter steadier on a shared machine. With a display
(DISPLAY set; e.g. Xvfb), the interactive window's redraw rate on the coarse PneuNet (six sliders, the
camera spinning, no solve). The live loop without a window (the interactive window's work per frame: a
warm-started Newton solve at the moved slider, then the shaded triangles drawn offscreen): the coarse PneuNet
scene, its six chambers' pressure slider dragged from 0 to 900 Pa in --live-frames frames, ms per frame of
the solve and of the drawing, each 3D view, and the frames per second of both together. Wall times on a
shared machine: compare ratios within one run.
"""

import argparse
import collections
import itertools
import json
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from taichi_pneuma import runtime
from taichi_pneuma.apps.bench import machine
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.pneunet import PneuNet
from taichi_pneuma.fem.gmsh_mesher import MeshSizes, estimate_tets, mesh_solid
from taichi_pneuma.render.camera import Camera
from taichi_pneuma.render.frames3d import BACKGROUND, FrameRenderer3D, Track3D, open_view, section_faces, shaded_triangles
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


def outer_faces(mesh) -> np.ndarray:
    """The body's boundary facets that lie on no chamber wall."""
    walls = {tuple(sorted(face)) for wall in mesh.chambers for face in wall[:, :3].tolist()}
    return np.array([face for face in mesh.surface[:, :3].tolist() if tuple(sorted(face)) not in walls])


def live(frames: int, size: float = 0.3, peak: float = 900.0) -> list[dict]:
    """The interactive loop's work per frame, headless (module docstring): a record per 3D view and Newton
    tolerance (the default, and the 2D live views' LIVE_TOL), wall and CPU time (the steadier on a shared
    machine)."""
    from taichi_pneuma.apps.bench import Meshed
    from taichi_pneuma.fem.tetmesh import tet_mesh
    from taichi_pneuma.scene import ChamberControl, Material, Scene
    from taichi_pneuma.render.interactive import LIVE_TOL
    from taichi_pneuma.solve.newton import NewtonOptions, NewtonSolver
    from taichi_pneuma.solve.schedule import ChamberSchedule

    meshed = mesh_solid(PneuNet().solid(), MeshSizes(size))
    names = tuple(meshed.chambers)
    geometry = Meshed(tet_mesh(meshed.vertices, meshed.tets, meshed.chambers, meshed.boundary),
                      tuple((name, None) for name in names))
    controls = tuple(ChamberControl(ChamberSchedule("pressure", ((1, peak),))) for _ in names)
    built = Scene(geometry, controls, 1, Material(1e4, 0.45)).build()  # one material (the scene's stiffer layer aside)
    mesh = built.mesh
    camera = Camera().fitted(mesh.vertices, 960, 640, margin=0.2)
    boundary = outer_faces(mesh)
    faces, walls = boundary[section_faces(mesh.vertices, boundary, camera)], np.concatenate(mesh.chambers)[:, :3]
    records = []
    for backend, tol in itertools.product(("numpy", "ggui"), (NewtonOptions.tol, LIVE_TOL)):
        try:
            view = open_view(backend, 960, 640, log=lambda _: None)
        except PneumaInputError as exc:
            print(f"{backend}: {exc}")
            continue
        solver = NewtonSolver(built.model, NewtonOptions(tol=tol))
        u = np.zeros_like(mesh.vertices)
        solve_s, draw_s, cpu_s, iterations, phases = [], [], [], [], collections.Counter()
        try:
            for k in range(-1, frames + 1):  # frame -1 (a tiny pressure: the kernels' first calls) is the warm-up
                start, cpu = time.perf_counter(), time.process_time()
                built.set_commands(np.full(len(built.chambers), peak * max(k, 0.01) / frames))
                u, record = solver.solve(u)
                middle = time.perf_counter()
                view.render(*shaded_triangles(mesh.vertices + u, faces, walls, camera), camera, BACKGROUND)
                if k >= 1:
                    solve_s.append(middle - start)
                    draw_s.append(time.perf_counter() - middle)
                    cpu_s.append(time.process_time() - cpu)
                    iterations.append(record.iterations)
                    phases.update(record.phase_seconds)
        finally:
            view.close()
        solve_ms, draw_ms = 1e3 * np.mean(solve_s), 1e3 * np.mean(draw_s)
        records.append({"tets": len(mesh.elements), "nodes": len(mesh.vertices), "view": view.name,
                        "solve_ms": solve_ms, "draw_ms": draw_ms, "newton_iterations": float(np.mean(iterations)),
                        "frames_per_second": 1e3 / (solve_ms + draw_ms), "linear_solver": solver.backend.name,
                        "cpu_ms": 1e3 * np.mean(cpu_s), "frames_per_cpu_second": 1 / np.mean(cpu_s),
                        "tol": solver.options.tol, "phases_ms_per_frame": {p: 1e3 * t / frames for p, t in phases.items()}})
        print(records[-1], flush=True)
    return records


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--frames", type=int, default=8)
    parser.add_argument("--live-frames", type=int, default=30)
    parser.add_argument("--only-live", action="store_true", help="the live loop alone (to render3d_live.md, .json)")
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results"))
    args = parser.parse_args()
    runtime.init("cpu")
    solid, data = PneuNet().solid(), {"meshing": [], "rendering": [], "live": live(args.live_frames)}
    for label, sizes in {} if args.only_live else MESH_SIZES.items():
        start = time.perf_counter()
        mesh = mesh_solid(solid, sizes)
        seconds = time.perf_counter() - start
        faces = len(mesh.boundary) + sum(len(w) for w in mesh.chambers.values())
        data["meshing"].append({"mesh": label, "size": sizes.size, "seconds": seconds, "tets": len(mesh.tets),
                                "nodes": len(mesh.vertices), "surface_triangles": faces,
                                "estimate": estimate_tets(solid, sizes)})
        print(data["meshing"][-1], flush=True)
    for label, sizes in {} if args.only_live else RENDER_SIZES.items():
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
    if os.environ.get("DISPLAY") and not args.only_live:
        mesh = mesh_solid(solid, MESH_SIZES["coarse (interactive)"])
        states = bent(mesh.vertices, 11)
        summary = explore_3d(lambda q: (states[int(round(10 * q[0]))], [f"c1 = {q[0]:.2f}"]),
                             [Slider(name, 0.0, 1.0, 0.0) for name in mesh.chambers], mesh.vertices, mesh.boundary,
                             tuple(mesh.chambers.values()), size=(960, 640), spin=2.0, max_frames=60)
        data["interactive"] = {"tets": len(mesh.tets), "frames_per_second": summary["fps"]}
        print(data["interactive"], flush=True)
    args.out.mkdir(parents=True, exist_ok=True)
    stem = "render3d_live" if args.only_live else "render3d"  # the live loop alone leaves the full tables as they are
    (args.out / f"{stem}.json").write_text(json.dumps({"machine": machine(), "data": data}, indent=2))
    lines = [f"Machine: {machine()}", "", "| PneuNet mesh | size | tetrahedra | nodes | surface triangles | "
             "estimate | meshing (s) |", "|---|---|---|---|---|---|---|"]
    lines += [f"| {r['mesh']} | {r['size']:g} | {r['tets']} | {r['nodes']} | {r['surface_triangles']} | "
              f"{r['estimate']:.0f} | {r['seconds']:.2f} |" for r in data["meshing"]]
    lines += ["", "| surface | triangles (drawn after the section) | view | ms / frame (960 x 540) | CPU ms / frame |",
              "|---|---|---|---|---|"]
    lines += [f"| {r['mesh']} | {r['surface_triangles']} ({r['drawn_triangles']}) | {r['view']} | "
              f"{r['ms_per_frame']:.0f} | {r['cpu_ms_per_frame']:.0f} |" for r in data["rendering"]]
    lines += ["", f"Live loop without a window (coarse PneuNet, {args.live_frames} frames of a pressure slider 0 -> 900 Pa, "
                  "960 x 640):", "", "| tetrahedra | nodes | view | linear solver | Newton tol | Newton iterations / frame | "
                  "solve ms / frame | draw ms / frame | frames/s | CPU ms / frame | frames / CPU s |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
    lines += [f"| {r['tets']} | {r['nodes']} | {r['view']} | {r['linear_solver']} | {r['tol']:g} | "
              f"{r['newton_iterations']:.1f} | {r['solve_ms']:.0f} | {r['draw_ms']:.0f} | {r['frames_per_second']:.1f} | "
              f"{r['cpu_ms']:.0f} | {r['frames_per_cpu_second']:.1f} |" for r in data["live"]]
    if "interactive" in data:
        lines += ["", f"Interactive window (960 x 640, coarse PneuNet of {data['interactive']['tets']} tetrahedra, "
                      f"no solve): {data['interactive']['frames_per_second']:.0f} frames/s"]
    (args.out / f"{stem}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
