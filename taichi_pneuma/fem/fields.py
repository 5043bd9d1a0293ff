"""Per-element fields of a deformed mesh, for output (not the solve): det F, largest stretch, Cauchy stress
and von Mises stress, each the quadrature-weighted mean over the element of its value at the points of
the element family's rule (fem/elements.py; one point for linear triangles, where F is constant).

At quadrature point q of an element with nodes a and rest shape-function gradients G_qa,

    F_q = sum_a x_a G_qa^T,   J = det F.

The mean of det F is the element's current volume (area) over its rest one, exactly (det F is of
degree 2 on a quadratic triangle, which its 3-point rule integrates exactly). The largest principal
stretch is the largest singular value of F (in plane strain the out-of-plane stretch is 1).

The stress comes from the material law's own first Piola stress, the code the solver uses
(materials/law.py, cauchy_stresses): sigma = P F^T / J of F embedded in 3 x 3, so in plane strain
sigma_zz is the stress that holds the thickness fixed. The von Mises stress is of the full 3 x 3 tensor:

    sigma_vm = sqrt(((s_xx - s_yy)^2 + (s_yy - s_zz)^2 + (s_zz - s_xx)^2) / 2 + 3 (s_xy^2 + s_yz^2 + s_xz^2)).

The stresses hold for J > 0 (the solver never accepts an inverted element).
"""

from __future__ import annotations

import numpy as np

from ..materials import cauchy_stresses
from .elements import family_of

NEAR_REPEATED = 1e-6  # 1 - |r| below which max_stretch asks LAPACK (the closed form's error: 1e-16 / sqrt(1 - |r|))


class ElementFields:
    """The fields of one mesh at any positions: the quadrature (rest shape-function gradients G (m, nq, k, d)
    and weights W (m, nq)) depends on the rest mesh only, so it is computed once, here."""

    def __init__(self, rest: np.ndarray, elements: np.ndarray):
        self.elements = elements
        self.gradients, self.weights = family_of(elements, rest.shape[1]).quadrature(rest, elements)

    def deformation_gradients(self, positions: np.ndarray) -> np.ndarray:
        """F (m, nq, d, d) at the quadrature points, from the current node positions (n, d)."""
        return np.swapaxes(positions[self.elements], 1, 2)[:, None] @ self.gradients  # (m, 1, d, k) @ (m, nq, k, d)

    def largest_stretch(self, positions: np.ndarray) -> float:
        """The largest principal stretch at any quadrature point (of any element) at the node positions (n, d)."""
        F = self.deformation_gradients(positions)
        return float(max_stretch(F.reshape(-1, *F.shape[2:])).max())

    def at(self, positions: np.ndarray, law=None, parameters=None) -> dict[str, np.ndarray]:
        """Per element (quadrature-weighted means): det_F and max_stretch, and, given a material law and its
        parameter vectors (one per element, (m, p)), stress (the mean Cauchy stress, (m, 3, 3)) and von_mises (of
        it)."""
        F, weights = self.deformation_gradients(positions), self.weights
        m, nq = weights.shape
        mean = lambda values: (
            np.einsum("mq,mq...->m...", weights, values.reshape(m, nq, *values.shape[1:]))
            / weights.sum(axis=1).reshape(-1, *([1] * (values.ndim - 1)))
        )
        flat = F.reshape(m * nq, *F.shape[2:])
        fields = {"det_F": mean(determinants(flat)), "max_stretch": mean(max_stretch(flat))}
        if law is not None:
            fields["stress"] = mean(cauchy_stress(flat, law, np.repeat(parameters, nq, axis=0)))
            fields["von_mises"] = von_mises(fields["stress"])
        return fields


def determinants(F: np.ndarray) -> np.ndarray:
    """det F of each F (N, d, d), d = 2 or 3, by cofactors (a tenth of the time of LU per matrix)."""
    if F.shape[1] == 2:
        return F[:, 0, 0] * F[:, 1, 1] - F[:, 0, 1] * F[:, 1, 0]
    return (
        F[:, 0, 0] * (F[:, 1, 1] * F[:, 2, 2] - F[:, 1, 2] * F[:, 2, 1])
        - F[:, 0, 1] * (F[:, 1, 0] * F[:, 2, 2] - F[:, 1, 2] * F[:, 2, 0])
        + F[:, 0, 2] * (F[:, 1, 0] * F[:, 2, 1] - F[:, 1, 1] * F[:, 2, 0])
    )


def max_stretch(F: np.ndarray) -> np.ndarray:
    """Largest principal stretch of each F (N, d, d): its largest singular value, sqrt of the largest eigenvalue of
    C = F^T F, in closed form (NumPy's batched SVD is 7 times slower in 2D, 20 times in 3D). In 2D:
    (C00 + C11) / 2 + sqrt(((C00 - C11) / 2)^2 + C01^2) (no cancellation near F = I). In 3D, the trigonometric
    form of the symmetric eigenproblem (Smith 1961): with q = tr C / 3, p^2 = (|C - q I|_F^2) / 6 and
    r = det((C - q I) / p) / 2 in [-1, 1], lambda_max = q + 2 p cos(arccos(r) / 3) (q where p = 0: C = q I). Its
    relative error is about 1e-16 / sqrt(1 - |r|), so where two eigenvalues nearly coincide (1 - |r| below
    NEAR_REPEATED: an equibiaxial stretch) they come from LAPACK's eigvalsh instead."""
    C = np.swapaxes(F, 1, 2) @ F
    if F.shape[1] == 2:
        return np.sqrt(0.5 * (C[:, 0, 0] + C[:, 1, 1]) + np.hypot(0.5 * (C[:, 0, 0] - C[:, 1, 1]), C[:, 0, 1]))
    q = (C[:, 0, 0] + C[:, 1, 1] + C[:, 2, 2]) / 3
    a, b, c = C[:, 0, 0] - q, C[:, 1, 1] - q, C[:, 2, 2] - q  # the diagonal of C - q I
    d, e, f = C[:, 0, 1], C[:, 0, 2], C[:, 1, 2]
    p = np.sqrt((a * a + b * b + c * c + 2 * (d * d + e * e + f * f)) / 6)
    scale = np.where(p > 0, p, 1.0) ** 3
    determinant = a * (b * c - f * f) - d * (d * c - f * e) + e * (d * f - b * e)
    r = np.clip(determinant / scale / 2, -1.0, 1.0)
    largest = q + 2 * p * np.cos(np.arccos(r) / 3)
    near = (np.abs(r) > 1 - NEAR_REPEATED) & (p > 0)  # arccos loses half the digits there: LAPACK's eigvalsh
    largest[near] = np.linalg.eigvalsh(C[near])[:, -1]
    return np.sqrt(np.maximum(largest, 0.0))


def cauchy_stress(F: np.ndarray, law, parameters: np.ndarray) -> np.ndarray:
    """Cauchy stress (N, 3, 3) of each F (N, d, d) under the law with parameter vectors (N, p), from the law's
    own P: sigma = P F^T / J (module docstring)."""
    out = np.empty((len(F), 3, 3))
    cauchy_stresses(
        law,
        F.shape[1],
        np.ascontiguousarray(F, dtype=np.float64),
        np.ascontiguousarray(parameters, dtype=np.float64),
        out,
    )
    return out


def von_mises(sigma: np.ndarray) -> np.ndarray:
    """Von Mises stress of each 3 x 3 stress tensor (m, 3, 3)."""
    s = sigma
    normal = (s[:, 0, 0] - s[:, 1, 1]) ** 2 + (s[:, 1, 1] - s[:, 2, 2]) ** 2 + (s[:, 2, 2] - s[:, 0, 0]) ** 2
    shear = s[:, 0, 1] ** 2 + s[:, 1, 2] ** 2 + s[:, 0, 2] ** 2
    return np.sqrt(0.5 * normal + 3.0 * shear)


def element_fields(
    rest: np.ndarray, positions: np.ndarray, elements: np.ndarray, law=None, parameters=None
) -> dict[str, np.ndarray]:
    """ElementFields(rest, elements).at(positions, law, parameters), for one state."""
    return ElementFields(rest, elements).at(positions, law, parameters)
