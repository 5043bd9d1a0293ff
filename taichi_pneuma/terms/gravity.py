"""Gravity: the weight of the body, with mass lumped to the vertices from a density.

    E = sum_i m_i g y_i,   m_i = rho int N_i (mesh.nodal_measures(): in 2D rho sum_{triangles t at i} |t| / 3),

(g > 0, pulling towards -y, in 2D and 3D alike). The gradient is the constant m_i g e_y; the Hessian is zero.
Linear in x: one NumPy expression, no kernel.
"""

import numpy as np

from .base import Term


class Gravity(Term):
    """Weight of lumped vertex masses m_i under gravitational acceleration g along -y."""

    name = "gravity"
    quadratic = True

    def __init__(self, config, masses: np.ndarray, g: float):
        self.config = config
        self.weight = np.asarray(masses, dtype=np.float64) * g
        self._gradient = np.zeros_like(config.rest)
        self._gradient[:, 1] = self.weight

    def energy(self) -> float:
        return float(self.weight @ (self.config.rest[:, 1] + self.config.u[:, 1]))

    def gradient(self) -> np.ndarray:
        return self._gradient.copy()
