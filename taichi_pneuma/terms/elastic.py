"""Hyperelasticity of a mesh of any element family (fem/elements.py) under any material law (materials/).

The energy is integrated by quadrature, E = sum_q W_q psi(F_q): at quadrature point q of an element
with nodes a = 0..k-1 and rest shape-function gradients G_qa = dN_a/dX,

    F_q = sum_a x_a G_qa^T = sum_{a >= 1} (x_a - x_0) G_qa^T      (sum_a G_qa = 0),

so every kernel runs over elements and their quadrature points, whatever the element (P1: one point
per triangle or tetrahedron, F constant; P2: three or four). The nodal force is W_q P(F_q) G_qa, and the
Hessian block of nodes (a, b) is

    W_q sum_jl G_qa,j M_(ij)(kl) G_qb,l,   M = d2psi/dF2 = sum_s lambda_s v_s v_s^T over its eigenpairs;

the projected Hessian clamps the negative lambda_s to zero at each quadrature point, which equals the
exact one wherever d2psi/dF2 is already PSD (only it takes the eigenpairs). The law supplies psi, P, d2psi/dF2
and the eigenpairs (materials/law.py), on F embedded in 3 x 3 (plane strain: F_33 = 1).

The kernels take the law and the dimension d as template arguments and the element's node and point
counts as runtime loop bounds: they compile once per (law, d), and linear and quadratic elements share
them. The Hessian kernel's loops are runtime loops, not unrolled ones: Taichi traces the body once,
which keeps its compile time short.
"""

from typing import TypeAlias

import numpy as np

from ..backend import ti
from ..fem.elements import FAMILIES, family_of
from ..fem.fields import ElementFields
from ..materials.law import element_parameters, embedded, in_plane, stress_eigensystem
from ..materials.neo_hookean import cofactor
from .base import Nodal, Table, Term, block_pattern, int32s, smallest_positive_cubic_root, smallest_positive_root

Nodes: TypeAlias = ti.types.ndarray(dtype=ti.i32, ndim=2)  # (m, k): the nodes of each element
Gradients: TypeAlias = ti.types.ndarray(dtype=ti.f64, ndim=4)  # (m, nq, k, d): dN_a/dX at each quadrature point
Weights: TypeAlias = ti.types.ndarray(dtype=ti.f64, ndim=2)  # (m, nq): the quadrature weights W
Parameters: TypeAlias = ti.types.ndarray(dtype=ti.f64, ndim=2)  # (m, p): the law's parameter vector per element
MAX_NODES = {d: max(f.n_nodes for f in FAMILIES if f.dim == d) for d in {f.dim for f in FAMILIES}}


@ti.func
def deformation_gradient(
    rest: ti.template(), u: ti.template(), nodes: ti.template(), grads: ti.template(), e, q, d: ti.template()
):
    """F (d x d) at quadrature point q of element e, from the edges x_a - x_0 = (X_a - X_0) + (u_a - u_0)
    (formed from rest and displacement differences, so short edges keep their digits)."""
    F = ti.Matrix.zero(ti.f64, d, d)
    n0 = nodes[e, 0]
    for a in range(1, nodes.shape[1]):
        na = nodes[e, a]
        for i, j in ti.static(ti.ndrange(d, d)):
            F[i, j] += ((rest[na, i] - rest[n0, i]) + (u[na, i] - u[n0, i])) * grads[e, q, a, j]
    return F


@ti.kernel
def elastic_energy(
    law: ti.template(),
    d: ti.template(),
    rest: Nodal,
    u: Nodal,
    nodes: Nodes,
    grads: Gradients,
    weights: Weights,
    parameters: Parameters,
) -> tuple[ti.f64, ti.f64]:
    """(sum_q W_q psi(F_q), min_q det F_q): the energy, and whether an element is inverted somewhere."""
    total = 0.0
    smallest = ti.math.inf
    for e, q in ti.ndrange(nodes.shape[0], weights.shape[1]):
        F = embedded(deformation_gradient(rest, u, nodes, grads, e, q, d), d)
        total += weights[e, q] * law.energy(F, element_parameters(law, parameters, e))
        ti.atomic_min(smallest, F.determinant())
    return total, smallest


@ti.kernel
def energy_densities(
    law: ti.template(),
    d: ti.template(),
    rest: Nodal,
    u: Nodal,
    nodes: Nodes,
    grads: Gradients,
    weights: Weights,
    parameters: Parameters,
    out: Weights,
):
    """out[e, q] = psi(F_q) of element e."""
    for e, q in ti.ndrange(nodes.shape[0], weights.shape[1]):
        F = embedded(deformation_gradient(rest, u, nodes, grads, e, q, d), d)
        out[e, q] = law.energy(F, element_parameters(law, parameters, e))


@ti.kernel
def elastic_gradient(
    law: ti.template(),
    d: ti.template(),
    rest: Nodal,
    u: Nodal,
    nodes: Nodes,
    grads: Gradients,
    weights: Weights,
    parameters: Parameters,
    out: Nodal,
):
    """out = dE/dx: W_q P_q G_qa scattered to the nodes."""
    for v, i in ti.ndrange(out.shape[0], d):
        out[v, i] = 0.0
    for e, q in ti.ndrange(nodes.shape[0], weights.shape[1]):
        F = embedded(deformation_gradient(rest, u, nodes, grads, e, q, d), d)
        P = weights[e, q] * law.stress(F, element_parameters(law, parameters, e))
        P_d = ti.Matrix([[P[i, j] for j in ti.static(range(d))] for i in ti.static(range(d))], dt=ti.f64)
        for a in range(nodes.shape[1]):
            force = P_d @ ti.Vector([grads[e, q, a, j] for j in ti.static(range(d))], dt=ti.f64)
            node = nodes[e, a]
            for i in ti.static(range(d)):
                out[node, i] += force[i]


@ti.kernel
def elastic_hessian(
    law: ti.template(),
    d: ti.template(),
    rest: Nodal,
    u: Nodal,
    nodes: Nodes,
    grads: Gradients,
    weights: Weights,
    parameters: Parameters,
    project: ti.i32,
    out: Table,
):
    """out[e] = the dk x dk block of element e, row-major: for nodes a <= b the d x d block (and its transpose at
    b, a) sum_q (D_qa^T M_q D_qb), (D_qa^T M D_qb)_ik = sum_jl G_qa,j M_(ij)(kl) G_qb,l, with M_q = W_q
    d2psi/dF2, or if project W_q sum_s max(lambda_qs, 0) v_qs v_qs^T over its eigenpairs (the exact Hessian takes
    no eigensystem): M once per point, then T_b = M D_qb per node, then one d x d product per node pair."""
    for e in range(nodes.shape[0]):
        k = nodes.shape[1]
        n = d * k
        for i in range(n * n):
            out[e, i] = 0.0
        for q in range(weights.shape[1]):
            F = embedded(deformation_gradient(rest, u, nodes, grads, e, q, d), d)
            p = element_parameters(law, parameters, e)
            M = ti.Matrix.zero(ti.f64, d * d, d * d)
            if project:
                lambdas, vectors = stress_eigensystem(law, F, p, d)
                for r, c in ti.ndrange(d * d, d * d):
                    entry = 0.0
                    for s in range(d * d):
                        entry += ti.max(lambdas[s], 0.0) * vectors[s, r] * vectors[s, c]
                    M[r, c] = weights[e, q] * entry
            else:
                M = weights[e, q] * in_plane(law.stress_derivative(F, p), d)
            T = ti.Matrix.zero(ti.f64, d * d, d * ti.static(MAX_NODES[d]))  # T[(i, j), (b, kk)] = (M D_qb)
            for r, b, kk in ti.ndrange(d * d, k, d):
                entry = 0.0
                for l in ti.static(range(d)):
                    entry += M[r, d * kk + l] * grads[e, q, b, l]
                T[r, d * b + kk] = entry
            for a in range(k):
                for b in range(a, k):
                    for i, kk in ti.static(ti.ndrange(d, d)):
                        h = 0.0
                        for j in ti.static(range(d)):
                            h += grads[e, q, a, j] * T[d * i + j, d * b + kk]
                        out[e, n * (d * a + i) + d * b + kk] += h
                        if b != a:
                            out[e, n * (d * b + kk) + d * a + i] += h


@ti.kernel
def inversion_step(d: ti.template(), rest: Nodal, u: Nodal, dx: Nodal, nodes: Nodes, grads: Gradients) -> ti.f64:
    """Smallest alpha > 0 with det(F_q + alpha dF_q) = 0 over all quadrature points (inf if none):

    d = 2:  det F + alpha cof F : dF + alpha^2 det dF,
    d = 3:  det F + alpha cof F : dF + alpha^2 F : cof dF + alpha^3 det dF."""
    bound = ti.math.inf
    for e, q in ti.ndrange(nodes.shape[0], grads.shape[1]):
        F = deformation_gradient(rest, u, nodes, grads, e, q, d)
        dF = ti.Matrix.zero(ti.f64, d, d)
        for a in range(1, nodes.shape[1]):
            for i, j in ti.static(ti.ndrange(d, d)):
                dF[i, j] += (dx[nodes[e, a], i] - dx[nodes[e, 0], i]) * grads[e, q, a, j]
        if ti.static(d == 2):
            cross = F[0, 0] * dF[1, 1] + F[1, 1] * dF[0, 0] - F[0, 1] * dF[1, 0] - F[1, 0] * dF[0, 1]
            ti.atomic_min(bound, smallest_positive_root(F.determinant(), cross, dF.determinant()))
        else:
            ti.atomic_min(
                bound,
                smallest_positive_cubic_root(
                    F.determinant(), (cofactor(F) * dF).sum(), (F * cofactor(dF)).sum(), dF.determinant()
                ),
            )
    return bound


class Elasticity(Term):
    """The elastic energy of a mesh (elements (m, k) of any family of the configuration's dimension) under one
    material law, with one parameter vector per element: parameters (m, len(law.parameter_names))."""

    name = "elastic"
    piecewise = True  # a sum of one energy per element (Term.restricted takes a subset)

    def __init__(self, config, elements: np.ndarray, law, parameters: np.ndarray):
        self.config = config
        self.dim = config.rest.shape[1]
        self.family = family_of(elements, self.dim)
        self.law = law
        grads, weights = self.family.quadrature(config.rest, elements)
        self.nodes = int32s(elements)
        self.grads = np.ascontiguousarray(grads)
        self.weights = np.ascontiguousarray(weights)
        self.parameters = np.ascontiguousarray(parameters, dtype=np.float64)
        self._rows, self._cols = block_pattern(self.nodes, self.dim)

    def piece_nodes(self) -> np.ndarray:
        """The elements' nodes: an element is a piece."""
        return self.nodes

    def on_pieces(self, config, pieces: np.ndarray, nodes: np.ndarray) -> "Elasticity":
        return type(self)(config, nodes, self.law, self.parameters[pieces])

    def scale_pieces(self, scale: np.ndarray) -> None:
        """Scale each element's quadrature weights (its energy) by scale (m,)."""
        self.weights = np.ascontiguousarray(self.weights * scale[:, None])

    def _arguments(self):
        return (
            self.law,
            self.dim,
            self.config.rest,
            self.config.u,
            self.nodes,
            self.grads,
            self.weights,
            self.parameters,
        )

    def energy(self) -> float:
        return elastic_energy(*self._arguments())[0]

    def gradient(self) -> np.ndarray:
        out = np.empty_like(self.config.rest)
        elastic_gradient(*self._arguments(), out)
        return out

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._rows, self._cols

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        n = self.dim * self.nodes.shape[1]
        out = np.empty((len(self.nodes), n * n))
        elastic_hessian(*self._arguments(), int(psd_only), out)
        return out.ravel()

    def max_step(self, dx: np.ndarray) -> float:
        """Largest step fraction along dx that keeps det F positive at every quadrature point."""
        return inversion_step(
            self.dim,
            self.config.rest,
            self.config.u,
            np.ascontiguousarray(dx, dtype=np.float64),
            self.nodes,
            self.grads,
        )

    def fault(self) -> str | None:
        """The material law as the cause of a breakdown, in words, or None: at some quadrature point its energy
        density is not finite, or lies below the rest state's, psi(F) < psi(I) (by more than 1e-9 of the law's
        modulus): a stable law's stress-free rest state is its energy minimum, so a law below it there gives
        energy by deforming further (a Yeoh C20 < 0 at large stretch, say) and no equilibrium exists. Names the
        element of the lowest point and its principal stretches (the singular values of F)."""
        density, rest = np.empty_like(self.weights), np.empty_like(self.weights)
        energy_densities(*self._arguments(), density)
        energy_densities(*self._arguments()[:3], np.zeros_like(self.config.u), *self._arguments()[4:], rest)
        drop = np.where(np.isfinite(density), density - rest, -np.inf)
        drop[drop >= -1e-9 * self.law.modulus(self.parameters)[:, None]] = 0.0
        e, q = np.unravel_index(np.argmin(drop), drop.shape)
        if drop[e, q] == 0.0:
            return None
        F = ElementFields(self.config.rest, self.nodes).deformation_gradients(self.config.rest + self.config.u)[e, q]
        stretches = ", ".join(f"{s:.3g}" for s in np.linalg.svd(F, compute_uv=False))
        why = (
            f"its energy density there, {density[e, q]:.4g}, lies below the rest state's {rest[e, q]:.4g}, so it "
            f"gives energy by deforming further and no equilibrium exists; check its coefficients over the "
            f"stretches reached"
            if np.isfinite(density[e, q])
            else "its energy density there is not finite: these stretches are outside the law's range"
        )
        return f"the material law {self.law.name!r} is unstable at element {e} (principal stretches {stretches}): {why}"

    def min_determinant(self) -> float:
        """Smallest det F over the quadrature points (negative where an element is inverted)."""
        return elastic_energy(*self._arguments())[1]
