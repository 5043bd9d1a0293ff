"""The live equilibrium of a view: one Newton step per frame toward the equilibrium at the commands on screen, so a
moving slider never waits for convergence (LiveEquilibrium); a session (session.py) and the 3D window
(interactive.py explore_solid) drive one, or its reduced counterpart (reduced.py).
"""

from __future__ import annotations

import math

import numpy as np

from ..solve.newton import CHORD_MAX_CONTRACTION, NewtonOptions, NewtonSolver
from ..solve.simulate import state_fault

# Newton tolerance of live forward solves: with the tangent predictor one Newton iteration reaches it
# (the default 1e-6 often takes two); it moves the tip by ~1e-6 of the body length, far below the 1e-3 target tolerance.
LIVE_TOL = 1e-5


class LiveEquilibrium:
    """The 3D live window's solve: one Newton step per frame, so a moving slider never waits for convergence.

    frame(commands) takes, from the state on screen, one Newton step at the commands: while they move, a
    chord step (the previous frame's factorisation reused, no Hessian assembled: solve's reuse_factor); while
    they rest, chord steps as long as each contracts the residual by CHORD_MAX_CONTRACTION or better, else a
    full Newton step, one per frame until the residual |g| / force scale is within the Newton tolerance, so the
    state a resting slider settles to is the equilibrium a full Newton solve finds at those commands. The line
    search never lets a tetrahedron invert (terms' max_step). A step the line search refuses leaves the state as
    it was and the next frame takes a fresh Hessian; where even that fails, the loop waits for the commands to move.
    A state within the tolerance is an equilibrium only if it is a physical one, as a ramp's is (simulate.settle):
    no chamber wall through itself, no element inverted (state_fault), no obstacle overlapping the body
    (BuiltScene.obstacle_overlap); otherwise `fault` says why, and the loop waits for the commands to move."""

    def __init__(self, built, options: NewtonOptions | None = None):
        self.built, self.solver = built, NewtonSolver(built.model, options or NewtonOptions(tol=LIVE_TOL))
        self.u = np.zeros_like(built.mesh.vertices)
        self.commands: np.ndarray | None = None  # the commands the state is (converging to) the equilibrium at
        self.residual, self.stuck, self.reuse = math.inf, False, False
        self.fault: str | None = None  # why the state within the tolerance is no physical one, or None
        self.contraction = math.inf  # the last step's residual over its start's
        self.iterations = 0  # Newton steps taken since the commands last moved

    @property
    def options(self) -> NewtonOptions:
        return self.solver.options

    @property
    def converged(self) -> bool:
        """Whether the state is an equilibrium at the commands: within the tolerance, and a physical state."""
        return self.residual <= self.solver.options.tol and self.fault is None

    def pressures(self) -> np.ndarray:
        """Each chamber's pressure in the model's state."""
        return np.array([c.pressure() for c in self.built.chambers])

    def measures(self) -> np.ndarray:
        """Each chamber's enclosed measure over its rest measure, in the model's state."""
        return np.array([c.area() / c.rest_area for c in self.built.chambers])

    @property
    def state(self) -> str:
        """In words: 'equilibrium' (converged), 'no physical state: ...' (within the tolerance, but `fault`), 'stuck'
        (the line search refused a fresh Hessian's step) or 'converging'."""
        if self.fault is not None:
            return f"no physical state: {self.fault}"
        return "equilibrium" if self.converged else "stuck" if self.stuck else "converging"

    def hold(self, commands: np.ndarray, u: np.ndarray, residual: float) -> None:
        """Take an equilibrium found elsewhere (an inverse-control reach) as the state at `commands`; the next
        step takes a fresh Hessian."""
        self.commands, self.u, self.residual = np.array(commands, dtype=float), u, residual
        self.built.set_commands(self.commands)
        self.iterations, self.stuck, self.reuse, self.contraction = 0, False, False, math.inf
        self.fault = None

    def frame(self, commands: np.ndarray) -> bool:
        """One frame's step at the commands; whether the state changed."""
        moved = self.commands is None or not np.array_equal(commands, self.commands)
        if moved:
            self.commands = np.array(commands, dtype=float)
            self.built.set_commands(self.commands)
            self.stuck, self.iterations, self.fault = False, 0, None
        elif self.residual <= self.solver.options.tol or self.stuck:
            return False
        reuse = self.reuse and (moved or self.contraction <= CHORD_MAX_CONTRACTION)
        u, record = self.solver.solve(self.u, max_iterations=1, reuse_factor=reuse)
        self.contraction = record.residuals[-1] / record.residuals[0] if record.iterations else math.inf
        self.residual = record.residual
        if record.iterations:
            self.u, self.iterations = u, self.iterations + 1
        elif not record.converged:  # the line search refused the step
            self.stuck = not reuse
        self.reuse = bool(record.iterations)
        if self.residual <= self.solver.options.tol:
            assert self.commands is not None  # set by the first call, whose commands always count as moved
            self.built.model.set_displacements(self.u)
            self.fault = state_fault(self.built, self.commands) or self.built.obstacle_overlap()
        return bool(record.iterations)
