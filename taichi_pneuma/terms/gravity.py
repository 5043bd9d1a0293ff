"""Gravity: the weight of the body, with mass lumped to the vertices from a density.

    E = sum_i m_i g y_i,   m_i = rho sum_{triangles t at i} |t| / 3,

(g > 0, pulling towards -y). The gradient is the constant m_i (0, g); the Hessian is zero.
"""


import numpy as np
import taichi as ti

from .base import Term


@ti.data_oriented
class Gravity(Term):
    """Weight of lumped vertex masses m_i under gravitational acceleration g along -y."""

    name = "gravity"

    def __init__(self, config, masses: np.ndarray, g: float):
        self.config = config
        self.weight = ti.field(ti.f64, config.n_vertices)
        self.weight.from_numpy(np.asarray(masses, dtype=np.float64) * g)
        self._gradient = np.column_stack([np.zeros(len(masses)), np.asarray(masses, dtype=np.float64) * g])

    @ti.kernel
    def energy(self) -> ti.f64:
        total = 0.0
        for i in self.weight:
            total += self.weight[i] * self.config.x(i)[1]
        return total

    def gradient(self) -> np.ndarray:
        return self._gradient.copy()
