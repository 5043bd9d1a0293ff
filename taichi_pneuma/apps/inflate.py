"""Run a scene's schedule (a scene file, a shipped scene by name, or the reference beam by its flags) and
show how it bends.

    pneuma-inflate --cy 0.15                     (or python -m taichi_pneuma.apps.inflate --cy 0.15)
    pneuma-inflate --scene bidirectional

Prints the mesh size, the terms built, each chamber's rest area, final area ratio and pressure,
the tip deflection and rotation and the peak chamber pressure; writes the per-step history (CSV),
the states (npz), a summary (JSON), the scene as run (TOML) and the ParaView files (a VTU per step as
it is solved, indexed by a PVD) under --out, and, unless --no-video, a plot of the history (PNG), a
video of the run (body coloured by --color beside its area/pressure trace) and a PNG of its most
deformed frame. The files are named by the scene (inflate_cy+0.15 for the reference beam's flags) and what
the run changed of it (stems.result_stem: '_order2_E2e4', or the scene's hash when that is long; '_high' for
a --quality), so a different run never overwrites them and a re-run of the same one replaces only its own.
--set KEY=VALUE changes any dotted scene-file key. --interactive instead opens a window with a slider
for the commanded area (a 3D scene: a slider per chamber, and the camera turned by dragging the mouse).
A 3D scene's video shows the body in 3D, opened by a section to show its chambers (docs/3d.md).

Before any work, a run past the resource limits (estimated triangles, increments, frame pixels; see
limits.py) is refused in one line naming the flag that raises the limit. A ramp that finds no equilibrium
past some step writes every file, pictures included, up to its last equilibrium (the summary's "stopped" says
where); a scene whose ramp is meant to end at a limit point (schedule.ends_at_limit_point: balloon_pressure's
pressure peak) then exits 0 with a line saying so, any other prints its error line and exits 1. Ctrl-C (or
SIGTERM, SIGHUP) during the ramp stops it within a Newton iteration, saves the increments done (summary marked
interrupted; no pictures: rendering can take minutes) and exits 130 (143, 129); one after the last increment
is solved waits until every result file is written, then exits so.
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import TYPE_CHECKING, cast

import numpy as np

from .. import runtime
from ..errors import require
from ..fem.tip import COLUMNS as TIP_COLUMNS
from ..io.output import lock_stems, prepare_directory, save_json
from ..io.units import AREA, FORCE, LENGTH, MEASURES, MOMENT, PRESSURE, in_dimension
from ..signals import holding
from .cli import (
    MEASURE,
    add_ramp_arguments,
    add_scene_arguments,
    add_video_arguments,
    app_parser,
    budget,
    build,
    exit_code,
    newton_options,
    render_report,
    rendering_flags,
    scene_of_flags,
    solve,
)
from .stems import result_stem

if TYPE_CHECKING:
    from ..result import Result

# by dimension: the tip's rotation in the last step's line and over the run
TURN_WORDS = {2: ("tip rotation", "rotation"), 3: ("bend angle", "bend angle")}


def parser() -> argparse.ArgumentParser:
    p = app_parser("pneuma-inflate", __doc__)
    add_scene_arguments(p, cy_help="chamber centre height (above the neutral axis curls down)")
    add_ramp_arguments(p)
    add_video_arguments(p, "960x384")
    p.add_argument(
        "--interactive",
        action="store_true",
        help="open a window (needs a display) with a slider for the commanded area (3D: one per chamber, "
        "the view turned by dragging); re-solves live",
    )
    p.add_argument(
        "--reduced",
        metavar="MODEL.npz",
        help="with --interactive on a 3D scene: solve on this reduced model of the scene (pneuma-reduce) inside its "
        "training range (outside: the full)",
    )
    return p


def run(args: argparse.Namespace) -> dict:
    from ..terms.chambers import AreaControl

    scene = scene_of_flags(args)
    # a scene's name is a plain file name (Scene checks it): every result file lands inside --out
    stem = result_stem(scene.name if args.scene else f"inflate_cy{args.cy:+.2f}", args, scene)
    size = rendering_flags(args, scene.geometry.dim)
    require(not (args.interactive and args.no_video), "--interactive and --no-video exclude each other")
    require(
        args.reduced is None or (args.interactive and scene.geometry.dim == 3),
        f"--reduced {args.reduced} needs --interactive on a 3D scene (the live page: pneuma-serve --reduced)",
    )
    if args.interactive:
        require(
            bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")),
            "--interactive needs a display (DISPLAY is not set); run without it for headless video output",
        )
        require(
            scene.geometry.dim == 3 or isinstance(scene.controls[0].kind, AreaControl),
            "--interactive needs an area-controlled first chamber (a 2D scene)",
        )
    out = prepare_directory(args.out)
    runtime.init(args.arch)
    if args.interactive and scene.geometry.dim == 3:
        from ..realtime.interactive import explore_solid

        return explore_solid(scene, size, newton_options(args), budget=budget(args), reduced=args.reduced)
    if args.interactive:
        from ..realtime.interactive import explore

        return explore(scene, args.growth, size, args.renderer, newton_options(args), budget=budget(args))
    with lock_stems(out, stem):  # no other run writes these files meanwhile
        return run_scene(args, scene, stem, size, out)


def run_scene(args: argparse.Namespace, scene, stem: str, size: tuple[int, int], out) -> dict:
    from ..render.paraview import VtkSeries

    built = build(scene, args)
    vtk = VtkSeries(out, stem, built)
    with holding():  # from the last solve to the last file, a signal waits for the files (the ramp's own: stopping)
        return solve_and_save(args, built, stem, size, out, vtk)


def solve_and_save(args: argparse.Namespace, built, stem: str, size: tuple[int, int], out, vtk) -> dict:
    """Solve the ramp, report it and write every result file. A ramp with no equilibrium past some step reports and
    writes the steps done, pictures included: a scene whose ramp ends at a limit point (schedule.ends_at_limit_point)
    then returns as done, any other re-raises (exit 1). A ramp stopped by a signal writes its data but no pictures
    (rendering a 3D video takes seconds to minutes: whoever pressed Ctrl-C wants the run to end now)."""
    from ..solve.simulate import RampInterrupted, RampStopped

    try:
        return report_and_save(args, solve(args, built, vtk=vtk), stem, size, out, vtk)
    except RampStopped as stopped:
        done = cast("Result", stopped.result)  # (solve's: tp.simulate made it a Result)
        if not done.steps:  # the rest state itself has no equilibrium
            raise
        if isinstance(stopped, RampInterrupted):
            written = done.save_history(out, stem) + [vtk.pvd]
            written.append(save_json(out / f"{stem}_summary.json", done.summary(interrupted=True)))
            print(f"saved the {len(done.steps)} steps done in " + ", ".join(str(p) for p in written))
            raise
        planned = built.scene.ends_at_limit_point and softened(done)
        if built.scene.ends_at_limit_point and not planned:
            print(
                f"the scene declares that its ramp ends at a limit point, but no chamber softened before the stop "
                f"(its compliance d measure / d pressure did not reach {SOFTENING:g} times its first): not a limit "
                f"point"
            )
        if planned:  # the step, the pressure with no equilibrium and the last equilibrium's (simulate.settle's words)
            print(f"stopped at the limit point, as the scene plans (schedule.ends_at_limit_point): {stopped}")
        reason = "limit point" if planned else "no equilibrium"
        stop = {"step": len(done.steps), "reason": reason, "message": str(stopped)}
        summary = report_and_save(args, done, stem, size, out, vtk, stop)
        if not planned:
            raise
        return summary


SOFTENING = 3.0  # a limit point's sign: the last secant compliance dV/dp this many times the first, or more


def softened(result: Result) -> bool:
    """Whether the run softened towards its stop as a structure does at a limit point, where dV/dp -> infinity:
    for some chamber, the secant compliance (V_k - V_(k-1)) / (p_k - p_(k-1)) of the last increment done is at least
    SOFTENING times that of the first (two increments at least; increments with no pressure change skipped)."""
    measure, pressure = np.asarray(result.area), np.asarray(result.pressure)
    for v, p in zip(measure.T, pressure.T):
        dv, dp = np.diff(v), np.diff(p)
        moving = np.abs(dp) > 1e-12 * max(np.abs(p).max(), 1e-300)
        compliance = dv[moving] / dp[moving]
        if len(compliance) >= 2 and compliance[0] > 0 and compliance[-1] >= SOFTENING * compliance[0]:
            return True
    return False


def report_and_save(
    args: argparse.Namespace, result: Result, stem: str, size: tuple[int, int], out, vtk, stopped: dict | None = None
) -> dict:
    """Print the run's figures and write its files and pictures; stopped: the step with no equilibrium and why (the
    summary's "stopped"), for a ramp that ended before its last increment."""
    scene = result.scene
    final, summary = result.steps[-1], result.summary()
    if stopped is not None:  # the steps done all converged, but the run did not reach its end
        summary["stopped"] = stopped
        summary["all_converged"] = summary["all_converged"] and stopped["reason"] == "limit point"
    area, length, pressure = (scene.units.suffix(d) for d in (AREA, LENGTH, PRESSURE))
    force, moment = (scene.units.suffix(in_dimension(d, result.mesh.dim)) for d in (FORCE, MOMENT))
    measure = scene.units.suffix(MEASURES[result.mesh.dim])
    extremes = summary["extremes"]

    def span(column: str, text: str) -> str:
        """A column's range over the run: 'min (step i) to max (step j)', each value formatted by text (round-off,
        under 1e-9 of the range's larger end, as 0)."""
        e = extremes[column]
        lo, hi = (0.0 if abs(v) <= 1e-9 * max(abs(e["min"]), abs(e["max"])) else v for v in (e["min"], e["max"]))
        return f"{text.format(lo)} (step {e['min_step']}) to {text.format(hi)} (step {e['max_step']})"

    for name, c in final.chambers.items():
        print(
            f"{name}: {MEASURE[result.mesh.dim]} {c.area / c.area_ratio:.3f} -> {c.area:.3f}{measure} "
            f"(x{c.area_ratio:.2f}), pressure {c.pressure:.4g}{pressure}; over the run "
            f"{span(f'{name}.area_ratio', 'x{:.2f}')}, pressure {span(f'{name}.pressure', '{:.4g}' + pressure)}"
        )
    turn, turn_over_run = TURN_WORDS[result.mesh.dim]
    beyond_y = "".join(f"tip dz {dz:+.4f}{length}; " for dz in final.tip[2:])
    print(
        f"tip deflection (mean y displacement of {summary['tip_at']}): "
        f"{result.tip_deflection:+.4f}{length}; {beyond_y}{turn} {final.tip_rotation:+.1f} deg"
        + ("" if final.tip_twist is None else f"; twist about x {final.tip_twist:+.1f} deg")
    )
    tip = [f"{column[4:]} {span(column, '{:+.4f}' + length)}" for column in TIP_COLUMNS[: result.mesh.dim]]
    print(f"tip over the run: {', '.join(tip)}; {turn_over_run} {span('tip_rotation', '{:+.1f}')} deg")
    print(f"peak chamber pressure |p|: {result.peak_pressure:.4g}{pressure}")
    print(
        f"largest principal stretch: {summary['max_stretch']:.2f} (step {summary['max_stretch_step']}; a run past "
        f"max_stretch = {summary['max_stretch_limit']:g} warns)"
    )
    for name, (fx, fy, magnitude) in final.contact.items():
        fz = f", {final.contact_fz[name]:+.4g}" if name in final.contact_fz else ""
        print(f"{name} contact force on the body: ({fx:+.4g}, {fy:+.4g}{fz}){force}; sum of |f| {magnitude:.4g}{force}")
    if final.blocked_force is not None:
        print(f"blocked force (on the obstacles): {final.blocked_force:.4g}{force}")
    if final.clamp:
        forces = ", ".join(f"{final.clamp[k]:+.4g}" for k in final.clamp if k.startswith("f"))
        moments = ", ".join(f"{final.clamp[k]:+.4g}" for k in final.clamp if k.startswith("m"))
        print(f"clamp reaction: force ({forces}){force}, moment ({moments}){moment}")
    print(
        f"Newton: {summary['newton_iterations_total']} iterations over {summary['steps'] - 1} solves "
        f"(max {summary['newton_iterations_max']}, {summary['increment_cuts']} increment cuts), "
        f"all converged: {summary['all_converged']}"
        + ("" if stopped is None else f" (stopped at step {stopped['step']}: {stopped['reason']})")
        + f"; run {result.seconds:.2f} s"
    )
    # results saved before rendering: a Ctrl-C there loses none
    written = result.save(out, stem, vtk=False, plot=not args.no_video, extra=summary) + [vtk.pvd]
    if not args.no_video:
        done = result.video(
            args.video or out / f"{stem}.mp4",
            out / f"{stem}.png",
            size,
            args.fps,
            args.color,
            args.renderer,
            quiet=args.quiet,
        )
        summary.update(
            renderer=done.renderer,
            video_frames=done.frames,
            video_size=[done.width, done.height],
            render_ms_per_frame=done.ms_per_frame,
        )
        print(render_report(done, summary["solve_seconds_per_step"]))
        written = [done.video, done.png] + written
        save_json(out / f"{stem}_summary.json", summary)
    print("wrote " + ", ".join(str(p) for p in written) + f" (+ {len(vtk.entries)} VTU files in {vtk.folder})")
    return summary


def main(argv: list[str] | None = None) -> int:
    return exit_code(run, parser().parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
