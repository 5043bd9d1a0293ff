"""Penalty clamp: 1/2 K sum_{i in pinned} |u_i|^2 (u = x - X), gradient K u_i, Hessian K I on pinned DOFs."""


import numpy as np
import taichi as ti

from .base import Term, vertex_dofs


@ti.data_oriented
class Clamp(Term):
    """Springs of stiffness K holding the pinned vertices at their rest positions."""

    name = "clamp"

    def __init__(self, config, pinned: np.ndarray, stiffness: float):
        self.config = config
        self.k = float(stiffness)
        self.n_pinned = len(pinned)
        self.pinned = ti.field(ti.i32, self.n_pinned)
        self.force = ti.Vector.field(2, ti.f64, config.n_vertices)
        self.pinned.from_numpy(np.asarray(pinned, dtype=np.int32))
        self._dofs = vertex_dofs(pinned)

    @ti.kernel
    def energy(self) -> ti.f64:
        total = 0.0
        for i in range(self.n_pinned):
            total += 0.5 * self.k * self.config.u[self.pinned[i]].norm_sqr()
        return total

    @ti.kernel
    def _compute_force(self):
        """K u on the pinned vertices (the only non-zero rows of the force field)."""
        for i in range(self.n_pinned):
            self.force[self.pinned[i]] = self.k * self.config.u[self.pinned[i]]

    def gradient(self) -> np.ndarray:
        self._compute_force()
        return self.force.to_numpy()

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._dofs, self._dofs

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        return np.full(len(self._dofs), self.k)
