"""Per-triangle fields of a deformed mesh, in NumPy (vectorised over triangles): for output, not the solve.

On a linear triangle with rest corners X0, X1, X2 and current ones x0, x1, x2 the deformation
gradient is constant:

    F = Ds Dm^-1,   Ds = [x1 - x0, x2 - x0],   Dm = [X1 - X0, X2 - X0],   J = det F.

Largest principal stretch: the largest singular value of F, sqrt of the largest eigenvalue of
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


def deformation_gradients(rest: np.ndarray, positions: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """F of every triangle, (m, 2, 2), from rest and current vertex positions (n, 2)."""
    def edges(points):
        p = points[triangles]
        return np.stack([p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]], axis=2)  # columns are the two edges

    return edges(positions) @ np.linalg.inv(edges(rest))


def max_stretch(F: np.ndarray) -> np.ndarray:
    """Largest principal stretch of each F (m, 2, 2): sqrt(tr C / 2 + sqrt((tr C / 2)^2 - det C)), C = F^T F."""
    half_trace = 0.5 * np.einsum("mij,mij->m", F, F)
    det_c = np.linalg.det(F) ** 2
    return np.sqrt(half_trace + np.sqrt(np.maximum(half_trace ** 2 - det_c, 0.0)))


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


def triangle_fields(rest: np.ndarray, positions: np.ndarray, triangles: np.ndarray, mu, lam) -> dict[str, np.ndarray]:
    """det_F, max_stretch, stress (m, 3, 3) and von_mises of every triangle."""
    F = deformation_gradients(rest, positions, triangles)
    sigma = cauchy_stress(F, mu, lam)
    return {"det_F": np.linalg.det(F), "max_stretch": max_stretch(F), "stress": sigma, "von_mises": von_mises(sigma)}
