"""Design studies: one scene run many times with dotted scene keys varied over a grid or a Latin
hypercube sample; each run a task on a local process pool or on Ray; one CSV row per run.

    axes = [parse_vary("chambers[0].center[1]=-0.15:0.15:3"), parse_vary("material.E=1e4,2e4")]
    sweep = Sweep(base_scene, axes, out="out", name="sweep")     # reads the rows done before (resumable)
    with LocalPool(workers=2) as pool:                          # or RayCluster(address)
        report = sweep.run(pool, on_row=print)

A task is plain data (the base scene's TOML text, the values of the varied keys, the solver options)
and run_task never raises: an invalid scene, a ramp with no equilibrium or any other exception becomes
the row's `error`. Rows are appended (and fsynced) to <name>.csv as runs finish; the same study run
again reads them back and runs only the rest. <name>.json records the grid, the base scene, the
versions and the machine; <name>.png plots the tip deflection against the varied keys.
"""

from __future__ import annotations

import csv
import ctypes
import io
import itertools
import json
import math
import os
import platform
import signal
import socket
import sys
import threading
import time
from concurrent.futures import ProcessPoolExecutor, as_completed, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import redirect_stdout
from dataclasses import asdict, dataclass, field, replace
from datetime import datetime, timezone
from importlib import metadata
from importlib.util import find_spec
from multiprocessing import get_context
from pathlib import Path

import numpy as np
import tomllib
from scipy.stats import qmc

from .. import backend, limits, runtime, signals
from ..fem import sizing
from ..errors import PneumaInputError, require, require_finite
from ..io.keys import SHORT_KEYS, dotted
from ..io.output import (
    FORMULA,
    check_stem,
    lock_stem,
    open_appending,
    prepare_directory,
    read_input,
    save_json,
    write_atomic,
)
from ..scene.scenefile import read_scene
from ..scene.sceneformat import scene_data
from ..scene.schema import parse_key, parse_value
from ..scene.build import Scene
from ..solve.newton import NewtonOptions
from ..solve.simulate import MAX_CUTS, RampStopped

ALIASES = SHORT_KEYS  # the short key names (io/keys.py), under their former name here
MAX_RUNS = limits.MAX_RUNS
MAX_CELL = 10_000  # characters of a varied value in the CSV (csv reads fields of at most 131,072)
MAX_ERROR = 1_000  # characters of a run's error kept in its row
MAX_RECORD_BYTES = 256_000_000  # the most of a study's CSV or JSON read back
MAX_DRAWN = 1e100  # numbers the plot draws as such (matplotlib's axis arithmetic overflows near 1e308)
PR_SET_PDEATHSIG = 1  # prctl's option: the signal a process gets when its parent dies (Linux)
# Worker processes: one thread each (Taichi's pool is set by runtime.init), no Taichi banner per worker
WORKER_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
              backend.environment_name("banner"): "0"}


# --- the varied keys -------------------------------------------------------------------------------

def is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


@dataclass(frozen=True)
class Axis:
    """One varied key: a range (low, high, count: count evenly spaced values, ends included; integers
    if both ends are) or a list of values; name: the short name the user gave it (io/keys.py), if any."""

    key: str
    spec: str
    low: float | None = None
    high: float | None = None
    count: int | None = None
    items: tuple = ()
    name: str = ""

    @property
    def label(self) -> str:
        """The key as the user wrote it: its short name, else the dotted key."""
        return self.name or self.key

    @property
    def is_range(self) -> bool:
        return self.low is not None

    @property
    def integer(self) -> bool:
        return self.is_range and isinstance(self.low, int) and isinstance(self.high, int)

    def grid(self) -> list:
        """The values of a full grid."""
        if not self.is_range:
            return list(self.items)
        require(self.count is not None, f"--vary {self.key}={self.spec}: a range needs a count (start:stop:count) "
                                        f"unless --samples is given")
        values = np.linspace(self.low, self.high, self.count)
        if self.integer:
            values = np.round(values).astype(int)
            require(len(set(values)) == len(values),
                    f"--vary {self.key}={self.spec}: {self.count} integers do not fit between {self.low} and "
                    f"{self.high}")
        return [v.item() for v in values]

    def sample(self, u: np.ndarray) -> list:
        """Values at the unit-interval coordinates u: uniform over a range (integers: each equally
        likely), over the items of a list."""
        if not self.is_range:
            return [self.items[i] for i in np.minimum((u * len(self.items)).astype(int), len(self.items) - 1)]
        if self.integer:
            span = self.high - self.low + 1
            return [int(v) for v in np.minimum(self.low + np.floor(u * span), self.high)]
        return [float(v) for v in self.low + u * (self.high - self.low)]


def parse_vary(text: str) -> Axis:
    """'KEY=start:stop:count' (or start:stop with --samples) or 'KEY=v1,v2,...' -> Axis. KEY is a dotted
    scene key (material.E, chambers[0].center[1]) or a short name of io/keys.py (cy, cx, E, nu, k, max_area)."""
    typed, sep, spec = text.partition("=")
    key, spec = dotted(typed.strip()), spec.strip()
    name = typed.strip() if key != typed.strip() else ""
    require(bool(sep) and key and spec, f"--vary {text[:100]!r} must look like KEY=start:stop:count or KEY=v1,v2,...")
    parse_key(key)  # the dotted-key syntax
    where = f"--vary {key}={spec}"
    if ":" in spec:
        parts = spec.split(":")
        require(len(parts) in (2, 3), f"{where}: a range is start:stop:count (or start:stop with --samples)")
        ends = [parse_value(p, where) for p in parts[:2]]
        for end in ends:
            require(is_number(end), f"{where}: {end!r} is not a number")
            require_finite(where, end)
        count = None
        if len(parts) == 3:
            count = parse_value(parts[2], where)
            require(isinstance(count, int) and not isinstance(count, bool) and 1 <= count <= MAX_RUNS,
                    f"{where}: count {parts[2]!r} must be an integer from 1 to {MAX_RUNS}")
        return Axis(key, spec, ends[0], ends[1], count, name=name)
    items = [p.strip() for p in spec.split(",")]
    require(all(items), f"{where}: an empty value in the list")
    values = tuple(parse_value(p, where) for p in items)
    require(all(len(cell(v)) <= MAX_CELL for v in values),
            f"--vary {key}: a value of more than {MAX_CELL} characters (as a CSV cell)")
    require(len({cell(v) for v in values}) == len(values), f"{where}: a value is listed twice")
    return Axis(key, spec, items=values, name=name)


def plan(axes: list[Axis], samples: int | None = None, seed: int = 0, max_runs: int = MAX_RUNS) -> list[dict]:
    """The runs: every combination of the axes' values, or `samples` points of a Latin hypercube over
    them (scipy.stats.qmc, seeded: the same command plans the same runs), without repeats."""
    if samples is None:
        values = [axis.grid() for axis in axes]
        total = math.prod(len(v) for v in values)  # Python integers: no int64 wrap-around
        require(total <= max_runs, f"the grid has {total} runs; the limit is {max_runs} (--max-runs raises it)")
        runs = [dict(zip([a.key for a in axes], combination)) for combination in itertools.product(*values)]
    else:
        require(1 <= samples <= max_runs, f"--samples {samples} must lie in 1 .. {max_runs} (--max-runs raises it)")
        u = qmc.LatinHypercube(len(axes), seed=seed).random(samples)
        columns = [axis.sample(u[:, j]) for j, axis in enumerate(axes)]
        runs = [dict(zip([a.key for a in axes], values)) for values in zip(*columns)]
    unique = {run_key(run): run for run in runs}  # discrete axes can draw a combination twice
    return list(unique.values())


def lookup(data: dict, key: str):
    """The value of a dotted key in scene data, or KeyError."""
    node = data
    for part in parse_key(key):
        try:
            node = node[part]
        except (IndexError, TypeError):
            raise KeyError(key) from None
    return node


def check_axes(base: Scene, axes: list[Axis]) -> list[Axis]:
    """The axes checked against the scene, numbers made floats where the scene holds a float (so
    cy=0:1:3 is 0.0, 0.5, 1.0, not integers). Refuses a key the scene does not have and a value of the
    wrong kind (a word for a number).

    A key present in the base scene's data takes values of its kind; a key that is not (a new effect's
    table, say) must be accepted by the scene reader for at least one of its values. Values that make
    an invalid scene (a chamber outside the body) are not refused here: those runs record the error."""
    require(len({a.key for a in axes}) == len(axes), "a key is varied twice")
    data, checked = scene_data(base), []
    for axis in axes:
        values = [axis.low, axis.high] if axis.is_range else list(axis.items)
        try:
            current = lookup(data, axis.key)
        except KeyError:
            errors = []
            for value in values:
                try:
                    base.with_value(axis.key, value)
                    break
                except PneumaInputError as exc:
                    errors.append(str(exc))
            else:
                raise PneumaInputError(f"--vary {axis.key}: {errors[0]}") from None
            checked.append(axis)
            continue
        for value in values:
            same = is_number(value) if is_number(current) else isinstance(value, type(current))
            kind = "number" if is_number(current) else type(current).__name__
            require(same, f"--vary {axis.key}: {value!r} is not a {kind} like the scene's {axis.key} = {current!r}")
        if isinstance(current, float):
            axis = replace(axis, items=tuple(float(v) for v in axis.items)) if not axis.is_range else \
                replace(axis, low=float(axis.low), high=float(axis.high))
        checked.append(axis)
    return checked


# --- one run -------------------------------------------------------------------------------------

@dataclass(frozen=True)
class RunOptions:
    """What every run of a study shares besides the scene: Newton's settings, the resource limits, the backend."""

    tol: float = NewtonOptions.tol
    max_iterations: int = NewtonOptions.max_iterations
    max_cuts: int = MAX_CUTS
    max_triangles: int = limits.MAX_TRIANGLES
    max_increments: int = limits.MAX_INCREMENTS
    arch: str = "cpu"


@dataclass(frozen=True)
class Task:
    scene: str  # the base scene's TOML text
    values: dict  # dotted key -> value
    options: RunOptions = field(default_factory=RunOptions)


def one_line(exc: BaseException) -> str:
    """The exception's message on one line, cut to MAX_ERROR characters."""
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if len(text) <= MAX_ERROR else text[:MAX_ERROR - 3] + "..."


def measures(result, names: list[str]) -> dict:
    """The row's figures of an api.Result (finished or partial); its chambers' columns are named `names`
    (the base scene's chamber names: a run that varies a chamber's name keeps the study's columns)."""
    final = result.steps[-1]
    row = {"tip_dx": float(final.tip_dx), "tip_dy": float(final.tip_dy), "tip_rotation": float(final.tip_rotation)}
    if final.tip_dz is not None:  # a 3D body
        row["tip_dz"] = float(final.tip_dz)
    for i, name in enumerate(names):
        row[f"{name}.area_ratio"] = float(result.area_ratio[-1, i])
        row[f"{name}.peak_pressure"] = float(np.abs(result.pressure[:, i]).max())
    row.update(converged=result.converged, iterations=int(result.history["iterations"].sum()),
               increments=len(result.steps) - 1, vertices=int(result.mesh.n_vertices))
    return row


def run_task(task: Task) -> dict:
    """Run one scene of a study; never raises. Returns the row: the varied values, the figures (those of
    the steps done, for a ramp that stopped), converged, seconds, and error (None, or one line)."""
    from ..api import simulate

    start = time.perf_counter()
    row = dict(task.values)
    try:
        with redirect_stdout(io.StringIO()):  # ti.init prints its arch, once per worker
            runtime.init(task.options.arch, cpu_threads=1)
        base = read_scene(tomllib.loads(task.scene), "scene")
        names = base.chamber_names
        scene = base.with_values(task.values)
        sizing.check_scene(scene, task.options.max_triangles, task.options.max_increments)
        options = task.options
        with limits.budget(options.max_triangles):
            row.update(measures(simulate(scene, tol=options.tol, max_iterations=options.max_iterations,
                                         max_cuts=options.max_cuts), names), error=None)
    except RampStopped as exc:  # no equilibrium: keep the figures of the steps done
        if exc.result.steps:
            row.update(measures(exc.result, names), converged=False)
        row["error"] = one_line(exc)
    except PneumaInputError as exc:
        row["error"] = one_line(exc)
    except Exception as exc:  # noqa: BLE001 -- a failing run never stops the study
        row["error"] = f"{type(exc).__name__}: {one_line(exc)}"
    row["seconds"] = time.perf_counter() - start
    return row


# --- executors -----------------------------------------------------------------------------------

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


class LocalPool:
    """Spawned worker processes on this machine, one Taichi runtime (one CPU thread) each."""

    def __init__(self, workers: int | None = None):
        self.workers = (os.cpu_count() or 1) if workers is None else workers
        require(isinstance(self.workers, int) and self.workers >= 1, f"--workers {workers!r} must be >= 1")
        self._pool, self._saved_env = None, {}

    def describe(self) -> dict:
        return {"executor": "process pool", "workers": self.workers}

    def __enter__(self):
        # workers are spawned as runs are submitted and inherit this environment (read as numpy loads)
        self._saved_env = {k: os.environ.get(k) for k in WORKER_ENV}
        os.environ.update(WORKER_ENV)
        self._pool = ProcessPoolExecutor(self.workers, mp_context=get_context("spawn"), initializer=_worker_start,
                                         initargs=(os.getpid(),))
        return self

    def __exit__(self, *exc):
        self._pool.shutdown(wait=True, cancel_futures=True)
        for k, v in self._saved_env.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v

    def run(self, tasks: list[Task]):
        """Yield (index, row) as runs finish; row None for a run lost with a crashed worker process.
        On Ctrl-C: cancel the runs not started, yield those in flight as they finish, re-raise."""
        with signals.ignored():  # the first `workers` submissions start the workers: they inherit it
            futures = {self._pool.submit(run_task, task): i for i, task in enumerate(tasks[:self.workers])}
        futures.update({self._pool.submit(run_task, task): i for i, task in enumerate(tasks) if i >= self.workers})
        pending = set(futures)

        def outcome(future):
            pending.discard(future)
            i = futures[future]
            try:
                return i, future.result()
            except BrokenProcessPool:
                return i, None
            except Exception as exc:  # noqa: BLE001 -- run_task does not raise; this is the pool failing
                return i, {**tasks[i].values, "error": f"{type(exc).__name__}: {one_line(exc)}"}

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
    require(bool(sep) and host and port.isdigit(),
            f"--ray {address!r}: an address is HOST:PORT, ray://HOST:PORT or auto")
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

        return {"executor": "ray", "address": self.address or "local", "ray_cpus": ray.cluster_resources().get("CPU"),
                "ray_nodes": len(ray.nodes())}

    def __enter__(self):
        import ray

        if not ray.is_initialized():
            # address "local": a new Ray even where one runs already (ray.init(None) would join that one)
            local = {"num_cpus": self.workers or os.cpu_count()} if self.address is None else {}
            try:
                ray.init(address=self.address or "local", include_dashboard=False, log_to_driver=False,
                         runtime_env={"env_vars": WORKER_ENV}, **local)
            except (ConnectionError, ValueError, RuntimeError) as exc:
                raise PneumaInputError(f"--ray {self.address or ''}: {one_line(exc)}") from None
            self._started = True
        self._remote = ray.remote(num_cpus=1)(run_task)
        return self

    def __exit__(self, *exc):
        import ray

        if self._started:
            ray.shutdown()

    def run(self, tasks: list[Task]):
        """Yield (index, row) as runs finish; a task Ray could not run (its worker died) gives an error row."""
        import ray

        refs = {self._remote.remote(task): i for i, task in enumerate(tasks)}
        pending = list(refs)
        try:
            while pending:
                done, pending = ray.wait(pending, num_returns=1)
                i = refs[done[0]]
                try:
                    row = ray.get(done[0])
                except ray.exceptions.RayError as exc:
                    row = {**tasks[i].values, "error": f"ray: {one_line(exc)}"}
                yield i, row
        finally:
            for ref in pending:
                ray.cancel(ref)


# --- the study -----------------------------------------------------------------------------------

def cell(value) -> str:
    """CSV text of a value: '' for none, words as they are, numbers and booleans as JSON (exact floats); a
    word a spreadsheet would read as a formula (starting with one of FORMULA), or that reads as JSON, as a
    JSON string ("=1+1" in quotes): uncell reads every one back."""
    if value is None:
        return ""
    if not isinstance(value, str):
        return json.dumps(value)
    return json.dumps(value, ensure_ascii=False) if value.startswith(FORMULA) or uncell(value) != value else value


def uncell(text: str):
    """The value of a CSV cell (cell's inverse)."""
    if text == "":
        return None
    try:
        return json.loads(text)
    except (ValueError, RecursionError):
        return text


def run_key(values: dict) -> tuple:
    return tuple(cell(v) for v in values.values())


def versions(ray: bool = False) -> dict:
    names = ["taichi-pneuma", backend.NAME, "numpy", "scipy"] + (["ray"] if ray else [])
    found = {}
    for name in names:
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            found[name] = None
    return {"python": platform.python_version(), **found}


def machine() -> dict:
    model = None
    try:
        model = next(line.split(":", 1)[1].strip() for line in Path("/proc/cpuinfo").read_text().splitlines()
                     if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    return {"platform": platform.platform(), "machine": platform.machine(), "cpu": model or platform.processor(),
            "cores": os.cpu_count()}


@dataclass
class Report:
    """What Sweep.run did: planned runs, skipped (done before), ran now, failed (planned runs with an
    error row, before or now), lost (not run: a crashed worker), wall seconds; rows: the planned runs'
    rows in plan order (the CSV also keeps rows of runs outside this plan)."""

    planned: int
    skipped: int
    ran: int
    failed: int
    lost: int
    seconds: float
    rows: list[dict]
    files: list[Path]


class Sweep:
    """A study of `base` over `axes` (a full grid, or `samples` Latin-hypercube points), whose files are
    <out>/<name>.csv, .json and .png. Creating it reads the rows a previous run of the same study left
    (a different study under the same name is refused); run() runs the others."""

    def __init__(self, base: Scene, axes: list[Axis], out, name: str = "sweep", samples: int | None = None,
                 seed: int = 0, options: RunOptions = RunOptions(), retry_failed: bool = False,
                 max_runs: int = MAX_RUNS):
        require(len(axes) >= 1, "a study varies at least one key (--vary KEY=SPEC)")
        axes = check_axes(base, axes)
        self.base, self.axes, self.samples, self.seed, self.options = base, axes, samples, seed, options
        self.keys = [a.key for a in axes]
        self.runs = plan(axes, samples, seed, max_runs)
        self.scene_toml = base.to_toml()
        tip = ["tip_dx", "tip_dy", "tip_rotation"] + (["tip_dz"] if base.dim == 3 else [])
        figures = tip + [f"{c}.{f}" for c in base.chamber_names for f in ("area_ratio", "peak_pressure")]
        self.columns = self.keys + figures + ["converged", "iterations", "increments", "vertices", "seconds", "error"]
        self.name = check_stem(name)
        self.out = prepare_directory(out)
        self.csv, self.json, self.png = (self.out / f"{name}{suffix}" for suffix in (".csv", ".json", ".png"))
        self.identity = {"keys": self.keys, "base_scene": self.scene_toml, "options": asdict(options)}
        with lock_stem(self.out, name):  # (the sweep app holds it from before this to the end of run())
            self.done = self._read_done(retry_failed)
        self.todo = [run for run in self.runs if run_key(run) not in self.done]

    def _read_done(self, retry_failed: bool) -> dict[tuple, dict]:
        """Rows of a previous run of this study, by their values. The CSV and JSON are read back within
        MAX_RECORD_BYTES and not through a link; a row that is not one the study writes (a cut-off last
        line, a tampered one: a figure that is no finite number) is dropped, so that its run runs again."""
        if not os.path.lexists(self.csv):
            return {}
        try:
            previous = json.loads(read_input(self.json, MAX_RECORD_BYTES, "study record", follow_links=False))
            same = isinstance(previous, dict) and all(previous.get(k) == v for k, v in self.identity.items())
            text = read_input(self.csv, MAX_RECORD_BYTES, "study table", follow_links=False).decode("utf-8")
            reader = csv.DictReader(io.StringIO(text, newline=""))
            same = same and reader.fieldnames == self.columns
            rows = [row for row in reader if None not in row.values() and None not in row]
        except (PneumaInputError, ValueError, RecursionError, csv.Error):
            same = False
        require(same, f"{self.csv} holds another study (other keys, base scene or solver options), or it or its "
                      f"JSON is missing, damaged or not a plain file; give another --name or --out, or delete it")
        done = {}
        for text in rows:
            row = {k: uncell(v) for k, v in text.items()}
            if self.well_formed(row) and not (retry_failed and row["error"] is not None):
                done[tuple(text[k] for k in self.keys)] = row
        return done

    def well_formed(self, row: dict) -> bool:
        """Whether a row read back is one run_task could have made: its figures finite numbers (or empty, for
        a run that failed before any step), converged a boolean, the error a string."""
        figures = self.columns[len(self.keys):-1]
        numbers = [row[k] for k in figures if k != "converged"]
        if not all(v is None or (is_number(v) and math.isfinite(v)) for v in numbers):
            return False
        if row["error"] is None:
            return row["converged"] in (True, False) and None not in numbers
        return row["converged"] in (None, True, False) and isinstance(row["error"], str)

    def record(self, status: str, executor: dict | None = None, report: Report | None = None) -> dict:
        grid = {"axes": [{"key": a.key, "spec": a.spec, **({"values": a.grid()} if self.samples is None else {})}
                         for a in self.axes],
                "sampling": "full grid" if self.samples is None else "latin hypercube",
                "samples": self.samples, "seed": self.seed, "runs": len(self.runs)}
        data = {**self.identity, "status": status, "grid": grid, "executor": executor,
                "versions": versions(ray=bool(executor and executor["executor"] == "ray")),
                "machine": machine(), "updated": datetime.now(timezone.utc).isoformat(timespec="seconds")}
        if report is not None:
            data["result"] = {k: getattr(report, k) for k in ("planned", "skipped", "ran", "failed", "lost", "seconds")}
            data["result"]["runs_per_second"] = report.ran / report.seconds if report.ran else None
        return data

    def _write_csv(self, rows: list[dict]) -> Path:
        writer_rows = [[cell(row.get(c)) for c in self.columns] for row in rows]

        def write(tmp):
            with open(tmp, "w", newline="", encoding="utf-8") as f:
                csv.writer(f).writerows([self.columns] + writer_rows)
        return write_atomic(self.csv, write)

    def rows(self, new: dict[tuple, dict]) -> tuple[list[dict], list[dict]]:
        """The rows of the planned runs (in plan order), and those of runs this plan does not hold."""
        everything = {**self.done, **new}
        order = [run_key(run) for run in self.runs]
        planned = set(order)
        return [everything[k] for k in order if k in everything], \
            [row for k, row in everything.items() if k not in planned]

    def run(self, executor, on_row=None) -> Report:
        """Run the runs not done before on an entered executor (LocalPool, RayCluster; None when there is
        nothing to run), appending each row to the CSV as it finishes; on_row(row) after each. Writes
        the JSON (status running, then done or interrupted) and the plot. Ctrl-C: the rows done stay."""
        with lock_stem(self.out, self.name):  # no other run writes this study meanwhile
            return self._run(executor, on_row)

    def _run(self, executor, on_row) -> Report:
        start = time.perf_counter()
        described = executor.describe() if executor is not None else None
        save_json(self.json, self.record("running", described))
        self._write_csv(sum(self.rows({}), []))  # the rows kept, whole (drops a cut-off line)
        new: dict[tuple, dict] = {}
        lost = 0
        status = "interrupted"
        try:
            if self.todo:
                tasks = [Task(self.scene_toml, run, self.options) for run in self.todo]
                with open_appending(self.csv) as f:
                    writer = csv.writer(f)
                    for index, row in executor.run(tasks):
                        if row is None:
                            lost += 1
                            continue
                        new[run_key(self.todo[index])] = row
                        writer.writerow([cell(row.get(c)) for c in self.columns])
                        f.flush()
                        os.fsync(f.fileno())
                        if on_row is not None:
                            on_row(row)
            status = "done" if lost == 0 else "incomplete"
        finally:
            rows, others = self.rows(new)
            report = Report(len(self.runs), len(self.runs) - len(self.todo), len(new),
                            sum(row.get("error") is not None for row in rows), lost, time.perf_counter() - start,
                            rows, [self.csv, self.json])
            with signals.holding():  # a signal meanwhile waits for the files
                self._write_csv(rows + others)
                save_json(self.json, self.record(status, described, report))
        if any(row.get("tip_dy") is not None and row.get("error") is None for row in rows):
            figure = study_figure(rows, self.keys, sampled=self.samples is not None,
                                  labels=[a.label for a in self.axes])
            report.files.append(write_atomic(self.png, lambda tmp: figure.savefig(tmp, format="png", dpi=100)))
        return report


# --- the plot ------------------------------------------------------------------------------------

def _positions(values: list) -> tuple[np.ndarray, list | None]:
    """Numbers as they are, if a plot can draw them (MAX_DRAWN); anything else as category indices
    (returned with their labels)."""
    if all(is_number(v) and abs(v) <= MAX_DRAWN for v in values):
        return np.array(values, dtype=float), None
    labels = list(dict.fromkeys(cell(v) for v in values))
    return np.array([labels.index(cell(v)) for v in values], dtype=float), labels


def _edges(centres: np.ndarray) -> np.ndarray:
    """Cell edges around sorted cell centres (midpoints; one centre gets a cell of its own size)."""
    if len(centres) == 1:
        half = 0.5 * (abs(centres[0]) or 1.0)
        return np.array([centres[0] - half, centres[0] + half])
    mid = 0.5 * (centres[1:] + centres[:-1])
    return np.concatenate([[2 * centres[0] - mid[0]], mid, [2 * centres[-1] - mid[-1]]])


def study_figure(rows: list[dict], keys: list[str], sampled: bool = False, labels: list[str] | None = None):
    """Tip deflection against the varied keys (a matplotlib Figure, no pyplot), each axis labelled as the
    user named its key (labels: short names, default the keys). One key: curves of tip dy and dx. Two: a
    heatmap of tip dy over the grid (red up, blue down; a scatter coloured by it for a sampled study).
    More: tip dy against each key. A failed run has no figures: one key marks it by a shaded line at its
    value (never a point at y = 0, which would read as data); two keys by an x in its cell; more leave
    it out (the title counts it)."""
    from matplotlib.figure import Figure

    labels = labels or keys
    ok = [r for r in rows if r.get("error") is None and r.get("tip_dy") is not None]
    failed = [r for r in rows if r.get("error") is not None]
    n = len(ok)
    tip = np.clip([r["tip_dy"] for r in ok], -MAX_DRAWN, MAX_DRAWN)  # drawn; the CSV has them exact
    title = "tip deflection at the last step"
    if len(keys) > 2:
        figure = Figure(figsize=(4 * len(keys), 3.6), layout="constrained")
        axes = figure.subplots(1, len(keys), sharey=True)
        for ax, key, label in zip(axes, keys, labels):
            x, ticks = _positions([r[key] for r in ok])
            ax.plot(x, tip, "o", ms=4)
            if ticks:
                ax.set_xticks(range(len(ticks)), ticks)
            ax.set(xlabel=label)
        axes[0].set_ylabel("tip dy")
        figure.suptitle(title + (f" ({len(failed)} failed runs not shown)" if failed else ""))
        return figure
    figure = Figure(figsize=(6.5, 4.5), layout="constrained")
    ax = figure.add_subplot()
    positions = [_positions([r[k] for r in ok + failed]) for k in keys]
    x, xl = positions[0]
    if len(keys) == 1:
        order = np.argsort(x[:n], kind="stable")
        ax.plot(x[:n][order], tip[order], "o-", label="tip dy")
        ax.plot(x[:n][order], np.clip([r["tip_dx"] for r in ok], -MAX_DRAWN, MAX_DRAWN)[order], "s--", label="tip dx")
        ax.axhline(0, color="0.7", lw=0.8)
        for k, value in enumerate(x[n:]):
            ax.axvline(value, color="tab:red", alpha=0.25, lw=6, label="failed run (no figures)" if k == 0 else None)
        ax.set(ylabel="tip displacement")
    else:
        y, yl = positions[1]
        limit = float(np.abs(tip).max()) or 1.0
        colours = dict(cmap="coolwarm", vmin=-limit, vmax=limit)
        if sampled:
            image = ax.scatter(x[:n], y[:n], c=tip, s=40, edgecolors="k", linewidths=0.3, **colours)
        else:
            xs, ys = np.unique(x), np.unique(y)
            grid = np.full((len(ys), len(xs)), np.nan)
            grid[np.searchsorted(ys, y[:n]), np.searchsorted(xs, x[:n])] = tip
            image = ax.pcolormesh(_edges(xs), _edges(ys), np.ma.masked_invalid(grid), **colours)
            if grid.size <= 64:
                for (i, j), value in np.ndenumerate(grid):
                    if np.isfinite(value):
                        ax.text(xs[j], ys[i], f"{value:+.3f}", ha="center", va="center", fontsize=8,
                                color="w" if abs(value) > 0.6 * limit else "k")
        figure.colorbar(image, ax=ax, label="tip dy")
        if yl:
            ax.set_yticks(range(len(yl)), yl)
        ax.set(ylabel=labels[1])
        if failed:
            ax.plot(x[n:], y[n:], "x", color="k", ms=9, mew=2, label="failed run")
    if xl:
        ax.set_xticks(range(len(xl)), xl)
    ax.set(xlabel=labels[0], title=title)
    if len(keys) == 1 or failed:
        ax.legend()
    return figure
