"""A design study: one scene run many times with dotted scene keys varied over a grid or a Latin hypercube sample,
each run a task on a local process pool or on Ray, one CSV row per run.

    axes = [parse_vary("chambers[0].center[1]=-0.15:0.15:3"), parse_vary("material.E=1e4,2e4")]
    sweep = Sweep(base_scene, axes, out="out", name="sweep")     # reads the rows done before (resumable)
    with LocalPool(workers=2) as pool:                          # or RayCluster(address)
        report = sweep.run(pool, on_row=print)

Rows are appended (and fsynced) to <name>.csv as runs finish; the same study run again reads them back and runs
only the rest. <name>.json records the grid, the base scene, the versions and the machine; <name>.png plots the
tip deflection against the varied keys.
"""

from __future__ import annotations

import csv
import os
import platform
import time
from dataclasses import asdict, dataclass
from datetime import UTC, datetime
from importlib import metadata
from pathlib import Path
from typing import Any

from .. import backend, signals
from ..errors import require
from ..io.output import check_stem, lock_stem, open_appending, prepare_directory, save_json, write_atomic
from ..scene.build import Scene
from .figure import study_figure
from .table import cell, read_done, run_key, table_columns, write_table
from .task import RunOptions, Task
from .vary import MAX_RUNS, Axis, check_axes, plan

DEFAULT_OPTIONS = RunOptions()  # a study's solver options unless given


def versions(ray: bool = False) -> dict:
    names = ["taichi-pneuma", backend.NAME, "numpy", "scipy"] + (["ray"] if ray else [])
    found: dict[str, str | None] = {}
    for name in names:
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            found[name] = None
    return {"python": platform.python_version(), **found}


def machine() -> dict:
    model = None
    try:
        model = next(
            line.split(":", 1)[1].strip()
            for line in Path("/proc/cpuinfo").read_text().splitlines()
            if line.startswith("model name")
        )
    except (OSError, StopIteration):
        pass
    return {
        "platform": platform.platform(),
        "machine": platform.machine(),
        "cpu": model or platform.processor(),
        "cores": os.cpu_count(),
    }


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

    def __init__(
        self,
        base: Scene,
        axes: list[Axis],
        out,
        name: str = "sweep",
        samples: int | None = None,
        seed: int = 0,
        options: RunOptions = DEFAULT_OPTIONS,
        retry_failed: bool = False,
        max_runs: int = MAX_RUNS,
    ):
        require(len(axes) >= 1, "a study varies at least one key (--vary KEY=SPEC)")
        axes = check_axes(base, axes)
        self.base, self.axes, self.samples, self.seed, self.options = base, axes, samples, seed, options
        self.keys = [a.key for a in axes]
        self.runs = plan(axes, samples, seed, max_runs)
        self.scene_toml = base.to_toml()
        self.columns = table_columns(self.keys, base)
        self.name = check_stem(name)
        self.out = prepare_directory(out)
        self.csv, self.json, self.png = (self.out / f"{name}{suffix}" for suffix in (".csv", ".json", ".png"))
        self.identity = {"keys": self.keys, "base_scene": self.scene_toml, "options": asdict(options)}
        with lock_stem(self.out, name):  # (the sweep app holds it from before this to the end of run())
            self.done = read_done(self.csv, self.json, self.identity, self.columns, self.keys, retry_failed)
        self.todo = [run for run in self.runs if run_key(run) not in self.done]

    def record(self, status: str, executor: dict | None = None, report: Report | None = None) -> dict:
        grid = {
            "axes": [
                {"key": a.key, "spec": a.spec, **({"values": a.grid()} if self.samples is None else {})}
                for a in self.axes
            ],
            "sampling": "full grid" if self.samples is None else "latin hypercube",
            "samples": self.samples,
            "seed": self.seed,
            "runs": len(self.runs),
        }
        data: dict[str, Any] = {
            **self.identity,
            "status": status,
            "grid": grid,
            "executor": executor,
            "versions": versions(ray=bool(executor and executor["executor"] == "ray")),
            "machine": machine(),
            "updated": datetime.now(UTC).isoformat(timespec="seconds"),
        }
        if report is not None:
            data["result"] = {k: getattr(report, k) for k in ("planned", "skipped", "ran", "failed", "lost", "seconds")}
            data["result"]["runs_per_second"] = report.ran / report.seconds if report.ran else None
        return data

    def rows(self, new: dict[tuple, dict]) -> tuple[list[dict], list[dict]]:
        """The rows of the planned runs (in plan order), and those of runs this plan does not hold."""
        everything = {**self.done, **new}
        order = [run_key(run) for run in self.runs]
        planned = set(order)
        return [everything[k] for k in order if k in everything], [
            row for k, row in everything.items() if k not in planned
        ]

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
        write_table(self.csv, self.columns, sum(self.rows({}), []))  # the rows kept, whole (drops a cut-off line)
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
            report = Report(
                len(self.runs),
                len(self.runs) - len(self.todo),
                len(new),
                sum(row.get("error") is not None for row in rows),
                lost,
                time.perf_counter() - start,
                rows,
                [self.csv, self.json],
            )
            with signals.holding():  # a signal meanwhile waits for the files
                write_table(self.csv, self.columns, rows + others)
                save_json(self.json, self.record(status, described, report))
        if any(row.get("tip_dy") is not None and row.get("error") is None for row in rows):
            figure = study_figure(
                rows, self.keys, sampled=self.samples is not None, labels=[a.label for a in self.axes]
            )
            report.files.append(write_atomic(self.png, lambda tmp: figure.savefig(tmp, format="png", dpi=100)))
        return report
