"""Sensitivities of a converged equilibrium to the chamber commands, by the direct method.

At an equilibrium the residual r(u, q) = dE/du vanishes; q are the chamber commands (each its
kind's: area ratio under area control, pressure under pressure control). Differentiating r(u(q), q) = 0:

    H du/dq_j = -dr/dq_j,      H = d2E/du2, the *exact* Hessian at the equilibrium,

with -dr/dq_j from chamber j's term (command_force), non-zero on its wall only:

    area control      r_c = -k (ratio A_rest - A) grad A   ->  dr/d(ratio) = -k A_rest grad A
    pressure control  r_c = -p grad A                      ->  dr/dp       = -grad A

H is the sparse exact Hessian S (unprojected elastic blocks, the chambers' load stiffness -p d2A,
contact's b' Hess d, the clamp) plus the chambers' rank-1 parts (k gA gA^T under area control), which enter by
the Woodbury identity (linsolve.solve_low_rank_updated), as in Newton. One factorisation of S
serves every command (one right-hand side each). The PSD-projected Hessian is not the derivative
of r and gives wrong sensitivities: it is never used here. A stable equilibrium has H positive
definite, so a Cholesky backend normally works; if it refuses S (S alone may be indefinite:
it lacks k gA gA^T), SciPy's LU factorises it instead.

The adjoint form of one output o(u) is do/dq = -lambda^T dr/dq with H lambda = do/du: one solve
per output instead of one per command. With at most a handful of chambers the direct form costs
the same and also gives every vertex's du/dq, so that is what is computed.

Tip outputs (fem/tip.py tip_outputs: dx, dy, rotation, in 3D dz): the tip point is the mean of the tip vertices, so its
Jacobian is the mean of their rows of du/dq (x, y and, in 3D, z). The tip rotation (in 3D about z,
from the x-y positions) is the least-squares rigid rotation theta = atan2(S, C), S = sum_i r_i x c_i,
C = sum_i r_i . c_i, with r_i the centred rest and c_i the centred current tip positions; since
sum_i r_i = 0 the centring of du drops out:

    d theta = (C dS - S dC) / (S^2 + C^2),   dS = sum_i r_i x du_i,   dC = sum_i r_i . du_i.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..scene.build import BuiltScene
from .linsolve import FactorizationError, FixedPattern, make_backend, solve_low_rank_updated


@dataclass
class Sensitivity:
    """d(state)/d(commands) at one equilibrium; m = number of chambers, in the scene's order.

    displacements: (n, d, m) du/dq of every vertex; tip: (3, m) d(tip dx, tip dy, tip rotation in
    degrees)/dq, in 3D (4, m) with d(tip dz)/dq as its last row; backend: the linear solver that factorised
    the exact Hessian."""

    displacements: np.ndarray
    tip: np.ndarray
    backend: str


def command_forces(built: BuiltScene) -> np.ndarray:
    """-dr/dq as an (n_dofs, m) matrix: column j is chamber j's command_force() on its wall DOFs
    (k A_rest grad A under area control, grad A under pressure control)."""
    rhs = np.zeros((built.model.n_dofs, len(built.chambers)))
    for j, chamber in enumerate(built.chambers):
        rhs[chamber.dofs, j] = chamber.command_force()
    return rhs


def tip_rotation_gradient(rest_tip: np.ndarray, current_tip: np.ndarray) -> np.ndarray:
    """d theta / du_i (radians) of the least-squares tip rotation, (k, 2) for the k tip vertices."""
    r = rest_tip - rest_tip.mean(axis=0)
    c = current_tip - current_tip.mean(axis=0)
    s = float(np.sum(r[:, 0] * c[:, 1] - r[:, 1] * c[:, 0]))
    cc = float(np.sum(r * c))
    d_s = np.column_stack([-r[:, 1], r[:, 0]])  # dS/du_i = (-r_y, r_x)
    return (cc * d_s - s * r) / (s * s + cc * cc)


def solve_exact(
    built: BuiltScene, rhs: np.ndarray, pattern: FixedPattern | None = None, backend=None, factorised: bool = False
):
    """Solve H x = rhs with H the exact Hessian at the model's current state; return (x, backend name).

    pattern, backend: reuse a Newton solver's (its symbolic analysis) instead of new ones; factorised:
    the backend already holds S factorised (Newton's last exact factor, from within its last step of
    the equilibrium: an approximation, for inverse control's iterations), so only the solves remain."""
    model = built.model
    backend = backend or make_backend("auto")
    if not factorised:
        if pattern is None:
            pattern = FixedPattern(*model.hessian_pattern(), model.n_dofs)
        matrix = model.assemble(pattern, model.hessian_parts(psd_only=False))
        try:
            backend.factorize(matrix)
        except FactorizationError:
            backend = make_backend("scipy")
            backend.factorize(matrix)
    return solve_low_rank_updated(backend, rhs, model.low_rank()), backend.name


def sensitivity(
    built: BuiltScene,
    commands: np.ndarray,
    u: np.ndarray,
    pattern: FixedPattern | None = None,
    backend=None,
    factorised: bool = False,
) -> Sensitivity:
    """du/dq and the tip Jacobian at the equilibrium u (n, d) of `commands`; leaves them set on `built`.
    pattern, backend, factorised: see solve_exact. The tip outputs are fem.tip.tip_outputs (dx, dy, the rotation in the
    x-y plane (in 3D the bend angle about z), then in 3D dz)."""
    built.set_commands(commands)
    built.model.set_displacements(u)
    du, name = solve_exact(built, command_forces(built), pattern, backend, factorised)
    du = du.reshape(-1, built.mesh.dim, len(built.chambers))
    return Sensitivity(du, tip_jacobian(built, u, du), name)


def tip_jacobian(built: BuiltScene, u: np.ndarray, du: np.ndarray) -> np.ndarray:
    """d(tip dx, tip dy, tip rotation in degrees[, tip dz])/dq (3 or 4, m) from du/dq (n, d, m) at the displacements u
    (the module docstring: the mean of the tip vertices' rows, and the rotation's gradient)."""
    mesh = built.mesh
    tip_du = du[mesh.tip]  # (k, d, m)
    rest_tip = mesh.vertices[mesh.tip, :2]
    rotation = tip_rotation_gradient(rest_tip, rest_tip + np.reshape(u, (-1, mesh.dim))[mesh.tip, :2])
    d_theta = np.einsum("kd,kdm->m", rotation, tip_du[:, :2])
    mean = tip_du.mean(axis=0)
    return np.vstack([mean[:2], math.degrees(1.0) * d_theta, mean[2:]])
