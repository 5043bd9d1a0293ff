"""The local refinement that ends an optimisation (Optimization, --refine N): SciPy's COBYQA, a derivative-free
trust-region method on quadratic models that keeps to bounds and nonlinear inequality constraints, started from the
best design found so far.

The range variables are scaled to x in [0, 1]^n (x_k = (v_k - low_k) / (high_k - low_k)); integer and list
variables keep the start design's values. COBYQA minimises

    s * f(x)   subject to   c_i(x) <= -MARGIN  (i = 1 .. m),

s = +1 to minimise the objective f, -1 to maximise it; c_i the constraints' violations (study/goals.py). A design
with no objective value (short of a level at() asks for, or failed) scores the worst s * f the sampler's designs
had and, with constraints, violates each by its shortfall (1 if it failed): a flat or infeasible region that
COBYQA's trust region shrinks away from. (No constraint is given COBYQA when the study has none: a constraint
identically 0, on its bound everywhere, stalls its steps.) MARGIN, 1e-7 in the constraint's units, keeps a
design COBYQA converges to on a constraint's bound strictly feasible: COBYQA counts a violation under its
feasibility tolerance (about 1.5e-8) as none, the study none at all. COBYQA starts with a trust region of
radius 0.1 (a tenth of each range: the sampler has found the basin) and stops at 1e-3 or when the evaluations run
out.

Every design COBYQA asks for is first looked up among the study's evaluations (the same values to 1e-12 of each
range): COBYQA being deterministic, a resumed study replays the refinement to where it stopped, from the start
design and worst score stored in the study, and goes on without running a design twice.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

INITIAL_RADIUS, FINAL_RADIUS = 0.1, 1e-3
MARGIN = 1e-7  # COBYQA's constraints c_i <= -MARGIN (the module docstring)
FAILED = 1.0  # c_i(x) of a design that failed (no value, no shortfall)


class Spent(Exception):
    """The evaluations given to the refinement are spent."""


def start_of(rows: list[dict], sign: float) -> dict | None:
    """The design the refinement starts from: the best feasible row, else the one with the least largest
    violation among those with an objective value; None if no row has one."""
    scored = [r for r in rows if r["error"] is None and r.get("objective_0") is not None]
    feasible = [r for r in scored if r["feasible"]]
    if feasible:
        return min(feasible, key=lambda r: sign * r["objective_0"])
    violations = [k for k in (scored[0] if scored else {}) if k.startswith("violation_")]
    return min(scored, key=lambda r: max((r[k] for k in violations), default=0.0), default=None)


def worst_of(rows: list[dict], sign: float) -> float:
    """The worst scaled objective s * f among the rows with a value: a failed design's score."""
    return max((sign * r["objective_0"] for r in rows if r.get("objective_0") is not None), default=0.0)


class Refinement:
    """COBYQA over the range variables `keys` (bounds[k] = (low, high)) from `start` (a row: every variable's
    value), each new design run by evaluate(values) -> its row, at most `budget` of them (Spent after).
    `known`: the rows already evaluated (a resumed study's), looked up before running a design."""

    def __init__(
        self,
        keys: list[str],
        bounds: dict[str, tuple[float, float]],
        start: dict,
        worst: float,
        sign: float,
        constraints: int,
        known: list[dict],
        evaluate: Callable[[dict], dict],
        budget: int,
    ):
        self.keys, self.bounds, self.start, self.worst, self.sign = keys, bounds, start, worst, sign
        self.constraints, self.known, self.evaluate, self.budget = constraints, list(known), evaluate, budget
        self.ran = 0

    def values(self, x: np.ndarray) -> dict:
        """The design at scaled point x: the start's values with the range variables replaced."""
        design = dict(self.start)
        for k, xi in zip(self.keys, np.clip(x, 0.0, 1.0)):
            low, high = self.bounds[k]
            design[k] = float(low + xi * (high - low))
        return design

    def row(self, design: dict) -> dict:
        """The evaluated row of this design: a known one with the same values, else a new evaluation."""
        for row in self.known:
            if all(abs(row[k] - design[k]) <= 1e-12 * (self.bounds[k][1] - self.bounds[k][0]) for k in self.keys):
                return row
        if self.ran >= self.budget:
            raise Spent
        self.ran += 1
        row = self.evaluate(design)
        self.known.append(row)
        return row

    def scores(self, x: np.ndarray) -> tuple[float, np.ndarray]:
        """(s * f, [c_1, ..., c_m]) at x (the module docstring)."""
        row = self.row(self.values(x))
        objective = row.get("objective_0")
        if row["error"] is None and objective is not None and math.isfinite(objective):
            return self.sign * objective, np.array([row[f"violation_{i}"] for i in range(self.constraints)])
        shortfall = row.get("shortfall")
        return self.worst, np.full(self.constraints, FAILED if shortfall is None else shortfall)

    def run(self) -> None:
        """COBYQA from the start until it converges or the budget is spent."""
        from scipy.optimize import Bounds, NonlinearConstraint, minimize

        x0 = np.array(
            [(self.start[k] - self.bounds[k][0]) / (self.bounds[k][1] - self.bounds[k][0]) for k in self.keys]
        )
        constraints = [NonlinearConstraint(lambda x: self.scores(x)[1], -np.inf, -MARGIN)] if self.constraints else []
        try:
            minimize(
                lambda x: self.scores(x)[0],
                x0,
                method="COBYQA",
                bounds=Bounds(np.zeros_like(x0), np.ones_like(x0)),
                constraints=constraints,
                options={"initial_tr_radius": INITIAL_RADIUS, "final_tr_radius": FINAL_RADIUS, "maxfev": 10**6},
            )
        except Spent:
            pass
