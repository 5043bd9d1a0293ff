"""Penalty clamp: 1/2 K sum_{i in pinned} |u_i|^2 (u = x - X), gradient K u_i, Hessian K I on pinned DOFs.

Quadratic and per vertex: one NumPy expression each, no kernel."""


import numpy as np

from .base import Term, vertex_dofs


class Clamp(Term):
    """Springs of stiffness K holding the pinned vertices at their rest positions."""

    name = "clamp"

    def __init__(self, config, pinned: np.ndarray, stiffness: float):
        self.config = config
        self.k = float(stiffness)
        self.pinned = np.asarray(pinned, dtype=np.int64)
        self._dofs = vertex_dofs(pinned, config.dim)

    def energy(self) -> float:
        return 0.5 * self.k * float(np.sum(self.config.u[self.pinned] ** 2))

    def gradient(self) -> np.ndarray:
        force = np.zeros_like(self.config.u)
        force[self.pinned] = self.k * self.config.u[self.pinned]
        return force

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._dofs, self._dofs

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        return np.full(len(self._dofs), self.k)
