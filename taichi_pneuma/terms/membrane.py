"""A thin elastic sheet bonded to the body's nodes: a Saint Venant-Kirchhoff plane-stress membrane on cells of
m + 1 = d nodes (3D: triangles, m = 2; 2D: segments, m = 1, per unit depth), so a sheet of thickness t costs no
elements of size t.

A cell's rest shape is its m x m edge matrix Dm in its own tangent plane (3D: Dm = [[e1.t1, e2.t1], [0, e2.t2]]
in the orthonormal basis t1 = e1 / |e1|, t2 in the plane; 2D: Dm = [L0]); with D = Dm^-1 and the vectors
g_a = D[a - 1, :] (a = 1..m), g_0 = -sum_a g_a, the deformation gradient (d x m) is

    F = sum_a x_a g_a^T = [x_1 - x_0, ..., x_m - x_0] D,
    G = (F^T F - I) / 2                              (m x m Green strain),
    psi = lam/2 tr(G)^2 + mu tr(G^2),   lam = E nu / (1 - nu^2) (plane stress),  mu = E / (2 (1 + nu)),

and the energy is sum over cells W psi, W = t A0 (3D), t L0 (2D). In 2D, G = g = (s^2 - 1) / 2 with the stretch
s = l / L0 and psi = (lam/2 + mu) g^2 = E' g^2 / 2, E' = E / (1 - nu^2). With S = dpsi/dG = lam tr(G) I + 2 mu G,
the force on node a is W F S g_a and the Hessian block of nodes a, b is

    H_(ai)(bk) = W [ delta_ik g_a.S g_b + lam (F g_a)_i (F g_b)_k + mu ((F F^T)_ik g_a.g_b + (F g_b)_i (F g_a)_k) ].

With wrinkles = 0 it is indefinite under compression (the sheet buckles: tr(G) < 0 makes S negative); psd_only
projects each cell's d^2 x d^2 block onto the PSD cone, its negative eigenvalues clamped to 0, in NumPy (a batched
np.linalg.eigh after the kernel: Taichi has no eigensolver past 3 x 3).

Wrinkling (wrinkles = 1, the default): a paper or fabric sheet on soft rubber carries no compression, it wrinkles
(at a strain of order (E_s / E)^(2/3), 0.1 % for paper on silicone). The energy is then tension-field theory's
relaxed one (Pipkin 1986; Steigmann 1990), convex in G: with the principal Green strains g1 >= g2 of G and their
unit eigenvectors n, p (m = 2: the 2 x 2 symmetric eigenproblem in closed form; m = 1: g1 = g2 = G),
nu = lam / (lam + 2 mu) and E = 4 mu (lam + mu) / (lam + 2 mu) the sheet's own,

    taut      S2 = lam tr(G) + 2 mu g2 >= 0:  psi = lam/2 tr(G)^2 + mu tr(G^2),  S = lam tr(G) I + 2 mu G,
    wrinkled  S2 < 0 and g1 > 0:              psi = E/2 g1^2,                   S = E g1 n n^T,
    slack     otherwise (g1 <= 0):            psi = 0,                          S = 0,

C1 across the regimes (at g2 = -nu g1 both give E/2 g1^2; in 2D, m = 1, there is no wrinkled regime: the sheet
is tension-only). The material tangent d2psi[H1, H2] for symmetric H1, H2 is in every regime

    lam_t tr(H1) tr(H2) + 2 mu_t H1:H2 + c_n (n.H1 n)(n.H2 n) + c_np (n.H1 p)(n.H2 p),

(lam_t, mu_t, c_n, c_np) = (lam, mu, 0, 0) taut, (0, 0, E, 2 E g1 / (g1 - g2)) wrinkled (the second from the
derivative of the eigenprojector; g1 - g2 >= (1 + nu) g1 > 0 there), 0 slack. dG along node a, direction i is
sym(f_i g_a^T), f_i = F^T e_i, so a term c X (x) X of the tangent (X = n n^T, sym(n p^T)) adds
W c (f_i.X g_a)(f_k.X g_b) to H_(ai)(bk): f_i.(n n^T) g_a = (F n)_i (n.g_a), f_i.sym(n p^T) g_a =
((F n)_i (p.g_a) + (F p)_i (n.g_a)) / 2. The tangent is PSD and S >= 0, so the exact Hessian is PSD: psd_only
changes nothing. wrinkles = 0 keeps the SVK membrane in every regime.

The kernels take the dimension d as a template argument and everything else (cells, rest shapes, weights, lam,
mu and wrinkles) as arrays and runtime scalars: they compile once per d, whatever the mesh or the sheet.
"""

from typing import TypeAlias

import numpy as np

from ..backend import ti
from .base import Nodal, Scalars, Table, Term, block_pattern, int32s

Cells: TypeAlias = ti.types.ndarray(dtype=ti.i32, ndim=2)  # (f, d): the nodes of each cell


@ti.func
def strain_state(
    rest: ti.template(), u: ti.template(), cells: ti.template(), inverse: ti.template(), c, d: ti.template()
):
    """(F (d x m), the shape vectors g_0..g_m of cell c as the rows of a d x m matrix), m = d - 1, from D (the
    cell's row of inverse) and the edges x_a - x_0 = (X_a - X_0) + (u_a - u_0)."""
    m = ti.static(d - 1)
    D = ti.Matrix([[inverse[c, m * a + j] for j in ti.static(range(m))] for a in ti.static(range(m))], dt=ti.f64)
    edges = ti.Matrix.zero(ti.f64, d, m)
    n0 = cells[c, 0]
    for a in ti.static(range(m)):
        na = cells[c, a + 1]
        for i in ti.static(range(d)):
            edges[i, a] = (rest[na, i] - rest[n0, i]) + (u[na, i] - u[n0, i])
    shapes = ti.Matrix.zero(ti.f64, d, m)
    for a, j in ti.static(ti.ndrange(m, m)):
        shapes[a + 1, j] = D[a, j]
        shapes[0, j] -= D[a, j]
    return edges @ D, shapes


@ti.func
def row(A, a, m: ti.template()):
    """Row a of A (m columns) as a vector."""
    return ti.Vector([A[a, j] for j in ti.static(range(m))], dt=ti.f64)


@ti.func
def principal(G, m: ti.template()):
    """(g1, g2, n, p): the principal values g1 >= g2 of the symmetric m x m G and unit eigenvectors n (of g1), p
    (of g2). m = 2 in closed form, v = (h + r, b) if h >= 0 else (b, r - h) along n, with h = (G11 - G22) / 2,
    b = G12, r = sqrt(h^2 + b^2), g1,2 = tr(G) / 2 +- r (n = e1 where r = 0); m = 1: g1 = g2 = G, n = p = 1."""
    g1, g2 = G[0, 0], G[0, 0]
    n = ti.Vector.zero(ti.f64, m)
    n[0] = 1.0
    p = n
    if ti.static(m == 2):
        h, b = 0.5 * (G[0, 0] - G[1, 1]), G[0, 1]
        r = ti.sqrt(h * h + b * b)
        mean = 0.5 * (G[0, 0] + G[1, 1])
        g1, g2 = mean + r, mean - r
        v0, v1 = h + r, b
        if h < 0.0:
            v0, v1 = b, r - h
        length = ti.sqrt(v0 * v0 + v1 * v1)
        if length > 0.0:
            n = ti.Vector([v0 / length, v1 / length], dt=ti.f64)
        p = ti.Vector([-n[1], n[0]], dt=ti.f64)
    return g1, g2, n, p


@ti.func
def membrane_law(F, lam, mu, wrinkles, m: ti.template()):
    """(psi, S, tangent (lam_t, mu_t, c_n, c_np), n, p) of the deformation gradient F (d x m): the SVK membrane
    (wrinkles = 0) or its relaxed energy, taut, wrinkled or slack (module docstring)."""
    G = 0.5 * (F.transpose() @ F - ti.Matrix.identity(ti.f64, m))
    g1, g2, n, p = principal(G, m)
    psi = 0.5 * lam * G.trace() ** 2 + mu * (G * G).sum()
    S = lam * G.trace() * ti.Matrix.identity(ti.f64, m) + 2.0 * mu * G
    tangent = ti.Vector([lam, mu, 0.0, 0.0], dt=ti.f64)
    if wrinkles != 0 and lam * G.trace() + 2.0 * mu * g2 < 0.0:  # not taut
        psi, S, tangent = 0.0, ti.Matrix.zero(ti.f64, m, m), ti.Vector.zero(ti.f64, 4)  # slack
        if g1 > 0.0:  # wrinkled: then g1 - g2 >= (1 + nu) g1 > 0 (never for m = 1: S2 = (lam + 2 mu) g1 < 0 here)
            E = 4.0 * mu * (lam + mu) / (lam + 2.0 * mu)
            psi, S = 0.5 * E * g1 * g1, E * g1 * n.outer_product(n)
            tangent = ti.Vector([0.0, 0.0, E, 2.0 * E * g1 / (g1 - g2)], dt=ti.f64)
    return psi, S, tangent, n, p


@ti.kernel
def membrane_energy(
    d: ti.template(),
    rest: Nodal,
    u: Nodal,
    cells: Cells,
    inverse: Table,
    weights: Scalars,
    lam: ti.f64,
    mu: ti.f64,
    wrinkles: ti.i32,
) -> ti.f64:
    """sum_c W_c psi(G_c)."""
    total = 0.0
    for c in range(cells.shape[0]):
        F, _shapes = strain_state(rest, u, cells, inverse, c, d)
        psi, _S, _tangent, _n, _p = membrane_law(F, lam, mu, wrinkles, ti.static(d - 1))
        total += weights[c] * psi
    return total


@ti.kernel
def membrane_gradient(
    d: ti.template(),
    rest: Nodal,
    u: Nodal,
    cells: Cells,
    inverse: Table,
    weights: Scalars,
    lam: ti.f64,
    mu: ti.f64,
    wrinkles: ti.i32,
    out: Nodal,
):
    """out = dE/dx: W F S g_a scattered to the cells' nodes."""
    for v, i in ti.ndrange(out.shape[0], d):
        out[v, i] = 0.0
    for c in range(cells.shape[0]):
        m = ti.static(d - 1)
        F, shapes = strain_state(rest, u, cells, inverse, c, d)
        _psi, S, _tangent, _n, _p = membrane_law(F, lam, mu, wrinkles, m)
        P = weights[c] * F @ S
        for a in ti.static(range(d)):
            force = P @ row(shapes, a, m)
            for i in ti.static(range(d)):
                out[cells[c, a], i] += force[i]


@ti.kernel
def membrane_hessian(
    d: ti.template(),
    rest: Nodal,
    u: Nodal,
    cells: Cells,
    inverse: Table,
    weights: Scalars,
    lam: ti.f64,
    mu: ti.f64,
    wrinkles: ti.i32,
    out: Table,
):
    """out[c] = the exact d^2 x d^2 block of cell c, row-major: W [delta_ik g_a.S g_b + the tangent's terms]
    (module docstring's H_(ai)(bk))."""
    for c in range(cells.shape[0]):
        m = ti.static(d - 1)
        n = ti.static(d * d)
        F, shapes = strain_state(rest, u, cells, inverse, c, d)
        _psi, S, tangent, nn, pp = membrane_law(F, lam, mu, wrinkles, m)
        FFt = F @ F.transpose()
        Fn, Fp = F @ nn, F @ pp
        W = weights[c]
        for a, b in ti.static(ti.ndrange(d, d)):
            ga, gb = row(shapes, a, m), row(shapes, b, m)
            Fa, Fb = F @ ga, F @ gb
            Na, Nb = Fn * nn.dot(ga), Fn * nn.dot(gb)  # f_i.(n n^T) g_a
            Ya = 0.5 * (Fn * pp.dot(ga) + Fp * nn.dot(ga))  # f_i.sym(n p^T) g_a
            Yb = 0.5 * (Fn * pp.dot(gb) + Fp * nn.dot(gb))
            geometric = ga.dot(S @ gb)
            for i, k in ti.static(ti.ndrange(d, d)):
                h = (
                    tangent[0] * Fa[i] * Fb[k]
                    + tangent[1] * (FFt[i, k] * ga.dot(gb) + Fb[i] * Fa[k])
                    + tangent[2] * Na[i] * Nb[k]
                    + tangent[3] * Ya[i] * Yb[k]
                )
                if ti.static(i == k):
                    h += geometric
                out[c, n * (d * a + i) + d * b + k] = W * h


@ti.kernel
def membrane_stress(
    d: ti.template(),
    rest: Nodal,
    u: Nodal,
    cells: Cells,
    inverse: Table,
    lam: ti.f64,
    mu: ti.f64,
    wrinkles: ti.i32,
    stress: Table,
    stretch: Scalars,
):
    """stress[c] = the cell's Cauchy stress F S F^T / J (J = sqrt(det F^T F), its area ratio in 3D, its stretch in
    2D; the thickness taken unchanged) as a row-major 3 x 3 (zero past d), stretch[c] = its largest principal
    stretch sqrt(1 + 2 g1)."""
    for c in range(cells.shape[0]):
        m = ti.static(d - 1)
        F, _shapes = strain_state(rest, u, cells, inverse, c, d)
        _psi, S, _tangent, _n, _p = membrane_law(F, lam, mu, wrinkles, m)
        C = F.transpose() @ F
        J = ti.sqrt(C[0, 0])
        if ti.static(m == 2):
            J = ti.sqrt(C[0, 0] * C[1, 1] - C[0, 1] * C[1, 0])
        g1, _g2, _nn, _pp = principal(0.5 * (C - ti.Matrix.identity(ti.f64, m)), m)
        sigma = F @ S @ F.transpose() / J
        for i, j in ti.static(ti.ndrange(3, 3)):
            stress[c, 3 * i + j] = 0.0
            if ti.static(i < d and j < d):
                stress[c, 3 * i + j] = sigma[i, j]
        stretch[c] = ti.sqrt(1.0 + 2.0 * g1)


def rest_shapes(rest: np.ndarray, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(D = Dm^-1 flattened (f, m^2), the rest measures A0 (3D) or L0 (2D) (f,)) of cells (f, d) of the rest
    positions, Dm in each cell's own orthonormal tangent basis (module docstring)."""
    corners = rest[cells]
    e1 = corners[:, 1] - corners[:, 0]
    length = np.linalg.norm(e1, axis=1)
    if cells.shape[1] == 2:
        return (1.0 / length)[:, None], length
    e2 = corners[:, 2] - corners[:, 0]
    normal = np.cross(e1, e2)
    double_area = np.linalg.norm(normal, axis=1)
    t1 = e1 / length[:, None]
    t2 = np.cross(normal / double_area[:, None], t1)
    Dm = np.zeros((len(cells), 2, 2))
    Dm[:, 0, 0], Dm[:, 0, 1], Dm[:, 1, 1] = length, np.einsum("fi,fi->f", e2, t1), np.einsum("fi,fi->f", e2, t2)
    return np.linalg.inv(Dm).reshape(len(cells), 4), 0.5 * double_area


def projected(blocks: np.ndarray) -> np.ndarray:
    """Each symmetric block (f, n, n) with its negative eigenvalues clamped to 0 (V max(Lambda, 0) V^T)."""
    values, vectors = np.linalg.eigh(blocks)
    return np.einsum("fij,fj,fkj->fik", vectors, np.maximum(values, 0.0), vectors)


class Membrane(Term):
    """A Saint Venant-Kirchhoff plane-stress membrane of thickness t, Young's modulus E and Poisson's ratio nu on
    cells (f, d) of the configuration's nodes: triangles in 3D, segments in 2D; wrinkles: it wrinkles (in 2D:
    goes slack) instead of carrying compression, the relaxed energy (module docstring)."""

    name = "membrane"
    piecewise = True  # a sum of one energy per cell (Term.restricted takes a subset)

    def __init__(self, config, cells: np.ndarray, thickness: float, E: float, nu: float, wrinkles: bool = True):
        self.config = config
        self.dim = config.rest.shape[1]
        self.cells = int32s(cells)
        assert self.cells.shape[1] == self.dim, "a membrane's cells have d nodes (3D: triangles, 2D: segments)"
        inverse, measures = rest_shapes(config.rest, self.cells)
        self.inverse = np.ascontiguousarray(inverse)
        self.thickness, self.E, self.nu = thickness, E, nu
        self.weights = np.ascontiguousarray(thickness * measures)
        self.lam, self.mu = E * nu / (1.0 - nu**2), E / (2.0 * (1.0 + nu))
        self.wrinkles = bool(wrinkles)
        self._rows, self._cols = block_pattern(self.cells, self.dim)

    def piece_nodes(self) -> np.ndarray:
        """The cells' nodes: a cell is a piece."""
        return self.cells

    def on_pieces(self, config, pieces: np.ndarray, nodes: np.ndarray) -> "Membrane":
        return Membrane(config, nodes, self.thickness, self.E, self.nu, self.wrinkles)

    def scale_pieces(self, scale: np.ndarray) -> None:
        """Scale each cell's weight W = t A0 (its energy) by scale (f,)."""
        self.weights = np.ascontiguousarray(self.weights * scale)

    def _arguments(self):
        c = self.config
        return self.dim, c.rest, c.u, self.cells, self.inverse, self.weights, self.lam, self.mu, int(self.wrinkles)

    def energy(self) -> float:
        return membrane_energy(*self._arguments())

    def gradient(self) -> np.ndarray:
        out = np.empty_like(self.config.rest)
        membrane_gradient(*self._arguments(), out)
        return out

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._rows, self._cols

    def stress(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(the Cauchy stress (f, 3, 3) of each cell at displacements u, F S F^T / J: the force per current length
        of the sheet over its rest thickness, zero past d; the largest principal stretch (f,)) (membrane_stress)."""
        stress, stretch = np.empty((len(self.cells), 9)), np.empty(len(self.cells))
        c = self.config
        u = np.ascontiguousarray(u, dtype=np.float64)
        membrane_stress(
            self.dim, c.rest, u, self.cells, self.inverse, self.lam, self.mu, int(self.wrinkles), stress, stretch
        )
        return stress.reshape(-1, 3, 3), stretch

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        n = self.dim * self.dim
        out = np.empty((len(self.cells), n * n))
        membrane_hessian(*self._arguments(), out)
        return (projected(out.reshape(-1, n, n)) if psd_only and not self.wrinkles else out).ravel()  # PSD if wrinkles
