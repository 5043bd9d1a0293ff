"""Projected Newton with a backtracking line search over an EnergyModel.

Each iteration solves  (H + sum_j c_j u_j u_j^T) d = -g,  where H is the assembled sparse
Hessian (fixed pattern, factorised) and the rank-1 parts enter by the Woodbury identity.

H is the exact Hessian (unprojected elastic blocks, the chamber's pressure load stiffness) on the
first iteration and after a full step (alpha = 1, the sign that Newton is in its quadratic basin),
unless it cannot be factorised or its direction is not a descent direction; otherwise it is the PSD
one (each element's d2psi/dF2 eigen-clamped, the chamber's Gauss-Newton part only). Projected-only
Newton converges linearly on this problem; the exact Hessian near equilibrium restores quadratic
convergence, while the PSD one keeps far-off iterations stable. A Cholesky backend refuses an
indefinite sparse part H; after the first iteration SciPy's LU then factorises it: past a limit point
under volume or syringe control H alone is indefinite (it is the Hessian under pressure control)
while H plus the chamber's rank-1 part is positive definite at the stable equilibrium. (At the first
iteration the commands have just moved, the exact Hessian is a poor model there, and the PSD one is used.)
CHOLMOD's refusal (3D) goes to the PSD Hessian instead: an LU of a 3D system costs 15x its Cholesky
factorisation.

With the iterative backend (CG with multigrid, linsolve.py) d solves H d = -g only to the relative residual
eta = forcing_term(r, tol) at the Newton residual r: an inexact Newton method, as quadratically convergent
as the exact one while eta <= r. Where CG does not reach eta, an exact H is given up for the PSD one (an LU
of a large 3D Hessian is what the iterative backend avoids), and a PSD H goes to the direct backend.

In 3D a factorisation costs 3-10 times the rest of an iteration (more the larger the system), so a direction
may instead solve with the factorisation the backend holds, d = -H_old^-1 g (a chord step of modified Newton: a
descent direction while H_old is positive definite; the chamber's rank-1 parts are always the current ones).
Newton takes one after a full step (alpha = 1) that contracted the residual by rho = r_k / r_k-1 <=
CHORD_MAX_CONTRACTION, and more while each contracts it so and at most CHORD_MAX_NEEDED more, log(tol / r) /
log(rho), would reach the tolerance; otherwise a fresh Hessian. A solve may also start with one (reuse_factor: the
ramp's next increment, the live window's next frame). A chord step is taken whole or not at all: where its full step
does not decrease the energy enough (Armijo), it is given up for a fresh Hessian, as a line search along a poor
model's direction leaves the iterate off the path (pneunet_3d's 18 increments: 183 iterations with such steps, 85
without, the whole run 47.8 s against 29.3 s). The rule counts steps, not seconds, so a run's iterates do not depend
on the machine's load. (In 2D a factorisation costs about what the rest of an iteration does: no chord steps.)

A kinked term (Term.choose_branches: piecewise smooth, as a tension-only cord is taut or slack) makes Newton's
quadratic model wrong wherever a piece changes branch between u and u + d: a slack cord's model carries no stiffness,
the step stretches it far, the line search halves, and the active set thrashes (a stiff embedded cord: 143
iterations and 2 cut-backs for one increment). So d is solved again, up to BRANCH_SWEEPS times, with H and g of the
branches each piece is on at u + d (g shifted by the gradient difference, Term.branch_shift: a slack cord taut at
u + d enters with its two-sided force k (l - L0) < 0 and stiffness k n n^T), until no piece changes branch: a
primal-dual active-set / semismooth Newton step on the model (with the smooth terms' Hessian values of the first
solve: only the kinked terms' are computed again). A sweep whose Hessian differs from the factorised one by a rank
of at most MAX_UPDATE_RANK (a few segments changed branch) solves with the held factorisation and that difference
by the Woodbury identity (solve/branch_update.py; NewtonOptions.sweep_updates), any other a factorisation: the same
direction, to round-off, at a fraction of the cost (on the shipped bending actuator about half of the sweeps change
at most 3 segments: benchmarks/fibers.py). The energy, gradient and residual stay the exact ones. A model with a
kinked term takes no chord steps: a factorisation of another iterate's branches is a poor model (the fibre-reinforced
actuator: 20-40% more iterations and time with them). Taken only where every piece is on the factorisation's branch
at u and at u + d, they still cost iterations (35 to 40 for its first 2 kPa), and its ramp in 2 increments to 30 kPa
then found no equilibrium past 8.6 kPa; starting each direction on the branches at the last step's full length
(u + (1 - alpha) d) instead of those at u made more sweeps, not fewer.

The step u <- u + alpha d (u: displacements) starts at alpha = min(1, 0.9 max_step), the terms'
safe bound (no triangle inverts), and halves until the Armijo condition

    E(u + alpha d) <= E(u) + c1 alpha g.d

holds (a NaN energy never does), or, once the predicted decrease -alpha g.d is below the model's
energy resolution (a sum over thousands of elements cannot resolve smaller changes in float64),
until the gradient norm decreases instead. Converged when |g| / force_scale <= tol (force_scale:
the sum of the terms' force norms, see EnergyModel.gradient). Nothing fails silently: the
record says whether it converged and why it stopped; where it breaks down (a non-finite gradient, no
descent direction, no decrease) and a term names itself the cause (EnergyModel.fault: a material law
unstable at the state reached), the record gives that cause instead of the symptom.
"""

from __future__ import annotations

import math
import time
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np

from ..errors import require, require_finite
from ..terms.model import EnergyModel
from .branch_update import branch_update
from .linsolve import (
    BACKENDS,
    FactorizationError,
    FixedPattern,
    direct_backend,
    installed,
    make_backend,
    solve_low_rank_updated,
)

ARMIJO_C1 = 1e-4
MAX_HALVINGS = 40
STEP_SAFETY = 0.9
FORCING_MAX = 0.01  # forcing_term's largest eta
CHORD_MAX_CONTRACTION = 0.5  # a chord step contracting the residual less than this is followed by a fresh Hessian
BRANCH_SWEEPS = 4  # direction re-solves on the branches at u + d of kinked terms (the module docstring)
MAX_UPDATE_RANK = 9  # ... by a low-rank update of the held factorisation up to this rank (3 cord segments in 3D)
CHORD_MAX_NEEDED = 3  # ... and so is one after which more than this many would be needed to reach tol


def forcing_term(residual: float, tol: float) -> float:
    """The relative residual eta to which an iterative backend solves H d = -g at the Newton residual
    r = |g| / force scale: the next residual is about eta r + O(r^2), so eta = min(FORCING_MAX, r) keeps
    Newton's quadratic convergence (an inexact Newton method's forcing term; a looser FORCING_MAX, 0.1, cost
    Newton iterations on the nearly incompressible octant, more than the CG iterations it saved), and
    eta >= 0.1 tol / r stops solving more exactly than needed to land below tol (0.1 tol away from it)."""
    return max(min(FORCING_MAX, residual), 0.1 * tol / residual)


class PhaseClock:
    """Accumulates wall time per named phase into a dict: `with clock("factorize"): ...`."""

    def __init__(self, seconds: dict[str, float]):
        self.seconds = seconds

    @contextmanager
    def __call__(self, phase: str):
        start = time.perf_counter()
        try:
            yield
        finally:
            self.seconds[phase] = self.seconds.get(phase, 0.0) + time.perf_counter() - start


@dataclass
class SolveRecord:
    """What one Newton solve did."""

    converged: bool = False
    iterations: int = 0
    residuals: list[float] = field(default_factory=list)
    energies: list[float] = field(default_factory=list)
    step_sizes: list[float] = field(default_factory=list)
    line_search_trials: int = 0
    psd_fallbacks: int = 0
    exact_factor: bool = False  # the backend holds the exact Hessian of an iterate of this solve
    chord_steps: int = 0  # iterations that solved with a factorisation already held (no new Hessian)
    chord_rejected: int = 0  # chord steps tried and given up for a fresh Hessian (their full step not a decrease)
    factorizations: int = 0  # factorisations tried (branch sweeps' and refused ones included)
    stopped: bool = False  # the caller's stop() ended the solve
    phase_seconds: dict[str, float] = field(default_factory=dict)
    seconds: float = 0.0
    message: str = ""

    @property
    def residual(self) -> float:
        return self.residuals[-1] if self.residuals else math.nan


@dataclass
class NewtonOptions:
    tol: float = 1e-6
    max_iterations: int = 40
    linear_solver: str = "auto"
    chord_steps: bool | None = None  # reuse a held factorisation (the module docstring); None: in 3D only
    sweep_updates: bool = True  # branch sweeps of low rank by the held factorisation (the module docstring)

    def __post_init__(self):
        require(require_finite("tol", self.tol) > 0, f"tol = {self.tol!r} must be > 0")
        require(
            isinstance(self.max_iterations, int) and self.max_iterations >= 1,
            f"max_iterations = {self.max_iterations!r} must be an integer >= 1",
        )
        require(
            self.linear_solver in ("auto", *BACKENDS),
            f"linear solver = {self.linear_solver!r} is not one of auto, {', '.join(BACKENDS)}",
        )


class NewtonSolver:
    """Projected Newton over one EnergyModel; the sparsity pattern is analysed once."""

    def __init__(self, model: EnergyModel, options: NewtonOptions | None = None):
        self.model = model
        self.options = options or NewtonOptions()
        rows, cols = model.hessian_pattern()
        self.pattern = FixedPattern(rows, cols, model.n_dofs)
        self.backend = make_backend(self.options.linear_solver, model.config.rest)
        # an exact H that CHOLMOD refuses is not handed to an LU: in 3D an LU costs 15x the Cholesky factorisation
        # (1.15 s against 0.07 s at 12k DOFs) and fills far more; the PSD H serves instead
        self.indefinite_backend = (
            None
            if self.backend.name == "cholmod"
            else self.backend
            if self.backend.name == "scipy"
            else make_backend("scipy")
        )
        self.direct_backend = (
            self.backend
            if self.backend.name != "amg"
            else make_backend("cholmod" if installed("cvxopt") else direct_backend(), model.config.rest)
        )
        self.factored_by, self.factored = self.backend, False  # the backend holding the last factorisation
        self.factored_exact = False  # ... and whether it is of an exact Hessian
        self.factorizations = 0  # factorisations tried by this solver
        self.kinked_patterns = [t.hessian_pattern() if t.kinked else None for t in model.terms]
        self.chord = (
            model.config.dim == 3 and not model.kinked if self.options.chord_steps is None else self.options.chord_steps
        )
        self.cg_failed = False  # CG failed on a PSD Hessian of this model: the direct backend serves from then on

    def _energy_at(self, u: np.ndarray) -> float:
        self.model.set_displacements(u)
        return self.model.energy()

    def _backends(self, psd_only: bool, indefinite: bool) -> tuple:
        """The backends to try in turn: an exact H that a Cholesky backend refuses goes to SciPy's LU if indefinite
        (see the module docstring); the iterative backend's PSD H, where CG fails, to the direct backend (its
        exact H to the PSD one instead: an LU of a large 3D Hessian is what the iterative backend avoids). Once CG
        has failed on a PSD H, the direct backend takes every later H of this solver (CG's failed iterations would
        otherwise come before every direct factorisation of the run)."""
        if self.backend.name == "amg":
            if self.cg_failed:
                return (self.direct_backend,)
            return (self.backend, self.direct_backend) if psd_only else (self.backend,)
        if indefinite and not psd_only and self.indefinite_backend is not None:
            return self.backend, self.indefinite_backend
        return (self.backend,)

    def _direction(
        self, g: np.ndarray, psd_only: bool, clock: PhaseClock, indefinite: bool = False, rtol: float | None = None
    ) -> tuple[np.ndarray, float]:
        """Newton direction d = -H^-1 g (to the relative residual rtol where the backend is iterative) and the
        slope g.d (nan when every backend fails); indefinite: see _backends. Where kinked terms' pieces change
        branch between u and u + d, d is solved again with H and g of the branches at u + d (BRANCH_SWEEPS), by a
        low-rank update of the last factorisation where its rank is at most MAX_UPDATE_RANK (a direct backend's: CG
        preconditioned by multigrid gains nothing from it)."""
        with clock("hessian"):
            factored = self.model.hessian_parts(psd_only)
        d = self._solve(-g, factored, psd_only, clock, indefinite, rtol)
        for _ in range(BRANCH_SWEEPS):
            if not np.isfinite(d[0]) or not self.model.choose_branches(d):
                break
            with clock("hessian"):
                values = self.model.hessian_parts(psd_only, factored)
                low_rank = self.model.low_rank()
                update = (
                    branch_update(self.kinked_patterns, factored, values, MAX_UPDATE_RANK)
                    if self.options.sweep_updates and self.factored_by.name != "amg"
                    else None
                )
            rhs = -g - self.model.branch_shift()
            if update is None:
                d, factored = self._solve(rhs, values, psd_only, clock, indefinite, rtol), values
            else:
                with clock("solve"):
                    d = solve_low_rank_updated(self.factored_by, rhs, low_rank + update, rtol)
        self.model.choose_branches(None)
        return d, float(g @ d)

    def _solve(
        self,
        rhs: np.ndarray,
        values: list[np.ndarray],
        psd_only: bool,
        clock: PhaseClock,
        indefinite: bool,
        rtol: float | None,
    ) -> np.ndarray:
        """H^-1 rhs with a fresh factorisation of the Hessian of the terms' parts `values` (nan where every backend
        fails)."""
        with clock("hessian"):
            low_rank = self.model.low_rank()
        with clock("assemble"):
            matrix = self.model.assemble(self.pattern, values)
        for backend in self._backends(psd_only, indefinite):
            try:
                self.factorizations += 1
                with clock("factorize"):
                    backend.factorize(matrix)
                with clock("solve"):
                    d = solve_low_rank_updated(backend, rhs, low_rank, rtol)
                break
            except FactorizationError:  # singular, indefinite for a Cholesky backend, CG not converged
                self.cg_failed |= psd_only and backend.name == "amg"
                continue
        else:
            return rhs * math.nan
        self.factored_by, self.factored, self.factored_exact = backend, True, not psd_only
        return d

    def _reused_direction(self, g: np.ndarray, clock: PhaseClock, rtol: float) -> tuple[np.ndarray, float]:
        """d = -H_old^-1 g with the factorisation the backend holds (a chord step) and the slope g.d; nan where
        none is held."""
        if not self.factored:
            return g * math.nan, math.nan
        with clock("solve"):
            try:
                d = solve_low_rank_updated(self.factored_by, -g, self.model.low_rank(), rtol)
            except FactorizationError:  # the held factor is of a singular matrix: a fresh Hessian instead
                return g * math.nan, math.nan
        return d, float(g @ d)

    def _chord_pays(self, record: SolveRecord, chord_last: bool) -> bool:
        """Whether the next direction is a chord step, with the held factorisation (see the module docstring).
        chord_last: the last step was a chord step."""
        if not (self.chord and self.factored and record.step_sizes and record.step_sizes[-1] == 1.0):
            return False
        rho = record.residuals[-1] / record.residuals[-2]
        if not chord_last:
            return rho <= CHORD_MAX_CONTRACTION
        return rho <= CHORD_MAX_CONTRACTION and math.log(
            self.options.tol / record.residual
        ) >= CHORD_MAX_NEEDED * math.log(rho)

    def solve(
        self, u0: np.ndarray, max_iterations: int | None = None, reuse_factor: bool = False, stop=None
    ) -> tuple[np.ndarray, SolveRecord]:
        """Minimise the model's energy over displacements from u0 (n, d); returns the final u (n, d) and the record.

        max_iterations: this call's cap (default the options'; a live loop takes one step per frame).
        reuse_factor: the first direction is a chord step, with the factorisation the backend already holds (that
        of a direction of the previous call, at other commands or displacements) instead of a new Hessian;
        where it is not a descent direction, a fresh Hessian is taken.
        stop: asked before every iteration; when it returns True the solve ends unconverged, record.stopped set."""
        start = time.perf_counter()
        model, opts = self.model, self.options
        u = np.array(u0, dtype=np.float64).ravel()
        record = SolveRecord()
        clock = PhaseClock(record.phase_seconds)
        factorizations = self.factorizations
        with clock("line_search"):
            energy = self._energy_at(u)
        chord = False  # the last step was a chord step
        full = True  # the last step with a new Hessian was a full one (alpha = 1): the next Hessian may be exact
        while True:
            with clock("gradient"):
                g, scale = model.gradient()
            record.residuals.append(float(np.linalg.norm(g)) / scale)
            record.energies.append(energy)
            if not np.isfinite(record.residual):
                record.message = model.fault() or "non-finite gradient"
                break
            if record.residual <= opts.tol:
                record.converged = True
                record.message = "converged"
                break
            cap = opts.max_iterations if max_iterations is None else max_iterations
            if record.iterations >= cap:
                record.message = f"no convergence in {cap} iterations"
                break
            if stop is not None and stop():
                record.stopped, record.message = True, "stopped"
                break
            exact = full
            rtol = forcing_term(record.residual, opts.tol)
            chord = (reuse_factor and not record.step_sizes) or self._chord_pays(record, chord)
            d, slope = self._reused_direction(g, clock, rtol) if chord else (None, math.nan)
            step = None  # a chord step's (alpha, energy), taken only whole
            if chord and slope < 0:
                with clock("line_search"):
                    step = self._line_search(u, d, g, energy, slope, record, halvings=1)
                if step[0] != 1.0:  # a poor model: not worth a line search, a fresh Hessian instead
                    record.chord_rejected += 1
                    self.model.set_displacements(u)
                    step, slope = None, math.nan
            if not slope < 0:
                chord = False
                d, slope = self._direction(g, not exact, clock, bool(record.step_sizes), rtol)
            else:
                exact = False
            if exact and not slope < 0:
                record.psd_fallbacks += 1
                exact = False
                d, slope = self._direction(g, True, clock, rtol=rtol)
            record.exact_factor = self.factored_exact and self.factored_by is self.backend
            if not slope < 0:
                record.message = model.fault() or f"not a descent direction (g.d = {slope:.3e})"
                break
            if step is None:
                with clock("line_search"):
                    step = self._line_search(u, d, g, energy, slope, record)
            alpha, trial = step
            if alpha == 0.0:
                self.model.set_displacements(u)
                record.message = model.fault() or "line search found no decrease (energy at round-off)"
                break
            assert d is not None  # a descent direction, of slope < 0
            u = u + alpha * d
            energy = trial
            record.iterations += 1
            record.chord_steps += chord
            record.step_sizes.append(alpha)
            full = full if chord else alpha == 1.0
        record.factorizations = self.factorizations - factorizations
        record.seconds = time.perf_counter() - start
        return u.reshape(model.config.u.shape), record

    def _line_search(self, u, d, g, energy, slope, record, halvings: int = MAX_HALVINGS) -> tuple[float, float]:
        """Backtrack from min(1, 0.9 max_step), trying at most `halvings` steps; return (alpha, energy there), or (0,
        nan) if nothing is accepted."""
        model = self.model
        alpha = min(1.0, STEP_SAFETY * model.max_step(d))
        for _ in range(halvings):
            record.line_search_trials += 1
            trial = self._energy_at(u + alpha * d)
            if trial <= energy + ARMIJO_C1 * alpha * slope:
                return alpha, trial
            if -alpha * slope < model.energy_resolution and np.linalg.norm(model.gradient()[0]) < np.linalg.norm(g):
                return alpha, trial
            alpha *= 0.5
        return 0.0, math.nan
