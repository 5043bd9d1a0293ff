"""The live solve on a reduced model (reduce/): a frame's step in r coordinates instead of the full field's, so that
an accurate mesh runs live; and where the commands leave the range the model was trained on, the full solve.

ReducedLiveEquilibrium takes, per frame, one reduced Newton step (reduce/solve.py newton, one iteration: the exact
reduced Hessian, else the PSD-projected one; the line search keeps every sampled element uninverted) toward the
reduced equilibrium at the commands, from the state on screen, until |g_r| / force scale is within the tolerance.
As LiveEquilibrium does, a step reuses the last exact Hessian's factor (a chord step: no Hessian evaluated) while
the commands move, and while they rest as long as each step contracts the residual by CHORD_MAX_CONTRACTION or
better; a chord step the line search refuses is taken again with a fresh Hessian.
Once it settles there, the full model is put at u = V q and asked what the reduced solve cannot say (each once per
equilibrium: they cost a full evaluation): whether it is a physical state (state_fault, obstacle_overlap, as
LiveEquilibrium asks) and how far it is from the full model's own equilibrium (reduce/solve.py indicator: the full
residual |g(V q)| / force scale; a reduced state sits at 1e-3 to 1 on it, never at the full tolerance).

ReducedOrFull is the live equilibrium of a view given a reduced model: the reduced one while the commands lie in
the box of the training commands, the full one (LiveEquilibrium) outside it, each starting from the other's state
when the commands cross the box's edge (u = V q one way, q = V^T u the other). Both answer the same questions as
LiveEquilibrium (frame, hold, converged, state, u, ...), so a session or a window takes either.
"""

from __future__ import annotations

import math

import numpy as np

from ..reduce.model import ReducedModel
from ..reduce.solve import Indicator, indicator, newton, outside_training
from ..solve.newton import CHORD_MAX_CONTRACTION, NewtonOptions
from ..solve.simulate import state_fault
from .equilibrium import LIVE_TOL, LiveEquilibrium


class ReducedLiveEquilibrium:
    """One reduced Newton step per frame (the module docstring); check: the indicator of the last settled state."""

    def __init__(self, model: ReducedModel, options: NewtonOptions | None = None):
        self.model, self.built = model, model.built
        self.options = options or NewtonOptions(tol=LIVE_TOL)
        self.q = np.zeros(model.n_modes)
        self.u = model.displacements(self.q)
        self.commands: np.ndarray | None = None
        self.residual, self.stuck, self.iterations = math.inf, False, 0
        self.fault: str | None = None
        self.check: Indicator | None = None
        self._factor: tuple | None = None  # the Cholesky factor of the last exact reduced Hessian (chord steps)
        self.contraction = math.inf  # the last step's residual over its start's

    @property
    def converged(self) -> bool:
        return self.residual <= self.options.tol and self.fault is None

    @property
    def state(self) -> str:
        if self.fault is not None:
            return f"no physical state: {self.fault}"
        return "equilibrium" if self.converged else "stuck" if self.stuck else "converging"

    def inside(self, commands: np.ndarray) -> bool:
        """Whether the commands lie in the box of the training commands (reduce/solve.py outside_training)."""
        return not outside_training(self.model, commands)

    def pressures(self) -> np.ndarray:
        return np.array([c.pressure() for c in self.model.chambers])

    def measures(self) -> np.ndarray:
        return np.array([c.area / c.term.rest_area for c in self.model.chambers])

    def hold(self, commands: np.ndarray, u: np.ndarray, residual: float) -> None:
        """Take a state found elsewhere (a reach, the full solve) at `commands`: its coordinates q = V^T u."""
        self.commands = np.array(commands, dtype=float)
        self.built.set_commands(self.commands)
        self.q = self.model.basis.T @ np.ravel(u)
        self.u = self.model.displacements(self.q)
        self.model.set_coordinates(self.q)
        self.residual, self.iterations, self.stuck, self.fault, self.check = residual, 0, False, None, None
        if residual <= self.options.tol:
            self._settled()

    def frame(self, commands: np.ndarray) -> bool:
        """One frame's reduced Newton step at the commands; whether the state changed."""
        moved = self.commands is None or not np.array_equal(commands, self.commands)
        if moved:
            self.commands = np.array(commands, dtype=float)
            self.built.set_commands(self.commands)
            self.stuck, self.iterations, self.fault, self.check = False, 0, None, None
        elif self.residual <= self.options.tol or self.stuck:
            return False
        reuse = self._factor if moved or self.contraction <= CHORD_MAX_CONTRACTION else None
        record = newton(self.model, self.q, self.options.tol, max_iterations=1, held=reuse)
        self.residual, self._factor = record.residual, record.factor
        self.contraction = record.residuals[-1] / record.residuals[0] if record.iterations else math.inf
        if record.iterations:
            self.q, self.iterations = record.q, self.iterations + 1
            self.u = self.model.displacements(self.q)
        elif not record.converged:  # the line search refused the step: a chord one is retried with a fresh Hessian
            self.stuck, self._factor = reuse is None, None
        if self.residual <= self.options.tol:
            self._settled()
        return bool(record.iterations)

    def _settled(self) -> None:
        """The full model at V q: whether it is a physical state, and the indicator."""
        assert self.commands is not None
        self.check = indicator(self.model, self.commands, self.q)
        self.fault = state_fault(self.built, self.commands) or self.built.obstacle_overlap()


class ReducedOrFull:
    """The reduced live equilibrium inside the training box, the full one outside it (the module docstring)."""

    def __init__(self, model: ReducedModel, options: NewtonOptions | None = None):
        self.reduced = ReducedLiveEquilibrium(model, options)
        self.full = LiveEquilibrium(model.built, self.reduced.options)
        self.active: ReducedLiveEquilibrium | LiveEquilibrium = self.reduced
        self.options = self.reduced.options

    def frame(self, commands: np.ndarray) -> bool:
        wanted = self.reduced if self.reduced.inside(commands) else self.full
        if wanted is not self.active:
            if self.active.commands is not None:
                wanted.hold(self.active.commands, self.active.u.copy(), math.inf)
            self.active = wanted
        return self.active.frame(commands)

    def hold(self, commands: np.ndarray, u: np.ndarray, residual: float) -> None:
        self.active = self.reduced if self.reduced.inside(commands) else self.full
        self.active.hold(commands, u, residual)

    def pressures(self) -> np.ndarray:
        return self.active.pressures()

    def measures(self) -> np.ndarray:
        return self.active.measures()

    @property
    def model_line(self) -> str:
        """Which model solves, in words, with the reduced state's indicator or the commands outside the box."""
        model = self.reduced.model
        if self.active is self.full:
            assert self.full.commands is not None  # set before the full one became active
            names = self.reduced.built.scene.chamber_names
            outside = [
                f"{names[i]} {c:.4g} not in {lo:.4g} .. {hi:.4g}"
                for i, c, lo, hi in outside_training(model, self.full.commands)
            ]
            return f"full model: commands outside the reduced model's training range ({'; '.join(outside)})"
        check = self.reduced.check
        residual = f"full residual {check.residual:.1e}" if check is not None else "full residual when settled"
        return f"reduced model ({model.n_modes} modes, {len(model.elements)} elements): {residual}"

    @property
    def u(self) -> np.ndarray:
        return self.active.u

    @property
    def commands(self) -> np.ndarray | None:
        return self.active.commands

    @property
    def residual(self) -> float:
        return self.active.residual

    @property
    def iterations(self) -> int:
        return self.active.iterations

    @property
    def stuck(self) -> bool:
        return self.active.stuck

    @property
    def fault(self) -> str | None:
        return self.active.fault

    @property
    def converged(self) -> bool:
        return self.active.converged

    @property
    def state(self) -> str:
        return self.active.state
