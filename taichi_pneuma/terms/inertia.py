"""Inertia for implicit (backward) Euler dynamics, as an incremental potential.

One time step of size h from (x_n, v_n) minimises

    E(x) + sum_i m_i / (2 h^2) |x_i - xhat_i|^2,    xhat = x_n + h v_n,

whose stationarity condition m_i (x_i - xhat_i) / h^2 = -dE/dx_i is backward Euler; afterwards
v_{n+1} = (x_{n+1} - x_n) / h. In displacements, with v_n = (u_n - u_{n-1}) / h, the target is
uhat = 2 u_n - u_{n-1}. Gradient m_i / h^2 (u_i - uhat_i); Hessian diag(m_i / h^2), constant and PSD.
Quadratic and per vertex: one NumPy expression each, no kernel.
"""

import numpy as np

from .base import Term, vertex_dofs


class Inertia(Term):
    """Lumped vertex masses m_i stepping by backward Euler with time step h; advance() ends a step."""

    name = "inertia"

    def __init__(self, config, masses: np.ndarray, dt: float):
        self.config = config
        n = config.n_vertices
        masses = np.asarray(masses, dtype=np.float64)
        self.mass_over_h2 = masses / np.square(np.float64(dt))  # h past 1e154: h^2 = inf, no inertia (quasistatics)
        self.target = np.zeros_like(config.rest)  # uhat, zero at rest (u_0 = 0, v_0 = 0)
        self._previous = np.zeros_like(config.rest)
        self._dofs = vertex_dofs(np.arange(n), config.dim)
        self._diagonal = np.repeat(self.mass_over_h2, config.dim)

    def energy(self) -> float:
        return 0.5 * float(self.mass_over_h2 @ np.sum((self.config.u - self.target) ** 2, axis=1))

    def gradient(self) -> np.ndarray:
        return self.mass_over_h2[:, None] * (self.config.u - self.target)

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._dofs, self._dofs

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        return self._diagonal

    def advance(self, u: np.ndarray) -> None:
        """End the time step at displacements u: the next target is 2 u - u_previous."""
        self.target = 2.0 * u - self._previous
        self._previous = np.array(u, dtype=np.float64)
