"""Static inverse kinematics: the chamber commands that put the tip where you want it.

For a target tip point t (optionally a tip rotation theta_t), weights w and bounds lo <= q <= hi on
the chamber commands q (area ratios or pressures), minimise over q

    Phi(q) = |f(q)|^2 + rho^2 |s - s_ref|^2,    s = (q - lo) / (hi - lo)   (commands scaled to [0, 1]),
    f(q)   = (w_x (x(q) - t_x) / L,  w_y (y(q) - t_y) / L,  w_theta (theta(q) - theta_t) [radians],
              w_z (z(q) - t_z) / L),

with (x, y, z) the tip point and theta its rotation (about z) at the equilibrium of q and L the body
length. theta is the whole turn from rest, each equilibrium's continued from that of the one it was solved
from (fem/tip.py): theta_t = -200 asks for a clockwise curl past half a turn, which +160 is not. The z row
only for an (x, y, z) target on a 3D body, the theta row only when it is targeted. The regulariser
(rho, default 1e-4, towards the rest commands s_ref) acts only when the chambers outnumber the targeted
quantities: redundant chambers then take the least actuation that reaches the target; with no redundancy it
is off, so a reachable target is met exactly.

Each iteration linearises f with the sensitivity J = df/ds (sensitivity.py: exact Hessian, direct
method) and takes the bounded least-squares step (SciPy's lsq_linear, BVLS: exact at the bounds)

    min_ds |f + J ds|^2 + rho^2 |s + ds - s_ref|^2,    -s <= ds <= 1 - s,

then solves the equilibrium at the new commands (simulate.settle, from the last one, with the
first guess u + du/dq dq on the tangent). A step that does not decrease Phi by a fraction 1e-4 of
its predicted decrease is halved and solved again from the last accepted equilibrium. Every
iterate lies inside the bounds.

A descent stops *reached* when |tip - t| <= tol L, over the coordinates t gives (and
|theta - theta_t| <= angle_tol when the rotation is targeted); short of it when a step no longer moves the scaled
commands by step_tol, decreases Phi by less than a fraction `stall` of it, or the halvings or max_iterations run out.
Then the descent starts again from the centre of the command box and from quasi-random commands
(`restarts` in all: Phi need not be convex, e.g. the reference tip first lifts, then curls down as
the chamber grows). If none reaches the target it is *unreachable*: the closest pose found is kept,
and the chambers at a bound are named ("unreachable: closest tip error 0.12; chamber 'top' at its
max pressure 900").
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.optimize import lsq_linear
from scipy.stats import qmc

from ..errors import require, require_finite
from ..fem.tip import COLUMNS as TIP_COLUMNS
from ..fem.tip import tip_measures
from ..result import Result
from ..scene.build import BuiltScene, Scene
from ..scene.targets import Target
from ..solve.newton import NewtonOptions, NewtonSolver
from ..solve.records import StepRecord
from ..solve.sensitivity import sensitivity
from ..solve.simulate import MAX_CUTS, NoEquilibrium, chamber_records, settle

ARMIJO = 1e-4


def command_bounds(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) per chamber: the scene's `bounds`, or by default its kind's default_bounds of its keyframe
    values (the range its schedule drives: the rest command and every keyframe value)."""
    lo, hi = [], []
    for (name, _), control in zip(scene.geometry.chambers, scene.controls):
        if control.bounds is not None:
            low, high = control.bounds
        else:
            low, high = control.kind.default_bounds([float(v) for _, v in control.schedule.keyframes])
            require(
                low < high, f"chamber {name!r}: its keyframes span no range of commands; give it bounds = [min, max]"
            )
        lo.append(low)
        hi.append(high)
    return np.array(lo, float), np.array(hi, float)


def body_length(built: BuiltScene) -> float:
    """The longer side of the rest body's bounding box: the length scale of the tip tolerance."""
    return float(np.ptp(built.mesh.vertices, axis=0).max())


@dataclass(frozen=True)
class ReachOptions:
    """tol: tip position tolerance, a fraction of the body length; angle_tol: degrees; regularization:
    rho of the module docstring; step_tol: smallest move of the scaled commands that counts as progress;
    stall: a descent whose step decreases Phi by less than this fraction of it stops (a minimum short of
    the target); restarts: descents from other commands after one that stops short; reuse_factor: take
    the Jacobian from Newton's last factorisation of the exact Hessian (within one Newton step of the
    equilibrium) instead of factorising it at the equilibrium: a little less exact, one factorisation
    fewer per iteration (live mode)."""

    tol: float = 1e-3
    angle_tol: float = 0.5
    regularization: float = 1e-4
    max_iterations: int = 40
    max_halvings: int = 6
    step_tol: float = 1e-9
    stall: float = 1e-3
    restarts: int = 4
    reuse_factor: bool = False

    def __post_init__(self):
        for name in ("tol", "angle_tol", "step_tol"):
            require(require_finite(name, getattr(self, name)) > 0, f"{name} = {getattr(self, name)!r} must be > 0")
        require(
            require_finite("regularization", self.regularization) >= 0,
            f"regularization = {self.regularization!r} must be >= 0",
        )
        require(
            isinstance(self.max_iterations, int) and self.max_iterations >= 1,
            f"max_iterations = {self.max_iterations!r} must be an integer >= 1",
        )
        for name in ("max_halvings", "restarts"):
            value = getattr(self, name)
            require(isinstance(value, int) and value >= 0, f"{name} = {value!r} must be an integer >= 0")


@dataclass
class Pose:
    """An equilibrium: the commands, the displacements (n, d), the tip point (d,) (scene coordinates) and
    rotation (degrees, about z in 3D; continued from the pose it was solved from, fem/tip.py), and the forward
    solve that found it (Newton iterations, residual, seconds); coordinates: q, u = V q, on a reduced model."""

    commands: np.ndarray
    u: np.ndarray
    tip: np.ndarray
    rotation: float
    iterations: int = 0
    residual: float = 0.0
    seconds: float = 0.0
    coordinates: np.ndarray | None = None


@dataclass
class ReachResult:
    """What one reach did. path: the accepted equilibria, the starting one first; jumps: the indices in path
    of the poses not reached by a step from the one before (a restart's start, the best pose re-taken)."""

    target: Target
    pose: Pose
    error: float
    angle_error: float | None
    reached: bool
    active: list[tuple[str, str, str, float]]  # (chamber, "min" | "max", its kind's quantity, value)
    iterations: int
    forward_solves: int
    newton_iterations: int
    seconds: float
    path: list[Pose] = field(default_factory=list)
    jumps: list[int] = field(default_factory=list)
    reduced: Any = None  # a control/reduced.py ReducedPhase: the reduced search before the full model's polish

    def summary_line(self) -> str:
        """One line: 'reached: ...' or 'unreachable: closest tip error ...; chamber ... at its max ...'."""
        tip = ", ".join(f"{v:.6g}" for v in self.pose.tip)
        rotation = f", rotation {self.pose.rotation:+.2f} deg" + (
            f" (error {self.angle_error:.3g} deg)" if self.angle_error is not None else ""
        )
        if self.reached:
            return f"reached: tip ({tip}){rotation}; tip error {self.error:.3g}"
        bounds = "; ".join(
            f"chamber {name!r} at its {side} {unit} {value:g}" for name, side, unit, value in self.active
        )
        angle = f", rotation error {self.angle_error:.3g} deg" if self.angle_error is not None else ""
        return f"unreachable: closest tip error {self.error:.3g}{angle} at tip ({tip}); " + (
            bounds or "no bound active (a local minimum of the tip error)"
        )


class Objective:
    """Phi of the module docstring for one target and one Reacher's bounds.

    f = scale * (measured(pose) - target)[rows]: lengths over L, the rotation in radians; rows: x and y,
    z for an (x, y, z) target, and the rotation when targeted. rho is 0 unless chambers are redundant."""

    def __init__(self, reacher: Reacher, target: Target):
        self.target, self.reacher = target, reacher
        mesh = reacher.built.mesh
        require(len(target.tip) <= mesh.dim, f"target tip = {list(target.tip)!r}: a 2D scene's tip is [x, y]")
        require(
            target.angle is None or len(mesh.tip) >= 2,
            f"target angle {target.angle!r}: the tip rotation needs at least 2 tip vertices "
            f"(this mesh has {len(mesh.tip)})",
        )
        self.rows = [0, 1] + ([3] if len(target.tip) == 3 else []) + ([2] if target.angle is not None else [])
        self.rho = reacher.options.regularization if len(reacher.names) > len(self.rows) else 0.0
        self.span = reacher.hi - reacher.lo
        rest = reacher.built.scene.schedule.rest_commands
        self.s_ref = np.clip((rest - reacher.lo) / self.span, 0.0, 1.0)
        w_x, w_y, w_angle = target.weights
        length = reacher.length
        self.scale = np.array([w_x / length, w_y / length, w_angle * math.pi / 180.0, target.weight_z / length])[
            self.rows
        ]
        x, y, *z = target.tip
        self.wanted = np.array([x, y, target.angle or 0.0, *(z or [0.0])])[self.rows]

    def value(self, pose: Pose) -> tuple[np.ndarray, np.ndarray, float]:
        """(f, s, Phi) at a pose."""
        f = self.scale * (measured(pose)[self.rows] - self.wanted)
        s = (pose.commands - self.reacher.lo) / self.span
        return f, s, float(f @ f + self.rho**2 * np.sum((s - self.s_ref) ** 2))

    def done(self, pose: Pose) -> bool:
        """Within tol L of the tip point, and angle_tol of the rotation when it is targeted."""
        error, angle_error = self.reacher._errors(self.target, pose)
        opts = self.reacher.options
        return error <= opts.tol * self.reacher.length and (angle_error is None or angle_error <= opts.angle_tol)


def measured(pose: Pose) -> np.ndarray:
    """(tip x, tip y, rotation in degrees) and in 3D tip z: the rows of the tip Jacobian (sensitivity.py)."""
    return np.array([pose.tip[0], pose.tip[1], pose.rotation, *pose.tip[2:]])


class Reacher:
    """Inverse control of one built scene; holds the current equilibrium, so each reach starts from the last.

    bounds: (lo, hi) arrays per chamber (default command_bounds). start: the commands of the first
    equilibrium (clipped to the bounds), by default the centre of the box lo..hi: the rest state is a
    poor place to linearise, as with no pressure a chamber's first effect on the tip is often the
    opposite of its later one (the reference beam's tip first lifts, then curls down). first: instead, a pose
    whose displacements are the first guess at its commands (start_from: Newton there, no continuation from rest),
    e.g. a reduced model's pose, u = V q. solver: a NewtonSolver of built.model to use instead of a new one of the
    options `newton` (its symbolic analysis shared)."""

    def __init__(
        self,
        built: BuiltScene,
        bounds=None,
        options: ReachOptions | None = None,
        newton: NewtonOptions | None = None,
        max_cuts: int = MAX_CUTS,
        start=None,
        first: Pose | None = None,
        solver: NewtonSolver | None = None,
    ):
        moving = [o.name for o in built.scene.obstacles if o.moving]
        require(
            not moving,
            f"obstacle {moving[0] if moving else ''!r} moves (has keyframes): inverse control drives the chambers "
            f"only, so a scene's obstacles must be static there (drop its keyframes)",
        )
        self.built, self.options, self.max_cuts = built, options or ReachOptions(), max_cuts
        self.solver = solver or NewtonSolver(built.model, newton)
        self.names = [c.chamber_name for c in built.chambers]
        self.units = [c.kind.quantity for c in built.chambers]
        lo, hi = bounds if bounds is not None else command_bounds(built.scene)
        self.lo, self.hi = np.asarray(lo, float), np.asarray(hi, float)
        require(
            self.lo.shape == self.hi.shape == (len(self.names),) and np.all(self.lo < self.hi),
            f"bounds {self.lo.tolist()} .. {self.hi.tolist()} must give min < max for each of "
            f"{len(self.names)} chambers",
        )
        self.length = body_length(built)
        self.forward_solves = self.newton_iterations = 0
        rest = built.scene.schedule.rest_commands
        self.pose, self._previous = self._pose(rest, np.zeros_like(built.mesh.vertices), 0.0), None
        self._factored: Pose | None = None  # the pose whose exact Hessian the solver's factor is
        if first is None:
            self.settle((self.lo + self.hi) / 2 if start is None else start)
        else:
            self.start_from(first)

    def _pose(self, commands: np.ndarray, u: np.ndarray, near: float) -> Pose:
        """The pose of the equilibrium u at commands, its rotation continued from `near`, that of the pose it was
        solved from (fem/tip.py: the whole turn from rest)."""
        mesh = self.built.mesh
        rotation = tip_measures(mesh, u, near)[1]
        return Pose(np.array(commands, float), u, (mesh.vertices[mesh.tip] + u[mesh.tip]).mean(axis=0), rotation)

    def settle(self, commands: np.ndarray, tangent: np.ndarray | None = None) -> Pose:
        """The equilibrium at `commands` (clipped to the bounds), from the current one; it becomes current.
        Raises simulate.NoEquilibrium (the current pose unchanged) when there is none.

        tangent: du/dq (n, d, m) at the current pose, for the first guess u + du/dq dq (Newton then often
        needs one iteration): handed to simulate.predict as a previous equilibrium on the tangent line."""
        commands = np.clip(np.asarray(commands, float), self.lo, self.hi)
        previous = self._previous
        if tangent is not None:
            dq = commands - self.pose.commands
            previous = (self.pose.commands - dq, self.pose.u - tangent @ dq)
        start = time.perf_counter()
        try:
            u, _, previous, records, _ = settle(
                self.built, self.solver, self.pose.commands, self.pose.u, commands, previous, self.max_cuts
            )
        finally:
            self.forward_solves += 1
        iterations = sum(r.iterations for r in records)
        self.newton_iterations += iterations
        self._previous = previous
        self.pose = dataclasses.replace(
            self._pose(commands, u, self.pose.rotation),
            iterations=iterations,
            residual=records[-1].residual,
            seconds=time.perf_counter() - start,
        )
        # Newton's last factor: the exact Hessian within one Newton step of this equilibrium
        self._factored = self.pose if records[-1].iterations and records[-1].exact_factor else None
        return self.pose

    def start_from(self, first: Pose) -> Pose:
        """The equilibrium at first.commands (clipped to the bounds) by Newton from first.u, its rotation continued
        from first.rotation (where that finds none, by settle from the current pose); it becomes current."""
        current = self.pose, self._previous
        commands = np.clip(first.commands, self.lo, self.hi)
        self.pose = Pose(commands, np.asarray(first.u, float), first.tip, first.rotation)
        self._previous = None
        try:
            return self.settle(commands)
        except NoEquilibrium:
            self.pose, self._previous = current
            return self.settle(commands)

    def _sensitivity(self) -> tuple[np.ndarray, np.ndarray]:
        """(the tip Jacobian (3 or 4, m) at the current pose, the tangent settle takes: du/dq (n, d, m))."""
        sens = sensitivity(
            self.built,
            self.pose.commands,
            self.pose.u,
            self.solver.pattern,
            self.solver.backend,
            factorised=self.options.reuse_factor and self._factored is self.pose,
        )
        return sens.tip, sens.displacements

    def _errors(self, target: Target, pose: Pose) -> tuple[float, float | None]:
        error = tip_error(target, pose)
        if target.angle is None:
            return error, None
        return error, abs(pose.rotation - target.angle)

    def reach(self, target: Target) -> ReachResult:
        """Find the commands whose equilibrium puts the tip at `target` (see the module docstring).

        The descent starts from the current pose; if that ends short of the target, it starts again
        from the centre of the command box, then from quasi-random commands (`restarts` in all),
        and keeps the closest pose found."""
        start = time.perf_counter()
        solves0, newton0 = self.forward_solves, self.newton_iterations
        goal = Objective(self, target)
        path, iterations, jumps = [self.pose], 0, []
        best = self.pose
        starts = (q for q in self._restart_commands() if np.any(q != self.pose.commands))
        while True:
            reached, steps = self._descend(goal, path)
            iterations += steps
            if goal.value(self.pose)[2] < goal.value(best)[2] or reached:
                best = self.pose
            if reached:
                break
            try:
                restart = next(starts)
            except StopIteration:
                break
            try:
                path.append(self.settle(restart))
                jumps.append(len(path) - 1)
            except NoEquilibrium:
                continue
        if best is not self.pose:
            self.pose, self._previous = best, None
            path.append(best)
            jumps.append(len(path) - 1)
        self.built.set_commands(best.commands)
        self.built.model.set_displacements(best.u)
        error, angle_error = self._errors(target, best)
        active = [
            (name, side, unit, float(value))
            for name, unit, value, low, high in zip(self.names, self.units, best.commands, self.lo, self.hi)
            for side, bound in (("min", low), ("max", high))
            if value == bound
        ]
        return ReachResult(
            target,
            best,
            error,
            angle_error,
            reached,
            active,
            iterations,
            self.forward_solves - solves0,
            self.newton_iterations - newton0,
            time.perf_counter() - start,
            path,
            jumps,
        )

    def _restart_commands(self) -> list[np.ndarray]:
        """Commands to restart a descent from: the centre of the box, then scrambled Sobol points."""
        unit = [np.full(len(self.lo), 0.5)]
        if self.options.restarts > 1:
            unit += list(qmc.Sobol(len(self.lo), seed=0).random(2 ** math.ceil(math.log2(self.options.restarts))))
        return [self.lo + s * (self.hi - self.lo) for s in unit[: self.options.restarts]]

    def _descend(self, goal: Objective, path: list[Pose]) -> tuple[bool, int]:
        """Bounded Gauss-Newton steps from the current pose (module docstring); (reached, iterations)."""
        opts = self.options
        for iteration in range(opts.max_iterations):
            if goal.done(self.pose):
                return True, iteration
            f, s, phi = goal.value(self.pose)
            tip, tangent = self._sensitivity()
            jac = goal.scale[:, None] * tip[goal.rows] * goal.span
            a = np.vstack([jac, goal.rho * np.eye(len(s))])
            b = np.concatenate([-f, -goal.rho * (s - goal.s_ref)])
            ds = lsq_linear(a, b, bounds=(-s, 1.0 - s), method="bvls").x
            for _ in range(opts.max_halvings + 1):
                if np.max(np.abs(ds)) < opts.step_tol:
                    return False, iteration
                predicted = phi - float(np.sum((a @ ds - b) ** 2))
                current = self.pose, self._previous
                try:
                    trial = self.settle(self.lo + np.clip(s + ds, 0.0, 1.0) * goal.span, tangent)
                    decrease = phi - goal.value(trial)[2]
                    if decrease >= ARMIJO * predicted:
                        break
                    self.pose, self._previous = current  # back to the last accepted equilibrium
                except NoEquilibrium:
                    pass
                ds = ds / 2
            else:
                return False, iteration
            path.append(self.pose)
            if decrease < opts.stall * phi and not goal.done(self.pose):
                return False, iteration + 1  # crawling towards a minimum short of the target
        return goal.done(self.pose), opts.max_iterations

    def follow(self, targets: list[Target], progress=None) -> list[ReachResult]:
        """Reach each target in order, each from the pose the last one reached; progress(result) after each."""
        results = []
        for target in targets:
            results.append(self.reach(target))
            if progress is not None:
                progress(results[-1])
        return results


def tip_error(target: Target, pose: Pose) -> float:
    """The distance from the tip point to the target's, over the coordinates the target gives (x, y[, z])."""
    return float(np.linalg.norm(pose.tip[: len(target.tip)] - target.tip))


def frames(reacher: Reacher, results: list[ReachResult]) -> Result:
    """Every accepted equilibrium of a sequence of reaches, in order, as one run's Result (its history CSV,
    states and video are made as a ramp's are): each step's record carries the extra columns target (the
    index of the target pursued), target_x, target_y, target_angle (nan for a free angle), the tip point
    tip_x, tip_y and its distance to the target, tip_error (in 3D also target_z, nan where z is free, and
    tip_z), and descent: a count that goes up at every pose not reached by a step from the frame before (a
    restart, the best pose re-taken)."""
    built, mesh = reacher.built, reacher.built.mesh
    rest_tip = mesh.vertices[mesh.tip].mean(axis=0)
    steps: list[StepRecord] = []
    states: list[np.ndarray] = []
    descent = 0
    for k, result in enumerate(results):
        target = result.target
        for j, pose in enumerate(result.path[1 if k else 0 :], start=1 if k else 0):
            descent += j in result.jumps
            built.set_commands(pose.commands)
            built.model.set_displacements(pose.u)
            extra = {
                "target": k,
                "target_x": target.tip[0],
                "target_y": target.tip[1],
                "target_angle": math.nan if target.angle is None else target.angle,
                "tip_x": pose.tip[0],
                "tip_y": pose.tip[1],
                "tip_error": tip_error(target, pose),
                "descent": descent,
            }
            if mesh.dim == 3:
                extra.update(target_z=target.tip[2] if len(target.tip) == 3 else math.nan, tip_z=pose.tip[2])
            measures = dict(zip(TIP_COLUMNS, map(float, pose.tip - rest_tip)), tip_rotation=pose.rotation)
            stretch = mesh.fields.largest_stretch(mesh.vertices + pose.u)
            measures.update(min_det=built.elastic.min_determinant(), max_stretch=stretch)
            steps.append(
                StepRecord(
                    step=len(steps),
                    chambers=chamber_records(built, pose.commands),
                    measures=measures,
                    iterations=pose.iterations,
                    residual=pose.residual,
                    converged=True,
                    cuts=0,
                    substeps=1,
                    seconds=pose.seconds,
                    extra=extra,
                )
            )
            states.append(mesh.vertices + pose.u)
    built.set_commands(reacher.pose.commands)
    built.model.set_displacements(reacher.pose.u)
    return Result(built, steps, np.array(states), seconds=sum(r.seconds for r in results))
