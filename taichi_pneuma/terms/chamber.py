"""A sealed chamber under area ("volume") control or pressure control, as Taichi kernels.

The chamber wall is a closed counter-clockwise loop of straight edges (linear elements: nodes
x_0 .. x_{k-1}) or of quadratic edges (quadratic elements: corner a, midside m, corner b, ...). Its
signed area, 1/2 the closed integral of x cross dx, is exact for either: per edge

    straight (a, b):      1/2 a x b,
    quadratic (a, m, b):  1/6 (4 a x m + 4 m x b - a x b)     (the parabola through a, m, b; 1/2 a x b
                                                               when m is the midpoint),

so A(x) = sum_t c_t (x_i(t) x x_j(t)) over a fixed list of node pairs t with weights c_t, a quadratic
form: with d(p x q)/dp = (q_y, -q_x) and d(p x q)/dq = (-p_y, p_x) its gradient is the integrated
outward normal of the wall (outward from the chamber, into the rubber), and its Hessian is constant,
d2A/dx_i dy_j = c_t, d2A/dy_i dx_j = -c_t (and symmetric) for each pair t.

Area control (commanded area ratio r, A* = r A_rest):

    E = 1/2 k (A(x) - A*)^2,   dE/dx = -p dA/dx,   p = k (A* - A),
    Hessian  k dA dA^T - p d2A:

a PSD rank-1 Gauss-Newton part, handed to the solver as a low-rank term, plus the load stiffness
-p d2A of the follower pressure, which is indefinite. It does not vanish at equilibrium (there
A - A* = -p/k), so dropping it leaves Newton converging only linearly; it is returned as sparse
triplets unless the solver asks for the PSD Hessian only.

Pressure control (commanded pressure p): the work of a prescribed pressure,

    E = -p A(x),   dE/dx = -p dA/dx,   Hessian -p d2A,

which has no PSD part at all: with psd_only the term contributes nothing (the PSD elastic and
clamp Hessians alone keep projected Newton a descent method), and the exact Hessian is used once
Newton is in its quadratic basin. Both forms apply exactly a uniform pressure p to the wall.
"""


import numpy as np
import taichi as ti

from .base import Indices, Scalars, Term, Vec2s, int32s, position, vertex_dofs

Pairs = ti.types.ndarray(dtype=ti.types.vector(2, ti.i32), ndim=1)  # (P, 2) int32 index pairs


@ti.kernel
def wall_area(rest: Vec2s, u: Vec2s, loop: Indices, pairs: Pairs, weights: Scalars, gradient: Vec2s) -> ti.f64:
    """A(x) = sum_t weights[t] x_i x x_j over the pairs (i, j) of loop positions; gradient[i] = dA/dx of
    loop node i."""
    for i in range(gradient.shape[0]):
        gradient[i] = ti.Vector([0.0, 0.0])
    total = 0.0
    for t in range(pairs.shape[0]):
        i, j, c = pairs[t][0], pairs[t][1], weights[t]
        p, q = position(rest, u, loop[i]), position(rest, u, loop[j])
        total += c * p.cross(q)
        gradient[i] += c * ti.Vector([q[1], -q[0]])
        gradient[j] += c * ti.Vector([-p[1], p[0]])
    return total


def area_form(k: int, order: int) -> tuple[np.ndarray, np.ndarray]:
    """The (pairs (P, 2) of loop positions, weights (P,)) with A = sum_t w_t x_i x x_j for a loop of k nodes."""
    ring = np.arange(k)
    if order == 1:
        return np.column_stack([ring, np.roll(ring, -1)]), np.full(k, 0.5)
    a, m, b = ring[0::2], ring[1::2], np.roll(ring[0::2], -1)
    pairs = np.vstack([np.column_stack(p) for p in ((a, m), (m, b), (a, b))])
    return pairs, np.repeat([2 / 3, 2 / 3, -1 / 6], len(a))


class Chamber(Term):
    """The wall loop of one named chamber: its area, area gradient and the -p d2A load stiffness.

    order: 1 for a loop of straight edges, 2 for one of quadratic edges (corner, midside, corner, ...)."""

    control = "chamber"

    def __init__(self, config, loop: np.ndarray, name: str, order: int = 1):
        self.config = config
        self.chamber_name = name
        self.name = f"chamber:{name}"
        self.loop_vertices = np.asarray(loop, dtype=np.int64)
        self.loop = int32s(loop)
        self.dofs = vertex_dofs(self.loop_vertices, config.dim)
        self.n_wall = len(loop)
        pairs, self.weights = area_form(self.n_wall, order)
        self.pairs = int32s(pairs)
        xi, yi = 2 * self.loop_vertices[pairs[:, 0]], 2 * self.loop_vertices[pairs[:, 0]] + 1
        xj, yj = 2 * self.loop_vertices[pairs[:, 1]], 2 * self.loop_vertices[pairs[:, 1]] + 1
        self._rows = np.concatenate([xi, yj, yi, xj])
        self._cols = np.concatenate([yj, xi, xj, yi])
        self._area_hessian = np.concatenate([self.weights, self.weights, -self.weights, -self.weights])
        rest = config.rest[self.loop_vertices]
        p, q = rest[pairs[:, 0]], rest[pairs[:, 1]]
        self.rest_area = float(self.weights @ (p[:, 0] * q[:, 1] - p[:, 1] * q[:, 0]))

    def area_and_gradient(self) -> tuple[float, np.ndarray]:
        """A(x) and dA/dx on the wall nodes, (k, 2) in loop order."""
        gradient = np.empty((self.n_wall, 2))
        return wall_area(self.config.rest, self.config.u, self.loop, self.pairs, self.weights, gradient), gradient

    def area(self) -> float:
        """The signed area A(x) enclosed by the wall."""
        return self.area_and_gradient()[0]

    def gradient(self) -> np.ndarray:
        """dE/dx = -p dA/dx for both controls, non-zero on the wall nodes only."""
        area, area_gradient = self.area_and_gradient()
        force = np.zeros_like(self.config.u)
        force[self.loop_vertices] = -self.pressure_at(area) * area_gradient
        return force

    def pressure(self) -> float:
        return self.pressure_at(self.area())

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._rows, self._cols

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        return np.zeros(len(self._rows)) if psd_only else -self.pressure() * self._area_hessian


class AreaChamber(Chamber):
    """Area control: stiffness k pulls the enclosed area A(x) to target_area = command x rest area."""

    control = "area"

    def __init__(self, config, loop: np.ndarray, stiffness: float, name: str = "main", order: int = 1):
        super().__init__(config, loop, name, order)
        self.k = float(stiffness)
        self.target_area = self.rest_area

    def set_command(self, ratio: float) -> None:
        """Command the area ratio A* / A_rest."""
        self.target_area = float(ratio) * self.rest_area

    def pressure_at(self, area: float) -> float:
        """p = k (A* - A): positive when the chamber pushes its walls outward."""
        return self.k * (self.target_area - area)

    def energy(self) -> float:
        return 0.5 * self.k * (self.area() - self.target_area) ** 2

    def low_rank(self) -> list[tuple[np.ndarray, np.ndarray, float]]:
        return [(self.dofs, self.area_and_gradient()[1].ravel(), self.k)]


class PressureChamber(Chamber):
    """Pressure control: a prescribed pressure p does work p A(x) on the wall."""

    control = "pressure"

    def __init__(self, config, loop: np.ndarray, name: str = "main", order: int = 1):
        super().__init__(config, loop, name, order)
        self.prescribed = 0.0

    def set_command(self, pressure: float) -> None:
        """Command the pressure p."""
        self.prescribed = float(pressure)

    def pressure_at(self, area: float) -> float:
        return self.prescribed

    def pressure(self) -> float:
        return self.prescribed

    def energy(self) -> float:
        return -self.prescribed * self.area()
