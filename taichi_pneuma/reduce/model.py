"""The reduced model: displacements u = V q on a basis V (N, r) with V^T V = I, and the energy

    E_r(q) = sum_T sum_{e in E_T} w_e E_e(V q) + sum_t E_t(V q),

each piecewise term T (terms/base.py Term.piecewise: the elastic term's elements, a fibre's segments, a sheet's
cells) hyper-reduced to its sampled pieces E_T with weights w (ecsw.py), the chambers and the quadratic terms
(clamp, rollers, gravity) exact in q (exact.py: a chamber's measure is a polynomial in q), every other term
(contact, effects; a piecewise term given no sampling) evaluated whole on the full field V q and projected. Its
gradient and Hessian are

    g_r = V^T g(V q),   H_r = V^T H(V q) V   (+ c (V^T a)(V^T a)^T for every rank-one part c a a^T),

a piecewise term's part of each from its sampled pieces alone: sum_e w_e V_e^T f_e and sum_e w_e V_e^T H_e V_e, by
the full term's own class and kernels on the sampled pieces only: their nodes (numbered afresh) and each piece's
energy times w_e (Term.restricted). A term sampled with no pieces (no force in any snapshot) is left out. With
V = I and every piece at w = 1 it is the full model. A scene whose terms are all piecewise, exact or quadratic never
touches the full field in a solve: the full model is put at V q only to check a state (full_state).
"""

from __future__ import annotations

import numpy as np

from ..errors import require
from ..scene.build import BuiltScene
from ..solve.linsolve import FixedPattern
from ..terms.base import Term, vertex_dofs
from .ecsw import piece_basis, piecewise_terms
from .exact import ProjectedQuadratic, ReducedChamber, projected

Samples = dict[str, tuple[np.ndarray, np.ndarray]]  # a piecewise term's label: (its pieces, their weights)


class SampledTerm:
    """sum_{e in E} w_e E_e(V q): a piecewise term restricted to its sampled pieces, their energies weighted
    (Term.restricted), on the rows of V at their nodes (the module docstring)."""

    def __init__(self, term: Term, basis: np.ndarray, pieces: np.ndarray, weights: np.ndarray):
        self.term = term.restricted(pieces, weights)
        self.vertices, self.dim = self.term.vertices, term.config.dim
        self.basis = np.ascontiguousarray(basis[vertex_dofs(self.vertices, self.dim)])  # (n_E d, r)
        self.piece_basis = piece_basis(self.term, self.basis)  # (m, k d, r)
        self.u = self.term.config.u
        self._q: np.ndarray | None = None  # the coordinates set last, and the energy and gradient there (None: not yet)
        self._energy: float | None = None
        self._gradient: np.ndarray | None = None

    def set_coordinates(self, q: np.ndarray) -> None:
        """The sampled elements at V q; their energy and gradient kept while q stays (a live frame starts where the
        last one ended)."""
        if self._q is not None and np.array_equal(q, self._q):
            return
        self._q = np.array(q, dtype=np.float64)
        self.u[:] = (self.basis @ q).reshape(self.u.shape)
        self._energy = self._gradient = None

    def set_displacements(self, u: np.ndarray) -> None:
        """The sampled elements at the full field's displacements u (n, d), in the basis or not."""
        self._q, self._energy, self._gradient = None, None, None
        self.u[:] = np.asarray(u).reshape(-1, self.dim)[self.vertices]

    def energy(self) -> float:
        if self._energy is None:
            self._energy = self.term.energy()
        return self._energy

    def gradient(self) -> np.ndarray:
        """sum_e w_e V_e^T f_e (r,)."""
        if self._gradient is None:
            self._gradient = self.basis.T @ self.term.gradient().ravel()
        return self._gradient

    def hessian(self, psd_only: bool) -> np.ndarray:
        """sum_e w_e V_e^T H_e V_e (r, r): the term's blocks H_e, exact or PSD-projected as the term projects them."""
        m, n, r = self.piece_basis.shape
        blocks = self.term.hessian_values(psd_only).reshape(m, n, n)
        product = blocks @ self.piece_basis  # H_e V_e (m, n, r)
        return self.piece_basis.reshape(m * n, r).T @ product.reshape(m * n, r)

    def max_step(self, dq: np.ndarray) -> float:
        """The term's own step bound along V dq on the sampled pieces (the elastic term's: det F > 0)."""
        return self.term.max_step((self.basis @ dq).reshape(self.u.shape))


def every_piece(built: BuiltScene) -> Samples:
    """Every piece of every piecewise term at weight 1 (no hyper-reduction)."""
    return {
        label: (np.arange(t.n_pieces), np.ones(t.n_pieces)) for label, t in piecewise_terms(built.model.terms).items()
    }


def require_elementwise(built: BuiltScene) -> None:
    """Refuse (one line) a scene whose elastic term is not a sum over elements: ECSW samples elements."""
    require(
        built.elastic.piecewise,
        f"scene {built.scene.name!r}: a reduced model hyper-reduces element-wise elasticity only (mesh."
        f"volumetric = 'element' or 'mixed'); its volumetric = {built.scene.volumetric!r} couples the elements",
    )


def fixed_pattern(terms: list) -> tuple[np.ndarray, FixedPattern]:
    """(the DOFs the terms' Hessians touch, the pattern of their triplets numbered among them), for terms whose
    Hessian pattern is fixed."""
    patterns = [t.hessian_pattern() for t in terms]
    rows = np.concatenate([np.zeros(0, dtype=np.int64), *(r for r, _ in patterns)])
    cols = np.concatenate([np.zeros(0, dtype=np.int64), *(c for _, c in patterns)])
    touched, local = np.unique(np.concatenate([rows, cols]), return_inverse=True)
    return touched, FixedPattern(local[: len(rows)], local[len(rows) :], len(touched))


class ReducedModel:
    """The reduced energy of a built scene (the module docstring) on the basis V (N, r), with the sampled pieces and
    weights of its piecewise terms by label (ecsw.piecewise_terms; a piecewise term not in it is evaluated whole).
    training: the commands (S, c) of the equilibria it was trained on and their coordinates q_s = V^T u_s (S, r), from
    which solves start (solve.py), or None. sampled: the sampled terms with pieces, by label; chambers: the reduced
    chambers, in the order of built.chambers; exact: they and the projected quadratic terms; whole: the terms
    evaluated on the full field."""

    def __init__(
        self,
        built: BuiltScene,
        basis: np.ndarray,
        samples: Samples,
        training: tuple[np.ndarray, np.ndarray] | None = None,
    ):
        require_elementwise(built)
        self.built = built
        self.model = built.model
        self.basis = np.ascontiguousarray(basis, dtype=np.float64)
        piecewise = piecewise_terms(self.model.terms)
        self.samples = {
            label: (np.asarray(pieces, dtype=np.int64), np.asarray(weights, dtype=np.float64))
            for label, (pieces, weights) in samples.items()
        }
        sizes = {label: term.n_pieces for label, term in piecewise.items()}
        for label, (pieces, weights) in self.samples.items():
            require(
                label in sizes
                and len(weights) == len(pieces)
                and 0 <= pieces.min(initial=0) <= pieces.max(initial=0)
                and pieces.max(initial=0) < sizes[label],
                f"the sampled pieces of {label!r} do not fit this scene (its piecewise terms' pieces: {sizes})",
            )
        self.sampled = {
            label: SampledTerm(piecewise[label], self.basis, pieces, weights)
            for label, (pieces, weights) in self.samples.items()
            if len(pieces)
        }
        reduced = {id(piecewise[label]) for label in self.samples}
        others = [t for t in self.model.terms if id(t) not in reduced]
        self.chambers = [ReducedChamber(c, self.basis) for c in built.chambers]
        chamber_terms = {id(c) for c in built.chambers}
        quadratic = [ProjectedQuadratic(t, self.basis, self.model) for t in others if t.quadratic]
        self.exact: list[ReducedChamber | ProjectedQuadratic] = [*self.chambers, *quadratic]
        self.whole = [t for t in others if id(t) not in chamber_terms and not t.quadratic]
        self._fixed_terms = [t for t in self.whole if not t.dynamic and len(t.hessian_pattern()[0])]
        self._fixed = fixed_pattern(self._fixed_terms)  # found once
        self.training = training

    @property
    def elements(self) -> np.ndarray:
        """The elastic term's sampled elements (ids, ascending)."""
        return self.samples["elastic"][0] if "elastic" in self.samples else np.zeros(0, dtype=np.int64)

    @property
    def n_modes(self) -> int:
        return self.basis.shape[1]

    def displacements(self, q: np.ndarray) -> np.ndarray:
        """u = V q as (n, d)."""
        return (self.basis @ q).reshape(self.model.config.u.shape)

    def set_coordinates(self, q: np.ndarray) -> None:
        """Put the model at q: the sampled terms and the exact terms at q, the full model at V q where a term is
        evaluated whole."""
        for part in [*self.sampled.values(), *self.exact]:
            part.set_coordinates(q)
        if self.whole:
            self.model.set_displacements(self.displacements(q))

    def full_state(self, q: np.ndarray) -> np.ndarray:
        """Put the full model (every term) at V q, for a check of the state (solve.py indicator); return V q (n, d)."""
        u = self.displacements(q)
        self.model.set_displacements(u)
        return u

    def energy(self) -> float:
        parts = [t.energy() for t in [*self.sampled.values(), *self.exact, *self.whole]]
        return float(sum(parts))

    def gradient(self) -> tuple[np.ndarray, float]:
        """(g_r (r,), its force scale): the scale is the sum of the parts' norms, at least the model's force_floor
        (as EnergyModel.gradient)."""
        parts = [t.gradient() for t in [*self.sampled.values(), *self.exact]]
        parts += [self.basis.T @ t.gradient().ravel() for t in self.whole]
        scale = max(sum(float(np.linalg.norm(p)) for p in parts), self.model.force_floor)
        return np.sum(parts, axis=0), scale

    def hessian(self, psd_only: bool = False) -> np.ndarray:
        """H_r (r, r), the terms' rank-one parts included (dense: r is small). The whole terms' sparse Hessians are
        projected on the rows of V at the DOFs they touch only: the fixed terms' summed on their pattern, found once
        (solve/linsolve.py FixedPattern), a dynamic term's (a contact's) on the pattern of its last values."""
        H = np.zeros((self.n_modes, self.n_modes))
        for part in [*self.sampled.values(), *self.exact]:
            H += part.hessian(psd_only)
        touched, pattern = self._fixed
        if len(touched):
            V = self.basis[touched]
            H += V.T @ (pattern.matrix([t.hessian_values(psd_only) for t in self._fixed_terms]) @ V)
        for term in self.whole:
            if term.dynamic:
                values = term.hessian_values(psd_only)  # first: its pattern is that of its last values
                H += projected(self.basis, *term.hessian_pattern(), values)
        for dofs, vector, c in (part for t in self.whole for part in t.low_rank()):
            a = self.basis[dofs].T @ vector
            H += c * np.outer(a, a)
        return H

    def max_step(self, dq: np.ndarray) -> float:
        """Largest safe step fraction along dq: the sampled terms', the exact terms' and every whole term's bound
        along V dq."""
        bounds = [t.max_step(dq) for t in [*self.sampled.values(), *self.exact]]
        if self.whole:
            dx = self.displacements(dq)
            bounds += [t.max_step(dx) for t in self.whole]
        return min(bounds)

    def command_forces(self) -> np.ndarray:
        """-dr_r/dc (r, m): column j chamber j's reduced command force (exact.ReducedChamber.command_force)."""
        return (
            np.column_stack([c.command_force() for c in self.chambers])
            if self.chambers
            else np.zeros((self.n_modes, 0))
        )
