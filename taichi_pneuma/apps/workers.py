"""Where an app's independent tasks run: the --workers and --ray flags that pneuma-sweep and pneuma-reduce share, and
the executor they name (study/executors.py)."""

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


def executor_of(args: argparse.Namespace, here: bool):
    """The executor the flags name: Ray (--ray), a process pool (--workers, or always where not `here`), else this
    process (a null context, entered as None)."""
    from ..study import LocalPool, RayCluster

    if args.ray is not None:
        return RayCluster(args.ray or None, args.workers)
    return LocalPool(args.workers) if args.workers is not None or not here else contextlib.nullcontext()
