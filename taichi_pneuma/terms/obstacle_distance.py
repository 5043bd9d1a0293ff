"""The rigid obstacles' signed distance in the kernels (signed_distance), and its least value over each straight
piece of the body's surface (obstacle_reach: a nested golden-section search, d being convex).

Each shape is a signed distance d(x) in 3D, positive outside (a 2D scene evaluates it at x = (x, y, 0), so a
sphere is a circle there, a cylinder or capsule along z a circle, one along x or y a rectangle or a stadium):

    plane     d = (x - p) . n                                    (the body on the normal's side)
    sphere    d = |x - c| - R
    box       q = |x - c| - h (h the half-size): d = |max(q, 0)| outside, max_k q_k inside
    cylinder  t = (x - c) . a, w = (x - c) - t a, q = (|w| - R, |t| - L/2): the box distance of q (flat caps)
    capsule   d = |x - c - clamp(t, -L/2, L/2) a| - R

Each is an exact Euclidean distance outside, so 1-Lipschitz.

The shape's kind is a runtime integer and its parameters a small float array (PARAMETERS), so the kernels compile
once whatever the scene. signed_distance is the one place the kernels tell the shapes apart: a new shape is its
class (and kind) in terms/obstacle_shapes.py and its branch here.
"""

import math

from ..backend import kernel, ti
from .base import Nodal, Scalars, Table, Triples
from .obstacle_shapes import BOX, CAPSULE, PLANE, SPHERE

PARAMETERS = 8  # position (3: a point or centre), vector (3: normal, half-size or axis), radius, half-length
GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0
SEARCH = 48  # lowest's golden-section steps: the bracket shrinks to GOLDEN^48 ~ 1e-10 of the piece


@ti.func
def row3(a: ti.template(), v):
    """Row v of (n, d) nodal data as a 3-vector (z = 0 in 2D)."""
    x = ti.Vector([0.0, 0.0, 0.0])
    for k in ti.static(range(3)):
        if k < a.shape[1]:
            x[k] = a[v, k]
    return x


@ti.func
def point_of(rest: ti.template(), u: ti.template(), v):
    """x_v = X_v + u_v as a 3-vector."""
    return row3(rest, v) + row3(u, v)


@ti.func
def signed_distance(x, kind, p: ti.template()):
    """(d, n, r, s, t) at x: the signed distance, its gradient n, and its Hessian as (I - n n^T - s t t^T) / r
    (r = 0: none, a flat feature)."""
    c = ti.Vector([p[0], p[1], p[2]])
    v = ti.Vector([p[3], p[4], p[5]])
    radius, half = p[6], p[7]
    y = x - c
    d, r, s = 0.0, 0.0, 0.0
    n = ti.Vector([0.0, 0.0, 0.0])
    t = ti.Vector([0.0, 0.0, 0.0])
    if kind == PLANE:
        d, n = y.dot(v), v
    elif kind == SPHERE:
        rho = y.norm()
        d, n, r = rho - radius, y / rho, rho
    elif kind == BOX:
        q = ti.abs(y) - v
        if q.max() > 0:
            w = ti.Vector([0.0, 0.0, 0.0])
            count = 0
            for k in ti.static(range(3)):
                if q[k] > 0:
                    w[k] = ti.math.sign(y[k]) * q[k]
                    count += 1
                else:
                    t[k] = 1.0  # the edge's direction, when two components are out
            d = w.norm()
            n = w / d
            if count >= 2:
                r = d
                s = ti.select(count == 2, 1.0, 0.0)
        else:
            d = q.max()
            for k in ti.static(range(3)):
                if q[k] == d and n.norm_sqr() == 0:
                    n[k] = ti.math.sign(y[k])
    else:
        along = y.dot(v)
        if kind == CAPSULE:
            w = y - ti.math.clamp(along, -half, half) * v
            rho = w.norm()
            d, n, r = rho - radius, w / rho, rho
            if ti.abs(along) < half:
                s, t = 1.0, v
        else:  # CYLINDER
            w = y - along * v
            rho = w.norm()
            radial, axial = rho - radius, ti.abs(along) - half
            cap = ti.math.sign(along) * v
            if radial > 0 and axial > 0:  # the rim: a circle
                out = radial * (w / rho) + axial * cap
                d = out.norm()
                n, r, s, t = out / d, d, radius / rho, v.cross(w / rho)
            elif radial > axial:  # the side (or inside, nearer the side): the axis line
                d, n, r, s, t = radial, w / rho, rho, 1.0, v
            else:  # a cap (or inside, nearer a cap)
                d, n = axial, cap
    return d, n, r, s, t


@ti.func
def lowest(a, e, f, kind, p: ti.template(), depth: ti.template()):
    """(m, x): the least value m found of a convex g over t in [0, 1] and the point x where, by SEARCH golden-section
    steps (g(t1) <= g(t2), t1 < t2, keeps [lo, t2], else [t1, hi]: a minimiser stays in the bracket), then the ends
    and the bracket's middle: g(t) = d(a + t e) at depth 0; at depth 1 the least d over the segment from a + t e to
    a + t (e + f), convex too (a convex d minimised over the parallel slices of a triangle). One call site of g, so
    that the nested search compiles to one copy of each level."""
    lo, hi, g1 = 0.0, 1.0, 0.0
    best, where = ti.math.inf, a
    for step in range(2 * SEARCH + 3):
        t = 0.5 * (lo + hi)
        if step < 2 * SEARCH:
            t = hi - GOLDEN * (hi - lo) if step % 2 == 0 else lo + GOLDEN * (hi - lo)
        elif step < 2 * SEARCH + 2:
            t = float(step - 2 * SEARCH)
        g, x = profile(a, e, f, t, kind, p, depth)
        if g < best:
            best, where = g, x
        if step < 2 * SEARCH:
            if step % 2 == 0:
                g1 = g
            elif g1 <= g:
                hi = t
            else:
                lo = hi - GOLDEN * (hi - lo)
    return best, where


@ti.func
def profile(a, e, f, t, kind, p: ti.template(), depth: ti.template()):
    """lowest's g(t) and the point where it is taken."""
    x = a + t * e
    value = 0.0
    if ti.static(depth == 0):
        value = signed_distance(x, kind, p)[0]
    else:
        value, x = lowest(x, t * f, f * 0.0, kind, p, depth - 1)
    return value, x


@kernel
def obstacle_reach(rest: Nodal, u: Nodal, facets: Triples, kind: ti.i32, p: Scalars, out: Table):
    """out[k] = (m, x, y, z): the least signed distance m over facet k (a triangle a b c; a segment when c = b) and a
    point where it is taken; a facet whose corners all lie farther from the obstacle than its longest side (d is
    1-Lipschitz: no point of it can reach the obstacle) is not searched, m then its nearest corner's distance."""
    for k in range(facets.shape[0]):
        a = point_of(rest, u, facets[k][0])
        b = point_of(rest, u, facets[k][1])
        c = point_of(rest, u, facets[k][2])
        m, x = ti.math.inf, a
        for y in range(3):
            corner = point_of(rest, u, facets[k][y])
            dy = signed_distance(corner, kind, p)[0]
            if dy < m:
                m, x = dy, corner
        if m < ti.max((b - a).norm(), (c - b).norm(), (a - c).norm()):
            m, x = lowest(a, b - a, c - b, kind, p, 1)
        out[k, 0] = m
        for i in ti.static(range(3)):
            out[k, 1 + i] = x[i]
