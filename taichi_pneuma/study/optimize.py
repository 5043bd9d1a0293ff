"""A design optimisation: scene keys varied within bounds by an Optuna sampler (TPE, CMA-ES or NSGA-II) to minimise
or maximise one or two objectives under constraints (study/goals.py), each design simulated on a process pool, Ray
or this process (study/executors.py) and recorded; resumable.

    axes = check_variables(scene, [parse_vary("chambers[0].center[1]=-0.15:0.15"), parse_vary("E=5e3:2e4")])
    goals = Goals.parse(scene, [("minimize", "at(main.pressure, tip_rotation, -30)")], ["max_stretch<=1.6"])
    optimization = Optimization(scene, axes, goals, out="out", name="optimize", trials=30)
    with LocalPool(workers=2) as pool:
        report = optimization.run(pool, on_trial=print)

Batches: the sampler is asked for as many designs as the executor runs at once (its capacity()), they run
together (executor.run), and each result is told to the sampler as it comes; then the next batch. The study lives
in an SQLite file, <out>/<name>.db (Optuna's RDB storage, one transaction per change): the same study run again
(the same variables, goals, sampler, seed, base scene and solver options; a different one under that name is
refused) goes on from the trials told, asks again the designs that were running when it stopped (killed, Ctrl-C:
they are marked failed with user attribute `interrupted` and enqueued), and stops at `trials` evaluations in all.

Files under <out>: <name>/trial_NNNN/ (each evaluation's scene.toml, summary.json, history.csv, plot.png, written
whole or not at all), <name>.csv and <name>.json (every evaluation: its values, objectives, constraint violations,
feasibility, error, seconds; the JSON adds the best design or, for two objectives, the Pareto front, the executor,
versions, machine), <name>_trace.png (best so far against evaluation) and, for two objectives, <name>_pareto.png.
"""

from __future__ import annotations

import contextlib
import math
import os
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from datetime import UTC, datetime
from pathlib import Path

from .. import runtime, signals
from ..errors import require
from ..io.output import check_stem, lock_stem, prepare_directory, save_json, write_atomic
from ..scene.build import Scene
from .design import evaluate_design
from .goals import Goals, NoValue
from .optimize_figure import pareto_figure, pareto_front, trace_figure
from .refine import Refinement, start_of, worst_of
from .sweep import DEFAULT_OPTIONS, machine, versions
from .table import is_number, write_table
from .task import RunOptions, Task
from .template import SceneTemplate
from .vary import Axis, check_axes, parse_vary, require_distinct_keys

SAMPLERS = ("tpe", "cmaes", "nsga2")
MAX_TRIALS = 100_000


def check_variables(base: Scene, axes: list[Axis], template: SceneTemplate | None = None) -> list[Axis]:
    """The axes as an optimiser's variables: each a range LO:HI (LO < HI; integers if both ends are) or a list of
    choices (numbers, words, true/false), its key one the base scene takes (vary.check_axes) or, with a template,
    one of its scene()'s parameters."""
    require(len(axes) >= 1, "an optimisation varies at least one key (--vary KEY=LO:HI)")
    for axis in axes:
        where = f"--vary {axis.key}={axis.spec}"
        if axis.is_range:
            require(axis.count is None, f"{where}: an optimiser's variable is a range LO:HI (no count) or a list")
            low, high = axis.ends
            require(low < high, f"{where}: the low end {low!r} must be below the high end {high!r}")
        else:
            require(
                all(is_number(v) or isinstance(v, (str, bool)) for v in axis.items),
                f"{where}: a list of choices holds numbers, words or true/false",
            )
    if template is not None:
        require_distinct_keys(axes)
        template.check([a.key for a in axes])
        return axes
    return check_axes(base, axes)


def distribution(axis: Axis):
    from optuna.distributions import CategoricalDistribution, FloatDistribution, IntDistribution

    if not axis.is_range:
        return CategoricalDistribution(list(axis.items))
    low, high = axis.ends
    return IntDistribution(int(low), int(high)) if axis.integer else FloatDistribution(float(low), float(high))


def make_sampler(name: str, goals: Goals, trials: int, seed: int):
    """The Optuna sampler `name` (SAMPLERS), refusing what it cannot do: CMA-ES takes one objective and no
    constraints (TPE and NSGA-II read a trial's constraint violations, Trial.set_constraint). NSGA-II's population
    is trials / 4 (4 to 50) so that a short budget still breeds generations."""
    import optuna

    require(name in SAMPLERS, f"--sampler {name!r}: one of {', '.join(SAMPLERS)}")
    if name == "cmaes":
        require(len(goals.objectives) == 1, "--sampler cmaes optimises one objective; use tpe or nsga2 for two")
        require(not goals.constraints, "--sampler cmaes takes no --constraint (Optuna's CMA-ES has none); use tpe")
        return optuna.samplers.CmaEsSampler(seed=seed, warn_independent_sampling=False)
    if name == "nsga2":
        population = min(50, max(4, trials // 4))
        return optuna.samplers.NSGAIISampler(population_size=population, seed=seed)
    return optuna.samplers.TPESampler(seed=seed)


class Lost(Exception):
    """A design of the refinement was lost with a crashed worker process."""


class InProcess:
    """An executor that runs the tasks here, one after the other (a function that cannot be pickled, a test). Entered,
    it starts Taichi here as tp.simulate does (every core) unless it runs already, so that a design's runtime.init
    (one thread, as in a worker) finds it started."""

    def __enter__(self):
        runtime.ensure_initialised()
        return self

    def __exit__(self, *exc):
        return None

    def describe(self) -> dict:
        return {"executor": "this process"}

    def capacity(self) -> int:
        return 1

    def run(self, tasks: list, function=evaluate_design):
        for i, task in enumerate(tasks):
            yield i, function(task)


@dataclass
class OptimizationReport:
    """What Optimization.run did: best (the best feasible evaluation's row, one objective; None if none), pareto
    (the rows of the feasible evaluations no other dominates, two objectives), rows (every evaluation, in order),
    ran (evaluations run now), lost (designs lost with a crashed worker process: asked again by the next run),
    seconds, files written."""

    best: dict | None
    pareto: list[dict]
    rows: list[dict]
    ran: int
    lost: int
    seconds: float
    files: list[Path]


class Optimization:
    """An optimisation of `base` over `axes` towards `goals`, `trials` evaluations in all, whose files are
    <out>/<name>.* and <out>/<name>/ (the module docstring). Creating it opens (or creates) the study."""

    def __init__(
        self,
        base: Scene,
        axes: list[Axis],
        goals: Goals,
        out,
        name: str = "optimize",
        trials: int = 30,
        sampler: str = "tpe",
        seed: int = 0,
        options: RunOptions = DEFAULT_OPTIONS,
        refine: int = 0,
        template: SceneTemplate | None = None,
    ):
        require(isinstance(trials, int) and 1 <= trials <= MAX_TRIALS, f"--trials {trials!r}: 1 to {MAX_TRIALS}")
        self.axes = check_variables(base, axes, template)
        require(
            isinstance(refine, int) and 0 <= refine < trials,
            f"--refine {refine!r}: 0 to {trials - 1} (fewer than --trials {trials})",
        )
        if refine:
            require(len(goals.objectives) == 1, f"--refine {refine}: a local refinement takes one objective")
            require(
                any(a.is_range and not a.integer for a in self.axes),
                f"--refine {refine}: a local refinement needs a variable that is a range of real numbers",
            )
        self.base, self.goals, self.trials, self.options = base, goals, trials, options
        self.keys = [a.key for a in self.axes]
        self.name, self.out = check_stem(name), prepare_directory(out)
        self.scene_toml = base.to_toml()
        self.identity = {
            "keys": self.keys,
            "variables": [a.spec for a in self.axes],
            "objectives": goals.texts,
            "directions": list(goals.directions),
            "constraints": [c.text for c in goals.constraints],
            "sampler": sampler,
            "seed": seed,
            "base_scene": self.scene_toml,
            "options": asdict(options),
            **({"refine": refine} if refine else {}),  # (a study without one keeps its identity)
            **({"template_sha256": template.sha256} if template else {}),
        }
        make_sampler(sampler, goals, trials, seed)  # refuses what the sampler cannot do, before any file
        self.sampler_name, self.seed, self.refine, self.template = sampler, seed, refine, template
        self.folder = self.out / self.name
        self.db, self.csv, self.json = (self.out / f"{self.name}{s}" for s in (".db", ".csv", ".json"))
        self.trace_png, self.pareto_png = self.out / f"{self.name}_trace.png", self.out / f"{self.name}_pareto.png"
        self.columns = [
            "trial",
            *self.keys,
            *[f"objective_{i}" for i in range(len(goals.objectives))],
            *[f"violation_{i}" for i in range(len(goals.constraints))],
            "feasible",
            "seconds",
            "error",
            "folder",
        ]
        self.distributions = {a.key: distribution(a) for a in self.axes}

    def open(self):
        """The study in <name>.db: created, or read back (refused if it is another study), its interrupted
        trials marked failed and asked again."""
        import optuna
        from optuna.trial import TrialState

        optuna.logging.set_verbosity(optuna.logging.WARNING)
        storage = optuna.storages.RDBStorage(f"sqlite:///{self.db}")
        names = {s.study_name for s in optuna.get_all_study_summaries(storage)}
        if self.name in names:
            study = optuna.load_study(study_name=self.name, storage=storage)
            require(
                study.user_attrs.get("identity") == self.identity,
                f"{self.db} holds another study (other variables, goals, sampler, seed, base scene or solver "
                "options); give another --name or --out, or delete it",
            )
        else:
            study = optuna.create_study(storage=storage, study_name=self.name, directions=list(self.goals.directions))
            study.set_user_attr("identity", self.identity)
        for trial in study.get_trials(deepcopy=False, states=(TrialState.RUNNING,)):
            storage.set_trial_user_attr(trial._trial_id, "interrupted", True)
            storage.set_trial_state_values(trial._trial_id, TrialState.FAIL)
            study.enqueue_trial(trial.params, user_attrs={"asked_again": trial.number})
        # a sampler seeded past the trials made: a resumed study draws new random points, not the first ones again
        study.sampler = make_sampler(self.sampler_name, self.goals, self.trials, self.seed + len(study.trials))
        return study

    def rows(self, study) -> list[dict]:
        """Every evaluation (a trial told complete, or failed with an error), by trial number."""
        rows = []
        for trial in study.get_trials(deepcopy=False):
            attrs = trial.user_attrs
            if trial.state.name != "COMPLETE" and "error" not in attrs:
                continue  # running, waiting, or interrupted (asked again)
            violations = attrs.get("violations", [])
            rows.append(
                {
                    "trial": trial.number,
                    **{k: trial.params.get(k) for k in self.keys},
                    **{f"objective_{i}": v if math.isfinite(v) else None for i, v in enumerate(trial.values or [])},
                    **{f"violation_{i}": v for i, v in enumerate(violations)},
                    "feasible": trial.state.name == "COMPLETE"
                    and "error" not in attrs
                    and all(v <= 0 for v in violations),
                    "seconds": attrs.get("seconds"),
                    "error": attrs.get("error"),
                    "folder": attrs.get("folder"),
                    "shortfall": attrs.get("shortfall"),
                }
            )
        return sorted(rows, key=lambda row: row["trial"])

    def best(self, rows: list[dict]) -> tuple[dict | None, list[dict]]:
        """The best feasible row (one objective) and the Pareto front's rows (two objectives)."""
        feasible = [r for r in rows if r["feasible"]]
        if len(self.goals.objectives) == 2:
            return None, pareto_front(feasible, list(self.goals.directions))
        sign = 1.0 if self.goals.directions[0] == "minimize" else -1.0
        return min(feasible, key=lambda r: sign * r["objective_0"], default=None), []

    def tell(self, study, trial, row: dict | None) -> None:
        """Record an evaluation: its files under <name>/trial_NNNN/, its result told to the sampler. A design lost
        with a crashed worker process (row None) is marked interrupted, to be asked again (open)."""
        from optuna.trial import TrialState

        if row is None:
            trial.set_user_attr("interrupted", True)
            study.tell(trial, state=TrialState.FAIL)
            study.enqueue_trial(trial.params, user_attrs={"asked_again": trial.number})
            return
        error = row["error"]
        if row["files"]:
            folder = self.folder / f"trial_{trial.number:04d}"
            folder.mkdir(parents=True, exist_ok=True)
            for name, content in row["files"].items():
                binary = isinstance(content, bytes)
                write_atomic(
                    folder / name, lambda tmp, c=content, b=binary: tmp.write_bytes(c) if b else tmp.write_text(c)
                )
            trial.set_user_attr("folder", str(folder.relative_to(self.out)))
        trial.set_user_attr("seconds", row["seconds"])
        values = None
        if error is None:
            try:
                values, violations = self.goals.evaluate(row["record"])
            except NoValue as exc:
                error = str(exc)
                if exc.shortfall is not None and self.sampler_name != "cmaes":
                    # short of a level an at() asks for: worse than every design that gets there (the worst
                    # objective values), infeasible by how far it fell short (TPE and NSGA-II rank by that)
                    trial.set_user_attr("error", error)
                    trial.set_user_attr("shortfall", exc.shortfall)
                    trial.set_constraint("reached", exc.shortfall)
                    study.tell(trial, [math.inf if d == "minimize" else -math.inf for d in self.goals.directions])
                    return
        if error is not None:
            trial.set_user_attr("error", error)
            study.tell(trial, state=TrialState.FAIL)
            return
        trial.set_user_attr("violations", violations)
        if self.sampler_name != "cmaes":  # (CMA-ES takes no constraints)
            trial.set_constraint("reached", 0.0)
            for i, violation in enumerate(violations):
                trial.set_constraint(f"constraint_{i}", violation)
        study.tell(trial, values)

    def record(self, status: str, rows: list[dict], executor: dict | None, ran: int, seconds: float, lost: int) -> dict:
        best, pareto = self.best(rows)
        return {
            **self.identity,
            "status": status,
            "trials": self.trials,
            "evaluations": len(rows),
            "failed": sum(r["error"] is not None for r in rows),
            "feasible": sum(r["feasible"] for r in rows),
            "best": best,
            "pareto": pareto,
            "rows": rows,
            "ran": ran,
            "lost": lost,
            "seconds": seconds,
            "executor": executor,
            "versions": versions(ray=bool(executor and executor["executor"] == "ray")),
            "machine": machine(),
            "updated": datetime.now(UTC).isoformat(timespec="seconds"),
        }

    def write(
        self, study, status: str, executor: dict | None, ran: int, seconds: float, lost: int = 0, pictures: bool = True
    ) -> OptimizationReport:
        """The CSV, the JSON and (with pictures) the trace and Pareto pictures of every evaluation so far, each
        written whole."""
        rows = self.rows(study)
        with signals.holding():  # a signal meanwhile waits for the files
            files = [
                write_table(self.csv, self.columns, rows),
                save_json(self.json, self.record(status, rows, executor, ran, seconds, lost)),
            ]
        if pictures and any(r["error"] is None for r in rows):
            labels, directions = self.goals.texts, list(self.goals.directions)
            figure = trace_figure(rows, labels, directions)
            files.append(write_atomic(self.trace_png, lambda tmp: figure.savefig(tmp, format="png", dpi=100)))
            if len(labels) == 2:
                plane = pareto_figure(rows, labels, directions)
                files.append(write_atomic(self.pareto_png, lambda tmp: plane.savefig(tmp, format="png", dpi=100)))
        best, pareto = self.best(rows)
        return OptimizationReport(best, pareto, rows, ran, lost, seconds, files)

    def refinement(self, study, evaluate, budget: int) -> Refinement | None:
        """The local refinement (study/refine.py) from the best design so far, at most `budget` new evaluations;
        its start and its failed designs' score are stored in the study the first time, under the study's number
        of trials, so a resumed study replays the same refinement, and one continued to more trials refines
        afresh from the best design after its further sampling (the earlier refinement's designs looked up)."""
        sign = 1.0 if self.goals.directions[0] == "minimize" else -1.0
        rows = self.rows(study)
        stored = f"refine_{self.trials}"
        if stored not in study.user_attrs:
            start = start_of(rows, sign)
            chosen = None if start is None else {k: start[k] for k in self.keys}
            study.set_user_attr(stored, {"start": chosen, "worst": worst_of(rows, sign)})
        start, worst = study.user_attrs[stored]["start"], study.user_attrs[stored]["worst"]
        if start is None:
            return None  # no design has an objective value to start from: the sampler goes on
        reals = [a.key for a in self.axes if a.is_range and not a.integer]
        return Refinement(
            reals,
            {a.key: a.ends for a in self.axes if a.key in reals},
            start,
            worst,
            sign,
            len(self.goals.constraints),
            rows,
            evaluate,
            budget,
        )

    def run(self, executor, function=evaluate_design, on_trial=None) -> OptimizationReport:
        """Evaluate designs on an entered executor until `trials` evaluations are recorded, in batches of its
        capacity(); on_trial(row, (best, pareto)) after each (the best so far: Optimization.best). function(task):
        evaluate_design, or what returns rows like its (a test's analytic objective). A batch that lost designs
        with a crashed worker process (a broken pool) is the last (report.lost; the same study run again asks them
        again). Ctrl-C: the evaluations in flight are told, the files written, then it re-raises."""
        from optuna.trial import TrialState

        with lock_stem(self.out, self.name):  # no other run writes this study meanwhile
            study = self.open()
            described = executor.describe()
            start, ran, lost, status = time.perf_counter(), 0, 0, "interrupted"
            done = len(self.rows(study))
            refined = False

            def batch(asked: list) -> None:
                nonlocal ran, done, lost
                tasks = [
                    Task(self.scene_toml, {k: t.params[k] for k in self.keys}, self.options, self.template)
                    for t in asked
                ]
                for index, row in executor.run(tasks, function):
                    self.tell(study, asked[index], row)
                    if row is None:
                        lost += 1
                        continue
                    ran, done = ran + 1, done + 1
                    if on_trial is not None:
                        rows = self.rows(study)
                        on_trial(next(r for r in rows if r["trial"] == asked[index].number), self.best(rows))
                self.write(study, "running", described, ran, time.perf_counter() - start, lost, pictures=False)

            def evaluate(values: dict) -> dict:
                """One design of the refinement, run and told; its row."""
                study.enqueue_trial(values, user_attrs={"refine": True})
                trial = study.ask(self.distributions)
                batch([trial])
                if lost:
                    raise Lost
                return next(r for r in self.rows(study) if r["trial"] == trial.number)

            try:
                while done < self.trials and not lost:
                    waiting = study.get_trials(deepcopy=False, states=(TrialState.WAITING,))
                    if self.refine and not refined and not waiting and done >= self.trials - self.refine:
                        refined = True  # (once a run: what a converged refinement leaves goes to the sampler)
                        refinement = self.refinement(study, evaluate, self.trials - done)
                        with contextlib.suppress(Lost):
                            if refinement is not None:
                                refinement.run()
                        continue
                    # the sampler's batches stop where the refinement's evaluations begin (the designs asked again
                    # first, whatever the phase)
                    limit = self.trials - (self.refine if not refined else 0)
                    size = min(executor.capacity(), self.trials - done, max(limit - done, len(waiting), 1))
                    batch([study.ask(self.distributions) for _ in range(size)])
                status = "done" if not lost else "incomplete"
            finally:
                report = self.write(study, status, described, ran, time.perf_counter() - start, lost)
        return report


def optimize(
    scene: Scene | SceneTemplate,
    variables,
    *,
    minimize: str | Sequence[str] = (),
    maximize: str | Sequence[str] = (),
    constraints: Sequence[str] = (),
    trials: int = 30,
    sampler: str = "tpe",
    seed: int = 0,
    refine: int = 0,
    out: str | os.PathLike = "out",
    name: str = "optimize",
    executor=None,
    evaluate=None,
):
    """Optimise the scene's keys (pneuma-optimize; docs: Optimising a design) and return the report
    (OptimizationReport: .best, the best feasible evaluation's row with its values by dotted key
    and objective_0; .pareto, for two objectives; .rows, every evaluation; .files).

    scene: the base scene, or a study.SceneTemplate (SceneTemplate.read("part.py"): the variables are its
    scene()'s parameters, each design the Scene it returns; study/template.py).

    variables: {key: (low, high)} (integers if both are) or a list of pneuma-optimize's --vary texts
    ("KEY=LO:HI", "KEY=v1,v2"); minimize, maximize: one expression each, or a list (the minimised first, two in
    all at most); constraints: "EXPR<=VALUE" or "EXPR>=VALUE" texts; sampler: "tpe", "cmaes" or "nsga2"; refine:
    how many of the trials end the search as a local refinement by SciPy's COBYQA (study/refine.py). The study
    is kept in <out>/<name>.db: the same call again goes on from it (to `trials` evaluations in all). executor: a
    study.LocalPool(workers) or study.RayCluster(address) (not entered; this function enters it), or None: here,
    one design after another. evaluate(task) -> a row like study/design.py evaluate_design's (the default), for a
    cheap stand-in of the simulation."""
    texts = (
        [f"{k}={low!r}:{high!r}" for k, (low, high) in variables.items()] if isinstance(variables, dict) else variables
    )
    listed = [[e] if isinstance(e, str) else list(e) for e in (minimize, maximize)]
    objectives = [("minimize", e) for e in listed[0]] + [("maximize", e) for e in listed[1]]
    axes = [parse_vary(t) for t in texts]
    template = scene if isinstance(scene, SceneTemplate) else None
    base: Scene = scene.build({}) if isinstance(scene, SceneTemplate) else scene
    goals = Goals.parse(base, objectives, list(constraints))
    optimization = Optimization(base, axes, goals, out, name, trials, sampler, seed, refine=refine, template=template)
    with executor if executor is not None else InProcess() as entered:
        return optimization.run(entered, evaluate or evaluate_design)
