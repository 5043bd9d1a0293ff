"""Where an app's independent tasks run: the --workers and --ray flags that pneuma-sweep, pneuma-optimize and
pneuma-reduce share, the executor they name (study/executors.py), and the solver options every run of a study shares."""

from __future__ import annotations

import argparse
import contextlib


def add_executor_arguments(p: argparse.ArgumentParser, what: str, default: str) -> None:
    """--workers and --ray: where `what` runs (study/executors.py), else `default`."""
    p.add_argument(
        "--workers",
        type=int,
        default=None,
        help=f"run {what} on this many worker processes (default: {default}); with --ray and no address, the "
        "local Ray's CPUs",
    )
    p.add_argument(
        "--ray",
        nargs="?",
        const="",
        default=None,
        metavar="ADDRESS",
        help=f"run {what} as Ray tasks (pip install 'taichi-pneuma[ray]'): a local Ray started for it without "
        "ADDRESS, else the cluster whose head is at ADDRESS (HOST:PORT, auto, ray://HOST:PORT)",
    )


def run_options(args: argparse.Namespace):
    """What every run of a study shares besides the scene (study/task.py RunOptions), from the flags."""
    from ..study import RunOptions

    return RunOptions(
        args.tol,
        args.max_iterations,
        args.max_cuts,
        args.max_triangles,
        args.max_increments,
        args.max_fibers,
        args.max_obstacles,
        args.arch,
    )


def executor_of(args: argparse.Namespace, here: bool):
    """The executor the flags name: Ray (--ray), a process pool (--workers, or always where not `here`), else this
    process (a null context, entered as None)."""
    from ..study import LocalPool, RayCluster

    if args.ray is not None:
        return RayCluster(args.ray or None, args.workers)
    return LocalPool(args.workers) if args.workers is not None or not here else contextlib.nullcontext()
