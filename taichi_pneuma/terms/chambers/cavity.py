"""The volume a 3D chamber wall encloses, its gradient and its Hessian, as Taichi kernels (wall.py's measure in 3D).

The wall is a surface of triangles, linear (3 nodes) or quadratic (6: corners, then
the middles of edges 01, 12, 20), oriented outward from the cavity, and its enclosed volume is

    V(x) = 1/r sum over the wall's triangles of the integral of (P y) . (y_xi x y_eta) over the reference
    triangle,   y = x - o,

(y_xi x y_eta dxi deta = n dA; P = I and r = 3 for a closed wall or one closed by caps through the origin o,
or the projector of fem/tetmesh.Closure). The integrand is a polynomial of degree 1 on a linear triangle
(the one-point rule: V = 1/6 sum y_0 . (y_1 x y_2) for P = I) and of degree 4 on a quadratic one (the
degree-4 rule): both exact. With g = (P y) . (s x t), s = y_xi, t = y_eta (each a combination of the
triangle's nodes: y = sum N_a y_a, s = sum dN_a/dxi y_a, t = sum dN_a/deta y_a),

    dg/dy = P (s x t),   dg/ds = t x P y,   dg/dt = P y x s,
    d2g/dy ds = -P [t]x,   d2g/dy dt = P [s]x,   d2g/ds dt = -[P y]x   ([v]x w = v x w),

and no second derivative in one variable: the gradient and the Hessian (per triangle a dense block over
its nodes, which depends on x) follow by the chain rule.
"""

from typing import TypeAlias

import numpy as np

from ...backend import kernel, ti
from ...fem.elements import family_of
from ...fem.tetmesh import Closure
from ..base import Indices, Nodal, Scalars, Table, block_pattern, int32s

Faces: TypeAlias = ti.types.ndarray(dtype=ti.i32, ndim=2)  # (f, k) int32: each wall triangle's nodes, as wall positions
Derivatives: TypeAlias = ti.types.ndarray(dtype=ti.f64, ndim=3)  # (nq, k, 2): dN_a/dxi, dN_a/deta at each rule point


@ti.func
def face_point(
    rest: ti.template(),
    u: ti.template(),
    wall: ti.template(),
    faces: ti.template(),
    shapes: ti.template(),
    derivatives: ti.template(),
    f,
    q,
):
    """(y, y_xi, y_eta) at rule point q of wall triangle f."""
    y, s, t = ti.Vector.zero(ti.f64, 3), ti.Vector.zero(ti.f64, 3), ti.Vector.zero(ti.f64, 3)
    for a in range(faces.shape[1]):
        node = wall[faces[f, a]]
        x = ti.Vector([rest[node, i] + u[node, i] for i in ti.static(range(3))])
        y += shapes[q, a] * x
        s += derivatives[q, a, 0] * x
        t += derivatives[q, a, 1] * x
    return y, s, t


@ti.func
def cross_matrix(v):
    """[v]x: [v]x w = v x w."""
    return ti.Matrix([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


@kernel
def wall_volume(
    rest: Nodal,
    u: Nodal,
    wall: Indices,
    faces: Faces,
    shapes: Table,
    derivatives: Derivatives,
    weights: Scalars,
    projector: Table,
    gradient: Nodal,
) -> ti.f64:
    """V(x) = sum_f sum_q w_q (P y) . (y_xi x y_eta) (the weights carry 1/r and the reference area); gradient[i] =
    dV/dx of wall node i."""
    P = ti.Matrix([[projector[i, j] for j in ti.static(range(3))] for i in ti.static(range(3))])
    for i, j in ti.ndrange(gradient.shape[0], 3):
        gradient[i, j] = 0.0
    total = 0.0
    for f, q in ti.ndrange(faces.shape[0], weights.shape[0]):
        y, s, t = face_point(rest, u, wall, faces, shapes, derivatives, f, q)
        w, Py = weights[q], P @ y
        total += w * Py.dot(s.cross(t))
        dy, ds, dt = w * P @ s.cross(t), w * t.cross(Py), w * Py.cross(s)
        for a in range(faces.shape[1]):
            force = shapes[q, a] * dy + derivatives[q, a, 0] * ds + derivatives[q, a, 1] * dt
            for i in ti.static(range(3)):
                gradient[faces[f, a], i] += force[i]
    return total


@kernel
def wall_volume_hessian(
    rest: Nodal,
    u: Nodal,
    wall: Indices,
    faces: Faces,
    shapes: Table,
    derivatives: Derivatives,
    weights: Scalars,
    projector: Table,
    out: Table,
):
    """out[f] = d2V/dx2 on the nodes of wall triangle f, a dense 3k x 3k block, row-major."""
    P = ti.Matrix([[projector[i, j] for j in ti.static(range(3))] for i in ti.static(range(3))])
    for f in range(faces.shape[0]):
        k = faces.shape[1]
        n = 3 * k
        for i in range(n * n):
            out[f, i] = 0.0
        for q in range(weights.shape[0]):
            y, s, t = face_point(rest, u, wall, faces, shapes, derivatives, f, q)
            w = weights[q]
            ys, yt, st = -w * P @ cross_matrix(t), w * P @ cross_matrix(s), -w * cross_matrix(P @ y)
            for a, b in ti.ndrange(k, k):
                na, sa, ta = shapes[q, a], derivatives[q, a, 0], derivatives[q, a, 1]
                nb, sb, tb = shapes[q, b], derivatives[q, b, 0], derivatives[q, b, 1]
                block = (
                    na * sb * ys
                    + sa * nb * ys.transpose()
                    + na * tb * yt
                    + ta * nb * yt.transpose()
                    + sa * tb * st
                    + ta * sb * st.transpose()
                )
                for i, j in ti.static(ti.ndrange(3, 3)):
                    out[f, n * (3 * a + i) + 3 * b + j] += block[i, j]


class VolumeForm:
    """The enclosed volume of a 3D wall surface (module docstring), on the triangles (f, 3) or (f, 6) of the
    wall, closed (origin None: o at the wall's rest centroid, for round-off) or open and closed by caps
    (origin a Closure, or a point o on every cap plane).

    nodes: the wall's nodes (sorted); rest_measure: the volume at rest."""

    def __init__(self, config, faces: np.ndarray, origin):
        faces = np.asarray(faces, dtype=np.int64)
        self.config = config
        self.nodes = np.unique(faces)
        closure = (
            origin
            if isinstance(origin, Closure)
            else Closure(
                config.rest[self.nodes].mean(axis=0) if origin is None else np.asarray(origin, dtype=np.float64),
                np.eye(3),
            )
        )
        self.rest = config.rest - closure.origin
        self.wall = int32s(self.nodes)
        self.faces = int32s(np.searchsorted(self.nodes, faces))
        family = family_of(faces, 2)  # the wall's facets: linear or quadratic triangles
        points, weights = family.cell.rules[family.measure_degree]  # exact for N_a det dX/dxi
        self.shapes = np.ascontiguousarray(family.shape_functions(points))
        self.derivatives = np.ascontiguousarray(family.shape_gradients(points))
        self.weights = weights / (2.0 * np.trace(closure.projector))  # the reference triangle's area 1/2, 1/r
        self.projector = np.ascontiguousarray(closure.projector, dtype=np.float64)
        self.rows, self.cols = block_pattern(faces, 3)
        # (the wall nodes' displacements, V, dV/dx) of the last measure_and_gradient
        self._last: tuple[np.ndarray, float, np.ndarray] | None = None
        self.rest_measure = wall_volume(
            self.rest, np.zeros_like(self.rest), *self._data(), np.empty((len(self.nodes), 3))
        )

    def _data(self):
        return self.wall, self.faces, self.shapes, self.derivatives, self.weights, self.projector

    def measure_and_gradient(self, u: np.ndarray | None = None) -> tuple[float, np.ndarray]:
        """V(x) and dV/dx on the wall nodes, (k, 3, read-only), at the model's displacements or at u (n, 3).

        The last answer is given again while the wall nodes' displacements are the same (a Newton iteration
        asks for the energy and the gradient at one state: one kernel launch instead of two)."""
        u = self.config.u if u is None else np.ascontiguousarray(u, dtype=np.float64)
        wall_u = u[self.nodes]
        if self._last is not None and np.array_equal(wall_u, self._last[0]):
            return self._last[1], self._last[2]
        gradient = np.empty((len(self.nodes), 3))
        volume = wall_volume(self.rest, u, *self._data(), gradient)
        gradient.flags.writeable = False
        self._last = (wall_u, volume, gradient)
        return volume, gradient

    def fault(self, u: np.ndarray) -> str | None:
        """What is wrong with the wall at displacements u (n, 3), in words, or None: the enclosed volume not positive
        (turned inside out). A wall folded through itself is no wall fault of its own: a wall triangle of a
        tetrahedron with deformation gradient F = R U has the normal n = det F F^-T n0 (Nanson), so its angle to
        the rest normal carried by the element's rotation, n . R n0 = det F n0 . U^-1 n0, turns negative exactly
        where det F does (an inverted element: state_fault), and a fold that inverts none makes the surface cross
        itself (BuiltScene.surface_crossing). A triangle turned from its rest normal by the body's rotation, as a
        bending actuator's chamber is past 90 degrees, is no fold."""
        volume = self.measure_and_gradient(u)[0]
        return None if volume > 0 else f"wall turned inside out (enclosed volume {volume:.4g})"

    def hessian(self, u: np.ndarray | None = None) -> np.ndarray:
        """d2V/dx2 on the pattern (rows, cols), at the model's displacements or at u (n, 3)."""
        k = self.faces.shape[1]
        out = np.empty((len(self.faces), 9 * k * k))
        u = self.config.u if u is None else np.ascontiguousarray(u, dtype=np.float64)
        wall_volume_hessian(self.rest, u, *self._data(), out)
        return out.ravel()
