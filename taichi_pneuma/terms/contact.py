"""Contact as IPC-style smooth log barriers, with continuous collision checks bounding the line search.

The barrier on a distance d with activation threshold d_hat and stiffness kappa is

    b(d) = -kappa (d - d_hat)^2 ln(d / d_hat)   for 0 < d < d_hat,   0 for d >= d_hat,
    b'(d) = -kappa (d - d_hat) (2 ln(d / d_hat) + (d - d_hat) / d),
    b''(d) = -kappa (2 ln(d / d_hat) + 4 (d - d_hat) / d - (d - d_hat)^2 / d^2)  >= 0,

C2 at d_hat, infinite as d -> 0, so the energy forbids touching; max_step keeps every distance
positive along a Newton step (the solver steps at most 0.9 of it), so no step jumps through.

Ground: d_i = y_i - h for each vertex on the body's outer boundary (the line, or in 3D the plane, y = h): the
plane obstacle of terms/obstacles.py (the effect builds one), whose Hessian b''(d) e_y e_y^T is PSD and exact and
whose step bound is d_i / (-dy_i) where dy_i < 0. (Self-contact is 2D only.)

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

from ..backend import kernel, ti
from .base import Table, Term, Triples, Vec2s, block_pattern, edge, int32s, position, quadratic_roots


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


@ti.func
def squared_distance(rest: ti.template(), u: ti.template(), pairs: ti.template(), q):
    """s = d^2 of pair q = (p, a, b) and its gradient (6) and Hessian (6 x 6) over (p, a, b)."""
    idx = pairs[q]
    p, a, b = position(rest, u, idx[0]), position(rest, u, idx[1]), position(rest, u, idx[2])
    e = edge(rest, u, idx[1], idx[2])
    w = edge(rest, u, idx[1], idx[0])
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
        for m, n in ti.static(((2, 0), (1, 2), (0, 1))):  # (b, p), (a, b), (p, a) as vertex slots
            d2c[2 * m, 2 * n + 1] += 1.0
            d2c[2 * m + 1, 2 * n] -= 1.0
            d2c[2 * n + 1, 2 * m] += 1.0
            d2c[2 * n, 2 * m + 1] -= 1.0
        for k in ti.static(range(2)):
            d2L[2 + k, 2 + k] = 2.0
            d2L[4 + k, 4 + k] = 2.0
            d2L[2 + k, 4 + k] = -2.0
            d2L[4 + k, 2 + k] = -2.0
        cross_terms = dc.outer_product(dL) + dL.outer_product(dc)
        H = (
            2.0 / L * dc.outer_product(dc)
            + 2.0 * c / L * d2c
            - 2.0 * c / (L * L) * cross_terms
            + 2.0 * c * c / (L * L * L) * dL.outer_product(dL)
            - c * c / (L * L) * d2L
        )
    return s, g, H


@kernel
def self_contact_energy(rest: Vec2s, u: Vec2s, pairs: Triples, dhat: ti.f64, kappa: ti.f64) -> tuple[ti.f64, ti.f64]:
    """(sum of the barriers over the pairs at positive distance, smallest squared distance)."""
    total = 0.0
    nearest = ti.math.inf
    for q in range(pairs.shape[0]):
        s, _grad, _hess = squared_distance(rest, u, pairs, q)
        ti.atomic_min(nearest, s)
        if s > 0:
            total += barrier(ti.sqrt(s), dhat, kappa)[0]
    return total, nearest


@kernel
def self_contact_derivatives(
    rest: Vec2s, u: Vec2s, pairs: Triples, dhat: ti.f64, kappa: ti.f64, exact: ti.i32, gradient: Vec2s, hessian: Table
):
    """gradient = dE/dx; hessian[q] = the 6 x 6 block of pair q, row-major (Gauss-Newton part unless exact)."""
    for v in range(gradient.shape[0]):
        gradient[v] = ti.Vector([0.0, 0.0])
    for q in range(pairs.shape[0]):
        s, gs, Hs = squared_distance(rest, u, pairs, q)
        d = ti.sqrt(s)
        K = ti.Matrix.zero(ti.f64, 6, 6)
        if d < dhat:
            _, db, ddb = barrier(d, dhat, kappa)
            gd = gs / (2.0 * d)
            f = db * gd
            idx = pairs[q]
            for k in ti.static(range(3)):
                gradient[idx[k]] += ti.Vector([f[2 * k], f[2 * k + 1]])
            K = ddb * gd.outer_product(gd)
            if exact:
                K += db * (Hs / (2.0 * d) - gs.outer_product(gs) / (4.0 * d * d * d))
        for r in ti.static(range(6)):
            for c in ti.static(range(6)):
                hessian[q, 6 * r + c] = K[r, c]


@kernel
def self_contact_step(rest: Vec2s, u: Vec2s, dx: Vec2s, pairs: Triples) -> ti.f64:
    """Smallest alpha > 0 at which a point becomes collinear with a non-incident wall edge, on the edge."""
    bound = ti.math.inf
    for q in range(pairs.shape[0]):
        idx = pairs[q]
        e0 = edge(rest, u, idx[1], idx[2])
        w0 = edge(rest, u, idx[1], idx[0])
        de = dx[idx[2]] - dx[idx[1]]
        dw = dx[idx[0]] - dx[idx[1]]
        # cross(e0 + t de, w0 + t dw) = c0 + c1 t + c2 t^2
        roots = quadratic_roots(e0.cross(w0), e0.cross(dw) + de.cross(w0), de.cross(dw))
        for r in ti.static(range(2)):
            t = roots[r]
            if t >= 0 and t < ti.math.inf:
                e = e0 + t * de
                w = w0 + t * dw
                along = w.dot(e) / e.norm_sqr()
                if along >= -1e-9 and along <= 1.0 + 1e-9:
                    ti.atomic_min(bound, t)
    return bound


class SelfContact(Term):
    """Point-edge barriers between the vertices and edges of each chamber wall loop."""

    name = "self_contact"
    reports_contact = True

    def __init__(self, config, loops: list[np.ndarray], dhat: float, stiffness: float):
        self.config = config
        self.dhat, self.kappa = float(dhat), float(stiffness)
        rest = config.rest
        per_loop = []
        for loop in loops:
            loop = np.asarray(loop, dtype=np.int64)
            k = len(loop)
            i, j = np.meshgrid(np.arange(k), np.arange(k), indexing="ij")
            keep = (i != j) & (i != (j + 1) % k)
            p, a, b = loop[i[keep]], loop[j[keep]], loop[(j[keep] + 1) % k]
            far = point_segment_distance(rest[p], rest[a], rest[b]) >= 2.0 * self.dhat
            per_loop.append(np.column_stack([p, a, b])[far])
        pairs = np.vstack(per_loop)
        self.pairs = int32s(pairs)
        self._rows, self._cols = block_pattern(pairs, config.dim)

    def _energy(self) -> tuple[float, float]:
        return self_contact_energy(self.config.rest, self.config.u, self.pairs, self.dhat, self.kappa)

    def energy(self) -> float:
        total, nearest = self._energy()
        return total if nearest > 0 else np.inf

    def _derivatives(self, exact: bool) -> tuple[np.ndarray, np.ndarray]:
        gradient, hessian = np.empty_like(self.config.u), np.empty((len(self.pairs), 36))
        self_contact_derivatives(
            self.config.rest, self.config.u, self.pairs, self.dhat, self.kappa, int(exact), gradient, hessian
        )
        return gradient, hessian.ravel()

    def gradient(self) -> np.ndarray:
        return self._derivatives(False)[0]

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._rows, self._cols

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        return self._derivatives(not psd_only)[1]

    def max_step(self, dx: np.ndarray) -> float:
        return self_contact_step(
            self.config.rest, self.config.u, np.ascontiguousarray(dx, dtype=np.float64), self.pairs
        )

    def min_distance(self) -> float:
        """Smallest point-edge distance over all pairs."""
        return float(np.sqrt(max(self._energy()[1], 0.0)))


def point_segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distances from points p (k, 2) to segments (a, b), row by row."""
    e = b - a
    t = np.clip(np.sum((p - a) * e, axis=1) / np.sum(e * e, axis=1), 0.0, 1.0)
    return np.linalg.norm(p - (a + t[:, None] * e), axis=1)
