"""An energy model: the shared configuration (rest positions + displacements) and the terms whose energies add up.

The unknowns are displacements u = x - X, not positions: a stiff penalty clamp K (x - X) evaluated
from stored positions would carry a round-off of K * ulp(|x|) (1e-7 for K = 1e9, |x| ~ 2), a floor
under the attainable residual; from u it carries K * ulp(|u|), which is negligible.
"""

from __future__ import annotations

import math
from typing import TypeVar

import numpy as np

from . import Term

T = TypeVar("T", bound=Term)


class Configuration:
    """Rest positions X and displacements u of n vertices in dimension d, (n, d) float64 NumPy arrays; x = X + u.

    The terms' kernels take both as array arguments; set_displacements overwrites u in place."""

    def __init__(self, rest: np.ndarray):
        self.rest = np.array(rest, dtype=np.float64, order="C")
        self.u = np.zeros_like(self.rest)

    @property
    def n_vertices(self) -> int:
        return len(self.rest)

    @property
    def dim(self) -> int:
        return self.rest.shape[1]


class EnergyModel:
    """E(x) = sum of its terms' energies, over the displacements held in one Configuration.

    force_floor: the smallest force scale used to judge convergence (see gradient());
    energy_resolution: energy changes below it are round-off (the line search then uses |g|).
    """

    def __init__(self, rest: np.ndarray, force_floor: float, energy_resolution: float):
        self.config = Configuration(rest)
        self.terms: list[Term] = []
        self.force_floor = float(force_floor)
        self.energy_resolution = float(energy_resolution)

    @property
    def n_dofs(self) -> int:
        return self.config.dim * self.config.n_vertices

    def add(self, term: T) -> T:
        self.terms.append(term)
        return term

    def term_names(self) -> list[str]:
        return [t.name for t in self.terms]

    def set_displacements(self, u: np.ndarray) -> None:
        self.config.u[:] = np.reshape(u, self.config.u.shape)
        for t in self.terms:
            t.follow()

    def energy(self) -> float:
        return float(sum(t.energy() for t in self.terms))

    def gradient(self) -> tuple[np.ndarray, float]:
        """The total gradient (flat, interleaved) and the force scale: sum of the terms' gradient norms.

        The scale never drops below force_floor, so a state where all forces vanish (the rest
        state) counts as converged instead of dividing round-off by round-off.
        """
        parts = [t.gradient().ravel() for t in self.terms]
        scale = max(sum(float(np.linalg.norm(p)) for p in parts), self.force_floor)
        return np.sum(parts, axis=0), scale

    def fault(self) -> str | None:
        """The first term's account of why no equilibrium can be found from the current state (Term.fault), or None."""
        return next((fault for fault in (t.fault() for t in self.terms) if fault is not None), None)

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """The fixed (row, col) of the Hessian's triplets: every term's but the dynamic ones' (Term.dynamic)."""
        patterns = [t.hessian_pattern() for t in self.terms if not t.dynamic]
        return np.concatenate([p[0] for p in patterns]), np.concatenate([p[1] for p in patterns])

    def assemble(self, pattern, parts: list[np.ndarray]):
        """The sparse Hessian of the terms' parts (hessian_parts, just computed): pattern (solve/linsolve.py
        FixedPattern of hessian_pattern()) sums the fixed terms' parts, and the dynamic terms' triplets, on the
        pattern of their last hessian_values(), as its extra ones."""
        dynamic = [(t.hessian_pattern(), part) for t, part in zip(self.terms, parts, strict=True) if t.dynamic]
        fixed = [part for t, part in zip(self.terms, parts, strict=True) if not t.dynamic]
        if not dynamic:
            return pattern.matrix(fixed)
        rows, cols, values = (np.concatenate(column) for column in zip(*((r, c, v) for (r, c), v in dynamic)))
        return pattern.matrix(fixed, (rows, cols, values))

    def hessian_parts(self, psd_only: bool = False, reuse: list[np.ndarray] | None = None) -> list[np.ndarray]:
        """The terms' Hessian values, in the pattern's order (FixedPattern.matrix sums them without concatenating).
        reuse: the parts of an earlier call at the same u and psd_only, of which only the kinked terms' are computed
        again (their branches may have been chosen since: choose_branches)."""
        if reuse is None:
            return [t.hessian_values(psd_only) for t in self.terms]
        return [t.hessian_values(psd_only) if t.kinked else part for t, part in zip(self.terms, reuse, strict=True)]

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        return np.concatenate(self.hessian_parts(psd_only))

    @property
    def kinked(self) -> bool:
        """Whether a term is kinked (Term.kinked)."""
        return any(t.kinked for t in self.terms)

    def choose_branches(self, dx: np.ndarray | None) -> int:
        """Every kinked term's pieces take the branch they are on at u + dx (flat or (n, d); None: at u) for the
        Hessian and branch_shift (Term.choose_branches); returns how many pieces changed branch."""
        shaped = None if dx is None else dx.reshape(self.config.u.shape)
        return sum(t.choose_branches(shaped) for t in self.terms)

    def branch_shift(self) -> np.ndarray:
        """The gradient (flat) at u of the energy on the chosen branches minus the true gradient (Term.branch_shift)."""
        shift = np.zeros(self.n_dofs)
        for t in self.terms:
            part = t.branch_shift()
            if part is not None:
                shift += part.ravel()
        return shift

    def low_rank(self) -> list[tuple[np.ndarray, np.ndarray, float]]:
        return [part for t in self.terms for part in t.low_rank()]

    def max_step(self, dx: np.ndarray) -> float:
        return min((t.max_step(dx.reshape(self.config.u.shape)) for t in self.terms), default=math.inf)
