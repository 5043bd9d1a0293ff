"""Stable neo-Hookean elasticity on linear (P1) or quadratic (P2) triangles, plane strain, as Taichi kernels.

Per unit rest area (Macklin-Mueller form, rest-stable, finite for inverted elements):

    psi(F) = mu (1 - J) + lam/2 (1 - J)^2 + mu/2 (|F|_F^2 - 2),   J = det F,
    mu = E / (2 (1 + nu)),   lam = E nu / ((1 + nu)(1 - 2 nu)).

The energy is integrated by quadrature, E = sum_q W_q psi(F_q): at quadrature point q of an element
with nodes a = 0..k-1 and rest shape-function gradients G_qa = dN_a/dX,

    F_q = sum_a x_a G_qa^T = sum_{a >= 1} (x_a - x_0) G_qa^T      (sum_a G_qa = 0),

so every kernel runs over elements and their quadrature points, whatever the element: P1 has one point
per triangle (k = 3, F constant, W = the area), P2 three (k = 6, the 3-point rule of degree 2 at
barycentric (2/3, 1/6, 1/6) and permutations, W = area / 3: exact for the P2 stiffness of small strain).

With g = dJ/dF = cof F and c = mu + lam (1 - J):

    P = dpsi/dF = mu F - c g,   M = d2psi/dF2 = mu I + lam g g^T - c H_J,   H_J = d2J/dF2 (constant),

the nodal force is W_q P G_qa and the Hessian block of nodes (a, b) is W_q sum over M's eigenpairs
lambda_k (D^T v_k)_a (D^T v_k)_b^T, with (D^T v)_a = V G_qa for v = vec(V). The projected Hessian
clamps the negative lambda_k to zero at each quadrature point, which equals the exact one wherever
M is already PSD.

The eigensystem of M is analytic. With vec(F) = (F00, F01, F10, F11), H_J has eigenvalue +1 on
span{(1,0,0,1), (0,1,-1,0)} and -1 on span{(1,0,0,-1), (0,1,1,0)}, so mu I - c H_J is mu - c on the
first plane and mu + c on the second. Split g = a u_+ + b u_- into its parts in the two planes
(a, b >= 0, u_+- unit) and let w_+- complete each plane. Then

    M = (mu - c) w_+ w_+^T + (mu + c) w_- w_-^T + [u_+ u_-] B [u_+ u_-]^T,
    B = [[mu - c + lam a^2, lam a b], [lam a b, mu + c + lam b^2]],

and the 2 x 2 block B has closed-form eigenpairs: four eigenpairs of M, no iteration.
"""


import numpy as np
import taichi as ti

from .base import Table, Term, Vec2s, block_pattern, edge, int32s, smallest_positive_root

Nodes = ti.types.ndarray(dtype=ti.i32, ndim=2)  # (m, k): the nodes of each element
Gradients = ti.types.ndarray(dtype=ti.f64, ndim=4)  # (m, nq, k, 2): dN_a/dX at each quadrature point
Weights = ti.types.ndarray(dtype=ti.f64, ndim=2)  # (m, nq): the quadrature weights W
Moduli = ti.types.ndarray(dtype=ti.types.vector(2, ti.f64), ndim=1)  # (m, 2): mu, lam per element
SQRT_HALF = 0.7071067811865476
MAX_NODES = 6

# Reference triangle (xi, eta) = barycentric (1 - xi - eta, xi, eta); P2 node order: corners 0, 1, 2,
# then the midside nodes of edges 01, 12, 20. Rules: (points, weights summing to 1).
RULES = {1: (np.array([[1 / 3, 1 / 3]]), np.array([1.0])),
         2: (np.array([[1 / 6, 1 / 6], [2 / 3, 1 / 6], [1 / 6, 2 / 3]]), np.full(3, 1 / 3))}


def shape_gradients(order: int, xi: float, eta: float) -> np.ndarray:
    """dN_a/d(xi, eta) of the P1 (3 x 2) or P2 (6 x 2) shape functions at (xi, eta)."""
    l0, l1, l2 = 1.0 - xi - eta, xi, eta
    dl = np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])  # dL_i/d(xi, eta)
    if order == 1:
        return dl
    corners = [(4 * l - 1) * dl[i] for i, l in enumerate((l0, l1, l2))]  # N_i = L_i (2 L_i - 1)
    mids = [4 * (la * dl[j] + lb * dl[i]) for i, j, la, lb in ((0, 1, l0, l1), (1, 2, l1, l2), (2, 0, l2, l0))]
    return np.array(corners + mids)  # N = 4 L_i L_j on edge ij


def quadrature(vertices: np.ndarray, elements: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rest gradients G (m, nq, k, 2) and weights W (m, nq) at the quadrature points of straight-sided
    P1 (m, 3) or P2 (m, 6) elements."""
    order = 1 if elements.shape[1] == 3 else 2
    points, weights = RULES[order]
    corners = vertices[elements[:, :3]]
    jacobian = np.stack([corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]], axis=2)  # dX/d(xi, eta)
    inverse, area = np.linalg.inv(jacobian), 0.5 * np.linalg.det(jacobian)
    gradients = np.stack([shape_gradients(order, *p) @ inverse for p in points], axis=1)
    return gradients, area[:, None] * weights[None, :]


def lame_parameters(youngs_modulus, poisson_ratio):
    """(mu, lam) of an isotropic material from Young's modulus and Poisson's ratio (scalars or arrays)."""
    e, nu = youngs_modulus, poisson_ratio
    return e / (2.0 * (1.0 + nu)), e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))


@ti.func
def shape_gradient(grads: ti.template(), e, q, a):
    """G_qa of element e as a 2-vector."""
    return ti.Vector([grads[e, q, a, 0], grads[e, q, a, 1]])


@ti.func
def deformation_gradient(rest: ti.template(), u: ti.template(), nodes: ti.template(), grads: ti.template(), e, q):
    """F at quadrature point q of element e, from the edges to its first node."""
    F = ti.Matrix.zero(ti.f64, 2, 2)
    for a in range(1, nodes.shape[1]):
        F += edge(rest, u, nodes[e, 0], nodes[e, a]).outer_product(shape_gradient(grads, e, q, a))
    return F


@ti.func
def cofactor(F):
    """dJ/dF of a 2 x 2 matrix, flattened row-major as vec(F) = (F00, F01, F10, F11)."""
    return ti.Vector([F[1, 1], -F[1, 0], -F[0, 1], F[0, 0]])


@ti.func
def psi(F, mu, lam):
    J = F.determinant()
    return mu * (1.0 - J) + 0.5 * lam * (1.0 - J) ** 2 + 0.5 * mu * (F.norm_sqr() - 2.0)


@ti.func
def plane_split(g, p, q):
    """The part of g in the plane spanned by orthonormal p, q: its length a, unit direction u, and the
    unit w completing the plane (u = p, w = q when that part vanishes)."""
    s, t = g.dot(p), g.dot(q)
    a = ti.sqrt(s * s + t * t)
    uu, ww = p, q
    if a > 0:
        uu = (s * p + t * q) / a
        ww = (-t * p + s * q) / a
    return a, uu, ww


@ti.func
def stress_eigensystem(F, mu, lam):
    """Eigenvalues (4-vector) and unit eigenvectors (the rows of a 4 x 4 matrix) of d2psi/dF2."""
    g = cofactor(F)
    c = mu + lam * (1.0 - F.determinant())
    r = SQRT_HALF
    a, u_p, w_p = plane_split(g, ti.Vector([r, 0.0, 0.0, r]), ti.Vector([0.0, r, -r, 0.0]))
    b, u_m, w_m = plane_split(g, ti.Vector([r, 0.0, 0.0, -r]), ti.Vector([0.0, r, r, 0.0]))
    p, q, s = mu - c + lam * a * a, lam * a * b, mu + c + lam * b * b  # B = [[p, q], [q, s]]
    mean, half = 0.5 * (p + s), ti.sqrt(0.25 * (p - s) ** 2 + q * q)
    theta = 0.5 * ti.atan2(2.0 * q, p - s)  # (cos, sin) theta: the eigenvector of mean + half
    v1 = ti.cos(theta) * u_p + ti.sin(theta) * u_m
    v2 = -ti.sin(theta) * u_p + ti.cos(theta) * u_m
    return ti.Vector([mu - c, mu + c, mean + half, mean - half]), ti.Matrix.rows([w_p, w_m, v1, v2])


@ti.kernel
def elastic_energy(rest: Vec2s, u: Vec2s, nodes: Nodes, grads: Gradients, weights: Weights,
                   moduli: Moduli) -> tuple[ti.f64, ti.f64]:
    """(sum_q W_q psi(F_q), min_q det F_q): the energy, and whether an element is inverted somewhere."""
    total = 0.0
    smallest = ti.math.inf
    for e, q in ti.ndrange(nodes.shape[0], weights.shape[1]):
        F = deformation_gradient(rest, u, nodes, grads, e, q)
        total += weights[e, q] * psi(F, moduli[e][0], moduli[e][1])
        ti.atomic_min(smallest, F.determinant())
    return total, smallest


@ti.kernel
def elastic_gradient(rest: Vec2s, u: Vec2s, nodes: Nodes, grads: Gradients, weights: Weights, moduli: Moduli,
                     out: Vec2s):
    """out = dE/dx: W_q P_q G_qa scattered to the nodes."""
    for v in range(out.shape[0]):
        out[v] = ti.Vector([0.0, 0.0])
    for e, q in ti.ndrange(nodes.shape[0], weights.shape[1]):
        F = deformation_gradient(rest, u, nodes, grads, e, q)
        g = cofactor(F)
        mu, lam = moduli[e][0], moduli[e][1]
        P = weights[e, q] * (mu * F - (mu + lam * (1.0 - F.determinant())) * ti.Matrix([[g[0], g[1]], [g[2], g[3]]]))
        for a in range(nodes.shape[1]):
            out[nodes[e, a]] += P @ shape_gradient(grads, e, q, a)


@ti.kernel
def elastic_hessian(rest: Vec2s, u: Vec2s, nodes: Nodes, grads: Gradients, weights: Weights, moduli: Moduli,
                    project: ti.i32, out: Table):
    """out[e] = the 2k x 2k block sum_q W_q sum_k lambda_qk Q_qk Q_qk^T of element e, row-major, with
    Q_qk[2a + d] = (V_qk G_qa)_d (M's eigenvalues clamped to >= 0 if project). Runtime loops, not unrolled
    ones: Taichi traces the body once, which keeps its compile time short."""
    for e in range(nodes.shape[0]):
        n = 2 * nodes.shape[1]
        for i in range(n * n):
            out[e, i] = 0.0
        for q in range(weights.shape[1]):
            lambdas, vectors = stress_eigensystem(deformation_gradient(rest, u, nodes, grads, e, q), moduli[e][0],
                                                  moduli[e][1])
            if project:
                lambdas = ti.max(lambdas, 0.0)
            Q = ti.Matrix.zero(ti.f64, 4, 2 * MAX_NODES)
            for k, a, d in ti.ndrange(4, nodes.shape[1], 2):
                Q[k, 2 * a + d] = vectors[k, 2 * d] * grads[e, q, a, 0] + vectors[k, 2 * d + 1] * grads[e, q, a, 1]
            for i, j in ti.ndrange(n, n):
                h = 0.0
                for k in range(4):
                    h += lambdas[k] * Q[k, i] * Q[k, j]
                out[e, n * i + j] += weights[e, q] * h


@ti.kernel
def inversion_step(rest: Vec2s, u: Vec2s, dx: Vec2s, nodes: Nodes, grads: Gradients) -> ti.f64:
    """Smallest alpha > 0 with det(F_q + alpha dF_q) = 0 over all quadrature points (inf if none):
    det F + alpha cof F : dF + alpha^2 det dF."""
    bound = ti.math.inf
    for e, q in ti.ndrange(nodes.shape[0], grads.shape[1]):
        F = deformation_gradient(rest, u, nodes, grads, e, q)
        dF = ti.Matrix.zero(ti.f64, 2, 2)
        for a in range(1, nodes.shape[1]):
            dF += (dx[nodes[e, a]] - dx[nodes[e, 0]]).outer_product(shape_gradient(grads, e, q, a))
        cross = F[0, 0] * dF[1, 1] + F[1, 1] * dF[0, 0] - F[0, 1] * dF[1, 0] - F[1, 0] * dF[0, 1]
        ti.atomic_min(bound, smallest_positive_root(F.determinant(), cross, dF.determinant()))
    return bound


class NeoHookean(Term):
    """Stable neo-Hookean energy of a P1 (m, 3) or P2 (m, 6) triangle mesh, with per-element moduli.

    youngs_modulus and poisson_ratio: scalars, or one value per element.
    """

    name = "elastic"

    def __init__(self, config, elements: np.ndarray, youngs_modulus, poisson_ratio):
        self.config = config
        m = len(elements)
        mu, lam = lame_parameters(np.broadcast_to(np.asarray(youngs_modulus, dtype=np.float64), (m,)),
                                  np.broadcast_to(np.asarray(poisson_ratio, dtype=np.float64), (m,)))
        grads, weights = quadrature(config.rest, elements)
        self.nodes = int32s(elements)
        self.grads = np.ascontiguousarray(grads)
        self.weights = np.ascontiguousarray(weights)
        self.moduli = np.ascontiguousarray(np.column_stack([mu, lam]))
        self._rows, self._cols = block_pattern(self.nodes)

    def _mesh(self):
        return self.config.rest, self.config.u, self.nodes, self.grads

    def energy(self) -> float:
        return elastic_energy(*self._mesh(), self.weights, self.moduli)[0]

    def gradient(self) -> np.ndarray:
        out = np.empty_like(self.config.rest)
        elastic_gradient(*self._mesh(), self.weights, self.moduli, out)
        return out

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._rows, self._cols

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        n = 2 * self.nodes.shape[1]
        out = np.empty((len(self.nodes), n * n))
        elastic_hessian(*self._mesh(), self.weights, self.moduli, int(psd_only), out)
        return out.ravel()

    def max_step(self, dx: np.ndarray) -> float:
        """Largest step fraction along dx that keeps det F positive at every quadrature point."""
        return inversion_step(self.config.rest, self.config.u, np.ascontiguousarray(dx, dtype=np.float64),
                              self.nodes, self.grads)

    def min_determinant(self) -> float:
        """Smallest det F over the quadrature points (negative where an element is inverted)."""
        return elastic_energy(*self._mesh(), self.weights, self.moduli)[1]
