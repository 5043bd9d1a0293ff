"""Steering by chamber placement: the same inflation ramp with the chamber high, centred and low.

    pneuma-steer                                 (or python -m taichi_pneuma.apps.steer)

Solves the three ramps (cy = +0.15, 0, -0.15), prints their tip deflections and what each tip did (its
caption: "chamber high (cy = +0.15): tip up to +0.27 (step 10), then down to -0.28 (step 35)", read off the
run's tip history), writes each ramp's ParaView files (steer_cy+0.15.pvd, ...; a run whose flags or --set change
the scenes adds them to the names, stems.result_stem) and, unless --no-video, plays them side by side in one video
(all panels in one frame of reference, bodies coloured by --color on one scale, each under its caption) with a PNG
of the last frame. steer_summary.json has the captions and tip histories.
A ramp stopped (Ctrl-C, SIGTERM, SIGHUP, or no equilibrium) still writes steer_summary.json with the
steps each ramp did (interrupted: true for a signal).
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

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
    scene_for,
    solve,
)
from .stems import result_stem

PLACEMENTS = ((0.15, "chamber high"), (0.0, "centred"), (-0.15, "chamber low"))
STILL = 0.1  # a tip that never moves by more than this fraction of the largest |tip| of the runs compared "stays"


def tip_story(tip: np.ndarray, scale: float) -> str:
    """What a tip did over a run, from its history tip (steps,) of tip deflections: "tip stays within +-b" (b its
    largest |tip|, rounded up to 0.01) when that is at most STILL x scale (the largest |tip| of the runs compared);
    else each extreme beyond that band in the order reached, "tip up to +0.26 (step 9), then down to -0.28
    (step 35)", so a tip that rises before it falls is not told as only falling."""
    tip = np.asarray(tip, float)
    band = STILL * scale
    if np.abs(tip).max() <= band:
        return f"tip stays within +-{math.ceil(np.abs(tip).max() * 100 - 1e-9) / 100:.2f}"
    high, low = int(np.argmax(tip)), int(np.argmin(tip))
    moves = sorted((k, word) for k, word, reach in ((high, "up", tip[high]), (low, "down", -tip[low])) if reach > band)
    return "tip " + ", then ".join(f"{word} to {tip[k]:+.2f} (step {k})" for k, word in moves)


def captions(results) -> list[str]:
    """Each placement's caption: its name, its cy and its tip's story (tip_story, on the scale of all three)."""
    tips = [r.history["tip_dy"] for r in results]
    scale = max(float(np.abs(t).max()) for t in tips)
    return [f"{name} (cy = {cy:+.2f}): {tip_story(t, scale)}" for (cy, name), t in zip(PLACEMENTS, tips)]


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
    summary: dict = {"tip_deflection": {}, "caption": {}, "tip_history": {}, "all_converged": True}
    told = captions(solved)
    for (cy, _), caption, result in zip(PLACEMENTS, told, solved):
        print(
            f"{caption}; tip deflection {result.tip_deflection:+.4f}, "
            f"peak |p| {result.peak_pressure:.1f}, ramp {result.seconds:.1f} s"
        )
        key = f"{cy:+.2f}"
        summary["tip_deflection"][key] = result.tip_deflection
        summary["caption"][key] = caption
        summary["tip_history"][key] = [float(v) for v in result.history["tip_dy"]]
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
            titles=[caption.replace(": ", "\n", 1) for caption in told],  # name and cy, then the story
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
