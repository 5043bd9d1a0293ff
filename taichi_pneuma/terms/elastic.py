"""Stable neo-Hookean elasticity on linear triangles (plane strain), as Taichi kernels.

Per unit rest area (Macklin-Mueller form, rest-stable, finite for inverted elements):

    psi(F) = mu (1 - J) + lam/2 (1 - J)^2 + mu/2 (|F|_F^2 - 2),   J = det F,
    mu = E / (2 (1 + nu)),   lam = E nu / ((1 + nu)(1 - 2 nu)).

With F = Ds Dm^-1 (Ds = [x1 - x0, x2 - x0], Dm the same at rest) and g = dJ/dF = cof F:

    P = dpsi/dF = mu F - (mu + lam (1 - J)) g
    d2psi/dF2 = mu I + lam g g^T - (mu + lam (1 - J)) d2J/dF2

mu and lam may differ per element (a material per region). The element Hessian is  W D^T [d2psi/dF2]_+ D  (W rest area, D = dvec(F)/dx, 6 x 4), where
[.]_+ clamps the negative eigenvalues of the 4 x 4 matrix to zero (Jacobi eigen-decomposition);
it equals the exact Hessian wherever d2psi/dF2 is already PSD.
"""


import numpy as np
import taichi as ti

from .base import Term, quadratic_roots, vertex_dofs

JACOBI_SWEEPS = 8
PAIRS = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]


def lame_parameters(youngs_modulus, poisson_ratio):
    """(mu, lam) of an isotropic material from Young's modulus and Poisson's ratio (scalars or arrays)."""
    e, nu = youngs_modulus, poisson_ratio
    return e / (2.0 * (1.0 + nu)), e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))


@ti.func
def cofactor(F):
    """dJ/dF of a 2 x 2 matrix, flattened row-major as vec(F) = (F00, F01, F10, F11)."""
    return ti.Vector([F[1, 1], -F[1, 0], -F[0, 1], F[0, 0]])


@ti.func
def project_psd(M):
    """Clamp the negative eigenvalues of a symmetric 4 x 4 matrix to zero (cyclic Jacobi)."""
    A = M
    V = ti.Matrix.identity(ti.f64, 4)
    for _ in range(JACOBI_SWEEPS):
        for p, q in ti.static(PAIRS):
            if ti.abs(A[p, q]) > 1e-300:
                theta = (A[q, q] - A[p, p]) / (2.0 * A[p, q])
                t = 1.0 / (ti.abs(theta) + ti.sqrt(theta * theta + 1.0))
                if theta < 0:
                    t = -t
                c = 1.0 / ti.sqrt(t * t + 1.0)
                s = t * c
                R = ti.Matrix.identity(ti.f64, 4)
                R[p, p] = c
                R[q, q] = c
                R[p, q] = s
                R[q, p] = -s
                A = R.transpose() @ A @ R
                V = V @ R
    D = ti.Matrix.zero(ti.f64, 4, 4)
    for i in ti.static(range(4)):
        D[i, i] = ti.max(A[i, i], 0.0)
    return V @ D @ V.transpose()


@ti.data_oriented
class NeoHookean(Term):
    """Stable neo-Hookean energy of a triangle mesh, with per-element moduli, and the math above.

    youngs_modulus and poisson_ratio: scalars, or one value per triangle.
    """

    name = "elastic"

    def __init__(self, config, triangles: np.ndarray, youngs_modulus, poisson_ratio):
        self.config = config
        rest = config.rest_numpy
        n = config.n_vertices
        m = len(triangles)
        mu, lam = lame_parameters(np.broadcast_to(np.asarray(youngs_modulus, dtype=np.float64), (m,)),
                                  np.broadcast_to(np.asarray(poisson_ratio, dtype=np.float64), (m,)))
        self.n_triangles = m
        edges = np.stack([rest[triangles[:, 1]] - rest[triangles[:, 0]],
                          rest[triangles[:, 2]] - rest[triangles[:, 0]]], axis=2)  # (m, 2, 2) columns e1, e2
        self.rest_area = 0.5 * np.linalg.det(edges)
        self.tri = ti.Vector.field(3, ti.i32, m)
        self.dm_inv = ti.Matrix.field(2, 2, ti.f64, m)
        self.area = ti.field(ti.f64, m)
        self.mu = ti.field(ti.f64, m)
        self.lam = ti.field(ti.f64, m)
        self.force = ti.Vector.field(2, ti.f64, n)
        self.hess = ti.field(ti.f64, (m, 36))
        self.reduction = ti.field(ti.f64, ())
        self.dx = ti.Vector.field(2, ti.f64, n)
        self.tri.from_numpy(triangles.astype(np.int32))
        self.dm_inv.from_numpy(np.linalg.inv(edges))
        self.area.from_numpy(self.rest_area)
        self.mu.from_numpy(np.ascontiguousarray(mu))
        self.lam.from_numpy(np.ascontiguousarray(lam))
        dofs = vertex_dofs(triangles.ravel()).reshape(m, 6)
        self._rows = np.repeat(dofs, 6, axis=1).ravel()
        self._cols = np.tile(dofs, (1, 6)).ravel()

    @ti.func
    def deformation_gradient(self, e):
        i = self.tri[e]
        ds = ti.Matrix.cols([self.config.edge(i[0], i[1]), self.config.edge(i[0], i[2])])
        return ds @ self.dm_inv[e]

    @ti.func
    def psi(self, e, F):
        J = F.determinant()
        return self.mu[e] * (1.0 - J) + 0.5 * self.lam[e] * (1.0 - J) ** 2 + 0.5 * self.mu[e] * (F.norm_sqr() - 2.0)

    @ti.kernel
    def energy(self) -> ti.f64:
        total = 0.0
        for e in range(self.n_triangles):
            total += self.area[e] * self.psi(e, self.deformation_gradient(e))
        return total

    @ti.kernel
    def _compute_force(self):
        for v in self.force:
            self.force[v] = ti.Vector([0.0, 0.0])
        for e in range(self.n_triangles):
            F = self.deformation_gradient(e)
            g = cofactor(F)
            mu, lam = self.mu[e], self.lam[e]
            P = mu * F - (mu + lam * (1.0 - F.determinant())) * ti.Matrix([[g[0], g[1]], [g[2], g[3]]])
            G = self.area[e] * P @ self.dm_inv[e].transpose()
            i = self.tri[e]
            self.force[i[1]] += ti.Vector([G[0, 0], G[1, 0]])
            self.force[i[2]] += ti.Vector([G[0, 1], G[1, 1]])
            self.force[i[0]] -= ti.Vector([G[0, 0] + G[0, 1], G[1, 0] + G[1, 1]])

    def gradient(self) -> np.ndarray:
        self._compute_force()
        return self.force.to_numpy()

    @ti.kernel
    def _compute_hessian(self, project: ti.i32):
        for e in range(self.n_triangles):
            F = self.deformation_gradient(e)
            g = cofactor(F)
            mu, lam = self.mu[e], self.lam[e]
            c = mu + lam * (1.0 - F.determinant())
            # d2J/dF2 for vec(F) = (F00, F01, F10, F11)
            hj = ti.Matrix([[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, -1.0, 0.0], [0.0, -1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]])
            M = mu * ti.Matrix.identity(ti.f64, 4) + lam * g.outer_product(g) - c * hj
            if project:
                M = project_psd(M)
            B = self.dm_inv[e]
            # D[r, 2a + d] = dvec(F)_r / dx_{a,d}, r = 2 i + j:  dF_ij/dx_{a,d} = delta_id * dB_aj
            # with dB_1j = B[0, j], dB_2j = B[1, j], dB_0j = -(B[0, j] + B[1, j]).
            D = ti.Matrix.zero(ti.f64, 4, 6)
            for i, j in ti.static(ti.ndrange(2, 2)):
                D[2 * i + j, 2 * 1 + i] = B[0, j]
                D[2 * i + j, 2 * 2 + i] = B[1, j]
                D[2 * i + j, 2 * 0 + i] = -(B[0, j] + B[1, j])
            K = self.area[e] * D.transpose() @ M @ D
            for a in ti.static(range(6)):
                for b in ti.static(range(6)):
                    self.hess[e, 6 * a + b] = K[a, b]

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._rows, self._cols

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        self._compute_hessian(psd_only)
        return self.hess.to_numpy().ravel()

    @ti.kernel
    def _compute_step_bound(self):
        """Smallest alpha > 0 with det(Ds + alpha dDs) = 0 over all elements (inf if none)."""
        self.reduction[None] = ti.math.inf
        for e in range(self.n_triangles):
            i = self.tri[e]
            a1 = self.config.edge(i[0], i[1])
            a2 = self.config.edge(i[0], i[2])
            b1 = self.dx[i[1]] - self.dx[i[0]]
            b2 = self.dx[i[2]] - self.dx[i[0]]
            # det(a + t b) = c0 + c1 t + c2 t^2 with det([u, v]) = u x v
            c0 = a1.cross(a2)
            c1 = a1.cross(b2) + b1.cross(a2)
            c2 = b1.cross(b2)
            roots = quadratic_roots(c0, c1, c2)
            root = ti.math.inf
            for r in ti.static(range(2)):
                if roots[r] > 0:
                    root = ti.min(root, roots[r])
            ti.atomic_min(self.reduction[None], root)

    def max_step(self, dx: np.ndarray) -> float:
        """Largest step fraction along dx that keeps every triangle's determinant positive."""
        self.dx.from_numpy(dx)
        self._compute_step_bound()
        return float(self.reduction[None])

    def min_determinant(self) -> float:
        """Smallest det F over the mesh (negative when a triangle is inverted)."""
        self._compute_min_det()
        return float(self.reduction[None])

    @ti.kernel
    def _compute_min_det(self):
        self.reduction[None] = ti.math.inf
        for e in range(self.n_triangles):
            ti.atomic_min(self.reduction[None], self.deformation_gradient(e).determinant())
