"""Inverse control: find the chamber commands that put the tip where you want it.

    pneuma-reach --scene bidirectional --tip 1.7 -0.3
    pneuma-reach --scene beam_3d --tip 1.769 -0.179 0.006 --no-video    (a 3D body: X Y Z)
    pneuma-reach --scene pneunet_finger --targets pneunet_finger_targets.csv   (or a scene's [[targets]])
    pneuma-reach --design cy --tip-dy -0.2
    pneuma-reach --scene gripper_2d --output object.magnitude --value 20     (any measure of the state)
    pneuma-reach --scene pneunet_finger --targets pneunet_finger_targets.csv --reduced out/pneunet_finger_reduced.npz

X Y is where the tip point (the mean of the tip vertices, as in inflate's tip deflection) should be,
in scene coordinates (X Y Z on a 3D body; X Y alone leaves z free); --angle DEG adds the tip rotation
(in 3D about the bending axis z). Commands stay inside each chamber's bounds
(--bounds NAME MIN MAX, the scene file's `bounds`, or the range its keyframes drive). Prints the
commands found and a summary line starting with `reached:`; an unreachable target prints
`unreachable: ...` (the closest pose, the chambers at a bound) and exits with 1, its files still
written. Writes under --out the video (the target marker and the tip's path), its last frame,
the per-frame history CSV (commands, tip, target, error), the states and a summary JSON.
--design cy --tip-dy D instead finds the chamber height cy at which the reference ramp ends at tip deflection D
(writes design_cy_tip_dy<D>_summary.json, with what the flags changed). --output COLUMN --value V instead follows
the scene's own schedule to where a history column that measures the state (tip_rotation: the bending angle, the
whole turn from rest, tip_twist, tip_dx, blocked_force, a contact force, ...; not the solver's step, iterations,
residual, ...) equals V (control/outputs.py), prints `reached:` with the commands there (or `unreachable:` with the
closest step, or the value found where the column jumps over V inside a step, exit 1) and writes
<scene>_output_<COLUMN><V>_summary.json (COLUMN made a plain file name, with what the flags changed of the scene,
stems.result_stem).
--reduced MODEL.npz (a model pneuma-reduce trained for this scene; with --tip or --targets) searches on the reduced
model, then polishes each answer with a few full Newton solves and Gauss-Newton steps (control/reduced.py): the
answer is the full model's. Per target it prints a `reduced:` line: the reduced search's tip error and seconds, the
indicator (the full residual of the reduced state; the commands outside the training box, where the model is
extrapolated) and the polish's seconds.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time
from typing import TYPE_CHECKING

from .. import runtime
from ..errors import PneumaInputError, parse_number, require, require_finite
from ..io.output import lock_stems, prepare_directory, save_json
from ..signals import holding

if TYPE_CHECKING:
    from ..scene.build import Scene
    from ..scene.targets import Target

from .cli import (
    add_ramp_arguments,
    add_scene_arguments,
    add_video_arguments,
    app_parser,
    apply_set,
    budget,
    build,
    check_flags,
    exit_code,
    newton_options,
    render_report,
    rendering_flags,
    scene_file,
    scene_for,
)
from .stems import result_stem

# ReachOptions' defaults (control/inverse.py; tests/test_reach.py checks they agree)
TIP_TOL, ANGLE_TOL, RESTARTS = 1e-3, 0.5, 4


def parser() -> argparse.ArgumentParser:
    p = app_parser("pneuma-reach", __doc__)
    add_scene_arguments(p)
    p.add_argument(
        "--tip",
        nargs="+",
        type=float,
        metavar="COORD",
        help="target position of the tip point: X Y, or X Y Z on a 3D body",
    )
    p.add_argument("--angle", type=float, default=None, help="target tip rotation in degrees (with --tip)")
    p.add_argument(
        "--weights",
        nargs=3,
        type=float,
        default=[1.0, 1.0, 1.0],
        metavar=("WX", "WY", "WANGLE"),
        help="weights of the x, y and rotation errors (with --tip)",
    )
    p.add_argument(
        "--targets",
        help="CSV of targets followed in order (columns x, y, optional angle, wx, wy, wangle), "
        "a path or the name of a shipped one (pneunet_finger_targets.csv)",
    )
    p.add_argument(
        "--bounds",
        nargs=3,
        action="append",
        default=[],
        metavar=("CHAMBER", "MIN", "MAX"),
        help="command bounds of a chamber (pressure or area ratio); repeatable",
    )
    p.add_argument("--tip-tol", type=float, default=TIP_TOL, help="tip tolerance, a fraction of the body length")
    p.add_argument("--angle-tol", type=float, default=ANGLE_TOL, help="rotation tolerance, degrees")
    p.add_argument(
        "--restarts", type=int, default=RESTARTS, help="descents from other commands when one stops short of the target"
    )
    p.add_argument("--design", choices=["cy"], help="find the reference chamber height cy for --tip-dy instead")
    p.add_argument("--tip-dy", type=float, help="with --design cy: the tip deflection the ramp should end at")
    p.add_argument(
        "--output",
        metavar="COLUMN",
        help="instead of a tip target: the history column measuring the state (tip_rotation, blocked_force, ...; "
        "not step, iterations, residual, ...) to bring to --value along the scene's schedule",
    )
    p.add_argument("--value", type=float, help="with --output: the value the column should take")
    p.add_argument(
        "--reduced",
        metavar="MODEL.npz",
        help="search on this reduced model (pneuma-reduce, trained for this scene), then polish with the full model",
    )
    add_ramp_arguments(p)
    add_video_arguments(p, "960x384")
    p.add_argument(
        "--interactive",
        action="store_true",
        help="a window (needs a display): drag the target with the mouse, a slider per chamber",
    )
    return p


def with_bounds(scene, bounds: list[list[str]]):
    """The scene with each --bounds NAME MIN MAX applied to its chamber (checked as the scene file's are)."""
    names = scene.chamber_names
    controls = list(scene.controls)
    for name, low, high in bounds:
        require(name in names, f"--bounds: unknown chamber {name!r} (chambers: {', '.join(names)})")
        i = names.index(name)
        try:
            controls[i] = dataclasses.replace(controls[i], bounds=(parse_number("min", low), parse_number("max", high)))
        except PneumaInputError as exc:
            raise PneumaInputError(f"--bounds {name}: {exc}") from None
    return dataclasses.replace(scene, controls=tuple(controls))


def targets_of(args: argparse.Namespace, scene, required: bool = True) -> list:
    """--tip (with --angle, --weights), else --targets FILE.csv (a path or a shipped file's name), else the
    scene file's [[targets]] (if not required, else none)."""
    from ..scene.shipped import find
    from ..scene.targets import Target, read_targets_csv

    require(args.tip is None or args.targets is None, "give --tip or --targets, not both")
    require(args.angle is None or args.tip is not None, "--angle needs --tip")
    if args.tip is not None:
        require(len(args.tip) in (2, 3), f"--tip takes X Y or X Y Z, not {len(args.tip)} numbers")
        return [Target(tuple(args.tip), args.angle, tuple(args.weights))]
    if args.targets is not None:
        return read_targets_csv(find(args.targets, ".csv", "targets file"))
    require(
        bool(scene.targets) or not required,
        "no target: give --tip X Y, --targets FILE.csv, or [[targets]] in the scene file",
    )
    return list(scene.targets)


def describe(reacher, commands) -> str:
    return ", ".join(f"{name} = {q:.6g} ({unit})" for name, unit, q in zip(reacher.names, reacher.units, commands))


def reach_record(reacher, result) -> dict:
    return {
        "target": {
            "tip": list(result.target.tip),
            "angle": result.target.angle,
            "weights": list(result.target.weights),
        },
        "tip": result.pose.tip.tolist(),
        "tip_rotation_deg": result.pose.rotation,
        "tip_error": result.error,
        "angle_error_deg": result.angle_error,
        "reached": result.reached,
        "commands": dict(zip(reacher.names, result.pose.commands.tolist())),
        "active_bounds": [{"chamber": n, "bound": side, "value": v} for n, side, _, v in result.active],
        "iterations": result.iterations,
        "forward_solves": result.forward_solves,
        "newton_iterations": result.newton_iterations,
        "seconds": result.seconds,
        **({} if result.reduced is None else {"reduced": reduced_record(reacher, result.reduced)}),
    }


def reduced_record(reacher, phase) -> dict:
    """The reduced search of one reach (control/reduced.py ReducedPhase) for the summary JSON."""
    return {
        "commands": dict(zip(reacher.names, phase.result.pose.commands.tolist())),
        "tip_error": phase.result.error,
        "reduced_solves": phase.result.forward_solves,
        "seconds": phase.seconds,
        "polish_seconds": phase.polish_seconds,
        "indicator_residual": phase.indicator.residual,
        "outside_training": [
            {"chamber": reacher.names[i], "value": v, "range": [lo, hi]} for i, v, lo, hi in phase.indicator.outside
        ],
    }


def run(args: argparse.Namespace) -> dict:
    from ..control.inverse import ReachOptions, command_bounds

    if args.reduced is not None:
        require(
            not args.design and args.output is None and args.value is None and not args.interactive,
            "--reduced works with --tip and --targets (not --output, --design or --interactive)",
        )
    if args.design:
        return run_design(args)
    if args.output is not None or args.value is not None:
        from .reach_output import run_output

        return run_output(args)
    require(args.tip_dy is None, "--tip-dy needs --design cy")
    explicit_tol = args.tol is not None  # live mode keeps interactive.LIVE_TOL unless --tol is given
    check_flags(args)
    if args.scene:
        scene = scene_file(args)
        stem = result_stem(f"reach_{scene.name}", args, scene)
    else:
        scene = apply_set(scene_for(args, args.cy), args.set)
        stem = result_stem(f"reach_cy{args.cy:+.2f}", args, scene)
    trained = scene  # a reduced model is checked against the scene without --bounds: they do not change it
    scene = with_bounds(scene, args.bounds)
    lo, hi = command_bounds(scene)
    targets = targets_of(args, scene, required=not args.interactive)
    options = ReachOptions(args.tip_tol, args.angle_tol, restarts=args.restarts)
    size = rendering_flags(args, scene.dim)
    require(not (args.interactive and args.no_video), "--interactive and --no-video exclude each other")
    if args.interactive:
        require(scene.dim == 2, "--interactive reach works on 2D scenes (drag a target in the plane)")
        require(
            bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")),
            "--interactive needs a display (DISPLAY is not set)",
        )
    out = prepare_directory(args.out)
    runtime.init(args.arch)
    if args.interactive:
        from ..realtime.interactive import follow_mouse

        return follow_mouse(
            scene,
            (lo, hi),
            size,
            args.renderer,
            options,
            newton_options(args) if explicit_tol else None,
            targets[0] if targets else None,
            budget=budget(args),
        )
    with lock_stems(out, stem):  # no other run writes these files meanwhile
        return reach_targets(args, trained if args.reduced else scene, stem, targets, (lo, hi), options, size, out)


def reach_targets(
    args: argparse.Namespace,
    scene: Scene,
    stem: str,
    targets: list[Target],
    bounds,
    options,
    size: tuple[int, int],
    out,
) -> dict:
    from tqdm import tqdm

    from ..control.inverse import Reacher
    from ..control.reduced import ReducedReacher
    from ..reduce.store import load_reduced

    (lo, hi), built = bounds, build(scene, args)
    start = time.perf_counter()
    if args.reduced is not None:
        model = load_reduced(args.reduced, built)
        print(f"reduced model {args.reduced}: {model.n_modes} modes, {len(model.elements)} elements sampled")
        start = time.perf_counter()
        reacher: Reacher = ReducedReacher(model, (lo, hi), options, newton_options(args), args.max_cuts)
    else:
        reacher = Reacher(built, (lo, hi), options, newton_options(args), args.max_cuts)
    print(
        "bounds: "
        + ", ".join(f"{n} {a:g} .. {b:g}" for n, a, b in zip(reacher.names, lo, hi))
        + f"; start (box centre) solved in {time.perf_counter() - start:.2f} s"
    )
    # a bar on a terminal only (disable=None: off when stderr is not a TTY, so never in a piped log)
    bar = tqdm(
        total=len(targets),
        desc="reaching",
        unit="target",
        disable=True if args.quiet or len(targets) < 2 else None,
        leave=False,
    )

    done = 0

    def progress(result):
        nonlocal done
        done += 1
        bar.update()
        if not args.quiet:
            bar.write(
                f"  target {done}/{len(targets)} {tuple(result.target.tip)}: "
                f"{describe(reacher, result.pose.commands)}; tip error {result.error:.3g}; "
                f"{result.forward_solves} forward solves, {result.seconds:.2f} s"
            )
            if result.reduced is not None:
                bar.write("    " + result.reduced.summary_line(reacher.names))

    with bar:
        results = reacher.follow(targets, progress)
    with holding():  # from the last reach to the last file, a signal waits for the files
        return save_reaches(args, reacher, results, stem, size, out)


def save_reaches(args: argparse.Namespace, reacher, results: list, stem: str, size: tuple[int, int], out) -> dict:
    import numpy as np

    from ..control.inverse import frames
    from ..result import ELEMENTS

    built, (lo, hi) = reacher.built, (reacher.lo, reacher.hi)
    last = results[-1]
    trajectory = frames(reacher, results)  # every accepted equilibrium, as one run
    solves = [r.forward_solves for r in results]
    seconds = [r.seconds for r in results]
    summary = {
        "scene": built.scene.name,
        "vertices": built.mesh.n_vertices,
        ELEMENTS[built.mesh.dim]: built.mesh.n_elements,
        "body_length": reacher.length,
        "bounds": {n: [a, b] for n, a, b in zip(reacher.names, lo, hi)},
        **reach_record(reacher, last),
        "targets_reached": sum(r.reached for r in results),
        "targets": len(results),
        "worst_tip_error": max(r.error for r in results),
        "forward_solves_per_reach": float(np.mean(solves)),
        "seconds_per_reach": float(np.mean(seconds)),
        "reaches": [reach_record(reacher, r) for r in results],
        "all_converged": all(r.reached for r in results),
    }
    print("commands: " + describe(reacher, last.pose.commands))
    print(
        f"forward solves: {sum(solves)} for {len(results)} target(s) ({np.mean(solves):.1f} per reach, "
        f"{sum(r.newton_iterations for r in results)} Newton iterations); {np.mean(seconds):.3f} s per reach"
    )
    written = []
    if not args.no_video:
        done = trajectory.video(
            args.video or out / f"{stem}.mp4",
            out / f"{stem}.png",
            size,
            args.fps,
            args.color,
            args.renderer,
            quiet=args.quiet,
            png_step=-1,
        )  # the pose reached
        summary.update(renderer=done.renderer, video_frames=done.frames, video_size=[done.width, done.height])
        print(render_report(done, float(np.mean([s.seconds for s in trajectory.steps]))))
        written += [done.video, done.png]
    written += trajectory.save_history(out, stem) + [save_json(out / f"{stem}_summary.json", summary)]
    print("wrote " + ", ".join(str(p) for p in written))
    unreached = [(k, r) for k, r in enumerate(results, start=1) if not r.reached]
    if not unreached:
        if len(results) == 1:
            print(last.summary_line())
        else:
            tip = ", ".join(f"{v:.6g}" for v in last.pose.tip)
            print(
                f"reached: all {len(results)} targets in order; last tip ({tip}); "
                f"worst tip error {summary['worst_tip_error']:.3g}"
            )
    else:
        k, first = unreached[0]
        where = "" if len(results) == 1 else f"target {k} of {len(results)} ({len(unreached)} unreachable): "
        print(where + first.summary_line(), file=sys.stderr)
    return summary


def run_design(args: argparse.Namespace) -> dict:
    """--design cy --tip-dy D: the chamber height at which the reference ramp ends at tip deflection D."""
    from ..control.design import solve_design
    from ..fem.planar import BeamGeometry
    from ..solve.simulate import run_schedule

    require(args.tip_dy is not None, "--design cy needs --tip-dy D")
    wanted = require_finite("--tip-dy", args.tip_dy)
    require(
        not args.scene and args.tip is None and args.targets is None and not args.interactive,
        "--design cy works on the reference beam of the flags (no --scene, --tip, --targets, --interactive)",
    )
    centred = apply_set(scene_for(args, 0.0), args.set)  # validates the reference-beam flags and --set
    out = prepare_directory(args.out)
    runtime.init(args.arch)
    beam = BeamGeometry()
    limit = beam.height / 2 - beam.b - 1e-3 - 1e-6  # the valid range: |cy| + b < H/2 - 1e-3
    options = newton_options(args)

    def tip_dy(cy: float) -> float:
        started = time.perf_counter()
        result = run_schedule(
            apply_set(scene_for(args, cy), args.set).build(budget(args)), options=options, max_cuts=args.max_cuts
        )
        if not args.quiet:
            print(
                f"  cy = {cy:+.6f}: tip dy {result.tip_deflection:+.6f} ({time.perf_counter() - started:.2f} s)",
                flush=True,
            )
        return result.tip_deflection

    result = solve_design(tip_dy, -limit, limit, wanted)
    summary = {
        "design": "cy",
        "tip_dy_wanted": wanted,
        "cy": result.value,
        "tip_dy": result.measure,
        "tip_dy_error": abs(result.measure - wanted),
        "found": result.found,
        "range": [-limit, limit],
        "evaluations": len(result.evaluations),
        "seconds": result.seconds,
        "history": [{"cy": c, "tip_dy": m} for c, m in result.evaluations],
        "all_converged": result.found,
    }
    # named by the deflection sought and what the flags changed of the reference beam: no other run overwrites it
    path = save_json(out / f"{result_stem(f'design_cy_tip_dy{wanted:g}', args, centred)}_summary.json", summary)
    print(f"evaluations: {len(result.evaluations)} ramps (a new mesh each) in {result.seconds:.1f} s; wrote {path}")
    if result.found:
        print(
            f"reached: cy = {result.value:+.6f} ends the ramp at tip dy {result.measure:+.6f} "
            f"(error {abs(result.measure - wanted):.2g})"
        )
    else:
        print(
            f"unreachable: tip dy {wanted:+.6g} lies outside what cy in [{-limit:+.6f}, {limit:+.6f}] gives "
            f"({min(m for _, m in result.evaluations):+.6f} .. {max(m for _, m in result.evaluations):+.6f}); "
            f"closest cy = {result.value:+.6f}, tip dy {result.measure:+.6f}",
            file=sys.stderr,
        )
    return summary


def main(argv: list[str] | None = None) -> int:
    return exit_code(run, parser().parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
