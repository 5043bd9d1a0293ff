"""The wall of a sealed chamber: its enclosed measure (area in 2D, volume in 3D), the measure's gradient and the
load stiffness, as Taichi kernels.

In 2D (AreaForm) the chamber wall is a closed counter-clockwise loop of straight edges (linear elements: nodes
x_0 .. x_{k-1}) or of polynomial edges of the elements' order p (corner a, the edge's p - 1 nodes, corner b, ...).
Its signed area, 1/2 the closed integral of x cross dx, is exact for any order: with x(s) = sum_a N_a(s) x_a along
an edge (the segment's Lagrange shape functions), 1/2 int x cross x' ds = sum_{a < b} C_ab x_a x x_b with
C_ab = 1/2 int_0^1 (N_a N_b' - N_b N_a') ds (lagrange.swept_area_weights, exact rationals); per edge

    straight (a, b):      1/2 a x b,
    quadratic (a, m, b):  1/6 (4 a x m + 4 m x b - a x b)     (the parabola through a, m, b; 1/2 a x b
                                                               when m is the midpoint),

so A(x) = sum_t c_t (x_i(t) x x_j(t)) over a fixed list of node pairs t with weights c_t, a quadratic
form: with d(p x q)/dp = (q_y, -q_x) and d(p x q)/dq = (-p_y, p_x) its gradient is the integrated
outward normal of the wall (outward from the chamber, into the rubber), and its Hessian is constant,
d2A/dx_i dy_j = c_t, d2A/dy_i dx_j = -c_t (and symmetric) for each pair t.

A wall that ends on symmetry lines (a half or quarter model) is an open chain x_0 .. x_{k-1} from line to
line; with the origin o of the integral on the lines (their crossing for two), the flat cap along them adds
nothing and the enclosed area is the same form without the closing edge, on positions relative to o:

    A(x) = sum_t c_t (x_i(t) - o) x (x_j(t) - o)      (open wall: pairs (i, i+1) and no (k-1, 0)),

computed by the same kernel on rest positions shifted by -o; d2A is unchanged (o is fixed).

In 3D the wall is a surface of triangles and its measure the volume it encloses (cavity.py).

Every chamber kind (kind.py) loads its wall with a uniform pressure p(A) that the kind defines:

    dE/dx = -p dA/dx,   Hessian  -p'(A) dA dA^T - p d2A.

The first part is the kind's (a PSD rank-1 low-rank part when p falls as A grows); the second, the load
stiffness of the follower pressure, is shared here. It is indefinite and does not vanish at equilibrium,
so it is returned as sparse triplets unless the solver asks for the PSD Hessian only (then nothing: the
PSD elastic and clamp Hessians keep projected Newton a descent method).
"""

import math
from typing import TypeAlias

import numpy as np

from ...backend import kernel, ti
from ...errors import require
from ...fem.lagrange import swept_area_weights
from ..base import Indices, Scalars, Term, Vec2s, int32s, position, vertex_dofs
from .cavity import VolumeForm

Pairs: TypeAlias = ti.types.ndarray(dtype=ti.types.vector(2, ti.i32), ndim=1)  # (P, 2) int32 index pairs


@kernel
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


def area_form(k: int, order: int, closed: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """The (pairs (P, 2) of wall positions, weights (P,)) with A = sum_t w_t x_i x x_j for a wall of k nodes:
    a closed loop, or an open chain (no edge from its last node back to its first), of edges of `order`
    (corner, its order - 1 edge nodes, the next corner, ...): per edge the pairs of lagrange.swept_area_weights,
    exact for its polynomial arc (module docstring)."""
    along = np.array([0, *range(2, order + 1), 1])  # the segment's node at each wall position of an edge
    weights = swept_area_weights(order)[along][:, along]  # C in wall positions 0..order along the edge
    weights = np.triu(weights - weights.T)  # p x q = -q x p: each pair once, the earlier position first
    starts = np.arange(0, k if closed else k - 1, order)
    pairs, values = [], []
    for a, b in zip(*np.nonzero(weights)):
        pairs.append(np.column_stack([starts + a, (starts + b) % k]))
        values.append(np.full(len(starts), weights[a, b]))
    return np.vstack(pairs), np.concatenate(values)


def crossing_segments(points: np.ndarray, closed: bool) -> tuple[int, int] | None:
    """The first pair (i, j), i < j, of non-adjacent segments of the polygon through points (k, 2) that cross,
    or None where it is simple. Segment i runs from point i to point i + 1 (a closed polygon's last one back to
    point 0, an open chain's k - 1 segments have none). Segments ab and cd cross where c and d lie strictly on
    opposite sides of line ab and a and b strictly on opposite sides of line cd:

        side(p, q, r) = (q - p) x (r - p),   side(a, b, c) side(a, b, d) < 0  and  side(c, d, a) side(c, d, b) < 0,

    over all O(k^2) pairs at once (k ~ 100 wall nodes)."""
    a = points if closed else points[:-1]
    b = np.roll(points, -1, axis=0)[: len(a)]
    n = len(a)
    i, j = np.triu_indices(n, 2)
    if closed:  # the last segment touches the first
        keep = ~((i == 0) & (j == n - 1))
        i, j = i[keep], j[keep]

    def side(p, q, r):
        return (q[:, 0] - p[:, 0]) * (r[:, 1] - p[:, 1]) - (q[:, 1] - p[:, 1]) * (r[:, 0] - p[:, 0])

    hits = np.flatnonzero(
        (side(a[i], b[i], a[j]) * side(a[i], b[i], b[j]) < 0) & (side(a[j], b[j], a[i]) * side(a[j], b[j], b[i]) < 0)
    )
    return (int(i[hits[0]]), int(j[hits[0]])) if len(hits) else None


class AreaForm:
    """The enclosed area of a 2D wall loop (module docstring): a quadratic form with a constant Hessian.

    nodes: the wall's nodes in loop order; rest_measure: the area at rest."""

    def __init__(self, config, loop: np.ndarray, order: int, origin: np.ndarray | None):
        self.config = config
        self.rest = config.rest if origin is None else config.rest - np.asarray(origin, dtype=np.float64)
        self.nodes = np.asarray(loop, dtype=np.int64)
        self.loop = int32s(loop)
        self.closed = origin is None
        pairs, self.weights = area_form(len(loop), order, closed=self.closed)
        self.pairs = int32s(pairs)
        xi, yi = 2 * self.nodes[pairs[:, 0]], 2 * self.nodes[pairs[:, 0]] + 1
        xj, yj = 2 * self.nodes[pairs[:, 1]], 2 * self.nodes[pairs[:, 1]] + 1
        self.rows = np.concatenate([xi, yj, yi, xj])
        self.cols = np.concatenate([yj, xi, xj, yi])
        self._hessian = np.concatenate([self.weights, self.weights, -self.weights, -self.weights])
        rest = self.rest[self.nodes]
        p, q = rest[pairs[:, 0]], rest[pairs[:, 1]]
        self.rest_measure = float(self.weights @ (p[:, 0] * q[:, 1] - p[:, 1] * q[:, 0]))

    def measure_and_gradient(self, u: np.ndarray | None = None) -> tuple[float, np.ndarray]:
        """A(x) and dA/dx on the wall nodes, (k, 2) in loop order, at the model's displacements or at u (n, 2)."""
        gradient = np.empty((len(self.nodes), 2))
        u = self.config.u if u is None else np.ascontiguousarray(u, dtype=np.float64)
        return wall_area(self.rest, u, self.loop, self.pairs, self.weights, gradient), gradient

    def hessian(self, u: np.ndarray | None = None) -> np.ndarray:
        """d2A/dx2 on the pattern (rows, cols): constant, the same at every u."""
        return self._hessian

    def fault(self, u: np.ndarray) -> str | None:
        """What is wrong with the wall at displacements u (n, 2), in words, or None: the polygon through its
        nodes (corners and midside nodes) crosses itself (crossing_segments), or the enclosed area is not
        positive (the wall turned inside out: its orientation lost)."""
        points = self.rest[self.nodes] + u[self.nodes]
        crossing = crossing_segments(points, self.closed)
        if crossing is not None:
            return f"wall crosses itself (segments {crossing[0]} and {crossing[1]} of its {len(self.nodes)} nodes)"
        area = self.measure_and_gradient(u)[0]
        return None if area > 0 else f"wall turned inside out (enclosed area {area:.4g})"


class Chamber(Term):
    """The wall of one named chamber: its enclosed measure (area() and area_and_gradient(): the area in 2D, the
    volume in 3D), and the -p d2A load stiffness.

    A kind's term subclasses it with set_command(q), pressure_at(A), energy(), command_force() and,
    where p depends on A, low_rank(). kind: the ChamberKind (with its parameters) that made it; loop: in 2D
    the wall loop's nodes, in 3D the wall's triangles (f, 3 or 6); order: in 2D 1 for a loop of straight
    edges, 2 for one of quadratic edges (corner, midside, corner, ...); origin: None for a closed wall, else
    the wall is open, closed by caps along the symmetry lines (planes) through the origin o (in 3D a
    fem.tetmesh.Closure). loop_vertices: the wall's nodes, the rows of area_and_gradient()'s gradient."""

    def __init__(self, kind, config, loop: np.ndarray, name: str = "main", order: int = 1, origin=None):
        self.kind = kind
        self.config = config
        self.chamber_name = name
        self.name = f"chamber:{name}"
        self.form = AreaForm(config, loop, order, origin) if config.dim == 2 else VolumeForm(config, loop, origin)
        self.loop_vertices = self.form.nodes
        self.dofs = vertex_dofs(self.loop_vertices, config.dim)
        self.n_wall = len(self.loop_vertices)
        self.rest_area = self.form.rest_measure
        measure = "area" if config.dim == 2 else "volume"
        require(
            self.rest_area > 0,
            f"chamber {name!r}: rest {measure} {self.rest_area:.4g} is not positive: a "
            f"chamber's wall must enclose a cavity with the rubber outside it (its wall "
            f"oriented out of the cavity, into the rubber); the body's outer surface given as "
            f"a chamber encloses a negative {measure}",
        )

    def set_command(self, command: float) -> None:
        """Set the kind's command q (a pressure, a pumped or a displaced volume)."""
        raise NotImplementedError

    def pressure_at(self, area: float) -> float:
        """The pressure p(A) the kind gives at enclosed measure A."""
        raise NotImplementedError

    def energy_at(self, area: float) -> float:
        """The kind's energy psi(A) at enclosed measure A (with dpsi/dA = -p(A))."""
        raise NotImplementedError

    def stiffness_at(self, area: float) -> float:
        """-dp/dA at enclosed measure A: the weight c of the rank-one part c dA dA^T of the Hessian (0: none)."""
        return 0.0

    def command_scale_at(self, area: float) -> float:
        """s(A) with -dr/dq = s dA/dx: the residual's derivative by the command, a multiple of the wall's normal."""
        raise NotImplementedError

    def step_within(self, measure: np.ndarray) -> float:
        """The largest step fraction t the kind allows, the measure along the step being the polynomial A(t) of
        coefficients `measure` (lowest first): none but the gas kinds' bound it (inf)."""
        return math.inf

    def energy(self) -> float:
        return self.energy_at(self.area())

    def low_rank(self) -> list[tuple[np.ndarray, np.ndarray, float]]:
        """The rank-one part -p'(A) dA dA^T, where the kind's pressure depends on A."""
        area, gradient = self.area_and_gradient()
        stiffness = self.stiffness_at(area)
        return [(self.dofs, gradient.ravel(), stiffness)] if stiffness else []

    def command_force(self) -> np.ndarray:
        """-dr/dq = s(A) dA/dx on the wall's DOFs (self.dofs): the derivative of the equilibrium residual by the
        command."""
        area, gradient = self.area_and_gradient()
        return self.command_scale_at(area) * gradient.ravel()

    def area_and_gradient(self, u: np.ndarray | None = None) -> tuple[float, np.ndarray]:
        """A(x) and dA/dx on the wall nodes, (k, d) in the order of loop_vertices, at the model's displacements
        or at u (n, d)."""
        return self.form.measure_and_gradient(u)

    def area(self) -> float:
        """The signed measure A(x) enclosed by the wall (an area in 2D, a volume in 3D)."""
        return self.area_and_gradient()[0]

    def gradient(self) -> np.ndarray:
        """dE/dx = -p dA/dx, non-zero on the wall nodes only."""
        area, area_gradient = self.area_and_gradient()
        force = np.zeros_like(self.config.u)
        force[self.loop_vertices] = -self.pressure_at(area) * area_gradient
        return force

    def wall_fault(self) -> str | None:
        """What makes the wall in the model's current state no chamber wall any more, in words (form.fault:
        crossing itself or turned inside out in 2D, turned inside out in 3D), or None."""
        return self.form.fault(self.config.u)

    def pressure(self) -> float:
        """The chamber's (gauge) pressure p in the current state: positive when it pushes its walls outward."""
        return self.pressure_at(self.area())

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self.form.rows, self.form.cols

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        """The load stiffness -p d2A (nothing with psd_only)."""
        return np.zeros(len(self.form.rows)) if psd_only else -self.pressure() * self.form.hessian()

    @property
    def quantity(self) -> str:
        """What its command is, in words: its kind's quantity, an area ratio being a volume ratio in 3D."""
        quantity = self.kind.quantity
        return quantity.replace("area", "volume") if self.config.dim == 3 else quantity

    def describe(self, command: float, reached: float) -> str:
        """A command of a failed solve in words, with the last command that reached an equilibrium."""
        quantity = self.quantity
        return f"{quantity} {command:.6g} (last equilibrium at {quantity} {reached:.6g})"
