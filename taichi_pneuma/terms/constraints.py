"""Constraints as penalties on the displacements u = x - X of chosen nodes (no kernel: one NumPy expression each).

    clamp (every component):       E = 1/2 K sum_i |u_i|^2,       gradient K u_i,           Hessian K I
    roller (the normal component): E = 1/2 K sum_i (n . u_i)^2,   gradient K (n . u_i) n,   Hessian K n n^T

Both are E = 1/2 K sum_i u_i^T P u_i with a constant symmetric projector P (the identity, or n n^T for a unit
normal n): gradient K P u_i, and the constant Hessian K P on each node's d x d block, stored as its non-zero
entries only (the clamp's diagonal, a roller along an axis one entry per node). A roller along a symmetry line
holds the nodes on the line to it and leaves them free to slide along it.
"""

import numpy as np

from .base import Term


class NodalPenalty(Term):
    """Springs of stiffness K on the components P u_i of the displacements of the given nodes."""

    quadratic = True

    def __init__(self, config, nodes: np.ndarray, projector: np.ndarray, stiffness: float, name: str):
        self.config = config
        self.name = name
        self.k = float(stiffness)
        self.nodes = np.asarray(nodes, dtype=np.int64)
        self.projector = np.asarray(projector, dtype=np.float64)
        d = len(self.projector)
        a, b = np.nonzero(self.projector)
        self._rows = (d * self.nodes[:, None] + a).ravel()
        self._cols = (d * self.nodes[:, None] + b).ravel()
        self._values = np.tile(self.k * self.projector[a, b], len(self.nodes))

    def energy(self) -> float:
        u = self.config.u[self.nodes]
        return 0.5 * self.k * float(np.sum((u @ self.projector) * u))

    def gradient(self) -> np.ndarray:
        force = np.zeros_like(self.config.u)
        force[self.nodes] = self.k * (self.config.u[self.nodes] @ self.projector)
        return force

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._rows, self._cols

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        return self._values


class Clamp(NodalPenalty):
    """The clamp: every component of the pinned nodes' displacements held (P = I)."""

    def __init__(self, config, pinned: np.ndarray, stiffness: float):
        super().__init__(config, pinned, np.eye(config.u.shape[1]), stiffness, "clamp")


class NormalClamp(NodalPenalty):
    """A roller: the displacement of the nodes along the unit normal n held (P = n n^T), the tangential free."""

    def __init__(self, config, nodes: np.ndarray, normal: np.ndarray, stiffness: float):
        n = np.asarray(normal, dtype=np.float64) / np.linalg.norm(normal)
        super().__init__(config, nodes, np.outer(n, n), stiffness, "roller")
