"""3D meshing and rendering costs: the PneuNet meshed by gmsh, and ms per frame of both 3D views.

    python -m benchmarks.render3d [--frames 8] [--live-frames 30] [--only-live] [--out benchmarks/results]

(from the repository root)

Meshing: PneuNet() at the sizes below, wall time of mesh_solid (OpenCASCADE geometry, fragment, gmsh's
Delaunay, reading the arrays back), tetrahedra, surface triangles, and the estimate mesh_solid checks.
Rendering: the PneuNet's surface (outer faces and chamber walls) bent by an analytic displacement over
`frames` steps, drawn at 960 x 540 (trace panel and colour bar included) by the NumPy rasteriser and by
GGUI's scene (lavapipe on a CPU-only machine); ms per frame after one warm-up frame, wall-clock and
CPU time of the process (all its threads: lavapipe's included), the latter steadier on a shared machine. With a display
(DISPLAY set; e.g. Xvfb), the interactive window's redraw rate on the coarse PneuNet (six sliders, the
camera spinning, no solve), and with the live solve. The live loop without a window (the interactive window's
work per frame: the solve at the moved slider, then the shaded triangles drawn offscreen and read back): the
coarse PneuNet scene, its six chambers' pressure slider dragged from 0 to 900 Pa in --live-frames frames, ms
per frame of the solve and of the drawing, each 3D view, for a full Newton solve per move and for the
window's one Newton step per frame (render.interactive.LiveEquilibrium, then held until it converges), and
the frames per second of solve and drawing together. Wall times on a shared machine: compare ratios within one run.
"""

import argparse
import itertools
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from taichi_pneuma import runtime
from taichi_pneuma.apps.bench import machine
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.gmsh_mesher import MeshSizes, estimate_tets, mesh_solid
from taichi_pneuma.fem.pneunet import PneuNet
from taichi_pneuma.realtime.interactive3d import Slider, explore_3d
from taichi_pneuma.render.camera import Camera
from taichi_pneuma.render.colours import BACKGROUND
from taichi_pneuma.render.frames3d import FrameRenderer3D, Track3D, open_section, open_view, shaded_triangles

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the sibling scripts (solid.py's Meshed)

MESH_SIZES = {"coarse (interactive)": MeshSizes(0.3), "scene default": MeshSizes(0.1), "fine": MeshSizes(0.05)}
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


def live_scene(size: float = 0.3, peak: float = 900.0, order: int = 1):
    """The coarse PneuNet (gmsh at edge `size`; order 2: quadratic tetrahedra), its six chambers under pressure
    control (to `peak` Pa), one material (the scene's stiffer layer aside): (built scene, outer faces, chamber
    walls)."""
    from solid import Meshed

    from taichi_pneuma.fem.supports import PointSet
    from taichi_pneuma.fem.tetmesh import tet_mesh
    from taichi_pneuma.scene.build import ChamberControl, Material, Scene
    from taichi_pneuma.scene.schedule import ChamberSchedule

    meshed = mesh_solid(PneuNet().solid(), MeshSizes(size))
    names = tuple(meshed.chambers)
    geometry = Meshed(
        tet_mesh(meshed.vertices, meshed.tets, meshed.chambers, meshed.boundary, order=order, clamp=PointSet("left")),
        tuple((name, None) for name in names),
    )
    controls = tuple(ChamberControl(ChamberSchedule("pressure", ((1, peak),))) for _ in names)
    built = Scene(geometry, controls, 1, Material(1e4, 0.45)).build()
    return built, outer_faces(built.mesh), np.concatenate(built.mesh.chambers)[:, :3]


def live(frames: int, peak: float = 900.0, idle: int = 30, order: int = 1) -> list[dict]:
    """The interactive loop's work per frame, headless (module docstring): a record per 3D view and solve mode,
    wall and CPU time (the steadier on a shared machine). Modes: "full Newton" solves to the live tolerance at
    every slider move (warm-started); "one step" is the window's LiveEquilibrium (one Newton step per frame, the
    previous factorisation reused while the slider moves), followed by idle frames (at most `idle`) until it
    converges at the last command; its distance from the full solve there is recorded."""
    from taichi_pneuma.realtime.equilibrium import LIVE_TOL, LiveEquilibrium
    from taichi_pneuma.solve.newton import NewtonOptions, NewtonSolver

    built, boundary, walls = live_scene(peak=peak, order=order)
    mesh = built.mesh
    camera = Camera().fitted(mesh.vertices, 960, 640, margin=0.2)
    cut = open_section(mesh.vertices, boundary, walls, camera)
    command = np.full(len(built.chambers), peak)
    built.set_commands(command)
    reference, _ = NewtonSolver(built.model, NewtonOptions()).solve(np.zeros_like(mesh.vertices))
    records = []
    for backend, mode in itertools.product(("numpy", "ggui"), ("full Newton", "one step")):
        try:
            view = open_view(backend, 960, 640, log=lambda _: None)
        except PneumaInputError as exc:
            print(f"{backend}: {exc}")
            continue
        state = LiveEquilibrium(built, NewtonOptions(tol=LIVE_TOL))
        solver = state.solver

        def step(commands, mode=mode, state=state, solver=solver):  # this iteration's
            if mode == "one step":
                state.frame(commands)
                return state.iterations
            built.set_commands(commands)
            state.u, record = solver.solve(state.u)
            return record.iterations

        solve_s, draw_s, cpu_s, iterations = [], [], [], []
        try:
            for k in range(
                -1, frames + 1 + idle
            ):  # frame -1 (a tiny pressure: the kernels' first calls) is the warm-up
                if k > frames and (mode == "full Newton" or state.converged):
                    break
                start, cpu = time.perf_counter(), time.process_time()
                taken = step(np.full(len(built.chambers), peak * min(max(k, 0.01), frames) / frames))
                middle = time.perf_counter()
                view.render(
                    *shaded_triangles(cut.points(mesh.vertices + state.u), cut.surface, cut.walls, camera),
                    camera,
                    BACKGROUND,
                )
                if 1 <= k <= frames:
                    solve_s.append(middle - start)
                    draw_s.append(time.perf_counter() - middle)
                    cpu_s.append(time.process_time() - cpu)
                    iterations.append(taken if mode == "full Newton" else 1)
        finally:
            view.close()
        solve_ms, draw_ms = 1e3 * np.mean(solve_s), 1e3 * np.mean(draw_s)
        records.append(
            {
                "tets": len(mesh.elements),
                "nodes": len(mesh.vertices),
                "view": view.name,
                "mode": mode,
                "solve_ms": solve_ms,
                "draw_ms": draw_ms,
                "newton_iterations": float(np.mean(iterations)),
                "frames_per_second": 1e3 / (solve_ms + draw_ms),
                "linear_solver": solver.backend.name,
                "cpu_ms": 1e3 * np.mean(cpu_s),
                "frames_per_cpu_second": 1 / np.mean(cpu_s),
                "solve_frames_per_second": 1e3 / solve_ms,
                "tol": solver.options.tol,
                "idle_frames": k - frames if mode == "one step" else 0,
                "converged": bool(state.converged) if mode == "one step" else True,
                "distance_from_equilibrium": float(np.abs(state.u - reference).max() / np.abs(reference).max()),
            }
        )
        print(records[-1], flush=True)
    return records


def live_window(frames: int, peak: float = 900.0) -> dict:
    """The interactive window (explore_3d, needs a display) on the coarse PneuNet with the live solve
    (LiveEquilibrium): the six chambers' pressure moved 0 -> peak over `frames` frames (scripted, not the
    slider), then held for as many frames; its frames per second."""
    from taichi_pneuma.realtime.equilibrium import LiveEquilibrium

    built, boundary, walls = live_scene(peak=peak)
    state, ramp = LiveEquilibrium(built), iter(np.linspace(0.0, peak, frames + 1))

    def solve(_):
        state.frame(np.full(len(built.chambers), next(ramp, peak)))
        return built.mesh.vertices + state.u, [f"residual {state.residual:.1e}"]

    summary = explore_3d(
        solve,
        [Slider("pressure", 0.0, peak, 0.0)],
        built.mesh.vertices,
        boundary,
        tuple(c[:, :3] for c in built.mesh.chambers),
        size=(960, 640),
        max_frames=2 * frames,
    )
    return {
        "tets": len(built.mesh.elements),
        "frames": summary["frames"],
        "frames_per_second": summary["fps"],
        "residual": state.residual,
        "converged": state.converged,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--frames", type=int, default=8)
    parser.add_argument("--live-frames", type=int, default=30)
    parser.add_argument("--only-live", action="store_true", help="the live loop alone (to render3d_live.md, .json)")
    parser.add_argument(
        "--order",
        type=int,
        choices=(1, 2),
        default=1,
        help="the live loop's element order (2: quadratic tetrahedra; its tables get the suffix _p2)",
    )
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results"))
    args = parser.parse_args()
    runtime.init("cpu")
    load = os.getloadavg()[0]
    solid, data = PneuNet().solid(), {"meshing": [], "rendering": [], "live": live(args.live_frames, order=args.order)}
    for label, sizes in {} if args.only_live else MESH_SIZES.items():
        start = time.perf_counter()
        mesh = mesh_solid(solid, sizes)
        seconds = time.perf_counter() - start
        faces = len(mesh.boundary) + sum(len(w) for w in mesh.chambers.values())
        data["meshing"].append(
            {
                "mesh": label,
                "size": sizes.size,
                "seconds": seconds,
                "tets": len(mesh.tets),
                "nodes": len(mesh.vertices),
                "surface_triangles": faces,
                "estimate": estimate_tets(solid, sizes),
            }
        )
        print(data["meshing"][-1], flush=True)
    for label, sizes in {} if args.only_live else RENDER_SIZES.items():
        mesh = mesh_solid(solid, sizes)
        positions = bent(mesh.vertices, args.frames)
        track = Track3D(
            positions,
            mesh.boundary,
            tuple(mesh.chambers.values()),
            color=np.linalg.norm(positions - mesh.vertices, axis=2),
            color_label="|u|",
            captions=tuple((f"step {i}",) for i in range(args.frames)),
            trace=(("curvature", np.linspace(0, 0.45, args.frames)),),
        )
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
            data["rendering"].append(
                {
                    "mesh": label,
                    "surface_triangles": faces,
                    "drawn_triangles": len(renderer.kept) + len(renderer.walls),
                    "view": renderer.canvas.name,
                    "ms_per_frame": ms,
                    "cpu_ms_per_frame": cpu_ms,
                }
            )
            print(data["rendering"][-1], flush=True)
    if os.environ.get("DISPLAY") and not args.only_live:
        mesh = mesh_solid(solid, MESH_SIZES["coarse (interactive)"])
        states = bent(mesh.vertices, 11)
        summary = explore_3d(
            lambda q: (states[int(round(10 * q[0]))], [f"c1 = {q[0]:.2f}"]),
            [Slider(name, 0.0, 1.0, 0.0) for name in mesh.chambers],
            mesh.vertices,
            mesh.boundary,
            tuple(mesh.chambers.values()),
            size=(960, 640),
            spin=2.0,
            max_frames=60,
        )
        data["interactive"] = {"tets": len(mesh.tets), "frames_per_second": summary["fps"]}
        print(data["interactive"], flush=True)
    if os.environ.get("DISPLAY"):
        data["interactive_live"] = live_window(args.live_frames)
        print(data["interactive_live"], flush=True)
    args.out.mkdir(parents=True, exist_ok=True)
    stem = ("render3d_live" if args.only_live else "render3d") + ("_p2" if args.order == 2 else "")  # the live loop
    # alone (or quadratic) leaves the full tables as they are
    (args.out / f"{stem}.json").write_text(
        json.dumps({"machine": machine(), "load_average": load, "data": data}, indent=2)
    )
    lines = [f"Machine: {machine()}; load average (1 min) at the start: {load:.1f}"]
    if data["meshing"]:
        lines += [
            "",
            "| PneuNet mesh | size | tetrahedra | nodes | surface triangles | estimate | meshing (s) |",
            "|---|---|---|---|---|---|---|",
        ]
        lines += [
            f"| {r['mesh']} | {r['size']:g} | {r['tets']} | {r['nodes']} | {r['surface_triangles']} | "
            f"{r['estimate']:.0f} | {r['seconds']:.2f} |"
            for r in data["meshing"]
        ]
    if data["rendering"]:
        lines += [
            "",
            "| surface | triangles (drawn after the section) | view | ms / frame (960 x 540) | CPU ms / frame |",
            "|---|---|---|---|---|",
        ]
        lines += [
            f"| {r['mesh']} | {r['surface_triangles']} ({r['drawn_triangles']}) | {r['view']} | "
            f"{r['ms_per_frame']:.0f} | {r['cpu_ms_per_frame']:.0f} |"
            for r in data["rendering"]
        ]
    lines += [
        "",
        f"Live loop without a window (coarse PneuNet, its six chambers' pressure slider moved 0 -> 900 Pa in "
        f"{args.live_frames} frames, then held; 960 x 640; drawing includes the image's read-back):",
        "",
        "| tetrahedra | nodes | view | solve per frame | linear solver | Newton it / moving frame | solve ms | "
        "draw ms | frames/s | solve-only frames/s | CPU ms / frame | frames / CPU s | idle frames to converge | "
        "max abs(u - u*) / max abs(u*) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    lines += [
        f"| {r['tets']} | {r['nodes']} | {r['view']} | {r['mode']} | {r['linear_solver']} | "
        f"{r['newton_iterations']:.1f} | {r['solve_ms']:.0f} | {r['draw_ms']:.0f} | {r['frames_per_second']:.1f} | "
        f"{r['solve_frames_per_second']:.0f} | {r['cpu_ms']:.0f} | {r['frames_per_cpu_second']:.1f} | "
        f"{r['idle_frames']} | {r['distance_from_equilibrium']:.1e} |"
        for r in data["live"]
    ]
    if "interactive" in data:
        lines += [
            "",
            f"Interactive window (960 x 640, coarse PneuNet of {data['interactive']['tets']} tetrahedra, "
            f"no solve): {data['interactive']['frames_per_second']:.0f} frames/s",
        ]
    if "interactive_live" in data:
        r = data["interactive_live"]
        lines += [
            "",
            f"Interactive window with the live solve (960 x 640, coarse PneuNet of {r['tets']} tetrahedra, one "
            f"Newton step per frame, the slider moved over {args.live_frames} frames then held, "
            f"{r['frames']} frames): {r['frames_per_second']:.1f} frames/s; final residual "
            f"{r['residual']:.1e} (converged: {r['converged']})",
        ]
    (args.out / f"{stem}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
