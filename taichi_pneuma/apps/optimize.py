"""A design optimisation: the scene keys that minimise (or maximise) one or two objectives under constraints, found
by an Optuna sampler (TPE, CMA-ES, NSGA-II), each design simulated on every core of this machine or on a Ray cluster;
every evaluation recorded, resumable.

    pneuma-optimize benchmarks/optimize_beam.toml --vary cy=0:0.2 --vary chambers[0].semi_axes[1]=0.08:0.18 \\
        --minimize "at(main.pressure, tip_rotation, 6)" --constraint "at(max_stretch, tip_rotation, 6)<=1.35"
    pneuma-optimize fiber_bending_3d --vary chambers[0].radius=5:6.5 --vary fibers[0].path.radius=6.6:7.4 \\
        --minimize "at(chamber.pressure, tip_rotation, -90)" --constraint "max_stretch<=2.5" --trials 30 --ray

Objectives and constraints are expressions over the run's summary values (max_stretch, tip_rotation_deg,
blocked_force, chambers.<name>.final_pressure, extremes.tip_rotation.min, ...) and history columns (a name alone:
its final value; final(C), min(C), max(C); at(Y, X, v): Y where X first reaches v; rms(C, v): C's distance from a
value or, v a list [v1, v2, ...] of a value per step after rest, from a trajectory), with + - * / **,
abs() and sqrt(); a constraint is EXPR<=VALUE or EXPR>=VALUE (docs: Optimising a design).

Writes under --out: <name>.db (the Optuna study, SQLite: the same command again goes on from it, asking again the
designs that were running when it stopped), <name>/trial_NNNN/ (each design's scene.toml, summary.json, history.csv,
plot.png), <name>.csv and <name>.json (every evaluation; the best design or the Pareto front), <name>_trace.png (best
so far against evaluation) and, for two objectives, <name>_pareto.png. A design that fails (an invalid scene, no
equilibrium, an objective it has no value for) is a failed trial with its error, never the end of the study.

Exit codes: 0 when the evaluations asked for are recorded, 1 when designs were lost with a crashed worker process
(the same command runs them), 2 for bad input (one `error:` line; also when another
run is writing the study of the same --name in --out), 130 on Ctrl-C, 143 on SIGTERM, 129 on SIGHUP (the designs in
flight finish and are told; the same command resumes).
"""

from __future__ import annotations

import argparse
import sys

from .. import limits
from ..errors import require
from ..io.keys import SHORT_KEYS
from ..io.output import check_stem, lock_stem, prepare_directory
from .cli import (
    add_ramp_arguments,
    app_parser,
    check_flags,
    check_scene,
    exit_code,
    scene_of_flags,
    set_values,
)
from .workers import add_executor_arguments, executor_of, run_options


class Objective(argparse.Action):
    """--minimize and --maximize append (direction, expression) to one list, in the order given."""

    def __call__(self, parser, namespace, values, option_string=None):
        namespace.objectives = [*(namespace.objectives or []), (self.dest, values)]


def parser() -> argparse.ArgumentParser:
    p = app_parser("pneuma-optimize", __doc__)
    p.add_argument(
        "scene",
        nargs="?",
        default=None,
        help="the base scene file (TOML) or the name of a shipped scene; without it the reference beam of the "
        "flags (--cy --cx --growth --steps --E --nu --k --max-area --order)",
    )
    p.add_argument(
        "--template",
        metavar="FILE.py",
        help="instead of a scene: a Python file whose scene(**parameters) returns each design's Scene (a CAD part "
        "written for the parameters, say); --vary names its parameters (docs: Optimising a design)",
    )
    p.add_argument(
        "--vary",
        action="append",
        default=[],
        metavar="KEY=LO:HI",
        required=True,
        help="a dotted scene key and its bounds LO:HI (integers if both are) or its choices v1,v2,...; repeatable. "
        "Short keys: " + ", ".join(f"{k} = {v}" for k, v in SHORT_KEYS.items()),
    )
    for direction in ("minimize", "maximize"):
        p.add_argument(
            f"--{direction}",
            action=Objective,
            dest=direction,
            metavar="EXPR",
            help=f"an objective to {direction[:-1]}e (one, or two for a Pareto front; --minimize and --maximize mix)",
        )
    p.set_defaults(objectives=[])
    p.add_argument(
        "--constraint",
        action="append",
        default=[],
        metavar="EXPR<=VALUE",
        help="a constraint a design must meet to count (EXPR<=VALUE or EXPR>=VALUE; repeatable)",
    )
    p.add_argument("--trials", type=int, default=30, help="evaluations in all (a resumed study runs the rest)")
    p.add_argument(
        "--sampler", default="tpe", help="Optuna's sampler: tpe, cmaes (one objective, no constraints) or nsga2"
    )
    p.add_argument("--seed", type=int, default=0, help="the sampler's seed")
    p.add_argument(
        "--refine",
        type=int,
        default=0,
        metavar="N",
        help="the last N of the trials refine the best design found by SciPy's COBYQA, a local derivative-free "
        "method that keeps to the bounds and constraints (one objective; a third of --trials is a good share)",
    )
    add_executor_arguments(p, "the designs", "every core")
    p.add_argument("--name", default="optimize", help="the result files are <out>/<name>.db, .csv, .json, ...")
    p.add_argument("--cy", type=float, default=0.15, help="reference beam: chamber centre height")
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="change a dotted key of the base scene for every design (repeatable)",
    )
    add_ramp_arguments(p)
    p.set_defaults(max_frame_pixels=limits.MAX_FRAME_PIXELS)  # checked by cli.check_flags; no video here
    return p


def trial_line(row: dict, labels: list[str], keys: list[str], objectives: list[str], best) -> str:
    """An evaluation's line in the log: its values, its objectives (or its error), feasibility, the best so far."""
    from ..study.table import shown

    values = ", ".join(f"{label} = {shown(row[k])}" for k, label in zip(keys, labels))
    seconds = "" if row.get("seconds") is None else f" ({row['seconds']:.1f} s)"
    if row["error"] is not None:
        return f"  #{row['trial']} {values}: error: {row['error']}{seconds}"
    scores = ", ".join(f"{text} = {row[f'objective_{i}']:.6g}" for i, text in enumerate(objectives))
    flag = "" if row["feasible"] else " (violates a constraint)"
    single, front = best
    so_far = f"; best #{single['trial']}: {single['objective_0']:.6g}" if single else ""
    so_far += f"; Pareto front of {len(front)}" if front else ""
    return f"  #{row['trial']} {values}: {scores}{flag}{seconds}{so_far}"


def run(args: argparse.Namespace) -> dict:
    from ..study import SceneTemplate, parse_vary
    from ..study.goals import Goals
    from ..study.optimize import Optimization

    axes = [parse_vary(text) for text in args.vary]
    template = None
    if args.template is not None:
        require(args.scene is None, f"--template {args.template} replaces the scene {args.scene!r}: give one of them")
        check_flags(args)  # (the solver's flags, as a scene's)
        template = SceneTemplate.read(args.template, set_values(args.set))
        base = template.build({})
        check_scene(base, args)
    else:
        base = scene_of_flags(args)
    goals = Goals.parse(base, args.objectives, args.constraint)
    executor = executor_of(args, here=False)
    out = prepare_directory(args.out)
    with lock_stem(out, check_stem(args.name)):
        optimization = Optimization(
            base,
            axes,
            goals,
            out,
            args.name,
            args.trials,
            args.sampler,
            args.seed,
            run_options(args),
            args.refine,
            template,
        )
        return run_study(args, optimization, executor)


def run_study(args: argparse.Namespace, optimization, executor) -> dict:
    from tqdm import tqdm

    labels = [a.label for a in optimization.axes]
    goals = optimization.goals
    print(
        f"optimisation {args.name}: {args.trials} evaluations by {args.sampler}"
        + (f" ({args.refine} of them refining by COBYQA)" if args.refine else "")
        + " over "
        f"{', '.join(labels)}; {' and '.join(f'{d} {t}' for d, t in zip(goals.directions, goals.texts))}"
        + (f" subject to {', '.join(c.text for c in goals.constraints)}" if goals.constraints else "")
    )
    bar = tqdm(total=args.trials, desc="designs", unit="design", disable=True if args.quiet else None, leave=False)

    def on_trial(row, best):
        bar.update()
        if not args.quiet:
            tqdm.write(trial_line(row, labels, optimization.keys, goals.texts, best))

    try:
        with bar, executor:
            report = optimization.run(executor, on_trial=on_trial)
    except KeyboardInterrupt:
        print(f"kept the evaluations done in {optimization.db}; the same command runs the rest", file=sys.stderr)
        raise
    failed = sum(r["error"] is not None for r in report.rows)
    print(
        f"{len(report.rows)} evaluations ({report.ran} now, in {report.seconds:.1f} s): "
        f"{sum(r['feasible'] for r in report.rows)} feasible, {failed} failed"
    )
    if report.best is not None:
        values = ", ".join(f"{label} = {report.best[k]!r}" for k, label in zip(optimization.keys, labels))
        print(f"best: #{report.best['trial']} {values}: {goals.texts[0]} = {report.best['objective_0']:.6g}")
    elif len(goals.texts) == 2:
        print(
            f"Pareto front: {len(report.pareto)} designs (trials {', '.join(str(r['trial']) for r in report.pareto)})"
        )
    else:
        print("no feasible design found")
    if report.lost:
        print(
            f"error: {report.lost} designs lost with a crashed worker process; the same command runs them",
            file=sys.stderr,
        )
    print("wrote " + ", ".join(str(p) for p in [optimization.db, optimization.folder, *report.files]))
    # exit_code's contract: 0 when "all_converged"; here, when no design was lost
    return {"all_converged": report.lost == 0}


def main(argv: list[str] | None = None) -> int:
    return exit_code(run, parser().parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
