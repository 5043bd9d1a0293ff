"""Equilibria of a reduced model: Newton on the coordinates q, and the error indicator of a reduced state.

Each iteration solves H_r d = -g_r with the exact reduced Hessian (a Cholesky factorisation of the dense r x r
matrix); where it is not positive definite, with the Hessian of the PSD-projected terms; where that is singular
too, with its eigenvalues clamped to at least 1e-12 of the largest. The step q <- q + alpha d starts at alpha =
min(1, 0.9 max_step) (no sampled element inverts, no contact is crossed) and halves until Armijo's condition
E_r(q + alpha d) <= E_r(q) + 1e-4 alpha g_r.d holds (or, below the model's energy resolution, until |g_r|
decreases), as the full Newton's line search (solve/newton.py). Converged when |g_r| / force scale <= tol.

A solve that does not converge is cut back as settle does (solve/simulate.py): the change of commands from the
start is halved, at most max_cuts times. A solve starts from the training equilibrium whose commands are nearest.

The indicator of a reduced state q at commands c: the full model's residual |g(V q)| / force scale (what the
reduction leaves unbalanced, on the same scale as the full Newton's tolerance), and whether c lies in the box of
the training commands (outside it the basis is extrapolated).

The sensitivity of a reduced equilibrium to the commands c: differentiating g_r(q(c), c) = V^T r(V q, c) = 0,

    H_r dq/dc = -V^T dr/dc,     du/dc = V dq/dc,

with H_r the exact reduced Hessian (never the PSD-projected one: that is no derivative of g_r) and -V^T dr/dc the
chambers' reduced command forces s(A) dA/dq (exact.py: exact in q, so the derivative of g_r itself). The tip
Jacobian follows from du/dc as the full one does.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from ..solve.newton import ARMIJO_C1, MAX_HALVINGS, STEP_SAFETY
from ..solve.sensitivity import tip_jacobian
from ..solve.simulate import MAX_CUTS, NoEquilibrium
from .model import ReducedModel
from .snapshots import nearest


@dataclass
class ReducedSolve:
    """What one reduced solve did: q reached, converged, Newton iterations (all cut-backs), cuts, residual |g_r| /
    scale, seconds, why it stopped, and the Hessian factor of its last step."""

    q: np.ndarray
    converged: bool = False
    iterations: int = 0
    cuts: int = 0
    residuals: list[float] = field(default_factory=list)
    seconds: float = 0.0
    message: str = ""
    factor: tuple | None = None  # the Cholesky factor of the exact H_r of the last step (None: none exact)

    @property
    def residual(self) -> float:
        return self.residuals[-1] if self.residuals else math.nan


def direction(model: ReducedModel, g: np.ndarray, held=None) -> tuple[np.ndarray, tuple | None]:
    """d = -H_r^-1 g_r (the module docstring: exact, else PSD-projected, else eigenvalue-clamped), and the Cholesky
    factor of the exact H_r it used (None: not the exact one). held: such a factor from an earlier state, used
    instead where it gives a descent direction (a chord step: no Hessian evaluated)."""
    if held is not None:
        d = scipy.linalg.cho_solve(held, -g)
        if g @ d < 0:
            return d, held
    for psd_only in (False, True):
        H = model.hessian(psd_only)
        try:
            factor = scipy.linalg.cho_factor(H)
            d = scipy.linalg.cho_solve(factor, -g)
        except (np.linalg.LinAlgError, ValueError):
            continue
        if g @ d < 0:
            return d, None if psd_only else factor
    values, vectors = np.linalg.eigh(H)
    values = np.maximum(values, 1e-12 * max(float(np.abs(values).max()), 1e-300))
    return -vectors @ ((vectors.T @ g) / values), None


def newton(model: ReducedModel, q0: np.ndarray, tol: float = 1e-8, max_iterations: int = 40, held=None) -> ReducedSolve:
    """Minimise the reduced energy at the commands the model holds, from q0; the model is left at the q returned.
    held: the Cholesky factor of an earlier exact H_r, for a chord first step (direction); the record's factor is
    the last one used."""
    start = time.perf_counter()
    q = np.array(q0, dtype=np.float64)
    record = ReducedSolve(q)
    model.set_coordinates(q)
    energy = model.energy()
    while True:
        g, scale = model.gradient()
        record.residuals.append(float(np.linalg.norm(g)) / scale)
        if not np.isfinite(record.residual):
            record.message = "non-finite gradient"
            break
        if record.residual <= tol:
            record.converged, record.message = True, "converged"
            break
        if record.iterations >= max_iterations:
            record.message = f"no convergence in {max_iterations} iterations"
            break
        d, record.factor = direction(model, g, held if record.iterations == 0 else None)
        slope = float(g @ d)
        alpha = min(1.0, STEP_SAFETY * model.max_step(d))
        for _ in range(MAX_HALVINGS):
            model.set_coordinates(q + alpha * d)
            trial = model.energy()
            if trial <= energy + ARMIJO_C1 * alpha * slope:
                break
            if -alpha * slope < model.model.energy_resolution and np.linalg.norm(model.gradient()[0]) < np.linalg.norm(
                g
            ):
                break
            alpha *= 0.5
        else:
            model.set_coordinates(q)
            record.message = "line search found no decrease"
            break
        q, energy = q + alpha * d, trial
        record.iterations += 1
    record.q = q
    record.seconds = time.perf_counter() - start
    return record


def equilibrium(
    model: ReducedModel,
    commands: np.ndarray,
    start: tuple[np.ndarray, np.ndarray] | None = None,
    tol: float = 1e-8,
    max_cuts: int = MAX_CUTS,
) -> ReducedSolve:
    """The reduced equilibrium at `commands`, from start = (commands, q) (default: the nearest training equilibrium),
    cut back as the module docstring says; NoEquilibrium when the cuts run out. The model is left there."""
    began = time.perf_counter()
    target = np.asarray(commands, dtype=np.float64)
    if start is None:
        assert model.training is not None, "a reduced model without training equilibria needs a start"
        train_commands, train_q = model.training
        i = nearest(train_commands, target, train_commands.min(axis=0), train_commands.max(axis=0))
        start = (train_commands[i], train_q[i])
    origin, q = np.asarray(start[0], dtype=np.float64), np.asarray(start[1], dtype=np.float64)
    done, fraction = 0.0, 1.0
    total = ReducedSolve(q)
    while True:
        trial = min(1.0, done + fraction)
        model.built.set_commands(origin + trial * (target - origin))
        record = newton(model, q, tol)
        total.iterations += record.iterations
        total.residuals += record.residuals
        if record.converged:
            q, done = record.q, trial
            if trial == 1.0:
                total.q, total.converged, total.message = q, True, "converged"
                total.seconds = time.perf_counter() - began
                return total
            continue
        if total.cuts >= max_cuts:
            raise NoEquilibrium(
                f"no reduced equilibrium at commands {np.array2string(target, precision=4)} after {total.cuts} cuts; "
                f"residual {record.residual:.2e} ({record.message})"
            )
        total.cuts += 1
        fraction /= 2


@dataclass
class Indicator:
    """residual: the full model's |g(V q)| / force scale; outside: the commands outside the training box, as (index,
    value, low, high) (none: inside)."""

    residual: float
    outside: list[tuple[int, float, float, float]]

    @property
    def inside(self) -> bool:
        return not self.outside


def outside_training(model: ReducedModel, commands: np.ndarray) -> list[tuple[int, float, float, float]]:
    """The commands outside the box of the training commands (to 1e-9 of its size), as (index, value, low, high);
    none for a model without training equilibria."""
    if model.training is None:
        return []
    low, high = model.training[0].min(axis=0), model.training[0].max(axis=0)
    slack = 1e-9 * np.maximum(high - low, np.abs(high))
    return [
        (i, float(c), float(lo), float(hi))
        for i, (c, lo, hi, s) in enumerate(zip(commands, low, high, slack))
        if c < lo - s or c > hi + s
    ]


def indicator(model: ReducedModel, commands: np.ndarray, q: np.ndarray) -> Indicator:
    """The error indicator of the reduced state q at commands (the module docstring); the full model is left at V q
    and those commands."""
    model.built.set_commands(commands)
    model.full_state(q)
    g, scale = model.model.gradient()
    outside = outside_training(model, commands)
    return Indicator(float(np.linalg.norm(g)) / scale, outside)


@dataclass
class ReducedSensitivity:
    """dq/dc (r, m), du/dc = V dq/dc (n, d, m) and the tip Jacobian (3 or 4, m: solve/sensitivity.py) of a reduced
    equilibrium."""

    coordinates: np.ndarray
    displacements: np.ndarray
    tip: np.ndarray


def sensitivity(model: ReducedModel, commands: np.ndarray, q: np.ndarray) -> ReducedSensitivity:
    """The sensitivity of the reduced equilibrium q at `commands` (the module docstring): one Cholesky (else LU)
    factorisation of the dense H_r; the model is left at q and those commands."""
    model.built.set_commands(commands)
    model.set_coordinates(q)
    rhs = model.command_forces()
    H = model.hessian(psd_only=False)
    try:
        dq = scipy.linalg.cho_solve(scipy.linalg.cho_factor(H), rhs)
    except (np.linalg.LinAlgError, ValueError):
        dq = scipy.linalg.solve(H, rhs)
    du = (model.basis @ dq).reshape(*model.model.config.u.shape, -1)
    return ReducedSensitivity(dq, du, tip_jacobian(model.built, model.displacements(q), du))
