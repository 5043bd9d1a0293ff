"""Contact as IPC-style smooth log barriers, with continuous collision checks bounding the line search.

The barrier on a distance d with activation threshold d_hat and stiffness kappa is

    b(d) = -kappa (d - d_hat)^2 ln(d / d_hat)   for 0 < d < d_hat,   0 for d >= d_hat,
    b'(d) = -kappa (d - d_hat) (2 ln(d / d_hat) + (d - d_hat) / d),
    b''(d) = -kappa (2 ln(d / d_hat) + 4 (d - d_hat) / d - (d - d_hat)^2 / d^2)  >= 0,

C2 at d_hat, infinite as d -> 0, so the energy forbids touching; max_step keeps every distance
positive along a Newton step (the solver steps at most 0.9 of it), so no step jumps through.

Ground: d_i = y_i - h for each vertex on the body's outer boundary (the line y = h). The
Hessian b''(d) e_y e_y^T is PSD and exact. Step bound: d_i / (-dy_i) where dy_i < 0.

Self-contact of a chamber wall: for each wall vertex p and each wall edge (a, b) not incident to
it (and not within 2 d_hat of it at rest: neighbours along a smooth wall), d is the point-segment
distance, through s = d^2 (t = (p - a).e / |e|^2, e = b - a):

    t <= 0: s = |p - a|^2;   t >= 1: s = |p - b|^2;   else s = c^2 / L,  c = e x (p - a),  L = |e|^2,

with grad d = grad s / (2 d) and Hess d = Hess s / (2 d) - grad s grad s^T / (4 d^3). The PSD
Hessian keeps the Gauss-Newton part b''(d) grad d grad d^T; the exact one adds b'(d) Hess d.
Step bound: the first time in [0, 1] at which p becomes collinear with (a, b) while lying on the
segment (a quadratic in the step fraction), the continuous collision check.
"""


import numpy as np
import taichi as ti

from .base import Term, quadratic_roots, vertex_dofs


@ti.func
def barrier(d, dhat, kappa):
    """(b, b', b'') of the log barrier at distance d > 0 (all zero for d >= dhat)."""
    b, db, ddb = 0.0, 0.0, 0.0
    if d < dhat:
        r = d - dhat
        lg = ti.log(d / dhat)
        b = -kappa * r * r * lg
        db = -kappa * r * (2.0 * lg + r / d)
        ddb = -kappa * (2.0 * lg + 4.0 * r / d - r * r / (d * d))
    return b, db, ddb


@ti.data_oriented
class GroundContact(Term):
    """Barrier keeping the given vertices above the line y = height."""

    name = "ground"
    reports_contact = True

    def __init__(self, config, vertices: np.ndarray, height: float, dhat: float, stiffness: float):
        self.config = config
        self.height, self.dhat, self.kappa = float(height), float(dhat), float(stiffness)
        self.n = len(vertices)
        self.verts = ti.field(ti.i32, self.n)
        self.verts.from_numpy(np.asarray(vertices, dtype=np.int32))
        self.force = ti.Vector.field(2, ti.f64, config.n_vertices)
        self.hess = ti.field(ti.f64, self.n)
        self.dx = ti.Vector.field(2, ti.f64, config.n_vertices)
        self.reduction = ti.field(ti.f64, ())
        self._dofs = 2 * np.asarray(vertices, dtype=np.int64) + 1

    @ti.kernel
    def _energy(self) -> ti.f64:
        total = 0.0
        self.reduction[None] = ti.math.inf
        for k in range(self.n):
            d = self.config.x(self.verts[k])[1] - self.height
            ti.atomic_min(self.reduction[None], d)
            if d > 0:
                total += barrier(d, self.dhat, self.kappa)[0]
        return total

    def energy(self) -> float:
        total = self._energy()
        return total if self.reduction[None] > 0 else np.inf

    @ti.kernel
    def _compute(self):
        for v in self.force:
            self.force[v] = ti.Vector([0.0, 0.0])
        for k in range(self.n):
            d = self.config.x(self.verts[k])[1] - self.height
            _, db, ddb = barrier(d, self.dhat, self.kappa)
            self.force[self.verts[k]] = ti.Vector([0.0, db])
            self.hess[k] = ddb

    def gradient(self) -> np.ndarray:
        self._compute()
        return self.force.to_numpy()

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._dofs, self._dofs

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        self._compute()
        return self.hess.to_numpy()

    @ti.kernel
    def _step_bound(self):
        self.reduction[None] = ti.math.inf
        for k in range(self.n):
            dy = self.dx[self.verts[k]][1]
            if dy < 0:
                ti.atomic_min(self.reduction[None], (self.config.x(self.verts[k])[1] - self.height) / -dy)

    def max_step(self, dx: np.ndarray) -> float:
        self.dx.from_numpy(dx)
        self._step_bound()
        return float(self.reduction[None])


@ti.func
def perp(v):
    """d(e x w)/dw = (-e_y, e_x) for the 2D cross product e x w."""
    return ti.Vector([-v[1], v[0]])


@ti.func
def point_point(r, slot: ti.template()):
    """s = |r|^2, r = p - x_slot, with its gradient and Hessian over (p, a, b) (vertex slots 0, 1, 2)."""
    g = ti.Vector.zero(ti.f64, 6)
    H = ti.Matrix.zero(ti.f64, 6, 6)
    for k in ti.static(range(2)):
        g[k] = 2.0 * r[k]
        g[2 * slot + k] = -2.0 * r[k]
        H[k, k] = 2.0
        H[2 * slot + k, 2 * slot + k] = 2.0
        H[k, 2 * slot + k] = -2.0
        H[2 * slot + k, k] = -2.0
    return r.norm_sqr(), g, H


@ti.data_oriented
class SelfContact(Term):
    """Point-edge barriers between the vertices and edges of each chamber wall loop."""

    name = "self_contact"
    reports_contact = True

    def __init__(self, config, loops: list[np.ndarray], dhat: float, stiffness: float):
        self.config = config
        self.dhat, self.kappa = float(dhat), float(stiffness)
        rest = config.rest_numpy
        pairs = []
        for loop in loops:
            loop = np.asarray(loop, dtype=np.int64)
            k = len(loop)
            i, j = np.meshgrid(np.arange(k), np.arange(k), indexing="ij")
            keep = (i != j) & (i != (j + 1) % k)
            p, a, b = loop[i[keep]], loop[j[keep]], loop[(j[keep] + 1) % k]
            far = point_segment_distance(rest[p], rest[a], rest[b]) >= 2.0 * self.dhat
            pairs.append(np.column_stack([p, a, b])[far])
        pairs = np.vstack(pairs)
        self.n_pairs = len(pairs)
        self.pairs = ti.Vector.field(3, ti.i32, self.n_pairs)
        self.pairs.from_numpy(pairs.astype(np.int32))
        self.force = ti.Vector.field(2, ti.f64, config.n_vertices)
        self.hess = ti.field(ti.f64, (self.n_pairs, 36))
        self.dx = ti.Vector.field(2, ti.f64, config.n_vertices)
        self.reduction = ti.field(ti.f64, ())
        dofs = vertex_dofs(pairs.ravel()).reshape(self.n_pairs, 6)
        self._rows = np.repeat(dofs, 6, axis=1).ravel()
        self._cols = np.tile(dofs, (1, 6)).ravel()

    @ti.func
    def squared_distance(self, q):
        """s = d^2 of pair q and its gradient (6) and Hessian (6 x 6) over (p, a, b)."""
        idx = self.pairs[q]
        p, a, b = self.config.x(idx[0]), self.config.x(idx[1]), self.config.x(idx[2])
        e = self.config.edge(idx[1], idx[2])
        w = self.config.edge(idx[1], idx[0])
        L = e.norm_sqr()
        t = w.dot(e) / L
        s = 0.0
        g = ti.Vector.zero(ti.f64, 6)
        H = ti.Matrix.zero(ti.f64, 6, 6)
        if t <= 0.0:
            s, g, H = point_point(p - a, 1)
        elif t >= 1.0:
            s, g, H = point_point(p - b, 2)
        else:
            c = e.cross(w)
            s = c * c / L
            dc_p = perp(e)
            dc_b = ti.Vector([w[1], -w[0]])
            dc = ti.Vector([dc_p[0], dc_p[1], -dc_p[0] - dc_b[0], -dc_p[1] - dc_b[1], dc_b[0], dc_b[1]])
            dL = ti.Vector([0.0, 0.0, -2.0 * e[0], -2.0 * e[1], 2.0 * e[0], 2.0 * e[1]])
            g = 2.0 * c / L * dc - c * c / (L * L) * dL
            # d2c: c = b x p + a x b + p x a; d2(u x v)/du dv = [[0, 1], [-1, 0]]
            d2c = ti.Matrix.zero(ti.f64, 6, 6)
            d2L = ti.Matrix.zero(ti.f64, 6, 6)
            for u, v in ti.static(((2, 0), (1, 2), (0, 1))):  # (b, p), (a, b), (p, a) as vertex slots
                d2c[2 * u, 2 * v + 1] += 1.0
                d2c[2 * u + 1, 2 * v] -= 1.0
                d2c[2 * v + 1, 2 * u] += 1.0
                d2c[2 * v, 2 * u + 1] -= 1.0
            for k in ti.static(range(2)):
                d2L[2 + k, 2 + k] = 2.0
                d2L[4 + k, 4 + k] = 2.0
                d2L[2 + k, 4 + k] = -2.0
                d2L[4 + k, 2 + k] = -2.0
            cross_terms = dc.outer_product(dL) + dL.outer_product(dc)
            H = (2.0 / L * dc.outer_product(dc) + 2.0 * c / L * d2c - 2.0 * c / (L * L) * cross_terms
                 + 2.0 * c * c / (L * L * L) * dL.outer_product(dL) - c * c / (L * L) * d2L)
        return s, g, H

    @ti.kernel
    def _energy(self) -> ti.f64:
        total = 0.0
        self.reduction[None] = ti.math.inf
        for q in range(self.n_pairs):
            s, _grad, _hess = self.squared_distance(q)
            ti.atomic_min(self.reduction[None], s)
            if s > 0:
                total += barrier(ti.sqrt(s), self.dhat, self.kappa)[0]
        return total

    def energy(self) -> float:
        total = self._energy()
        return total if self.reduction[None] > 0 else np.inf

    @ti.kernel
    def _compute(self, exact: ti.i32):
        for v in self.force:
            self.force[v] = ti.Vector([0.0, 0.0])
        for q in range(self.n_pairs):
            s, gs, Hs = self.squared_distance(q)
            d = ti.sqrt(s)
            K = ti.Matrix.zero(ti.f64, 6, 6)
            if d < self.dhat:
                _, db, ddb = barrier(d, self.dhat, self.kappa)
                gd = gs / (2.0 * d)
                f = db * gd
                idx = self.pairs[q]
                for k in ti.static(range(3)):
                    self.force[idx[k]] += ti.Vector([f[2 * k], f[2 * k + 1]])
                K = ddb * gd.outer_product(gd)
                if exact:
                    K += db * (Hs / (2.0 * d) - gs.outer_product(gs) / (4.0 * d * d * d))
            for r in ti.static(range(6)):
                for c in ti.static(range(6)):
                    self.hess[q, 6 * r + c] = K[r, c]

    def gradient(self) -> np.ndarray:
        self._compute(0)
        return self.force.to_numpy()

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._rows, self._cols

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        self._compute(0 if psd_only else 1)
        return self.hess.to_numpy().ravel()

    @ti.kernel
    def _step_bound(self):
        """Smallest alpha > 0 at which a point becomes collinear with a non-incident wall edge, on the edge."""
        self.reduction[None] = ti.math.inf
        for q in range(self.n_pairs):
            idx = self.pairs[q]
            e0 = self.config.edge(idx[1], idx[2])
            w0 = self.config.edge(idx[1], idx[0])
            de = self.dx[idx[2]] - self.dx[idx[1]]
            dw = self.dx[idx[0]] - self.dx[idx[1]]
            # cross(e0 + t de, w0 + t dw) = c0 + c1 t + c2 t^2
            c0 = e0.cross(w0)
            c1 = e0.cross(dw) + de.cross(w0)
            c2 = de.cross(dw)
            roots = quadratic_roots(c0, c1, c2)
            for r in ti.static(range(2)):
                t = roots[r]
                if t >= 0 and t < ti.math.inf:
                    e = e0 + t * de
                    w = w0 + t * dw
                    along = w.dot(e) / e.norm_sqr()
                    if along >= -1e-9 and along <= 1.0 + 1e-9:
                        ti.atomic_min(self.reduction[None], t)

    def max_step(self, dx: np.ndarray) -> float:
        self.dx.from_numpy(dx)
        self._step_bound()
        return float(self.reduction[None])

    def min_distance(self) -> float:
        """Smallest point-edge distance over all pairs."""
        self._energy()
        return float(np.sqrt(max(self.reduction[None], 0.0)))


def point_segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distances from points p (k, 2) to segments (a, b), row by row."""
    e = b - a
    t = np.clip(np.sum((p - a) * e, axis=1) / np.sum(e * e, axis=1), 0.0, 1.0)
    return np.linalg.norm(p - (a + t[:, None] * e), axis=1)
