"""Run a scene's schedule: one warm-started Newton equilibrium per increment of the chambers' commands."""

from __future__ import annotations

import collections
import time

import numpy as np

from ..fem.fields import ElementFields
from ..scene.build import BuiltScene
from ..scene.schedule import Schedule
from .columns import StepState
from .newton import NewtonOptions, NewtonSolver, SolveRecord
from .records import ChamberRecord, Run, StepRecord

MAX_CUTS = 8
STALLED_CUTS = 3  # cuts whose solves all stop near the tolerance, no nearer one after another: cutting stops
NEAR_TOLERANCE = 100.0  # "near": a residual below this many times the tolerance


def predict(built: BuiltScene, previous, current, commands: np.ndarray) -> np.ndarray:
    """Initial guess for the equilibrium at `commands`: linear extrapolation through the last two
    equilibria (c, u) along the direction the commands last moved,

        u_guess = u1 + s (u1 - u0),   s = (c - c1).(c1 - c0) / |c1 - c0|^2,

    unless a term's max_step forbids the step from u1 to it (an inverted triangle, a contact crossed);
    then the last equilibrium u1."""
    c1, u1 = current
    if previous is None:
        return u1
    c0, u0 = previous
    step = c1 - c0
    if not np.any(step):
        return u1
    move = (u1 - u0) * (float(np.dot(commands - c1, step)) / float(np.dot(step, step)))
    built.model.set_displacements(u1)
    return u1 + move if built.model.max_step(move.ravel()) > 1.0 else u1


def chamber_records(built: BuiltScene, commands: np.ndarray) -> dict[str, ChamberRecord]:
    """Each chamber's command, area, area ratio and pressure in the model's current state, by name."""
    records = {}
    for chamber, command in zip(built.chambers, commands):
        area = chamber.area()
        records[chamber.chamber_name] = ChamberRecord(
            chamber.kind.name, float(command), area, area / chamber.rest_area, chamber.pressure()
        )
    return records


def clamp_reaction(built: BuiltScene) -> dict[str, float]:
    """The force the clamp exerts on the body, R = -sum_i g_i over the pinned nodes (g: the clamp term's
    gradient), and its moment about the centroid c of the pinned nodes' rest positions, M = sum_i (x_i - c) x f_i
    (x_i the current positions, f_i = -g_i): {"fx", "fy", "mz"} in 2D, {"fx", "fy", "fz", "mx", "my", "mz"} in 3D;
    empty without a clamp."""
    clamp = built.clamp
    if clamp is None:
        return {}
    pinned = built.mesh.pinned
    f = -clamp.gradient()[pinned]
    arm = built.model.config.u[pinned] + built.mesh.vertices[pinned] - built.mesh.vertices[pinned].mean(axis=0)
    force = f.sum(axis=0)
    if built.mesh.dim == 2:
        moment = [float(np.sum(arm[:, 0] * f[:, 1] - arm[:, 1] * f[:, 0]))]
        names = ["fx", "fy", "mz"]
    else:
        moment = np.cross(arm, f).sum(axis=0).tolist()
        names = ["fx", "fy", "fz", "mx", "my", "mz"]
    return dict(zip(names, [*map(float, force), *moment]))


class RampStopped(RuntimeError):
    """The ramp ended before its last increment; `result` holds the steps done (a Run; tp.simulate's: a Result)."""

    def __init__(self, message: str, result: Run):
        super().__init__(message)
        self.result = result


class RampFailed(RampStopped):
    """An increment found no equilibrium even after cutting it back."""


class RampInterrupted(RampStopped):
    """The caller's stop() asked the ramp to end after an increment (e.g. on Ctrl-C); signum: the signal that asked,
    where the caller knows it (signals.name_of reads it)."""

    signum: int | None = None


def describe_commands(built: BuiltScene, commands: np.ndarray, reached: np.ndarray) -> str:
    """The commands of a failed solve in words, each chamber by name when there are several."""
    parts = []
    for chamber, command, last in zip(built.chambers, commands, reached):
        text = chamber.describe(command, last)
        parts.append(text if len(built.chambers) == 1 else f"chamber {chamber.chamber_name!r} {text}")
    return "; ".join(parts)


def state_fault(built: BuiltScene, commands: np.ndarray) -> str | None:
    """What makes the model's current equilibrium (at `commands`) no physical state, in words, or None: a chamber
    wall that crosses or folds through itself or turns inside out (Chamber.wall_fault), an element whose det F is
    not positive, or two pieces of the body's surface (outer surface and chamber walls alike, 2D and 3D) that share
    no node and cross (BuiltScene.surface_crossing: walls pressed through each other with no element inverted,
    which 3D, having no self-contact, does not prevent). Such a state can be an exact equilibrium of the discrete
    energy (the area penalty does not care how the wall encloses its area), so only this check tells it apart."""
    for chamber, command in zip(built.chambers, commands):
        fault = chamber.wall_fault()
        if fault is not None:
            return (
                f"chamber {chamber.chamber_name!r} {fault} at {chamber.quantity} {command:.4g}: the body "
                f"cannot take its chamber that far (a wall through itself is not physical)"
            )
    min_det = built.elastic.min_determinant()
    if not min_det > 0:
        return f"an element turned inside out (min det F = {min_det:.3g})"
    crossing = built.surface_crossing()
    if crossing is None:
        return None
    at = ", ".join(
        (f"chamber {chamber.chamber_name!r} " if len(built.chambers) > 1 else "") + f"{chamber.quantity} {command:.4g}"
        for chamber, command in zip(built.chambers, commands)
    )
    covered = any(term.name == "surface_contact" for term in built.model.terms)
    note = "" if covered else "; [effects.surface_contact] keeps the surface from passing through itself"
    return (
        f"the body's surface passes through itself{' at ' + at if at else ''}: {crossing} (a surface through itself "
        f"is not physical{note})"
    )


class NoEquilibrium(RuntimeError):
    """settle() found no equilibrium even after cutting back; the model holds the last equilibrium's u."""


class Stopped(Exception):
    """settle() was asked to stop (its stop() returned True) before it reached its target; the model holds the
    last equilibrium's u."""


def settle(
    built: BuiltScene,
    solver: NewtonSolver,
    reached: np.ndarray,
    u: np.ndarray,
    target: np.ndarray,
    previous=None,
    max_cuts: int = MAX_CUTS,
    stop=None,
):
    """Solve the equilibrium at commands `target`, starting from the equilibrium u at commands `reached`.

    The change of commands is first cut into built.sweeps equal parts, so that no obstacle moves farther than its
    sweep between two equilibria, each solved in turn. A Newton solve that does not converge, or converges to a
    state in which an obstacle overlaps the body (BuiltScene.obstacle_overlap: checked apart from the barriers), is
    cut back: the remaining change of all chamber commands is halved and
    the smaller sub-increment solved from the last equilibrium, at most max_cuts times.
    previous: the equilibrium (commands, u) before (reached, u), for the predictor, or None.
    Returns (u, commands reached, previous, the SolveRecords, cuts); raises NoEquilibrium naming the
    commands and the residual (or the overlap) when the cuts run out, or naming the fault when a converged state is
    no physical one (state_fault: the ramp and reach refuse it), Stopped when stop() (asked before every Newton
    iteration, so between cuts too) returns True.
    """
    records: list[SolveRecord] = []
    origin = reached
    done, fraction, cuts = 0.0, 1.0 / built.sweeps(origin, target), 0
    while True:
        trial = min(1.0, done + fraction)
        commands = origin + trial * (target - origin)
        built.set_commands(commands)
        u_trial, record = solver.solve(
            predict(built, previous, (reached, u), commands), reuse_factor=solver.chord, stop=stop
        )
        records.append(record)
        if record.stopped:
            built.model.set_displacements(u)
            raise Stopped
        overlap = None
        if record.converged:
            built.model.set_displacements(u_trial)
            fault = state_fault(built, commands)
            if fault is not None:  # an equilibrium of the discrete energy, but no physical state: no cut helps
                built.set_commands(reached)
                built.model.set_displacements(u)
                raise NoEquilibrium(fault)
            overlap = built.obstacle_overlap()  # checked apart from the barriers: a smaller motion may help
            if overlap is None:
                previous = (reached, u)
                u, done, reached = u_trial, trial, commands
                if trial == 1.0:
                    return u, reached, previous, records, cuts
                continue
        if cuts < max_cuts and not stalled(records, solver.options.tol):
            cuts += 1
            fraction /= 2
        else:
            built.model.set_displacements(u)
            fault = built.model.fault()  # a cause the terms keep over the increment (a held object that slipped)
            cause = f": {fault}" if fault is not None and fault not in record.message else ""
            found = f"residual {record.residual:.2e} ({record.message}{cause})"
            if stalled(records, solver.options.tol):
                found += (
                    f"; the residual stalled at {record.residual / solver.options.tol:.3g} times the tolerance over "
                    f"the last {STALLED_CUTS} cuts, so smaller increments do not help: try a looser --tol, more "
                    f"--max-iterations, a finer mesh or quadratic elements (order 2)"
                )
            if overlap is not None:
                built.set_commands(reached)
                found = (
                    f"the equilibrium found is none: {overlap} (a 3D cylinder's contact holds the body's nodes only, "
                    f"and any obstacle moved too far in one increment can pass them: smaller elements where the body "
                    f"presses on it, or a smaller motion per increment, let the barriers hold it)"
                )
            raise NoEquilibrium(
                f"no equilibrium at {describe_commands(built, commands, reached)} after {cuts} cuts; {found}"
            )


def stalled(records: list[SolveRecord], tol: float) -> bool:
    """Whether cutting the increment has stopped helping: the last STALLED_CUTS + 1 solves (the increment and its
    cuts) all failed with a finite residual below NEAR_TOLERANCE tol, none of them below half the smallest before
    it (the Newton iterations end at a floor near the tolerance, as round-off or a kink makes them, whatever the
    increment's size)."""
    last = records[-(STALLED_CUTS + 1) :]
    if len(last) <= STALLED_CUTS or any(r.converged or not r.residual < NEAR_TOLERANCE * tol for r in last):
        return False
    residuals = [r.residual for r in last]
    return all(r >= 0.5 * min(residuals[:k]) for k, r in enumerate(residuals) if k)


def step_record(
    built: BuiltScene,
    step: int,
    commands: np.ndarray,
    u: np.ndarray,
    records: list[SolveRecord],
    cuts: int,
    seconds: float,
    stretches: ElementFields,
    previous: StepRecord | None = None,
) -> tuple[StepRecord, np.ndarray]:
    """What a run records of the equilibrium u at `commands` (the model holding it), reached by the Newton solves
    `records` with `cuts` cut-backs in `seconds`: its StepRecord (chambers, tip, contact forces by term, the clamp's
    reaction, the largest stretch) and the summed contact force per node (n, d). Its angles (tip rotation, twist)
    are continued from those of `previous`, the record of the state it was solved from (none: rest, 0 degrees):
    the whole turn from rest (fem/tip.py)."""
    mesh = built.mesh
    near = (0.0, 0.0) if previous is None else (previous.tip_rotation, previous.tip_twist or 0.0)
    state = StepState(built, u, stretches, near)
    contact, contact_fz, vertex_forces = {}, {}, np.zeros_like(u)
    by_name: dict[str, np.ndarray] = {}  # the nodal forces of the terms reported under each name (Term.reported_as)
    for term, f in state.contact_forces:
        vertex_forces += f
        by_name[term.reported_as] = by_name.get(term.reported_as, 0.0) + f
    for name, f in by_name.items():
        total = f.sum(axis=0)
        contact[name] = (float(total[0]), float(total[1]), float(np.linalg.norm(f, axis=1).sum()))
        if mesh.dim == 3:
            contact_fz[name] = float(total[2])
    final = records[-1]
    record = StepRecord(
        step=step,
        chambers=chamber_records(built, commands),
        measures=state.measure(),
        iterations=sum(r.iterations for r in records),
        residual=final.residual,
        converged=final.converged,
        cuts=cuts,
        substeps=len(records) - cuts,
        seconds=seconds,
        contact=contact,
        contact_fz=contact_fz,
        clamp=clamp_reaction(built),
        extra={name: value for term in built.model.terms for name, value in term.columns().items()},
    )
    return record, vertex_forces


def run_schedule(
    built: BuiltScene,
    schedule: Schedule | None = None,
    options: NewtonOptions | None = None,
    progress=None,
    max_cuts: int = MAX_CUTS,
    stop=None,
) -> Run:
    """Solve for equilibrium at each step of the schedule (the scene's own by default), each from the last.

    An increment whose Newton solve does not converge is cut back: the remaining change of all
    chamber commands is halved and the smaller sub-increment solved from the last equilibrium, as
    often as max_cuts times per increment; every cut is counted in the history. If it still fails,
    RampFailed names the step, the commands (for pressure control, the last pressure reached) and
    the residual, and carries the steps done; so does an equilibrium that is no physical state (settle's
    state_fault: a chamber wall through itself, an inverted element), which is not kept. progress, if given, is called
    after every increment as progress(step_record, positions, contact_force): the positions (n, d), d = 2 or
    3, and, if the scene has contact, the summed contact force per node (n, d), else None; stop, if given, is asked
    stop() after every increment but the last and before every Newton iteration (so a run cutting back asks
    it too), and when it returns True the ramp ends there with RampInterrupted carrying the steps done (not
    the increment it was solving). Returns the run's records, a Run (its seconds: the wall time of this call).
    """
    started = time.perf_counter()
    schedule = schedule or built.scene.schedule
    solver = NewtonSolver(built.model, options)
    mesh = built.mesh
    contact_terms = built.contact_terms()
    u = np.zeros_like(mesh.vertices)
    stretches = mesh.fields
    steps: list[StepRecord] = []
    states: list[np.ndarray] = []  # positions
    solves: list[SolveRecord] = []  # each step's last Newton solve
    forces: list[np.ndarray] = []  # contact forces on the vertices
    reached = schedule.rest_commands
    previous = None  # (commands, u) of the equilibrium before the last one, for the predictor
    newton = {
        "linear_solver": solver.backend.name,
        "chord_steps": 0,
        "factorizations": 0,
        "phase_seconds": collections.Counter(),
    }

    def partial():
        return Run(
            built,
            steps,
            np.array(states).reshape(-1, *mesh.vertices.shape),
            solves,
            np.array(forces).reshape(-1, *mesh.vertices.shape) if contact_terms else None,
            time.perf_counter() - started,
            newton,
        )

    for i in range(schedule.increments + 1):
        start = time.perf_counter()
        target = schedule.commands(i)
        try:
            u, reached, previous, records, cuts = settle(built, solver, reached, u, target, previous, max_cuts, stop)
        except NoEquilibrium as failure:
            raise RampFailed(f"step {i}: {failure}", partial()) from None
        except Stopped:
            raise RampInterrupted(f"interrupted during step {i} of {schedule.increments}", partial()) from None
        built.set_commands(target)
        built.model.set_displacements(u)
        for record in records:
            newton["chord_steps"] += record.chord_steps
            newton["factorizations"] += record.factorizations
            newton["phase_seconds"].update(record.phase_seconds)
        step, vertex_forces = step_record(
            built, i, target, u, records, cuts, time.perf_counter() - start, stretches, steps[-1] if steps else None
        )
        for term in built.model.terms:  # after the record: friction's force is that of the increment's slip
            term.advance(u)
        steps.append(step)
        states.append(mesh.vertices + u)
        forces.append(vertex_forces)
        solves.append(records[-1])
        if progress is not None:
            progress(step, states[-1], vertex_forces if contact_terms else None)
        if stop is not None and i < schedule.increments and stop():
            raise RampInterrupted(f"interrupted after step {i} of {schedule.increments}", partial())
    return partial()
