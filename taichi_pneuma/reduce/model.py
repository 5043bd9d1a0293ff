"""The reduced model: displacements u = V q on a basis V (N, r) with V^T V = I, and the energy

    E_r(q) = sum_{e in E} w_e E_e(V q) + sum_t E_t(V q),

its elastic part hyper-reduced to the sampled elements E with weights w (ecsw.py), the chambers and the quadratic
terms (clamp, rollers, gravity) exact in q (exact.py: a chamber's measure is a polynomial in q), every other term
(fibres, sheets, contact, effects) evaluated whole on the full field V q and projected. Its gradient and Hessian are

    g_r = V^T g(V q),   H_r = V^T H(V q) V   (+ c (V^T a)(V^T a)^T for every rank-one part c a a^T),

the elastic part of each from the sampled elements alone: sum_e w_e V_e^T f_e and sum_e w_e V_e^T H_e V_e, by the
full term's own class and kernels (terms/elastic.py) on the sampled elements only: their nodes (numbered afresh),
quadrature weights times w_e, and parameters (Elasticity.restricted). With V = I and w = 1 it is the full
model. A scene with no term of the last kind never touches the full field in a solve: the full model is put at V q
only for an output (full_state).
"""

from __future__ import annotations

import numpy as np

from ..errors import require
from ..scene.build import BuiltScene
from ..solve.linsolve import FixedPattern
from ..terms.base import vertex_dofs
from ..terms.elastic import Elasticity
from .exact import ProjectedQuadratic, ReducedChamber, projected


class SampledElasticity:
    """sum_{e in E} w_e E_e(V q): the elastic term restricted to its sampled elements, their energies weighted
    (Elasticity.restricted; one pressure per element, volumetric = "mixed", restricts alike), on the rows of V at
    their nodes (the module docstring)."""

    def __init__(self, elastic: Elasticity, basis: np.ndarray, elements: np.ndarray, weights: np.ndarray):
        self.term = elastic.restricted(elements, weights)
        self.vertices, self.dim = self.term.vertices, elastic.dim
        self.basis = np.ascontiguousarray(basis[vertex_dofs(self.vertices, self.dim)])  # (n_E d, r)
        m, k = self.term.nodes.shape
        self.element_basis = self.basis[vertex_dofs(self.term.nodes.ravel(), self.dim)].reshape(m, k * self.dim, -1)
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

    def min_determinant(self) -> float:
        return self.term.min_determinant()

    def gradient(self) -> np.ndarray:
        """sum_e w_e V_e^T f_e (r,)."""
        if self._gradient is None:
            self._gradient = self.basis.T @ self.term.gradient().ravel()
        return self._gradient

    def hessian(self, psd_only: bool) -> np.ndarray:
        """sum_e w_e V_e^T H_e V_e (r, r): H_e exact, or projected to PSD per quadrature point."""
        m, n, r = self.element_basis.shape
        blocks = self.term.hessian_values(psd_only).reshape(m, n, n)
        product = blocks @ self.element_basis  # H_e V_e (m, n, r)
        return self.element_basis.reshape(m * n, r).T @ product.reshape(m * n, r)

    def max_step(self, dq: np.ndarray) -> float:
        """Largest step fraction along V dq that keeps det F > 0 in the sampled elements."""
        return self.term.max_step((self.basis @ dq).reshape(self.u.shape))


def require_elementwise(built: BuiltScene) -> None:
    """Refuse (one line) a scene whose elastic term is not a sum over elements: ECSW samples elements."""
    require(
        built.elastic.elementwise,
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
    """The reduced energy of a built scene (the module docstring) on the basis V (N, r), with the elements E and
    weights w of its elastic term. training: the commands (S, c) of the equilibria it was trained on and their
    coordinates q_s = V^T u_s (S, r), from which solves start (solve.py), or None. chambers: the reduced chambers,
    in the order of built.chambers; exact: they and the projected quadratic terms; whole: the terms evaluated on
    the full field."""

    def __init__(
        self,
        built: BuiltScene,
        basis: np.ndarray,
        elements: np.ndarray,
        weights: np.ndarray,
        training: tuple[np.ndarray, np.ndarray] | None = None,
    ):
        require_elementwise(built)
        self.built = built
        self.model = built.model
        self.basis = np.ascontiguousarray(basis, dtype=np.float64)
        self.elements = np.asarray(elements, dtype=np.int64)
        self.weights = np.asarray(weights, dtype=np.float64)
        self.elastic = SampledElasticity(built.elastic, self.basis, self.elements, self.weights)
        others = [t for t in self.model.terms if t is not built.elastic]
        self.chambers = [ReducedChamber(c, self.basis) for c in built.chambers]
        chamber_terms = {id(c) for c in built.chambers}
        quadratic = [ProjectedQuadratic(t, self.basis, self.model) for t in others if t.quadratic]
        self.exact: list[ReducedChamber | ProjectedQuadratic] = [*self.chambers, *quadratic]
        self.whole = [t for t in others if id(t) not in chamber_terms and not t.quadratic]
        self._fixed_terms = [t for t in self.whole if not t.dynamic and len(t.hessian_pattern()[0])]
        self._fixed = fixed_pattern(self._fixed_terms)  # found once
        self.training = training

    @property
    def n_modes(self) -> int:
        return self.basis.shape[1]

    def displacements(self, q: np.ndarray) -> np.ndarray:
        """u = V q as (n, d)."""
        return (self.basis @ q).reshape(self.model.config.u.shape)

    def set_coordinates(self, q: np.ndarray) -> None:
        """Put the model at q: the sampled elements and the exact terms at q, the full model at V q where a term is
        evaluated whole."""
        self.elastic.set_coordinates(q)
        for part in self.exact:
            part.set_coordinates(q)
        if self.whole:
            self.model.set_displacements(self.displacements(q))

    def full_state(self, q: np.ndarray) -> np.ndarray:
        """Put the full model (every term) at V q, for an output; return V q (n, d)."""
        u = self.displacements(q)
        self.model.set_displacements(u)
        return u

    def energy(self) -> float:
        parts = [t.energy() for t in self.exact] + [t.energy() for t in self.whole]
        return self.elastic.energy() + float(sum(parts))

    def gradient(self) -> tuple[np.ndarray, float]:
        """(g_r (r,), its force scale): the scale is the sum of the parts' norms, at least the model's force_floor
        (as EnergyModel.gradient)."""
        parts = [self.elastic.gradient()] + [t.gradient() for t in self.exact]
        parts += [self.basis.T @ t.gradient().ravel() for t in self.whole]
        scale = max(sum(float(np.linalg.norm(p)) for p in parts), self.model.force_floor)
        return np.sum(parts, axis=0), scale

    def hessian(self, psd_only: bool = False) -> np.ndarray:
        """H_r (r, r), the terms' rank-one parts included (dense: r is small). The whole terms' sparse Hessians are
        projected on the rows of V at the DOFs they touch only: the fixed terms' summed on their pattern, found once
        (solve/linsolve.py FixedPattern), a dynamic term's (a contact's) on the pattern of its last values."""
        H = self.elastic.hessian(psd_only)
        for part in self.exact:
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
        """Largest safe step fraction along dq: the sampled elements', the exact terms' and every whole term's bound
        along V dq."""
        bounds = [self.elastic.max_step(dq), *(t.max_step(dq) for t in self.exact)]
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
