"""Run a scene's schedule (a scene file, or the reference beam by its flags) and show how it bends.

    python -m taichi_pneuma.apps.inflate --cy 0.15
    python -m taichi_pneuma.apps.inflate --scene assets/scenes/bidirectional.toml

Prints the mesh size, the terms built, each chamber's rest area, final area ratio and pressure,
the tip deflection and rotation and the peak chamber pressure; writes the per-step history (CSV),
the states (npz) and a summary (JSON) under --out, and, unless --no-video, a video of the run
(beam beside its area/pressure trace) and a PNG of its last frame. --interactive instead opens a
window with a slider for the commanded area.

Before any work, a run past the resource limits (estimated triangles, increments, frame pixels; see
limits.py) is refused in one line naming the flag that raises the limit. Ctrl-C during the ramp
stops it after the current increment, saves the steps done (summary marked interrupted) and exits 130.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
import time
from contextlib import contextmanager

import numpy as np
from tqdm import tqdm

from .. import limits, runtime
from ..errors import PneumaInputError, require, require_finite
from ..geometry import BeamGeometry
from ..newton import NewtonOptions
from ..output import prepare_directory, save_json, save_npz, save_text
from ..render import BACKENDS
from ..scene import Scene, reference_scene
from ..scenefile import load_scene
from ..schedule import area_ramp
from ..simulate import MAX_CUTS, RampFailed, RampInterrupted, RampStopped, run_schedule

# --quality presets: (max triangle area, element order, Newton tolerance); see the README's accuracy study
QUALITY = {"draft": (0.005, 1, 1e-4), "default": (BeamGeometry.max_area, 1, NewtonOptions.tol),
           "high": (0.005, 2, 1e-6), "accurate": (0.0012, 2, 1e-9)}


def add_ramp_arguments(p: argparse.ArgumentParser) -> None:
    """The reference-beam, ramp, solver and output flags shared by the apps (all but the chamber height)."""
    p.add_argument("--cx", type=float, default=0.0, help="chamber centre along the beam")
    p.add_argument("--growth", type=float, default=3.5, help="final commanded area / rest area")
    p.add_argument("--steps", type=int, default=36, help="commanded areas in the ramp, rest included")
    p.add_argument("--E", type=float, default=1e4, help="Young's modulus")
    p.add_argument("--nu", type=float, default=0.45, help="Poisson's ratio, in (-1, 0.5)")
    p.add_argument("--k", type=float, default=1e5, help="chamber stiffness (area control penalty)")
    p.add_argument("--quality", default="default", choices=list(QUALITY),
                   help="mesh density, element order and Newton tolerance, read off the accuracy-vs-time study: "
                        + "; ".join(f"{k}: max area {a:g}, order {o}, tol {t:g}" for k, (a, o, t) in QUALITY.items()))
    p.add_argument("--max-area", type=float, default=None, help="Triangle's maximum triangle area (overrides --quality)")
    p.add_argument("--order", type=int, default=None, choices=(1, 2),
                   help="1: linear triangles, 2: quadratic triangles (overrides --quality)")
    p.add_argument("--tol", type=float, default=None,
                   help="Newton tolerance on |gradient| / force scale (overrides --quality)")
    p.add_argument("--max-iterations", type=int, default=40, help="Newton iterations per solve before it counts as failed")
    p.add_argument("--max-cuts", type=int, default=MAX_CUTS,
                   help="times a non-converging increment may be halved before the run stops")
    p.add_argument("--max-triangles", type=int, default=limits.MAX_TRIANGLES,
                   help="refuse a scene whose mesh is estimated (before meshing) to have more triangles")
    p.add_argument("--max-increments", type=int, default=limits.MAX_INCREMENTS,
                   help="refuse a schedule of more increments")
    p.add_argument("--out", default="out", help="directory for the result files")
    p.add_argument("--arch", default="cpu", choices=sorted(runtime.ARCHES), help="Taichi backend")
    p.add_argument("--quiet", action="store_true", help="no per-step lines, no progress bars")


def add_video_arguments(p: argparse.ArgumentParser, size: str) -> None:
    """The rendering flags shared by the apps."""
    p.add_argument("--video", default=None,
                   help="video file (.mp4 H.264 or .gif); default <out>/<name>.mp4")
    p.add_argument("--fps", type=float, default=12.0, help="video frames per second (one frame per step)")
    p.add_argument("--size", default=size, help="frame size WIDTHxHEIGHT in pixels")
    p.add_argument("--renderer", default="auto", choices=BACKENDS,
                   help="auto: GGUI (Vulkan) if available, else ti.GUI")
    p.add_argument("--no-video", action="store_true", help="no rendering at all: no video, no PNG")
    p.add_argument("--max-frame-pixels", type=int, default=limits.MAX_FRAME_PIXELS,
                   help="refuse a --size of more pixels per frame")


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m taichi_pneuma.apps.inflate", description=__doc__.split("\n")[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--scene", help="a scene file (TOML); the reference-beam flags (--cy --cx --growth --steps --E --nu "
                                   "--k --max-area --order) are then ignored")
    p.add_argument("--cy", type=float, default=0.15, help="chamber centre height (above the neutral axis curls down)")
    add_ramp_arguments(p)
    add_video_arguments(p, "960x384")
    p.add_argument("--interactive", action="store_true",
                   help="open a window (needs a display) with a slider for the commanded area; re-solves live")
    return p


def rendering_flags(args: argparse.Namespace) -> tuple[int, int]:
    """Check the rendering flags before any work; return --size 'WIDTHxHEIGHT' as (width, height)."""
    from ..video import check_video

    check_video(args.video or "default.mp4", args.fps)
    text = args.size
    try:
        width, height = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise PneumaInputError(f"--size = {text!r} must look like 960x384") from None
    require(width >= 64 and height >= 64 and width % 2 == 0 and height % 2 == 0,
            f"--size = {text!r}: width and height must be even and >= 64")
    limits.check_frame(width, height, args.max_frame_pixels)
    return width, height


def newton_options(args: argparse.Namespace) -> NewtonOptions:
    return NewtonOptions(tol=args.tol, max_iterations=args.max_iterations)


def check_flags(args: argparse.Namespace) -> None:
    """Validate the solver flags; --max-area and --tol not given take their values from --quality."""
    max_area, order, tol = QUALITY[args.quality]
    args.max_area = max_area if args.max_area is None else args.max_area
    args.order = order if args.order is None else args.order
    args.tol = tol if args.tol is None else args.tol
    for name in ("cx", "growth", "E", "nu", "k", "max_area", "tol"):
        require_finite(f"--{name.replace('_', '-')}", getattr(args, name))
    newton_options(args)  # validates --tol and --max-iterations
    require(args.max_cuts >= 0, f"--max-cuts = {args.max_cuts!r} must be >= 0")
    for name in ("max_triangles", "max_increments", "max_frame_pixels"):
        require(getattr(args, name) >= 1, f"--{name.replace('_', '-')} = {getattr(args, name)!r} must be >= 1")
    area_ramp(args.growth, args.steps)  # validates growth and steps before any work


def scene_for(args: argparse.Namespace, cy: float) -> Scene:
    """The validated reference scene of the flags with its chamber at height cy (PneumaInputError on bad flags)."""
    check_flags(args)
    scene = reference_scene(require_finite("--cy", cy), args.cx, args.growth, args.steps, args.E, args.nu, args.k,
                            args.max_area, order=args.order)
    limits.check_scene(scene, args.max_triangles, args.max_increments)
    return scene


def build(scene: Scene):
    """Mesh the scene, build its terms and print the mesh size, the terms and each chamber's rest area."""
    built = scene.build()
    mesh = built.mesh
    kind = "triangles" if mesh.order == 1 else "quadratic triangles"
    print(f"scene {scene.name}: mesh {mesh.n_vertices} {'vertices' if mesh.order == 1 else 'nodes'}, "
          f"{mesh.n_triangles} {kind}; clamp {len(mesh.pinned)} vertices; terms: {', '.join(built.model.term_names())}")
    for chamber in built.chambers:
        print(f"chamber {chamber.chamber_name}: {chamber.control} control, wall {chamber.n_wall} vertices, "
              f"rest area {chamber.rest_area:.3f}")
    return built


@contextmanager
def stop_on_interrupt():
    """Yield a threading.Event that the first Ctrl-C (SIGINT) sets instead of raising KeyboardInterrupt;
    a second Ctrl-C interrupts at once. Outside the main thread (no signal handling) the event never sets."""
    requested = threading.Event()
    if threading.current_thread() is not threading.main_thread():
        yield requested
        return
    previous = signal.getsignal(signal.SIGINT)

    def handler(signum, frame):
        requested.set()
        signal.signal(signal.SIGINT, previous)
        print("interrupt: stopping after the current increment (Ctrl-C again to stop at once)", file=sys.stderr)

    signal.signal(signal.SIGINT, handler)
    try:
        yield requested
    finally:
        signal.signal(signal.SIGINT, previous)


def solve(args: argparse.Namespace, built, label: str = "solving"):
    """Run the scene's schedule with a progress bar; return (result, wall seconds).

    Raises RampFailed when an increment fails after its cuts, RampInterrupted after the increment
    during which Ctrl-C was pressed; both carry the steps done."""
    increments = built.scene.increments
    bar = tqdm(total=increments + 1, desc=label, unit="step", disable=args.quiet, leave=False)

    def progress(step):
        bar.update()
        if not args.quiet:
            chambers = "  ".join(f"{name}: x{c.area_ratio:5.3f} p = {c.pressure:8.2f}" for name, c in step.chambers.items())
            bar.write(f"  step {step.step:3d}/{increments}  {chambers}  tip dy = {step.tip_dy:+.4f} "
                      f"rot = {step.tip_rotation:+6.1f} deg  {step.iterations:2d} Newton it  {step.cuts} cuts  "
                      f"residual {step.residual:.1e}")

    start = time.perf_counter()
    with bar, stop_on_interrupt() as interrupted:
        result = run_schedule(built, options=newton_options(args), progress=progress, max_cuts=args.max_cuts,
                              stop=interrupted.is_set)
    return result, time.perf_counter() - start


def render_report(export, seconds_per_step: float) -> str:
    return (f"video: {export.frames} frames {export.width}x{export.height}; rendering {export.ms_per_frame:.1f} "
            f"ms/frame vs solving {1000 * seconds_per_step:.0f} ms/step")


def run(args: argparse.Namespace) -> dict:
    if args.scene:
        check_flags(args)
        scene = load_scene(args.scene)
        limits.check_scene(scene, args.max_triangles, args.max_increments)
        stem = scene.name  # a plain file name (Scene checks it): every result file lands inside --out
    else:
        scene = scene_for(args, args.cy)
        stem = f"inflate_cy{args.cy:+.2f}"
    size = rendering_flags(args)
    require(not (args.interactive and args.no_video), "--interactive and --no-video exclude each other")
    if args.interactive:
        require(bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")),
                "--interactive needs a display (DISPLAY is not set); run without it for headless video output")
        require(scene.controls[0].schedule.control == "area", "--interactive needs an area-controlled first chamber")
    out = prepare_directory(args.out)
    runtime.init(args.arch)
    if args.interactive:
        from ..interactive import explore
        return explore(scene, args.growth, size, args.renderer, newton_options(args))
    built = build(scene)
    mesh = built.mesh
    try:
        result, wall = solve(args, built)
    except RampStopped as stopped:
        written = save_history(out, stem, built, stopped.partial)
        if isinstance(stopped, RampInterrupted):
            summary = summarise(built, stopped.partial, float(stopped.partial.column("seconds").sum()), interrupted=True)
            written.append(save_json(out / f"{stem}_summary.json", summary))
        print(f"saved the {len(stopped.partial.steps)} steps done in " + ", ".join(str(p) for p in written))
        raise
    summary = summarise(built, result, wall)
    final = result.steps[-1]
    for name, c in final.chambers.items():
        print(f"{name}: area {c.area / c.area_ratio:.3f} -> {c.area:.3f} (x{c.area_ratio:.2f}), pressure {c.pressure:.1f}")
    print(f"tip deflection (mean y displacement of the right edge): {result.tip_deflection:+.4f}; "
          f"tip rotation {final.tip_rotation:+.1f} deg")
    print(f"peak chamber pressure |p|: {result.peak_pressure:.1f}")
    for name, (fx, fy, magnitude) in final.contact.items():
        print(f"{name} contact force on the body: ({fx:+.4g}, {fy:+.4g})")
    print(f"Newton: {summary['newton_iterations_total']} iterations over {summary['steps'] - 1} solves "
          f"(max {summary['newton_iterations_max']}, {summary['increment_cuts']} increment cuts), "
          f"all converged: {summary['all_converged']}; run {wall:.2f} s")
    summary_path = out / f"{stem}_summary.json"  # results saved before rendering: a Ctrl-C there loses none
    written = save_history(out, stem, built, result) + [save_json(summary_path, summary)]
    if not args.no_video:
        from ..render import FrameRenderer, Track
        from ..video import export

        ground = next((e.height for e in scene.effects if e.name == "ground"), None)
        renderer = FrameRenderer([Track.from_ramp(mesh, result, ground=ground)], *size, trace=True,
                                 backend=args.renderer)
        done = export(renderer, args.video or out / f"{stem}.mp4", out / f"{stem}.png", args.fps, args.quiet)
        summary.update(renderer=renderer.canvas.name, video_frames=done.frames, video_size=[done.width, done.height],
                       render_ms_per_frame=done.ms_per_frame)
        print(render_report(done, summary["solve_seconds_per_step"]))
        written = [done.video, done.png] + written
        save_json(summary_path, summary)
    print("wrote " + ", ".join(str(p) for p in written))
    return summary


def summarise(built, result, wall: float, interrupted: bool = False) -> dict:
    """The figures of a run (complete, or interrupted after result.steps) for the summary JSON."""
    mesh, final = built.mesh, result.steps[-1]
    iterations, seconds = result.column("iterations")[1:], result.column("seconds")[1:]
    return {
        "scene": built.scene.name, "terms": built.model.term_names(),
        "vertices": mesh.n_vertices, "triangles": mesh.n_triangles, "element_order": mesh.order,
        "chambers": {name: {"control": c.control, "rest_area": c.area / c.area_ratio, "final_area": c.area,
                            "area_ratio": c.area_ratio, "final_pressure": c.pressure,
                            "peak_pressure": float(np.abs(result.column(f"{name}.pressure")).max())}
                     for name, c in final.chambers.items()},
        "tip_deflection": result.tip_deflection, "tip_rotation_deg": final.tip_rotation,
        "peak_pressure": result.peak_pressure, "contact": final.contact,
        "all_converged": bool(all(s.converged for s in result.steps)),
        "max_residual": float(result.column("residual").max()),
        "min_det_F": float(result.column("min_det").min()),
        "newton_iterations_total": int(iterations.sum()), "newton_iterations_max": int(iterations.max(initial=0)),
        "increment_cuts": int(result.column("cuts").sum()),
        "wall_seconds": wall, "solve_seconds_per_step": float(seconds.mean()) if len(seconds) else 0.0,
        "steps": len(result.steps), "interrupted": interrupted,
    }


def save_history(out, stem: str, built, result) -> list:
    """Write the per-step history (CSV) and the states (npz) of a run, complete or partial.

    The npz holds positions (steps, n, 2), rest, triangles, pinned, tip, boundary, chamber_names and
    one chamber_loop_<i> per chamber, command / area / pressure as (steps, chambers), and, where
    the scene has them, contact_forces (steps, n, 2) and ground_height.
    """
    mesh = built.mesh
    names = [c.chamber_name for c in built.chambers]
    arrays = dict(positions=result.states, rest=mesh.vertices, triangles=mesh.triangles, pinned=mesh.pinned,
                  tip=mesh.tip, boundary=mesh.boundary, chamber_names=np.array(names),
                  **{f"chamber_loop_{i}": loop for i, loop in enumerate(mesh.chambers)},
                  **{key: np.column_stack([result.column(f"{n}.{key}") for n in names])
                     for key in ("command", "area", "pressure")})
    if result.contact_forces is not None:
        arrays["contact_forces"] = result.contact_forces
    for effect in built.scene.effects:
        if effect.name == "ground":
            arrays["ground_height"] = np.array(effect.height)
    return [
        save_text(out / f"{stem}_history.csv", result.history_csv()),
        save_npz(out / f"{stem}_states.npz", **arrays),
    ]


def exit_code(app_run, args: argparse.Namespace) -> int:
    """Run an app; bad input is one line and exit 2, a ramp with no equilibrium one line and exit 1,
    Ctrl-C one line and exit 130 (128 + SIGINT, as shells report it).

    NumPy's floating-point warnings (overflow, invalid value) are silenced: a huge input value overflows
    harmlessly in a check that then refuses it, and a solve that produces NaN or inf fails its own checks."""
    try:
        with np.errstate(all="ignore"):
            summary = app_run(args)
    except PneumaInputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except RampFailed as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except RampInterrupted as exc:
        print(f"error: {exc} (Ctrl-C)", file=sys.stderr)
        return 130
    except KeyboardInterrupt:
        print("error: interrupted (Ctrl-C)", file=sys.stderr)
        return 130
    return 0 if summary["all_converged"] else 1


def main(argv: list[str] | None = None) -> int:
    return exit_code(run, parser().parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
