"""Steering by chamber placement: the same inflation ramp with the chamber high, centred and low.

    pneuma-steer                                 (or python -m taichi_pneuma.apps.steer)

Solves the three ramps (cy = +0.15, 0, -0.15), prints their tip deflections, writes each ramp's ParaView
files (steer_cy+0.15.pvd, ...; a run whose flags or --set change the scenes adds them to the names,
cli.result_stem) and, unless --no-video, plays them side by side in one video (all panels in
one frame of reference, bodies coloured by --color on one scale) with a PNG of the last frame.
A ramp stopped (Ctrl-C, SIGTERM, SIGHUP, or no equilibrium) still writes steer_summary.json with the
steps each ramp did (interrupted: true for a signal).
"""

from __future__ import annotations

import argparse
import sys

from .. import runtime
from ..io.output import lock_stems, prepare_directory, save_json
from ..signals import holding
from .cli import (
    add_ramp_arguments,
    add_video_arguments,
    app_parser,
    apply_set,
    build,
    exit_code,
    render_report,
    rendering_flags,
    result_stem,
    scene_for,
    solve,
)

PLACEMENTS = ((0.15, "chamber high -> curls down"), (0.0, "centred -> no bend"), (-0.15, "chamber low -> curls up"))


def parser() -> argparse.ArgumentParser:
    p = app_parser("pneuma-steer", __doc__)
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="change a dotted scene-file key or a short name (cx E nu k max_area) of the three scenes (repeatable)",
    )
    add_ramp_arguments(p)
    add_video_arguments(p, "1344x320")
    return p


def run(args: argparse.Namespace) -> dict:
    scenes = [apply_set(scene_for(args, cy), args.set) for cy, _ in PLACEMENTS]
    size = rendering_flags(args)
    out = prepare_directory(args.out)
    runtime.init(args.arch)
    stems = [result_stem(f"steer_cy{cy:+.2f}", args, scene) for (cy, _), scene in zip(PLACEMENTS, scenes)]
    stem = result_stem("steer", args, *scenes)  # the video, its PNG and the summary
    # no other run writes these files meanwhile; a signal between two ramps stops the next at its start, one after
    # the last increment waits for the files (signals.holding, signals.stopping)
    with lock_stems(out, stem, *stems), holding():
        return run_placements(args, scenes, stem, stems, size, out)


def run_placements(args: argparse.Namespace, scenes, stem: str, stems: list[str], size: tuple[int, int], out) -> dict:
    from ..render.paraview import VtkSeries
    from ..solve.simulate import RampInterrupted, RampStopped

    built = [build(scene, args) for scene in scenes]
    series = [VtkSeries(out, stem, b) for b, stem in zip(built, stems)]
    solved = []
    for b, vtk, (cy, _) in zip(built, series, PLACEMENTS):
        try:
            solved.append(solve(args, b, f"cy = {cy:+.2f}", vtk))
        except RampStopped as stopped:  # the ramps done, and the steps of this one, are kept
            done = {f"{c:+.2f}": r for (c, _), r in zip(PLACEMENTS, solved + [stopped.result]) if r.steps}
            path = save_json(
                out / f"{stem}_summary.json",
                {
                    "tip_deflection": {k: r.tip_deflection for k, r in done.items()},
                    "steps": {k: len(r.steps) for k, r in done.items()},
                    "all_converged": False,
                    "interrupted": isinstance(stopped, RampInterrupted),
                },
            )
            print(f"saved the ramps done in {path} and {', '.join(str(v.pvd) for v in series[: len(done)])}")
            raise
    summary: dict = {"tip_deflection": {}, "all_converged": True}
    for (cy, title), result in zip(PLACEMENTS, solved):
        print(
            f"cy = {cy:+.2f} ({title}): tip deflection {result.tip_deflection:+.4f}, "
            f"peak |p| {result.peak_pressure:.1f}, ramp {result.seconds:.1f} s"
        )
        summary["tip_deflection"][f"{cy:+.2f}"] = result.tip_deflection
        summary["all_converged"] &= result.converged
    written: list = [vtk.pvd for vtk in series]
    if not args.no_video:
        from ..render.video import render_video

        export = render_video(
            solved,
            args.video or out / f"{stem}.mp4",
            out / f"{stem}.png",
            size,
            args.fps,
            args.color,
            args.renderer,
            trace=False,
            titles=[f"cy = {cy:+.2f}: {title}" for cy, title in PLACEMENTS],
            quiet=args.quiet,
        )
        seconds_per_step = sum(r.summary()["solve_seconds_per_step"] for r in solved) / len(solved)
        print(render_report(export, seconds_per_step))
        summary.update(
            renderer=export.renderer,
            video_frames=export.frames,
            video_size=[export.width, export.height],
            render_ms_per_frame=export.ms_per_frame,
            solve_seconds_per_step=seconds_per_step,
        )
        written += [export.video, export.png]
    summary["scene_sha256"] = {f"{cy:+.2f}": r.summary()["scene_sha256"] for (cy, _), r in zip(PLACEMENTS, solved)}
    written.append(save_json(out / f"{stem}_summary.json", summary))
    print("wrote " + ", ".join(str(p) for p in written))
    return summary


def main(argv: list[str] | None = None) -> int:
    return exit_code(run, parser().parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
