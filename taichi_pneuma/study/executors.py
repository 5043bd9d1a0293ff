"""Where a study's runs run: LocalPool (spawned worker processes on this machine, one Taichi runtime and one CPU
thread each) or RayCluster (Ray tasks, on a local Ray or a cluster). Both are context managers whose run(tasks)
yields (index, row) as runs finish, and describe() what they are for the study's JSON record.

    with LocalPool(workers=2) as pool:          # or RayCluster(address, workers)
        for index, row in pool.run(tasks): ...

run(tasks, function) runs another module-level function than a study's run_task on each task (plain data), as a
reduced model's training does (reduce/snapshots.py solve_points); it too returns a dict and never raises.
"""

from __future__ import annotations

import ctypes
import os
import signal
import socket
import sys
import threading
import time
from concurrent.futures import ProcessPoolExecutor, as_completed, wait
from concurrent.futures.process import BrokenProcessPool
from importlib.util import find_spec
from multiprocessing import get_context

from .. import backend, signals
from ..errors import PneumaInputError, require
from .task import Task, one_line, run_task

PR_SET_PDEATHSIG = 1  # prctl's option: the signal a process gets when its parent dies (Linux)
# Worker processes: one thread each (Taichi's pool is set by runtime.init), no Taichi banner per worker
WORKER_ENV = {
    "OMP_NUM_THREADS": "1",
    "OPENBLAS_NUM_THREADS": "1",
    "MKL_NUM_THREADS": "1",
    backend.environment_name("banner"): "0",
}


def _worker_start(parent: int) -> None:
    """Pool worker initializer: Ctrl-C and SIGHUP are the parent's business (it cancels the runs not started;
    the workers were started ignoring them, signals.ignored); a worker dies with its parent (parent_watch)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if hasattr(signal, "SIGHUP"):
        signal.signal(signal.SIGHUP, signal.SIG_IGN)
    parent_watch(parent)


def parent_watch(parent: int) -> None:
    """End this process when its parent (pid `parent`) ends, killed or not: on Linux the kernel sends it
    SIGKILL (prctl PR_SET_PDEATHSIG); elsewhere a thread looks every second. A parent already gone (it
    died while this process started) ends it at once."""
    if sys.platform.startswith("linux"):
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    else:

        def watch():
            while os.getppid() == parent:
                time.sleep(1.0)
            os._exit(1)

        threading.Thread(target=watch, daemon=True).start()
    if os.getppid() != parent:
        os._exit(1)


def failed_row(task, message: str) -> dict:
    """The row of a task that could not run: a study run's varied values (a Task's) and the error."""
    return {**(task.values if isinstance(task, Task) else {}), "error": message}


class LocalPool:
    """Spawned worker processes on this machine, one Taichi runtime (one CPU thread) each."""

    def __init__(self, workers: int | None = None):
        self.workers = (os.cpu_count() or 1) if workers is None else workers
        require(isinstance(self.workers, int) and self.workers >= 1, f"--workers {workers!r} must be >= 1")
        self._pool: ProcessPoolExecutor | None = None
        self._saved_env: dict[str, str | None] = {}

    def describe(self) -> dict:
        return {"executor": "process pool", "workers": self.workers}

    def capacity(self) -> int:
        """How many tasks run at once."""
        return self.workers

    def __enter__(self):
        # workers are spawned as runs are submitted and inherit this environment (read as numpy loads)
        self._saved_env = {k: os.environ.get(k) for k in WORKER_ENV}
        os.environ.update(WORKER_ENV)
        self._pool = ProcessPoolExecutor(
            self.workers, mp_context=get_context("spawn"), initializer=_worker_start, initargs=(os.getpid(),)
        )
        return self

    def __exit__(self, *exc):
        self._pool.shutdown(wait=True, cancel_futures=True)
        for k, v in self._saved_env.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v

    def run(self, tasks: list, function=run_task):
        """Yield (index, row) as runs finish; row None for a run lost with a crashed worker process.
        On Ctrl-C: cancel the runs not started, yield those in flight as they finish, re-raise."""
        pool = self._pool
        assert pool is not None  # (entered)
        with signals.ignored():  # the first `workers` submissions start the workers: they inherit it
            futures = {pool.submit(function, task): i for i, task in enumerate(tasks[: self.workers])}
        futures.update({pool.submit(function, task): i for i, task in enumerate(tasks) if i >= self.workers})
        pending = set(futures)

        def outcome(future):
            pending.discard(future)
            i = futures[future]
            try:
                return i, future.result()
            except BrokenProcessPool:
                return i, None
            except Exception as exc:  # noqa: BLE001 -- the function does not raise; this is the pool failing
                return i, failed_row(tasks[i], f"{type(exc).__name__}: {one_line(exc)}")

        try:
            for future in as_completed(futures):
                yield outcome(future)
        except KeyboardInterrupt:
            for future in pending:
                future.cancel()
            for future in wait(pending).done:
                if not future.cancelled():
                    yield outcome(future)
            raise


def check_address(address: str) -> None:
    """Refuse at once a host:port nothing listens on (ray.init would retry it for ever)."""
    host, sep, port = address.rpartition(":")
    require(
        bool(sep) and host and port.isdigit(), f"--ray {address!r}: an address is HOST:PORT, ray://HOST:PORT or auto"
    )
    try:
        socket.create_connection((host, int(port)), timeout=5).close()
    except OSError as exc:
        raise PneumaInputError(f"--ray {address!r}: no Ray cluster answers there ({exc.strerror or exc})") from None


class RayCluster:
    """Runs as Ray tasks (one CPU each): on a local Ray started for the study when address is None (with
    `workers` CPUs), on the cluster at address otherwise (HOST:PORT of its head, ray://HOST:PORT, auto).
    A Ray already initialised in this process (a notebook, a test) is used as it is."""

    def __init__(self, address: str | None = None, workers: int | None = None):
        require(find_spec("ray") is not None, "--ray needs Ray: pip install 'taichi-pneuma[ray]'")
        self.address, self.workers = address, workers
        require(workers is None or (isinstance(workers, int) and workers >= 1), f"--workers {workers!r} must be >= 1")
        if address not in (None, "auto") and not address.startswith("ray://"):
            check_address(address)
        self._started = False

    def describe(self) -> dict:
        import ray

        return {
            "executor": "ray",
            "address": self.address or "local",
            "ray_cpus": ray.cluster_resources().get("CPU"),
            "ray_nodes": len(ray.nodes()),
        }

    def capacity(self) -> int:
        """How many tasks run at once: the workers asked for, else the cluster's CPUs."""
        import ray

        return self.workers or max(int(ray.cluster_resources().get("CPU", 1)), 1)

    def __enter__(self):
        import ray

        if not ray.is_initialized():
            # address "local": a new Ray even where one runs already (ray.init(None) would join that one)
            local = {"num_cpus": self.workers or os.cpu_count()} if self.address is None else {}
            try:
                ray.init(
                    address=self.address or "local",
                    include_dashboard=False,
                    log_to_driver=False,
                    runtime_env={"env_vars": WORKER_ENV},
                    **local,
                )
            except (ConnectionError, ValueError, RuntimeError) as exc:
                raise PneumaInputError(f"--ray {self.address or ''}: {one_line(exc)}") from None
            self._started = True
        return self

    def __exit__(self, *exc):
        import ray

        if self._started:
            ray.shutdown()

    def run(self, tasks: list, function=run_task):
        """Yield (index, row) as runs finish; a task Ray could not run (its worker died) gives an error row."""
        import ray

        remote = ray.remote(num_cpus=1)(function)
        refs = {remote.remote(task): i for i, task in enumerate(tasks)}
        pending = list(refs)
        try:
            while pending:
                done, pending = ray.wait(pending, num_returns=1)
                i = refs[done[0]]
                try:
                    row = ray.get(done[0])
                except ray.exceptions.RayError as exc:
                    row = failed_row(tasks[i], f"ray: {one_line(exc)}")
                yield i, row
        finally:
            for ref in pending:
                ray.cancel(ref)
