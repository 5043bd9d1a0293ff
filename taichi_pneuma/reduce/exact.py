"""The terms a reduced model evaluates exactly in its own coordinates, never touching the full field: the chambers
and the quadratic terms (clamp, rollers, gravity).

A chamber's enclosed measure A(u) is a polynomial of degree d in the wall's nodal displacements (an area is
quadratic, a volume cubic: terms/chambers/wall.py, cavity.py), so on u = V q (V: the basis, r modes)

    A(q) = A_0 + a.q + 1/2 q^T B q + 1/6 C[q, q, q],
    dA/dq = a + B q + 1/2 C[q, q, .],     d2A/dq2 = B + C[q, ., .],

with a = V^T dA/dx(0), B = V^T d2A/dx2(0) V and the constant third derivative C (zero in 2D), found from the
Hessian's linearity in u: C[., ., k] = V^T (d2A/dx2(s V e_k) - d2A/dx2(0)) V / s, s a displacement of the body's
size (any s is exact; a large one keeps round-off at that of the Hessian). Every chamber kind is a function of A
(its energy psi(A), pressure p(A), stiffness -p'(A) and command scale s(A): wall.Chamber), so its reduced energy,
gradient and Hessian,

    psi(A),   -p dA/dq,   -p'(A) dA/dq dA/dq^T - p d2A/dq2,

cost O(r^3) numbers, the same to round-off as projecting the full term's.

A quadratic term (Term.quadratic: E(u) = E(0) + g(0).u + 1/2 u^T K u, the same at every command) is projected once:
E(q) = E(0) + (V^T g(0)).q + 1/2 q^T (V^T K V) q.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from ..errors import require
from ..terms.base import vertex_dofs

MAX_MODES_3D = 400  # the largest basis whose r^3 third derivative (8 r^3 bytes: 0.5 GB at 400) is formed


def projected(basis: np.ndarray, rows: np.ndarray, cols: np.ndarray, values: np.ndarray) -> np.ndarray:
    """V^T M V (r, r) for the sparse matrix M of triplets (rows, cols, values) on the full DOFs, through the rows of V
    that M touches only."""
    touched, local = np.unique(np.concatenate([rows, cols]), return_inverse=True)
    n = len(touched)
    matrix = sp.csr_matrix((values, (local[: len(rows)], local[len(rows) :])), (n, n))
    V = basis[touched]
    return V.T @ (matrix @ V)


class ReducedMeasure:
    """A chamber wall's measure (form: wall.AreaForm or cavity.VolumeForm) as the polynomial in q of the module
    docstring."""

    def __init__(self, form, basis: np.ndarray):
        config = form.config
        dim, r = config.dim, basis.shape[1]
        require(
            dim == 2 or r <= MAX_MODES_3D,
            f"a reduced model of a 3D chamber takes at most {MAX_MODES_3D} modes, not {r}",
        )
        zero = np.zeros_like(config.rest)
        self.rest, gradient = form.measure_and_gradient(zero)
        wall = basis[vertex_dofs(form.nodes, dim)]  # the rows of V on the wall's DOFs
        self.linear = wall.T @ gradient.ravel()
        rows, cols = form.rows, form.cols
        self.quadratic = projected(basis, rows, cols, form.hessian(zero))
        self.cubic = np.zeros((r, r, r))
        if dim == 3:
            size = float(np.ptp(config.rest, axis=0).max())
            for k in range(r):
                mode = basis[:, k].reshape(zero.shape)
                s = size / max(float(np.abs(mode).max()), 1e-300)
                self.cubic[:, :, k] = projected(basis, rows, cols, form.hessian(s * mode)) - self.quadratic
                self.cubic[:, :, k] /= s
            self.cubic = (self.cubic + self.cubic.transpose(1, 2, 0) + self.cubic.transpose(2, 0, 1)) / 3

    def value_and_gradient(self, q: np.ndarray) -> tuple[float, np.ndarray]:
        """(A(q), dA/dq (r,))."""
        Cq = self.cubic @ q  # C[., ., q]
        Bq = self.quadratic @ q
        value = self.rest + self.linear @ q + q @ Bq / 2 + q @ Cq @ q / 6
        return float(value), self.linear + Bq + Cq @ q / 2

    def hessian(self, q: np.ndarray) -> np.ndarray:
        """d2A/dq2 (r, r)."""
        return self.quadratic + self.cubic @ q

    def along(self, q: np.ndarray, dq: np.ndarray) -> np.ndarray:
        """The coefficients (lowest first, d + 1 of them) of the polynomial A(q + t dq) in t."""
        value, gradient = self.value_and_gradient(q)
        curvature = dq @ self.hessian(q) @ dq
        return np.array([value, gradient @ dq, curvature / 2, dq @ (self.cubic @ dq) @ dq / 6])


class ReducedChamber:
    """A chamber term (wall.Chamber) on its reduced measure: energy, gradient, Hessian, step bound and command force
    in q (the module docstring). set_coordinates(q) first; the term's command is the one it holds."""

    def __init__(self, chamber, basis: np.ndarray):
        self.term, self.name = chamber, chamber.name
        self.measure = ReducedMeasure(chamber.form, basis)
        self.q = np.zeros(basis.shape[1])
        self.area, self.area_gradient = self.measure.value_and_gradient(self.q)

    def set_coordinates(self, q: np.ndarray) -> None:
        self.q = q
        self.area, self.area_gradient = self.measure.value_and_gradient(q)

    def pressure(self) -> float:
        return self.term.pressure_at(self.area)

    def energy(self) -> float:
        return self.term.energy_at(self.area)

    def gradient(self) -> np.ndarray:
        return -self.pressure() * self.area_gradient

    def hessian(self, psd_only: bool) -> np.ndarray:
        """-p'(A) dA dA^T, and - p d2A unless psd_only (as the full term: wall.Chamber)."""
        a = self.area_gradient
        H = self.term.stiffness_at(self.area) * np.outer(a, a)
        return H if psd_only else H - self.pressure() * self.measure.hessian(self.q)

    def max_step(self, dq: np.ndarray) -> float:
        return self.term.step_within(self.measure.along(self.q, dq))

    def command_force(self) -> np.ndarray:
        """-dr_r/dc = s(A) dA/dq (r,)."""
        return self.term.command_scale_at(self.area) * self.area_gradient


class ProjectedQuadratic:
    """A quadratic term (Term.quadratic) projected once: E(q) = E_0 + b.q + 1/2 q^T K q (the module docstring)."""

    def __init__(self, term, basis: np.ndarray, model):
        self.term, self.name = term, term.name
        held = model.config.u.copy()
        model.set_displacements(np.zeros_like(held))
        self.rest_energy = float(term.energy())
        self.linear = basis.T @ term.gradient().ravel()
        rows, cols = term.hessian_pattern()
        r = basis.shape[1]
        self.stiffness = projected(basis, rows, cols, term.hessian_values()) if len(rows) else np.zeros((r, r))
        model.set_displacements(held)
        self.q = np.zeros(r)

    def set_coordinates(self, q: np.ndarray) -> None:
        self.q = q

    def energy(self) -> float:
        return self.rest_energy + float(self.linear @ self.q + self.q @ self.stiffness @ self.q / 2)

    def gradient(self) -> np.ndarray:
        return self.linear + self.stiffness @ self.q

    def hessian(self, psd_only: bool) -> np.ndarray:
        return self.stiffness

    def max_step(self, dq: np.ndarray) -> float:
        return math.inf
