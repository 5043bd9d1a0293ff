"""Lagrange elements of any order p on the simplex of dimension d, built from the simplex lattice.

The nodes of order p are the lattice points alpha = (alpha_0, ..., alpha_d), alpha_i >= 0 integers summing to p,
at barycentric coordinates L = alpha / p (L_0 = 1 - sum_i xi_i, L_i = xi_i for i = 1..d on the reference simplex
with corners 0, e_1, ..., e_d). Node alpha's shape function is the product of one 1D Lagrange factor per
barycentric coordinate,

    N_alpha(L) = prod_i f_{alpha_i}(L_i),   f_n(L) = prod_{k=0}^{n-1} (p L - k) / (k + 1),

which is 1 at alpha / p and 0 at every other lattice point (some factor vanishes there), a polynomial of degree p;
the k = (p + d)! / (p! d!) of them span the polynomials of degree p, so they partition unity and reproduce every
such polynomial from its nodal values. Its gradient is the product rule,
dN_alpha/dxi = sum_i (f'_{alpha_i}(L_i) prod_{j != i} f_{alpha_j}(L_j)) dL_i/dxi. Order 1 gives N_i = L_i, order 2
N = L_i (2 L_i - 1) at corner i and 4 L_i L_j at the middle of edge ij.

The numbering (lattice): the d + 1 corners p e_i; then each listed edge (i, j)'s p - 1 nodes from corner i to
corner j (alpha_i = p - t, alpha_j = t, t = 1..p - 1); then, in a triangle, the interior nodes, the lattice of order
p - 3 shifted by (1, 1, 1) and numbered the same way (recursively). With the edges (0, 1), (1, 2), (2, 0) this is
VTK's Lagrange triangle (and meshio's and gmsh's triangle10 at p = 3); the tetrahedron's face nodes (p >= 3) are not
numbered (no such family here).

Rules (conical_rule): the Stroud conical product rule of any degree on the simplex, for degrees a family asks
for and the fixed rules of elements.py do not hold: Gauss-Jacobi points in the collapsed coordinates, exact for
every polynomial of degree 2 n - 1 with n points per direction.
"""

from __future__ import annotations

import itertools
import math
from fractions import Fraction

import numpy as np

from ..errors import PneumaInputError


def lattice(dim: int, order: int, edges: tuple) -> tuple[tuple[int, ...], ...]:
    """The lattice points (module docstring) of order `order` on the dim-simplex, in node order: corners, the edges'
    nodes, then (dim 2) the interior, recursively."""
    if order == 0:
        return ((0,) * (dim + 1),)
    corners = [tuple(order * int(i == c) for i in range(dim + 1)) for c in range(dim + 1)]
    on_edges = []
    for i, j in edges:
        for t in range(1, order):
            alpha = [0] * (dim + 1)
            alpha[i], alpha[j] = order - t, t
            on_edges.append(tuple(alpha))
    inner: list = []
    if dim == 2 and order >= 3:
        inner = [tuple(a + 1 for a in alpha) for alpha in lattice(2, order - 3, ((0, 1), (1, 2), (2, 0)))]
    elif dim == 3 and order >= 3:
        raise PneumaInputError(f"order = {order} on a {dim}D simplex: its face nodes are not numbered (order <= 2)")
    return tuple(corners + on_edges + inner)


def _factor(n: int, p: int, L: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """f_n(L) and f'_n(L) (module docstring) of order p at L (any shape)."""
    terms = [(p * L - k) / (k + 1) for k in range(n)]
    value = np.ones_like(L)
    for term in terms:
        value = value * term
    slope = np.zeros_like(L)
    for m in range(n):
        others = np.ones_like(L)
        for k, term in enumerate(terms):
            if k != m:
                others = others * term
        slope = slope + p / (m + 1) * others
    return value, slope


def shape_values(nodes: tuple, order: int, L: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """N_alpha (p, k) and dN_alpha/dL_i (p, k, d + 1) at barycentric points L (p, d + 1) for the lattice nodes."""
    values = np.ones((len(L), len(nodes)))
    partial = np.ones((len(L), len(nodes), L.shape[1]))
    for a, alpha in enumerate(nodes):
        for i, n in enumerate(alpha):
            f, df = _factor(n, order, L[:, i])
            values[:, a] = values[:, a] * f
            for j in range(L.shape[1]):
                partial[:, a, j] = partial[:, a, j] * (df if j == i else f)
    return values, partial


def split_triangles(nodes: tuple, order: int) -> tuple[tuple[int, int, int], ...]:
    """The order^2 counter-clockwise linear triangles of a triangle's lattice (alpha = (p - i - j, i, j)): the upward
    ones (i, j), (i + 1, j), (i, j + 1), then the downward ones (i + 1, j), (i + 1, j + 1), (i, j + 1); each row j by
    i. Order 2: the three corner triangles, then the middle one."""
    index = {alpha: a for a, alpha in enumerate(nodes)}
    at = lambda i, j: index[(order - i - j, i, j)]
    up = [(at(i, j), at(i + 1, j), at(i, j + 1)) for j in range(order) for i in range(order - j)]
    down = [(at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)) for j in range(order - 1) for i in range(order - 1 - j)]
    return tuple(up + down)


def permuted(nodes: tuple, corners: tuple) -> tuple[int, ...]:
    """The node permutation that renumbers the corners as `corners` (node a of the result is the old node whose
    lattice point is a's with its components permuted), e.g. corners (0, 2, 1): the mirror image."""
    index = {alpha: a for a, alpha in enumerate(nodes)}
    return tuple(index[tuple(alpha[c] for c in corners)] for alpha in nodes)


def facet_nodes(nodes: tuple, facet_lattice: tuple, corners: tuple) -> tuple[int, ...]:
    """The element's nodes (indices) on the facet with these corners, in the facet family's order (facet_lattice:
    its lattice): the facet's lattice point beta is the element's alpha with alpha[corners[i]] = beta_i."""
    index = {alpha: a for a, alpha in enumerate(nodes)}
    size = len(nodes[0])
    out = []
    for beta in facet_lattice:
        alpha = [0] * size
        for c, b in zip(corners, beta):
            alpha[c] = b
        out.append(index[tuple(alpha)])
    return tuple(out)


def segment_polynomials(order: int) -> list[list[Fraction]]:
    """The order-p segment's shape functions N_a(s) on 0 <= s <= 1 (L_0 = 1 - s, L_1 = s), node order: corners,
    then the interior from s = 0 to 1, as exact coefficient lists c_0 + c_1 s + ..."""
    out = []
    for alpha in lattice(1, order, ((0, 1),)):
        poly = [Fraction(1)]
        for i, n in enumerate(alpha):
            for k in range(n):  # times (p L_i - k) / (k + 1), L_0 = 1 - s, L_1 = s: c + d s
                c, d = (
                    (Fraction(order - k, k + 1), Fraction(-order, k + 1))
                    if i == 0
                    else (Fraction(-k, k + 1), Fraction(order, k + 1))
                )
                poly = [c * a + d * b for a, b in zip([*poly, Fraction(0)], [Fraction(0), *poly])]
        out.append(poly)
    return out


def swept_area_weights(order: int) -> np.ndarray:
    """C (k, k) with 1/2 int x x dx along one order-p edge = sum_{a < b} C_ab x_a x x_b for its nodes x_a (corners,
    then the interior), x(s) = sum_a N_a(s) x_a: C_ab = 1/2 int_0^1 (N_a N_b' - N_b N_a') ds, exact (Fraction)."""
    polys = segment_polynomials(order)
    derivative = lambda p: [m * p[m] for m in range(1, len(p))]
    integral = lambda p, q: sum(p[i] * q[j] / (i + j + 1) for i in range(len(p)) for j in range(len(q)))
    k = len(polys)
    C = np.zeros((k, k))
    for a, b in itertools.combinations(range(k), 2):
        pa, pb = polys[a], polys[b]
        C[a, b] = float((integral(pa, derivative(pb)) - integral(pb, derivative(pa))) / 2)
    return C


def conical_rule(dim: int, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """The Stroud conical product rule on the reference dim-simplex exact to `degree`: (points (q, dim), weights
    summing to 1). With n = ceil((degree + 1) / 2) Gauss-Jacobi points t_k of weight (1 - t)^(dim - k) on [0, 1] in
    each collapsed direction k = 1..dim, xi_k = t_k prod_{l < k} (1 - t_l) (the Duffy map)."""
    from scipy.special import roots_jacobi  # imported here: only families without a fixed rule of their degree ask

    n = max(1, math.ceil((degree + 1) / 2))
    factors = []
    for k in range(dim):
        x, w = roots_jacobi(n, dim - 1 - k, 0)  # weight (1 - x)^a on [-1, 1]
        factors.append(((x + 1) / 2, w / w.sum()))
    points, weights = [], []
    for combo in itertools.product(*(range(n) for _ in range(dim))):
        ts = [factors[k][0][i] for k, i in enumerate(combo)]
        scale, xi = 1.0, []
        for t in ts:
            xi.append(scale * t)
            scale *= 1 - t
        points.append(xi)
        weights.append(np.prod([factors[k][1][i] for k, i in enumerate(combo)]))
    return np.array(points), np.array(weights)
