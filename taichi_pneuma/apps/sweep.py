"""A design study: run a scene with dotted scene keys varied over a grid (or a Latin hypercube sample),
on every core of this machine or on a Ray cluster; one CSV row per run, resumable.

    pneuma-sweep --vary cy=-0.15,0,0.15
    pneuma-sweep --scene bidirectional --vary material.E=5e3:2e4:4 --vary chambers[0].center[1]=0.15:0.25:3
    pneuma-sweep --vary cy=-0.17:0.17 --vary E=5e3:2e4 --samples 32 --ray 10.0.0.1:6379

Writes <out>/<name>.csv (a row per run: the varied values, tip dx/dy/rotation, each chamber's final
area ratio and peak |pressure|, converged, Newton iterations, increments done, vertices, seconds, error),
<name>.json (the grid, the base scene, solver options, versions, machine, executor, counts) and
<name>.png (tip deflection against the varied keys). A run that fails (an invalid scene, no
equilibrium) is a row with its error, never the end of the study. The same command again runs only
the runs that have no row yet (--retry-failed: also those with an error).

Exit codes: 0 when every run has its row (failed runs included), 1 when runs were lost with a
crashed worker process (the same command runs them), 2 for bad input (one `error:` line; also when
another run is writing the study of the same --name in --out), 130 on Ctrl-C, 143 on SIGTERM, 129 on
SIGHUP (runs in flight finish and are kept; the same command resumes). The workers ignore Ctrl-C (the
command decides) and die with the command, even one killed outright.
"""

from __future__ import annotations

import argparse
import sys

from .. import limits
from ..io.keys import SHORT_KEYS
from ..io.output import check_stem, lock_stem, prepare_directory
from .cli import add_ramp_arguments, add_scene_arguments, app_parser, exit_code, scene_of_flags
from .workers import add_executor_arguments, executor_of, run_options


def parser() -> argparse.ArgumentParser:
    p = app_parser("pneuma-sweep", __doc__)
    p.add_argument(
        "--vary",
        action="append",
        default=[],
        metavar="KEY=SPEC",
        required=True,
        help="a dotted scene key and its values: start:stop:count (evenly spaced, ends included; "
        "integers if both ends are), start:stop (with --samples) or v1,v2,...; repeatable (a full "
        "grid over all). Short keys: " + ", ".join(f"{k} = {v}" for k, v in SHORT_KEYS.items()),
    )
    p.add_argument(
        "--samples",
        type=int,
        default=None,
        help="run N points of a Latin hypercube over the ranges (a list is sampled by its items; a "
        "range's count is ignored) instead of the full grid",
    )
    p.add_argument(
        "--seed", type=int, default=0, help="seed of the Latin hypercube (the same seed plans the same runs)"
    )
    add_executor_arguments(p, "the runs", "every core")
    p.add_argument("--name", default="sweep", help="the result files are <out>/<name>.csv, .json and .png")
    p.add_argument("--retry-failed", action="store_true", help="run again the runs recorded with an error")
    p.add_argument("--max-runs", type=int, default=limits.MAX_RUNS, help="refuse a study of more runs")
    add_scene_arguments(p, "the base scene, for every run")
    add_ramp_arguments(p)
    p.set_defaults(max_frame_pixels=limits.MAX_FRAME_PIXELS)  # checked by cli.check_flags; no video here
    return p


def row_line(row: dict, keys: list[str], labels: list[str]) -> str:
    """A run's line in the log: its varied values (floats to 12 digits: the CSV keeps them all), then its tip's
    motion or its error."""
    from ..study.table import shown

    values = ", ".join(f"{label} = {shown(row[k])}" for k, label in zip(keys, labels))
    seconds = "" if row.get("seconds") is None else f" ({row['seconds']:.1f} s)"  # none: the run was lost
    if row.get("error") is not None:
        return f"  {values}: error: {row['error']}{seconds}"
    return (
        f"  {values}: tip dy {row['tip_dy']:+.4f} dx {row['tip_dx']:+.4f} rot {row['tip_rotation']:+.1f} deg, "
        f"{row['iterations']} Newton it{seconds}"
    )


def run(args: argparse.Namespace) -> dict:
    from ..study import Sweep, parse_vary

    axes = [parse_vary(text) for text in args.vary]
    base = scene_of_flags(args)
    executor = executor_of(args, here=False)
    options = run_options(args)
    out = prepare_directory(args.out)
    with lock_stem(out, check_stem(args.name)):  # from reading the rows done to writing the last: this run's
        sweep = Sweep(base, axes, out, args.name, args.samples, args.seed, options, args.retry_failed, args.max_runs)
        return run_study(args, sweep, executor)


def run_study(args: argparse.Namespace, sweep, executor) -> dict:
    from tqdm import tqdm

    where = (
        "a local Ray"
        if args.ray == ""
        else f"Ray at {args.ray}"
        if args.ray
        else f"a process pool of {min(executor.workers, len(sweep.todo))} workers"
    )
    print(
        f"study {args.name}: {len(sweep.runs)} runs ({'full grid' if args.samples is None else 'Latin hypercube'} "
        f"over {', '.join(a.label for a in sweep.axes)}); {len(sweep.runs) - len(sweep.todo)} done before, "
        f"{len(sweep.todo)} to run" + (f" on {where}" if sweep.todo else "")
    )
    bar = tqdm(total=len(sweep.todo), desc="runs", unit="run", disable=True if args.quiet else None, leave=False)

    def on_row(row):
        bar.update()
        if not args.quiet:
            tqdm.write(row_line(row, sweep.keys, [a.label for a in sweep.axes]))

    try:
        with bar:
            if sweep.todo:
                with executor:
                    report = sweep.run(executor, on_row)
            else:
                report = sweep.run(None)
    except KeyboardInterrupt:
        print(f"kept the rows done in {sweep.csv}; the same command runs the rest", file=sys.stderr)
        raise
    ok = len(report.rows) - report.failed
    rate = f"; {report.ran / report.seconds:.2f} runs/s" if report.ran else ""
    print(
        f"{report.planned} runs: {ok} without error, {report.failed} failed, {report.ran} run now in "
        f"{report.seconds:.1f} s{rate}"
    )
    if report.lost:
        print(
            f"error: {report.lost} runs lost with a crashed worker process; the same command runs them", file=sys.stderr
        )
    print("wrote " + ", ".join(str(p) for p in report.files))
    # exit_code's contract: 0 when "all_converged"; here, when every planned run has its row
    return {"all_converged": report.lost == 0}


def main(argv: list[str] | None = None) -> int:
    return exit_code(run, parser().parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
