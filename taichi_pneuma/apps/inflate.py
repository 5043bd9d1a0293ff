"""Inflate the chamber of the reference beam and report how it bends.

    python -m taichi_pneuma.apps.inflate --cy 0.15

Prints the mesh size, the chamber's rest area, the final area ratio, the tip deflection and the
peak chamber pressure; writes the per-step history (CSV), the states (npz) and a summary (JSON)
under --out, and, unless --no-video, a video of the ramp (beam beside its area/pressure trace) and
a PNG of its last frame. --interactive instead opens a window with a slider for the commanded area.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

from tqdm import tqdm

from .. import runtime
from ..errors import PneumaInputError, require, require_finite
from ..geometry import BeamGeometry
from ..newton import NewtonOptions
from ..output import prepare_directory, save_json, save_npz, save_text
from ..render import BACKENDS
from ..scene import BeamScene, Material
from ..simulate import MAX_CUTS, RampFailed, area_ramp, run_ramp


# --quality presets: (max triangle area, Newton tolerance); see the README's accuracy-versus-time study
QUALITY = {"draft": (0.005, 1e-4), "default": (BeamGeometry.max_area, NewtonOptions.tol), "high": (0.0003, 1e-9)}


def add_ramp_arguments(p: argparse.ArgumentParser) -> None:
    """The scene, ramp, solver and output flags shared by the apps (all but the chamber height)."""
    p.add_argument("--cx", type=float, default=0.0, help="chamber centre along the beam")
    p.add_argument("--growth", type=float, default=3.5, help="final commanded area / rest area")
    p.add_argument("--steps", type=int, default=36, help="commanded areas in the ramp, rest included")
    p.add_argument("--E", type=float, default=1e4, help="Young's modulus")
    p.add_argument("--nu", type=float, default=0.45, help="Poisson's ratio, in (-1, 0.5)")
    p.add_argument("--k", type=float, default=1e5, help="chamber stiffness (area control penalty)")
    p.add_argument("--quality", default="default", choices=list(QUALITY),
                   help="mesh density and Newton tolerance, read off the accuracy-vs-time study: "
                        + "; ".join(f"{k}: max area {a:g}, tol {t:g}" for k, (a, t) in QUALITY.items()))
    p.add_argument("--max-area", type=float, default=None, help="Triangle's maximum triangle area (overrides --quality)")
    p.add_argument("--tol", type=float, default=None,
                   help="Newton tolerance on |gradient| / force scale (overrides --quality)")
    p.add_argument("--max-iterations", type=int, default=40, help="Newton iterations per solve before it counts as failed")
    p.add_argument("--max-cuts", type=int, default=MAX_CUTS,
                   help="times a non-converging increment may be halved before the run stops")
    p.add_argument("--out", default="out", help="directory for the result files")
    p.add_argument("--arch", default="cpu", choices=sorted(runtime.ARCHES), help="Taichi backend")
    p.add_argument("--quiet", action="store_true", help="no per-step lines, no progress bars")


def add_video_arguments(p: argparse.ArgumentParser, size: str) -> None:
    """The rendering flags shared by the apps."""
    p.add_argument("--video", default=None,
                   help="video file (.mp4 H.264 or .gif); default <out>/<name>.mp4")
    p.add_argument("--fps", type=float, default=12.0, help="video frames per second (one frame per ramp step)")
    p.add_argument("--size", default=size, help="frame size WIDTHxHEIGHT in pixels")
    p.add_argument("--renderer", default="auto", choices=BACKENDS,
                   help="auto: GGUI (Vulkan) if available, else ti.GUI")
    p.add_argument("--no-video", action="store_true", help="no rendering at all: no video, no PNG")


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m taichi_pneuma.apps.inflate", description=__doc__.split("\n")[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
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
    return width, height


def newton_options(args: argparse.Namespace) -> NewtonOptions:
    return NewtonOptions(tol=args.tol, max_iterations=args.max_iterations)


def scene_for(args: argparse.Namespace, cy: float) -> BeamScene:
    """The validated scene of the flags with its chamber at height cy (raises PneumaInputError on bad flags).

    --max-area and --tol not given take their values from the --quality preset."""
    max_area, tol = QUALITY[args.quality]
    args.max_area = max_area if args.max_area is None else args.max_area
    args.tol = tol if args.tol is None else args.tol
    for name in ("cx", "growth", "E", "nu", "k", "max_area", "tol"):
        require_finite(f"--{name.replace('_', '-')}", getattr(args, name))
    newton_options(args)  # validates --tol and --max-iterations
    require(args.max_cuts >= 0, f"--max-cuts = {args.max_cuts!r} must be >= 0")
    area_ramp(1.0, args.growth, args.steps)  # validates growth and steps before any work
    return BeamScene(BeamGeometry(cx=args.cx, cy=require_finite("--cy", cy), max_area=args.max_area),
                     Material(args.E, args.nu), chamber_stiffness=args.k)


def build(scene: BeamScene):
    """Mesh the scene, build its terms and print the mesh size and the chamber's rest area."""
    built = scene.build()
    mesh = built.mesh
    print(f"mesh: {mesh.n_vertices} vertices, {mesh.n_triangles} triangles; chamber wall {len(mesh.chamber_loop)} "
          f"vertices, clamp {len(mesh.pinned)} vertices")
    print(f"chamber rest area: {built.rest_area:.3f}")
    return built


def solve(args: argparse.Namespace, built, label: str = "solving"):
    """Run the flags' ramp on a built scene with a progress bar; return (result, wall seconds).

    Raises RampFailed (carrying the converged steps) when an increment fails after its cuts."""
    bar = tqdm(total=args.steps, desc=label, unit="step", disable=args.quiet, leave=False)

    def progress(step):
        bar.update()
        if not args.quiet:
            bar.write(f"  step {step.step:3d}/{args.steps - 1}  area x{step.area_ratio:5.3f}  "
                      f"p = {step.pressure:8.2f}  tip dy = {step.tip_dy:+.4f}  {step.iterations:2d} Newton it  "
                      f"{step.cuts} cuts  residual {step.residual:.1e}")

    start = time.perf_counter()
    with bar:
        result = run_ramp(built, area_ramp(built.rest_area, args.growth, args.steps), newton_options(args), progress,
                          args.max_cuts)
    return result, time.perf_counter() - start


def render_report(export, seconds_per_step: float) -> str:
    return (f"video: {export.frames} frames {export.width}x{export.height}; rendering {export.ms_per_frame:.1f} "
            f"ms/frame vs solving {1000 * seconds_per_step:.0f} ms/step")


def run(args: argparse.Namespace) -> dict:
    scene = scene_for(args, args.cy)
    size = rendering_flags(args)
    require(not (args.interactive and args.no_video), "--interactive and --no-video exclude each other")
    if args.interactive:
        require(bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")),
                "--interactive needs a display (DISPLAY is not set); run without it for headless video output")
    out = prepare_directory(args.out)
    runtime.init(args.arch)
    if args.interactive:
        from ..interactive import explore
        return explore(scene, args.growth, size, args.renderer, newton_options(args))
    built = build(scene)
    mesh = built.mesh
    stem = f"inflate_cy{args.cy:+.2f}"
    try:
        result, wall = solve(args, built)
    except RampFailed as failure:
        written = save_history(out, stem, built, failure.partial)
        print(f"saved the {len(failure.partial.steps)} converged steps in " + ", ".join(str(p) for p in written))
        raise
    final = result.steps[-1]
    iterations = result.column("iterations")[1:]
    seconds_per_step = float(result.column("seconds")[1:].mean())
    summary = {
        "cx": args.cx, "cy": args.cy, "vertices": mesh.n_vertices, "triangles": mesh.n_triangles,
        "rest_area": built.rest_area, "final_area": final.area, "area_ratio": final.area_ratio,
        "tip_deflection": result.tip_deflection, "peak_pressure": result.peak_pressure,
        "all_converged": bool(all(s.converged for s in result.steps)),
        "max_residual": float(result.column("residual").max()),
        "min_det_F": float(result.column("min_det").min()),
        "newton_iterations_total": int(iterations.sum()), "newton_iterations_max": int(iterations.max()),
        "increment_cuts": int(result.column("cuts").sum()),
        "wall_seconds": wall, "solve_seconds_per_step": seconds_per_step,
    }
    print(f"area: {built.rest_area:.3f} -> {final.area:.3f} (x{final.area_ratio:.2f})")
    print(f"tip deflection (mean y displacement of the right edge): {result.tip_deflection:+.4f}")
    print(f"peak chamber pressure |p|: {result.peak_pressure:.1f}")
    print(f"Newton: {summary['newton_iterations_total']} iterations over {len(iterations)} solves "
          f"(max {summary['newton_iterations_max']}, {summary['increment_cuts']} increment cuts), "
          f"all converged: {summary['all_converged']}; ramp {wall:.2f} s")
    written = []
    if not args.no_video:
        from ..render import FrameRenderer, Track
        from ..video import export

        renderer = FrameRenderer([Track.from_ramp(mesh, result, built.rest_area)], *size, trace=True,
                                 backend=args.renderer)
        done = export(renderer, args.video or out / f"{stem}.mp4", out / f"{stem}.png", args.fps, args.quiet)
        summary.update(renderer=renderer.canvas.name, video_frames=done.frames, video_size=[done.width, done.height],
                       render_ms_per_frame=done.ms_per_frame)
        print(render_report(done, seconds_per_step))
        written += [done.video, done.png]
    written += save_history(out, stem, built, result) + [save_json(out / f"{stem}_summary.json", summary)]
    print("wrote " + ", ".join(str(p) for p in written))
    return summary


def save_history(out, stem: str, built, result) -> list:
    """Write the per-step history (CSV) and the states (npz) of a ramp, complete or partial."""
    mesh = built.mesh
    return [
        save_text(out / f"{stem}_history.csv", result.history_csv()),
        save_npz(out / f"{stem}_states.npz", positions=result.states, rest=mesh.vertices, triangles=mesh.triangles,
                 chamber_loop=mesh.chamber_loop, pinned=mesh.pinned, tip=mesh.tip,
                 target_area=result.column("target_area"), area=result.column("area"),
                 pressure=result.column("pressure")),
    ]


def exit_code(app_run, args: argparse.Namespace) -> int:
    """Run an app; bad input is one line and exit 2, a ramp with no equilibrium one line and exit 1."""
    try:
        summary = app_run(args)
    except PneumaInputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except RampFailed as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    return 0 if summary["all_converged"] else 1


def main(argv: list[str] | None = None) -> int:
    return exit_code(run, parser().parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
