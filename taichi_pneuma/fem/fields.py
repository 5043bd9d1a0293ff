"""Per-element fields of a deformed mesh, in NumPy (vectorised over elements): for output, not the solve.

At quadrature point q of an element with nodes a and rest shape-function gradients G_qa (the elastic
term's own points and weights, terms/elastic.quadrature: one point for linear triangles, where F is
constant, three for quadratic ones)

    F_q = sum_a x_a G_qa^T,   J = det F.

Each field is reported per element as its quadrature-weighted mean over the element (linear triangles:
the one value). The mean of det F is then the element's current area over its rest area, exactly
(det F is of degree 2 on a quadratic triangle, which the 3-point rule integrates exactly).

Largest principal stretch: the largest singular value of F, sqrt of the larger eigenvalue of
C = F^T F (in plane; the out-of-plane stretch is 1 in plane strain).

Cauchy stress of the stable neo-Hookean model (terms/elastic.py), P = mu F - (mu + lam (1 - J)) cof F
and cof F F^T = J I, so

    sigma = P F^T / J = (mu / J) F F^T - (mu + lam (1 - J)) I.

Out of plane: the 2D energy is the 3D Macklin-Mueller energy mu/2 (I_C - 3) - mu (J - 1) + lam/2 (J - 1)^2
restricted to F_33 = 1 (plane strain), whose zz component of the same formula is

    sigma_zz = mu / J - (mu + lam (1 - J)),

the stress that holds the thickness fixed. The in-plane shear components xz, yz are zero. The von Mises
stress is taken of the full 3 x 3 tensor:

    sigma_vm = sqrt(((s_xx - s_yy)^2 + (s_yy - s_zz)^2 + (s_zz - s_xx)^2) / 2 + 3 s_xy^2).

The formulas hold for J > 0 (the solver never accepts an inverted triangle).
"""

from __future__ import annotations

import numpy as np

from ..terms.elastic import quadrature


class ElementFields:
    """The fields of one mesh at any positions: the quadrature (rest shape-function gradients G (m, nq, k, 2)
    and weights W (m, nq)) depends on the rest mesh only, so it is computed once, here."""

    def __init__(self, rest: np.ndarray, elements: np.ndarray):
        self.elements = elements
        self.gradients, self.weights = quadrature(rest, elements)

    def deformation_gradients(self, positions: np.ndarray) -> np.ndarray:
        """F (m, nq, 2, 2) at the quadrature points, from the current node positions (n, 2)."""
        return np.einsum("mai,mqaj->mqij", positions[self.elements], self.gradients)

    def at(self, positions: np.ndarray, mu=None, lam=None) -> dict[str, np.ndarray]:
        """Per element (quadrature-weighted means): det_F and max_stretch, and, given the Lame parameters
        mu, lam (scalars or one per element), stress (the mean Cauchy stress, (m, 3, 3)) and von_mises (of it)."""
        F, weights = self.deformation_gradients(positions), self.weights
        m, nq = weights.shape
        mean = lambda values: np.einsum("mq,mq...->m...", weights, values.reshape(m, nq, *values.shape[1:])) \
            / weights.sum(axis=1).reshape(-1, *([1] * (values.ndim - 1)))
        flat = F.reshape(-1, 2, 2)
        fields = {"det_F": mean(np.linalg.det(flat)), "max_stretch": mean(max_stretch(flat))}
        if mu is not None:
            per_point = lambda v: np.repeat(np.broadcast_to(v, (m,)), nq)
            fields["stress"] = mean(cauchy_stress(flat, per_point(mu), per_point(lam)))
            fields["von_mises"] = von_mises(fields["stress"])
        return fields


def max_stretch(F: np.ndarray) -> np.ndarray:
    """Largest principal stretch of each F (m, 2, 2): sqrt of the larger eigenvalue of C = F^T F,
    (C00 + C11) / 2 + sqrt(((C00 - C11) / 2)^2 + C01^2) (no cancellation near F = I)."""
    C = np.swapaxes(F, 1, 2) @ F
    return np.sqrt(0.5 * (C[:, 0, 0] + C[:, 1, 1]) + np.hypot(0.5 * (C[:, 0, 0] - C[:, 1, 1]), C[:, 0, 1]))


def cauchy_stress(F: np.ndarray, mu, lam) -> np.ndarray:
    """Cauchy stress (m, 3, 3) of each F (m, 2, 2) under plane strain (see the module docstring);
    mu, lam: scalars or one value per triangle."""
    J = np.linalg.det(F)
    mu, lam = np.broadcast_to(mu, J.shape), np.broadcast_to(lam, J.shape)
    pressure_part = mu + lam * (1.0 - J)
    sigma = np.zeros((len(F), 3, 3))
    sigma[:, :2, :2] = (mu / J)[:, None, None] * (F @ np.swapaxes(F, 1, 2)) - pressure_part[:, None, None] * np.eye(2)
    sigma[:, 2, 2] = mu / J - pressure_part
    return sigma


def von_mises(sigma: np.ndarray) -> np.ndarray:
    """Von Mises stress of each 3 x 3 stress tensor (m, 3, 3)."""
    s = sigma
    normal = (s[:, 0, 0] - s[:, 1, 1]) ** 2 + (s[:, 1, 1] - s[:, 2, 2]) ** 2 + (s[:, 2, 2] - s[:, 0, 0]) ** 2
    shear = s[:, 0, 1] ** 2 + s[:, 1, 2] ** 2 + s[:, 0, 2] ** 2
    return np.sqrt(0.5 * normal + 3.0 * shear)


def triangle_fields(rest: np.ndarray, positions: np.ndarray, elements: np.ndarray, mu=None, lam=None
                    ) -> dict[str, np.ndarray]:
    """ElementFields(rest, elements).at(positions, mu, lam), for one state."""
    return ElementFields(rest, elements).at(positions, mu, lam)
