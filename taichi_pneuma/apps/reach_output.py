"""pneuma-reach --output COLUMN --value V: the commands along the scene's schedule at which a history column takes
the value V (control/outputs.py reach_output), a line per step as the ramp runs, and its summary file."""

from __future__ import annotations

import argparse
import sys

from .. import runtime
from ..errors import require, require_finite
from ..io.output import lock_stems, prepare_directory, reduce_to_stem, save_json
from .cli import apply_set, build, check_flags, newton_options, scene_file, scene_for
from .progress import step_line
from .stems import result_stem


def run_output(args: argparse.Namespace) -> dict:
    """--output COLUMN --value V: the commands along the scene's schedule at which the column equals V."""
    from ..control.outputs import reach_output
    from ..result import scene_sha256

    require(args.output is not None and args.value is not None, "--output COLUMN and --value V go together")
    wanted = require_finite("--value", args.value)
    require(
        args.tip is None and args.targets is None and not args.interactive,
        "--output works along the scene's schedule (no --tip, --targets, --interactive)",
    )
    check_flags(args)
    scene = scene_file(args) if args.scene else apply_set(scene_for(args, args.cy), args.set)
    out = prepare_directory(args.out)
    runtime.init(args.arch)
    built = build(scene, args)
    increments = built.scene.increments

    def progress(step, positions, forces) -> None:
        if not args.quiet:
            print(f"{step_line(step, increments, scene.units)}  {args.output} = {step.row()[args.output]:.6g}")

    result = reach_output(built, args.output, wanted, newton_options(args), progress=progress, max_cuts=args.max_cuts)
    commands = ", ".join(f"{name} {c:.6g}" for name, c in zip(scene.chamber_names, result.commands))
    summary = {
        "scene": scene.name,
        "output": args.output,
        "wanted": wanted,
        "found": result.found,
        "value": result.value,
        "step": result.step,
        "commands": dict(zip(scene.chamber_names, map(float, result.commands))),
        "evaluations": len(result.evaluations),
        "seconds": result.seconds,
        "all_converged": result.found and result.run.converged,  # exit 1 when not reached
    }
    if result.failure is not None:
        summary["failure"] = result.failure
    summary["scene_sha256"] = scene_sha256(scene)
    # named by the output and value sought and what the run changed of the scene: no other run overwrites it
    # (the column made a plain file name: a chamber's or an obstacle's name in it may hold any character)
    stem = result_stem(f"{scene.name}_output_{reduce_to_stem(args.output)}{wanted:g}", args, scene)
    with lock_stems(out, stem):  # no other run writes this file meanwhile
        path = save_json(out / f"{stem}_summary.json", summary)
    print(f"wrote {path}")
    print(f"{result.summary_line()}: {commands}", file=sys.stdout if result.found else sys.stderr)
    return summary
