"""A scene's live state, apart from any window or page: the commands the user set, the equilibrium converging
toward them, the schedule played, a target reached by inverse control, the figures and fields shown, the states
kept. The browser page (live/web.py) drives one; it knows nothing of pages.

Each frame (advance) takes one Newton step toward the equilibrium at the commands (LiveEquilibrium: chord steps
while they move, full steps until the residual |g| / force scale is within the live tolerance once they rest), so a
moving slider never waits for convergence. Playing the schedule moves the commands along it by PLAY_INCREMENT of
an increment each time the state has settled, so every command played is an equilibrium before the next one; a
target for the tip is reached by inverse control (control/inverse.py: Reacher.reach from the state shown), the
commands it finds become the sliders'. Each settled equilibrium at new commands is kept, as a ramp's step is, and
save() writes them like Result.save.

Where no equilibrium is found at the commands (the Newton options' max_iterations steps since they last moved
without converging, a step the line search refuses even with a fresh Hessian: past a pressure control's limit point,
or a state within the tolerance that is no physical one: LiveEquilibrium.fault), the state goes back to the last
equilibrium and, as a ramp cuts an increment, solves half way there (MAX_CUTS times at most for one command, so a
command costs at most (2 MAX_CUTS + 1) max_iterations frames); past that, the state stays the last equilibrium and
the figures say "no equilibrium at this command". The session waits there until the commands move, then starts from
that equilibrium (at its own commands, it is shown at once).

A field shown on the body is per node: the mean over the elements that hold the node of each element's value
(fem/fields.py: the largest principal stretch, det F, the von Mises stress of the mean Cauchy stress), or the
displacement's length.
"""

from __future__ import annotations

import math
import time

import numpy as np

from ..control.inverse import Reacher, ReachOptions
from ..control.reduced import ReducedReacher
from ..errors import require, require_finite
from ..fem.fields import ElementFields
from ..limits import Budget
from ..reduce.store import load_reduced
from ..result import Result
from ..scene.build import Scene
from ..scene.targets import Target
from ..solve.newton import NewtonOptions, SolveRecord
from ..solve.simulate import MAX_CUTS, step_record
from .equilibrium import LIVE_TOL, LiveEquilibrium
from .interactive import chamber_sliders
from .reduced import ReducedOrFull

NO_EQUILIBRIUM = "no equilibrium at this command"  # the state's words where none was found
PLAY_INCREMENT = 0.25  # the schedule's step advanced per settled frame while playing (a quarter increment)
FIELDS = {  # the fields a live view colours the body by: label and unit kind (None: a ratio)
    "none": ("", None),
    "max_stretch": ("max stretch [-]", None),
    "det_F": ("det F [-]", None),
    "von_mises": ("von Mises stress", "pressure"),
    "displacement": ("displacement", "length"),
}


class LiveSession:
    """One scene built (in the budget) and held live: set commands, play, reach; advance() once per frame."""

    def __init__(self, scene: Scene, budget: Budget = Budget(), newton: NewtonOptions | None = None, reduced=None):
        self.scene, self.built = scene, scene.build(budget)
        mesh = self.mesh = self.built.mesh
        options = newton or NewtonOptions(tol=LIVE_TOL)
        self.reduced = None if reduced is None else load_reduced(reduced, self.built)
        self.equilibrium: LiveEquilibrium | ReducedOrFull = (
            LiveEquilibrium(self.built, options) if self.reduced is None else ReducedOrFull(self.reduced, options)
        )
        self.sliders = chamber_sliders(scene)
        self.commands = np.array([s.value for s in self.sliders], dtype=float)
        self.triangles = mesh.display_triangles()
        self.playing, self.schedule_step = False, 0.0
        self.driven = 0  # how often the session set the commands itself (playing, reaching): a view's sliders follow
        self._fields = ElementFields(mesh.vertices, mesh.elements)
        self._material = scene.element_material(mesh)
        self._counts = np.bincount(mesh.elements.ravel(), minlength=mesh.n_vertices).astype(float)
        self._target: np.ndarray | None = None  # a target waiting to be reached
        self._reacher: Reacher | None = None
        self.reached: float | None = None  # the last reach's distance from its target (None: none yet)
        self.steps: list = []  # the settled equilibria kept: StepRecord and positions
        self._kept_at: np.ndarray | None = None  # the commands of the last one kept
        self._positions: list[np.ndarray] = []
        self._started = time.perf_counter()
        self.failed: np.ndarray | None = None  # the commands no equilibrium was found at (the state: the last one)
        self._last: tuple | None = None  # the last equilibrium: its commands, displacements and residual
        self._goal = self.commands.copy()  # the commands the solving below is for
        self._solving = self.commands.copy()  # the commands solved at now: the goal's, or a cut back toward it
        self._cuts = 0  # the cut-backs taken for the goal

    @property
    def names(self) -> list[str]:
        return [s.name for s in self.sliders]

    def command(self, index: int, value: float) -> None:
        """Set chamber `index`'s command (a finite number, clipped to its slider's range); stops the schedule
        playing."""
        require(0 <= index < len(self.sliders), f"chamber index {index} is not one of 0 .. {len(self.sliders) - 1}")
        slider = self.sliders[index]
        value = require_finite(f"chamber {slider.name}'s command", value)
        self.commands[index] = min(max(value, slider.low), slider.high)
        self.playing = False

    def play(self, on: bool) -> None:
        """Start (from the schedule's start once it has ended) or pause playing the scene's schedule."""
        if on and self.schedule_step >= self.scene.schedule.increments:
            self.schedule_step = 0.0
        self.playing = bool(on)

    def aim(self, point) -> None:
        """Ask for the tip at `point` (scene coordinates: 2 or 3 finite numbers, the first d taken); the next frame
        reaches for it."""
        require(
            isinstance(point, (list, tuple, np.ndarray)) and self.mesh.dim <= len(point) <= 3,
            f"target {point!r} is not {self.mesh.dim} or 3 coordinates",
        )
        coordinates = [require_finite(f"target coordinate {axis}", v) for axis, v in zip("xyz", point)]
        self._target = np.array(coordinates[: self.mesh.dim])
        self.playing = False

    def advance(self) -> bool:
        """One frame: a pending target reached, else the schedule moved on (playing, settled) and one Newton step
        toward the equilibrium at the commands (or at a cut-back command on the way: _cut); an equilibrium settled
        at new commands is kept, and where none is found the last one is shown (the module docstring). Whether the
        state changed."""
        if self._target is not None:
            return self._reach(self._target)
        live = self.equilibrium
        if self.failed is not None and np.array_equal(self.failed, self.commands):
            return False
        if self.playing and self._at_commands() and live.converged:
            self.schedule_step = min(self.schedule_step + PLAY_INCREMENT, self.scene.schedule.increments)
            self.playing = self.schedule_step < self.scene.schedule.increments
            self.commands = self.scene.schedule.commands(self.schedule_step)
            self.driven += 1
        if self.failed is not None or not np.array_equal(self._goal, self.commands):  # the commands moved
            self.failed, self._goal, self._solving, self._cuts = None, self.commands.copy(), self.commands.copy(), 0
        changed = live.frame(self._solving)
        if live.converged:
            self._last = (np.array(live.commands), live.u.copy(), live.residual)
            self._solving = self.commands.copy()  # a cut-back command reached: on to the commands
        elif live.stuck or live.fault is not None or live.iterations >= live.options.max_iterations:
            return self._cut()
        self._keep()
        return changed

    def _at_commands(self) -> bool:
        """Whether the state is (converging to) the one at the commands, not at a cut-back command."""
        return self.equilibrium.commands is not None and np.array_equal(self.equilibrium.commands, self.commands)

    def _cut(self) -> bool:
        """No equilibrium found where solving: back to the last equilibrium, and from there half way (as a ramp
        cuts an increment, MAX_CUTS times for one command at most); past that, none at the commands: the state
        stays the last equilibrium and playing stops. Before any equilibrium was found (commands set before the first
        frames settled), the way back is to the undeformed body at the schedule's first commands, where a ramp
        starts."""
        start = self.scene.schedule.commands(0)
        if self._last is None and not np.array_equal(self._solving, start):
            self.equilibrium.hold(start, np.zeros_like(self.equilibrium.u), math.inf)
            self._solving = np.array(start, dtype=float)
            return True
        if self._last is not None:
            commands, u, residual = self._last
            self.equilibrium.hold(commands, u.copy(), residual)
            if self._cuts < MAX_CUTS and not np.array_equal(commands, self._solving):
                self._cuts += 1
                self._solving = commands + (self._solving - commands) / 2
                return True
        self.failed, self.playing = self.commands.copy(), False
        return True

    def _reach(self, point: np.ndarray) -> bool:
        """Reach for the target from the state shown (the reacher settled at the commands on screen first; where
        none was found there, at the last equilibrium's)."""
        self._target = None
        if self.failed is not None and self.equilibrium.commands is not None:
            self.commands, self.failed = np.array(self.equilibrium.commands), None
        if self._reacher is None:
            bounds = (np.array([s.low for s in self.sliders]), np.array([s.high for s in self.sliders]))
            options = ReachOptions(restarts=0, reuse_factor=True)
            self._reacher = (
                Reacher(self.built, bounds, options, self.equilibrium.options, start=self.commands)
                if self.reduced is None
                else ReducedReacher(
                    self.reduced, bounds, options, self.equilibrium.options, start=self.commands, polish=False
                )
            )
        reacher = self._reacher
        if not np.array_equal(reacher.pose.commands, self.commands) or not np.array_equal(
            reacher.pose.u, self.equilibrium.u
        ):
            reacher.settle(self.commands)
        result = reacher.reach(Target(tuple(point)))
        self.reached = float(result.error)
        self.commands = np.array(result.pose.commands, dtype=float)
        self.driven += 1
        self.equilibrium.hold(self.commands, result.pose.u, result.pose.residual)
        self._keep()
        return True

    def _keep(self) -> None:
        """Keep the state if it is an equilibrium at commands not kept last."""
        live = self.equilibrium
        if live.commands is None or not live.converged or not self._at_commands():
            return
        if self._kept_at is not None and np.array_equal(self._kept_at, live.commands):
            return
        self._kept_at = np.array(live.commands)
        record = SolveRecord(converged=True, iterations=live.iterations, residuals=[live.residual])
        step, _ = step_record(
            self.built,
            len(self.steps),
            live.commands,
            live.u,
            [record],
            0,
            time.perf_counter() - self._started,
            self._fields,
            self.steps[-1] if self.steps else None,
        )
        self.steps.append(step)
        self._positions.append(self.mesh.vertices + live.u)

    def positions(self) -> np.ndarray:
        """The node positions shown (n, d)."""
        return self.mesh.vertices + self.equilibrium.u

    def field(self, name: str) -> np.ndarray | None:
        """The field `name` (a FIELDS key) per node at the state shown; None for 'none'."""
        require(name in FIELDS, f"field {name!r} is not one of {', '.join(FIELDS)}")
        if name == "none":
            return None
        u = self.equilibrium.u
        if name == "displacement":
            return np.linalg.norm(u, axis=1)
        law, parameters = self._material if name == "von_mises" else (None, None)
        cells = self._fields.at(self.mesh.vertices + u, law, parameters)[name]
        nodal = np.zeros(self.mesh.n_vertices)
        np.add.at(nodal, self.mesh.elements, cells[:, None])
        return nodal / np.maximum(self._counts, 1.0)

    def figures(self) -> dict:
        """The state's figures: tip (its mean displacement, d values) and rotation (degrees), per chamber the
        command and pressure, the Newton iterations since the commands last moved, the residual and whether it
        is an equilibrium, the schedule's step and whether it plays, the last reach's distance to its target. The
        rotation is continued from the last state kept (fem/tip.py: the whole turn from rest)."""
        from ..fem.tip import tip_measures

        live = self.equilibrium
        tip, rotation = tip_measures(self.mesh, live.u, self.steps[-1].tip_rotation if self.steps else 0.0)
        return {
            "tip": np.asarray(tip, dtype=float),
            "rotation": float(rotation),
            "commands": self.commands.copy(),
            "pressures": live.pressures(),
            "iterations": live.iterations,
            "residual": float(live.residual),
            "state": NO_EQUILIBRIUM if self.failed is not None else live.state,
            "schedule_step": self.schedule_step,
            "playing": self.playing,
            "reach_error": self.reached,
            "model": live.model_line if isinstance(live, ReducedOrFull) else None,
        }

    def result(self) -> Result:
        """The equilibria kept so far as one run's Result (its history, states, summary, video)."""
        require(bool(self.steps), "nothing to save yet: no equilibrium has settled")
        return Result(
            self.built, list(self.steps), np.array(self._positions), seconds=time.perf_counter() - self._started
        )

    def save(self, directory, stem: str) -> list:
        """Write the kept equilibria under directory as Result.save does (<stem>_history.csv, _states.npz,
        _summary.json, _scene.toml, _plot.png, ParaView files); return the paths."""
        return self.result().save(directory, stem)
