"""Steering by chamber placement: the same inflation ramp with the chamber high, centred and low.

    pneuma-steer                                 (or python -m taichi_pneuma.apps.steer)

Solves the three ramps (cy = +0.15, 0, -0.15), prints their tip deflections, writes each ramp's ParaView
files (steer_cy+0.15.pvd, ...) and, unless --no-video, plays them side by side in one video (all panels in
one frame of reference, bodies coloured by --color on one scale) with a PNG of the last frame.
"""

from __future__ import annotations

import argparse
import sys

from .. import runtime
from .cli import (
    add_ramp_arguments,
    add_video_arguments,
    app_parser,
    apply_set,
    build,
    exit_code,
    render_report,
    rendering_flags,
    scene_for,
    solve,
)

PLACEMENTS = ((0.15, "chamber high -> curls down"), (0.0, "centred -> no bend"), (-0.15, "chamber low -> curls up"))


def parser() -> argparse.ArgumentParser:
    p = app_parser("pneuma-steer", __doc__)
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="change a dotted scene-file key or a short name (cx E nu k max_area) of the three scenes "
                        "(repeatable)")
    add_ramp_arguments(p)
    add_video_arguments(p, "1344x320")
    return p


def run(args: argparse.Namespace) -> dict:
    from ..io.output import prepare_directory, save_json
    from ..io.vtk import VtkSeries

    scenes = [apply_set(scene_for(args, cy), args.set) for cy, _ in PLACEMENTS]
    size = rendering_flags(args)
    out = prepare_directory(args.out)
    runtime.init(args.arch)
    built = [build(scene) for scene in scenes]
    series = [VtkSeries(out, f"steer_cy{cy:+.2f}", b) for b, (cy, _) in zip(built, PLACEMENTS)]
    solved = [solve(args, b, f"cy = {cy:+.2f}", vtk) for b, vtk, (cy, _) in zip(built, series, PLACEMENTS)]
    summary = {"tip_deflection": {}, "all_converged": True}
    for (cy, title), result in zip(PLACEMENTS, solved):
        print(f"cy = {cy:+.2f} ({title}): tip deflection {result.tip_deflection:+.4f}, "
              f"peak |p| {result.peak_pressure:.1f}, ramp {result.seconds:.1f} s")
        summary["tip_deflection"][f"{cy:+.2f}"] = result.tip_deflection
        summary["all_converged"] &= result.converged
    written = [vtk.pvd for vtk in series]
    if not args.no_video:
        from ..render.video import render_video

        done = render_video(solved, args.video or out / "steer.mp4", out / "steer.png", size, args.fps, args.color,
                            args.renderer, trace=False, titles=[f"cy = {cy:+.2f}: {title}" for cy, title in PLACEMENTS],
                            quiet=args.quiet)
        seconds_per_step = sum(r.summary()["solve_seconds_per_step"] for r in solved) / len(solved)
        print(render_report(done, seconds_per_step))
        summary.update(renderer=done.renderer, video_frames=done.frames, video_size=[done.width, done.height],
                       render_ms_per_frame=done.ms_per_frame, solve_seconds_per_step=seconds_per_step)
        written += [done.video, done.png]
    written.append(save_json(out / "steer_summary.json", summary))
    print("wrote " + ", ".join(str(p) for p in written))
    return summary


def main(argv: list[str] | None = None) -> int:
    return exit_code(run, parser().parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
