"""Stable neo-Hookean elasticity on linear triangles (plane strain), as Taichi kernels.

Per unit rest area (Macklin-Mueller form, rest-stable, finite for inverted elements):

    psi(F) = mu (1 - J) + lam/2 (1 - J)^2 + mu/2 (|F|_F^2 - 2),   J = det F,
    mu = E / (2 (1 + nu)),   lam = E nu / ((1 + nu)(1 - 2 nu)).

With F = Ds Dm^-1 (Ds = [x1 - x0, x2 - x0], Dm the same at rest) and g = dJ/dF = cof F:

    P = dpsi/dF = mu F - c g,   c = mu + lam (1 - J),
    M = d2psi/dF2 = mu I + lam g g^T - c H_J,   H_J = d2J/dF2 (constant),

mu and lam may differ per element (a material per region). The element Hessian is  W D^T M D
(W rest area, D = dvec(F)/dx, 4 x 6); the projected one uses [M]_+, M with its negative
eigenvalues clamped to zero, which equals M wherever M is already PSD.

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

from .base import Scalars, Table, Term, Triples, Vec2s, block_pattern, edge, int32s, smallest_positive_root

Mat2s = ti.types.ndarray(dtype=ti.types.matrix(2, 2, ti.f64), ndim=1)  # (m, 2, 2): Dm^-1 per triangle
VEC3 = ti.types.vector(3, ti.f64)
Params = ti.types.ndarray(dtype=VEC3, ndim=1)  # (m, 3): rest area W, mu, lam per triangle
SQRT_HALF = 0.7071067811865476


def lame_parameters(youngs_modulus, poisson_ratio):
    """(mu, lam) of an isotropic material from Young's modulus and Poisson's ratio (scalars or arrays)."""
    e, nu = youngs_modulus, poisson_ratio
    return e / (2.0 * (1.0 + nu)), e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))


@ti.func
def deformation_gradient(rest: ti.template(), u: ti.template(), tri: ti.template(), dm_inv: ti.template(), e):
    i = tri[e]
    return ti.Matrix.cols([edge(rest, u, i[0], i[1]), edge(rest, u, i[0], i[2])]) @ dm_inv[e]


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
def elastic_energy(rest: Vec2s, u: Vec2s, tri: Triples, dm_inv: Mat2s, params: Params) -> tuple[ti.f64, ti.f64]:
    """(sum_e W_e psi(F_e), min_e det F_e): the energy, and whether a triangle is inverted."""
    total = 0.0
    smallest = ti.math.inf
    for e in range(tri.shape[0]):
        F = deformation_gradient(rest, u, tri, dm_inv, e)
        total += params[e][0] * psi(F, params[e][1], params[e][2])
        ti.atomic_min(smallest, F.determinant())
    return total, smallest


@ti.kernel
def elastic_gradient(rest: Vec2s, u: Vec2s, tri: Triples, dm_inv: Mat2s, params: Params, out: Vec2s):
    """out = dE/dx: W P Dm^-T scattered to the triangles' vertices."""
    for v in range(out.shape[0]):
        out[v] = ti.Vector([0.0, 0.0])
    for e in range(tri.shape[0]):
        F = deformation_gradient(rest, u, tri, dm_inv, e)
        g = cofactor(F)
        w, mu, lam = params[e][0], params[e][1], params[e][2]
        P = mu * F - (mu + lam * (1.0 - F.determinant())) * ti.Matrix([[g[0], g[1]], [g[2], g[3]]])
        G = w * P @ dm_inv[e].transpose()
        i = tri[e]
        out[i[1]] += ti.Vector([G[0, 0], G[1, 0]])
        out[i[2]] += ti.Vector([G[0, 1], G[1, 1]])
        out[i[0]] -= ti.Vector([G[0, 0] + G[0, 1], G[1, 0] + G[1, 1]])


@ti.kernel
def elastic_hessian(rest: Vec2s, u: Vec2s, tri: Triples, dm_inv: Mat2s, params: Params, project: ti.i32, out: Table):
    """out[e] = the 6 x 6 block W D^T M D of triangle e, row-major (M projected to PSD if project), summed
    over the eigenpairs of M as W sum_k lambda_k q_k q_k^T, q_k = D^T v_k.

    D = dvec(F)/dx: with G the 3 x 2 matrix whose row a holds the weights of x_a in F's columns
    (-(B0 + B1), B0, B1 for the rows B0, B1 of Dm^-1), (D^T v)_{2a+d} = sum_j G[a, j] v[2d + j].
    (Runtime loops, not unrolled ones: Taichi traces the body once, which keeps its compile time short.)"""
    for e in range(tri.shape[0]):
        lambdas, vectors = stress_eigensystem(deformation_gradient(rest, u, tri, dm_inv, e), params[e][1], params[e][2])
        if project:
            lambdas = ti.max(lambdas, 0.0)
        B = dm_inv[e]
        G = ti.Matrix([[-B[0, 0] - B[1, 0], -B[0, 1] - B[1, 1]], [B[0, 0], B[0, 1]], [B[1, 0], B[1, 1]]])
        Q = ti.Matrix.zero(ti.f64, 4, 6)
        for k, a, d in ti.ndrange(4, 3, 2):
            Q[k, 2 * a + d] = G[a, 0] * vectors[k, 2 * d] + G[a, 1] * vectors[k, 2 * d + 1]
        for i, j in ti.ndrange(6, 6):
            h = 0.0
            for k in range(4):
                h += lambdas[k] * Q[k, i] * Q[k, j]
            out[e, 6 * i + j] = params[e][0] * h


@ti.kernel
def inversion_step(rest: Vec2s, u: Vec2s, dx: Vec2s, tri: Triples) -> ti.f64:
    """Smallest alpha > 0 with det(Ds + alpha dDs) = 0 over all triangles (inf if none)."""
    bound = ti.math.inf
    for e in range(tri.shape[0]):
        i = tri[e]
        a1, a2 = edge(rest, u, i[0], i[1]), edge(rest, u, i[0], i[2])
        b1, b2 = dx[i[1]] - dx[i[0]], dx[i[2]] - dx[i[0]]
        # det(a + t b) = c0 + c1 t + c2 t^2 with det([p, q]) = p x q
        ti.atomic_min(bound, smallest_positive_root(a1.cross(a2), a1.cross(b2) + b1.cross(a2), b1.cross(b2)))
    return bound


class NeoHookean(Term):
    """Stable neo-Hookean energy of a triangle mesh, with per-element moduli, and the math above.

    youngs_modulus and poisson_ratio: scalars, or one value per triangle.
    """

    name = "elastic"

    def __init__(self, config, triangles: np.ndarray, youngs_modulus, poisson_ratio):
        self.config = config
        rest = config.rest
        m = len(triangles)
        mu, lam = lame_parameters(np.broadcast_to(np.asarray(youngs_modulus, dtype=np.float64), (m,)),
                                  np.broadcast_to(np.asarray(poisson_ratio, dtype=np.float64), (m,)))
        self.n_triangles = m
        edges = np.stack([rest[triangles[:, 1]] - rest[triangles[:, 0]],
                          rest[triangles[:, 2]] - rest[triangles[:, 0]]], axis=2)  # (m, 2, 2) columns e1, e2
        self.rest_area = 0.5 * np.linalg.det(edges)
        self.tri = int32s(triangles)
        self.dm_inv = np.ascontiguousarray(np.linalg.inv(edges))
        self.params = np.ascontiguousarray(np.column_stack([self.rest_area, mu, lam]))
        self._rows, self._cols = block_pattern(triangles)

    def _mesh(self):
        return self.config.rest, self.config.u, self.tri, self.dm_inv

    def energy(self) -> float:
        return elastic_energy(*self._mesh(), self.params)[0]

    def gradient(self) -> np.ndarray:
        out = np.empty_like(self.config.rest)
        elastic_gradient(*self._mesh(), self.params, out)
        return out

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._rows, self._cols

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        out = np.empty((self.n_triangles, 36))
        elastic_hessian(*self._mesh(), self.params, int(psd_only), out)
        return out.ravel()

    def max_step(self, dx: np.ndarray) -> float:
        """Largest step fraction along dx that keeps every triangle's determinant positive."""
        return inversion_step(self.config.rest, self.config.u, np.ascontiguousarray(dx, dtype=np.float64), self.tri)

    def min_determinant(self) -> float:
        """Smallest det F over the mesh (negative when a triangle is inverted)."""
        return elastic_energy(*self._mesh(), self.params)[1]
