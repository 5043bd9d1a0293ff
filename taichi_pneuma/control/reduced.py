"""Inverse control on a reduced model, polished by the full one.

The search of control/inverse.py (bounded Gauss-Newton on Phi, restarts) runs on the reduced model
(reduce/model.py): every equilibrium is the reduced one, Newton in q with u = V q (reduce/solve.py equilibrium,
from the last reduced equilibrium; after a Gauss-Newton step first from the predictor q + dq/dc dc), and every
sensitivity the reduced one,

    H_r dq/dc = -V^T dr/dc,     du/dc = V dq/dc,

H_r = V^T H V the exact reduced Hessian, -dr/dc the chambers' command forces at V q (reduce/solve.py sensitivity),
from which the tip Jacobian follows as the full one does. At the reduced optimum c_r (the reduced model's best pose
for the target) the full model is solved at c_r by Newton from the reconstructed field V q (Reacher.start_from),
and the full Reacher polishes the commands from there (no restarts: a few Gauss-Newton iterations) to its own
tolerance, so the answer is the full model's. The reduced phase is judged by the indicator at c_r (reduce/solve.py
indicator: the full residual of V q, and the commands outside the training box, where the reduced model is
extrapolated and the polish has more to do). Without the polish (polish=False: a live view's dragged target, where
a frame cannot wait for the full model) the answer is the reduced model's.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from ..reduce.model import ReducedModel
from ..reduce.solve import Indicator, equilibrium, indicator, newton, sensitivity
from ..scene.targets import Target
from ..solve.newton import NewtonOptions
from ..solve.simulate import MAX_CUTS
from .inverse import Pose, Reacher, ReachOptions, ReachResult


@dataclass
class ReducedPhase:
    """The reduced search of one reach: its result (on the reduced model), the indicator at its commands, the
    seconds of the reduced search and of the full model's polish."""

    result: ReachResult
    indicator: Indicator
    seconds: float
    polish_seconds: float

    def summary_line(self, names: list[str]) -> str:
        """One line: the reduced phase's tip error, the indicator, and the two times."""
        outside = "; ".join(
            f"chamber {names[i]!r} at {value:g} outside its training range {low:g} .. {high:g}"
            for i, value, low, high in self.indicator.outside
        )
        r = self.result
        return (
            f"reduced: tip error {r.error:.3g} on the reduced model in {self.seconds:.3f} s ({r.forward_solves} "
            f"reduced solves); indicator residual {self.indicator.residual:.2e}"
            + (f"; {outside} (extrapolated)" if outside else ", inside the training box")
            + f"; full polish {self.polish_seconds:.3f} s"
        )


class ReducedReacher(Reacher):
    """A Reacher whose search runs on the reduced model and whose answers are polished by the full Reacher (the
    module docstring). bounds, options, newton (the full Newton's options), max_cuts, start: as Reacher's; the
    reduced model's poses carry their coordinates q. Its full Newton solver is the polish's; polish=False leaves
    the answer the reduced search's."""

    def __init__(
        self,
        model: ReducedModel,
        bounds=None,
        options: ReachOptions | None = None,
        newton: NewtonOptions | None = None,
        max_cuts: int = MAX_CUTS,
        start=None,
        polish: bool = True,
    ):
        self.reduced, self.polish = model, polish
        self.polisher: Reacher | None = None  # the full Reacher, made at the first polish
        super().__init__(model.built, bounds, options, newton, max_cuts, start)

    def settle(self, commands: np.ndarray, tangent: np.ndarray | None = None) -> Pose:
        """The reduced equilibrium at `commands` (clipped to the bounds) from the current one (the first from the
        nearest training equilibrium); tangent: dq/dc (r, m) there, for the first guess q + dq/dc dc. It becomes
        current; NoEquilibrium (the current pose unchanged) when there is none."""
        commands = np.clip(np.asarray(commands, float), self.lo, self.hi)
        pose, started, iterations = self.pose, time.perf_counter(), 0
        try:
            record = None
            if tangent is not None and pose.coordinates is not None:
                self.built.set_commands(commands)
                guess = newton(self.reduced, pose.coordinates + tangent @ (commands - pose.commands))
                iterations = guess.iterations
                record = guess if guess.converged else None
            if record is None:
                start = None if pose.coordinates is None else (pose.commands, pose.coordinates)
                record = equilibrium(self.reduced, commands, start, max_cuts=self.max_cuts)
                iterations += record.iterations
        finally:
            self.forward_solves += 1
            self.newton_iterations += iterations
        q = record.q
        self.pose = dataclasses.replace(
            self._pose(commands, self.reduced.displacements(q), pose.rotation),
            iterations=iterations,
            residual=record.residual,
            seconds=time.perf_counter() - started,
            coordinates=q,
        )
        return self.pose

    def _sensitivity(self) -> tuple[np.ndarray, np.ndarray]:
        """(the tip Jacobian of the reduced equilibrium, dq/dc: the tangent settle takes)."""
        assert self.pose.coordinates is not None
        sens = sensitivity(self.reduced, self.pose.commands, self.pose.coordinates)
        return sens.tip, sens.coordinates

    def reach(self, target: Target) -> ReachResult:
        """The reduced search for `target`, then the full polish (the module docstring). The result is the full
        model's: its pose, errors and counts the polish's (its full solves, the first at the reduced optimum), its
        path the reduced search's then the polish's, its `reduced` the ReducedPhase. The reduced pose stays
        current, so the next reach searches from it."""
        found = super().reach(target)
        if not self.polish:
            return found
        assert found.pose.coordinates is not None
        check = indicator(self.reduced, found.pose.commands, found.pose.coordinates)
        started, solves, iterations = time.perf_counter(), 0, 0
        if self.polisher is None:
            polish = dataclasses.replace(self.options, restarts=0)
            self.polisher = Reacher(
                self.built, (self.lo, self.hi), polish, max_cuts=self.max_cuts, first=found.pose, solver=self.solver
            )
        else:
            solves, iterations = self.polisher.forward_solves, self.polisher.newton_iterations
            self.polisher.start_from(found.pose)
        polished = self.polisher.reach(target)
        polish_seconds = time.perf_counter() - started
        n = len(found.path)
        return dataclasses.replace(
            polished,
            forward_solves=self.polisher.forward_solves - solves,  # the full solve at the reduced optimum included
            newton_iterations=self.polisher.newton_iterations - iterations,
            seconds=found.seconds + polish_seconds,
            path=found.path + polished.path,
            jumps=found.jumps + [n] + [n + j for j in polished.jumps],
            reduced=ReducedPhase(found, check, found.seconds, polish_seconds),
        )
