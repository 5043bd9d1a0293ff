"""Embedded fibres: tension-only elastic cords that follow the body, as a scene's [[fibers]] tables declare them.

A fibre's curve (fem/fiber_paths.py) is sampled into points p_a no farther apart than its spacing, each embedded in
the mesh (fem/embedding.py: p_a = sum_i w_ai x_i over the d + 1 corners of the linear piece that contains it), and
consecutive points joined by segments (a closed ring's last point to its first). A segment of rest length L0 (the
distance of its embedded points at rest) and axial stiffness E A, at the current length l = |p_b - p_a|, stores

    psi = 1/2 k (l - L0)^2  for l > L0,  0 otherwise,        k = E A / L0,

a cord that buckles freely: it pulls with the force E A (l / L0 - 1) = E A (stretch - 1) when stretched and
carries nothing when slack. With n = (p_b - p_a) / l, dpsi/dp_b = -dpsi/dp_a = k (l - L0) n, and

    d2psi/dp_b2 = k n n^T + k (l - L0) / l (I - n n^T)        (l > L0; PSD: psd_only changes nothing),

mapped to the nodes through the weights: dpsi/dx_i = sum_a w_ai dpsi/dp_a, a dense Hessian block over the 2 (d + 1)
nodes of a segment's two points (slot c_s = -w_ai for the first point's nodes, +w_bi for the second's: block
c_s c_t d2psi/dp_b2). The kernels are dimension-generic (d from the arrays' shapes, vectors padded to 3), so they
compile once per process for 2D and 3D alike.

The kink at l = L0 is handled by the Newton solver's branch sweeps (solve/newton.py): choose_branches(dx) makes the
Hessian and branch_shift use the segments taut at u + dx (two-sided there, k (l - L0) of either sign) and leave out
those slack there; energy and gradient are always the exact tension-only ones.

In 2D a fibre is a layer of cords per unit depth: its `area` is a cross-section per unit depth (a length), and E A a
force per unit depth like every 2D force.
"""

import math
from dataclasses import dataclass
from typing import TypeAlias

import numpy as np

from ..backend import kernel, ti
from ..errors import PneumaInputError, require, require_positive
from ..fem.embedding import embed, first_crossing, inside
from ..fem.fiber_paths import LAYOUTS, PLANAR, Layout
from ..io.output import check_heading
from .base import Indices, Nodal, Scalars, Table, Term, block_pattern, int32s

Pairs: TypeAlias = ti.types.ndarray(dtype=ti.i32, ndim=2)  # (P, d + 1) embedding nodes, or (s, 2) segment points
MAX_FIBER_POINTS = 100_000  # sample points of one fibre: each segment's Hessian block is up to 24 x 24


@ti.func
def segment_vector(rest: ti.template(), u: ti.template(), nodes: ti.template(), weights: ti.template(), a, b):
    """p_b - p_a (padded to 3), rest and displacement parts summed apart so short segments keep their digits."""
    dX = ti.Vector.zero(ti.f64, 3)
    du = ti.Vector.zero(ti.f64, 3)
    for j in range(nodes.shape[1]):
        for i in ti.static(range(3)):
            if i < rest.shape[1]:
                dX[i] += weights[b, j] * rest[nodes[b, j], i] - weights[a, j] * rest[nodes[a, j], i]
                du[i] += weights[b, j] * u[nodes[b, j], i] - weights[a, j] * u[nodes[a, j], i]
    return dX + du


@kernel
def cord_energy(
    rest: Nodal, u: Nodal, nodes: Pairs, weights: Table, segments: Pairs, stiffness: Scalars, rest_length: Scalars
) -> ti.f64:
    """sum over segments of 1/2 (E A / L0) (l - L0)^2 where l > L0."""
    total = 0.0
    for s in range(segments.shape[0]):
        l = segment_vector(rest, u, nodes, weights, segments[s, 0], segments[s, 1]).norm()
        if l > rest_length[s]:
            total += 0.5 * stiffness[s] / rest_length[s] * (l - rest_length[s]) ** 2
    return total


@kernel
def cord_gradient(
    rest: Nodal,
    u: Nodal,
    nodes: Pairs,
    weights: Table,
    segments: Pairs,
    stiffness: Scalars,
    rest_length: Scalars,
    branch: Indices,
    out: Nodal,
):
    """out = dE/dx: k (l - L0) n times w_bi at the second point's nodes, times -w_ai at the first's, for each taut
    segment: l > L0 where branch[s] < 0, else branch[s] == 1."""
    for v, i in ti.ndrange(out.shape[0], out.shape[1]):
        out[v, i] = 0.0
    for s in range(segments.shape[0]):
        a, b = segments[s, 0], segments[s, 1]
        r = segment_vector(rest, u, nodes, weights, a, b)
        l = r.norm()
        if ti.select(branch[s] < 0, l > rest_length[s], branch[s] == 1):
            force = stiffness[s] / rest_length[s] * (l - rest_length[s]) / l * r
            for j in range(nodes.shape[1]):
                for i in ti.static(range(3)):
                    if i < out.shape[1]:
                        out[nodes[b, j], i] += weights[b, j] * force[i]
                        out[nodes[a, j], i] -= weights[a, j] * force[i]


@kernel
def cord_hessian(
    rest: Nodal,
    u: Nodal,
    nodes: Pairs,
    weights: Table,
    segments: Pairs,
    stiffness: Scalars,
    rest_length: Scalars,
    branch: Indices,
    out: Table,
):
    """out[s] = the segment's (2 (d + 1) d)^2 block, row-major: c_p c_q (k n n^T + k max(l - L0, 0) / l (I - n n^T))
    at node slots (p, q) for a taut segment (as in cord_gradient), zero for a slack one."""
    for s in range(segments.shape[0]):
        d, k = rest.shape[1], nodes.shape[1]
        n = 2 * k * d
        a, b = segments[s, 0], segments[s, 1]
        r = segment_vector(rest, u, nodes, weights, a, b)
        l = r.norm()
        H = ti.Matrix.zero(ti.f64, 3, 3)
        if ti.select(branch[s] < 0, l > rest_length[s], branch[s] == 1):
            stiff = stiffness[s] / rest_length[s]
            direction = r / l
            nn = direction.outer_product(direction)
            H = stiff * nn + stiff * ti.max(l - rest_length[s], 0.0) / l * (ti.Matrix.identity(ti.f64, 3) - nn)
        for p, q in ti.ndrange(2 * k, 2 * k):
            cp = ti.select(p < k, -weights[a, p % k], weights[b, p % k])
            cq = ti.select(q < k, -weights[a, q % k], weights[b, q % k])
            for i, j in ti.static(ti.ndrange(3, 3)):
                if i < d and j < d:
                    out[s, n * (d * p + i) + d * q + j] = cp * cq * H[i, j]


class Cords(Term):
    """Tension-only cords between embedded points: point a at sum_i weights[a, i] x_{nodes[a, i]} (nodes, weights
    (P, d + 1)); segments (s, 2) point indices, stiffness (s,) E A, rest_length (s,) L0 > 0."""

    name = "fibers"
    kinked = True
    piecewise = True  # a sum of one energy per segment (Term.restricted takes a subset)

    def __init__(self, config, nodes, weights, segments, stiffness, rest_length):
        self.config = config
        self.nodes, self.segments = int32s(nodes), int32s(segments)
        self.weights = np.ascontiguousarray(weights, dtype=np.float64)
        self.stiffness = np.ascontiguousarray(stiffness, dtype=np.float64)
        self.rest_length = np.ascontiguousarray(rest_length, dtype=np.float64)
        self._pattern = block_pattern(self.piece_nodes(), config.dim)
        self._block = (2 * self.nodes.shape[1] * config.dim) ** 2
        self._own = np.full(len(self.segments), -1, dtype=np.int32)  # every segment on its own branch
        self.branch = self._own  # the branches the Hessian uses: -1 its own, 0 slack, 1 taut

    def piece_nodes(self) -> np.ndarray:
        """(s, 2 (d + 1)): a segment's first point's embedding nodes, then its second's (its Hessian block's)."""
        return np.hstack([self.nodes[self.segments[:, 0]], self.nodes[self.segments[:, 1]]])

    def on_pieces(self, config, pieces: np.ndarray, nodes: np.ndarray) -> "Cords":
        """The segments `pieces`, each with its two points of its own: points 2 i and 2 i + 1 for segment i."""
        k = self.nodes.shape[1]
        ends = self.segments[pieces]
        weights = np.stack([self.weights[ends[:, 0]], self.weights[ends[:, 1]]], axis=1).reshape(-1, k)
        segments = np.arange(2 * len(pieces)).reshape(-1, 2)
        return Cords(config, nodes.reshape(-1, k), weights, segments, self.stiffness[pieces], self.rest_length[pieces])

    def scale_pieces(self, scale: np.ndarray) -> None:
        """Scale each segment's stiffness E A (its energy) by scale (s,)."""
        self.stiffness = np.ascontiguousarray(self.stiffness * scale)

    def _arguments(self) -> tuple:
        c = self.config
        return (c.rest, c.u, self.nodes, self.weights, self.segments, self.stiffness, self.rest_length)

    def energy(self) -> float:
        return cord_energy(*self._arguments())

    def _gradient(self, branch: np.ndarray) -> np.ndarray:
        out = np.empty_like(self.config.u)
        cord_gradient(*self._arguments(), branch, out)
        return out

    def gradient(self) -> np.ndarray:
        return self._gradient(self._own)

    def points(self, x: np.ndarray) -> np.ndarray:
        """The embedded points' values (P, d) of nodal values x (n, d): their positions of the nodes' positions,
        their displacements of the nodes' displacements."""
        return np.einsum("pi,pid->pd", self.weights, x[self.nodes])

    def lengths(self, u: np.ndarray) -> np.ndarray:
        """Each segment's current length l at displacements u (rest and displacement parts summed apart)."""
        rest, moved = self.points(self.config.rest), self.points(u)
        first, second = self.segments.T
        return np.linalg.norm((rest[second] - rest[first]) + (moved[second] - moved[first]), axis=1)

    def tension(self, u: np.ndarray) -> np.ndarray:
        """Each segment's axial force at displacements u: E A (l / L0 - 1) where taut (l > L0), 0 where slack."""
        return self.stiffness * np.maximum(self.lengths(u) / self.rest_length - 1.0, 0.0)

    def _taut(self, u: np.ndarray) -> np.ndarray:
        """Whether each segment is taut (l > L0) at displacements u."""
        return self.lengths(u) > self.rest_length

    def choose_branches(self, dx: np.ndarray | None) -> int:
        """Taut or slack as at u + dx; the count of segments whose branch changes."""
        now = self._taut(self.config.u)
        new = self._own if dx is None else self._taut(self.config.u + dx).astype(np.int32)
        changed = int(np.count_nonzero(np.where(new < 0, now, new) != np.where(self.branch < 0, now, self.branch)))
        self.branch = new
        return changed

    def branch_shift(self) -> np.ndarray | None:
        return None if self.branch is self._own else self._gradient(self.branch) - self.gradient()

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._pattern

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        out = np.empty((len(self.segments), self._block))
        cord_hessian(*self._arguments(), self.branch, out)
        return out.ravel()


@dataclass(frozen=True)
class Fiber:
    """An embedded fibre ([[fibers]]): its curve (path, a fem/fiber_paths.py layout), Young's modulus E, its
    cross-section as exactly one of area (in 2D: per unit depth, a length) and diameter (3D; A = pi diameter^2 /
    4), the sample spacing of its curve (None: half the mean edge length of the mesh's elements), and an optional
    name for messages, held to a chamber name's rule (output.check_heading)."""

    path: Layout
    E: float
    area: float | None = None
    diameter: float | None = None
    spacing: float | None = None
    name: str | None = None

    def __post_init__(self):
        require(isinstance(self.path, Layout), f"path = {self.path!r} must be a fibre layout ({', '.join(LAYOUTS)})")
        require_positive("E", self.E)
        require(
            (self.area is None) != (self.diameter is None),
            f"area = {self.area!r}, diameter = {self.diameter!r}: give exactly one of area and diameter",
        )
        require_positive("area", self.area, allow_none=True)
        require_positive("diameter", self.diameter, allow_none=True)
        require_positive("spacing", self.spacing, allow_none=True)
        if self.name is not None:
            check_heading("fiber name", self.name)

    @property
    def layout(self) -> str:
        return self.path.name

    @property
    def what(self) -> str:
        """The fibre in messages: its name, else its layout."""
        return f"fiber {self.name!r}" if self.name else f"the {self.layout} fiber"

    def section(self, dim: int) -> float:
        """The cross-section A (per unit depth in 2D)."""
        require(
            dim == 3 or self.diameter is None,
            f"{self.what}: diameter = {self.diameter!r} is for a 3D body; a 2D fibre is a layer of cords per unit "
            f"depth: give area, its cross-section per unit depth",
        )
        if self.diameter is not None:
            return math.pi * self.diameter**2 / 4
        assert self.area is not None, "__post_init__ takes exactly one of area and diameter"
        return self.area

    def terms(self, config, mesh, lumped_area, budget) -> list:
        """One Cords term of this fibre's segments, embedded in the mesh. Refused before any point is made past
        MAX_FIBER_POINTS sample points (counted exactly, Layout.size), or past the budget (limits.Budget) by the
        memory of their Hessian blocks (check_entries); and after embedding, where a point lies outside the body
        or a segment between two points passes through its boundary (a chamber: embedding.first_crossing) or,
        running from boundary to boundary, has its middle outside (a cord across a chamber from wall to wall)."""
        d = mesh.dim
        require(
            d == 3 or self.path.planar,
            f"{self.what}: layout = {self.layout!r} is 3D only; a 2D body takes {', '.join(PLANAR)}",
        )
        require(self.path.dim == d, f"{self.what}: its points have {self.path.dim} coordinates; the body is {d}D")
        area = self.section(d)
        corners = mesh.vertices[mesh.elements[:, : d + 1]]
        edges = [np.linalg.norm(corners[:, i] - corners[:, j], axis=1) for i in range(d + 1) for j in range(i)]
        spacing = self.spacing or 0.5 * float(np.mean(edges))
        count, points = self.path.size(spacing)
        require(
            points <= MAX_FIBER_POINTS,
            f"{self.what}: spacing {spacing:.6g} would sample it at {points:.3g} points; at most {MAX_FIBER_POINTS} "
            f"are allowed (give a larger spacing, or fewer rings or strands)",
        )
        segments_made = points if self.path.closed else points - count
        budget.check_entries(segments_made * (2 * (d + 1) * d) ** 2, f"{self.what} ({segments_made} cord segments)")
        curves = self.path.curves(spacing)
        starts = np.cumsum([0] + [len(c) for c in curves])
        segments = np.vstack(
            [np.column_stack([np.arange(s, e - 1), np.arange(s + 1, e)]) for s, e in zip(starts[:-1], starts[1:])]
            + ([np.column_stack([starts[1:] - 1, starts[:-1]])] if self.path.closed else [])
        )
        nodes, weights = embed(mesh, np.vstack(curves), self.what)
        at_rest = np.einsum("pi,pid->pd", weights, mesh.vertices[nodes])
        first, second = at_rest[segments[:, 0]], at_rest[segments[:, 1]]
        crossing = first_crossing(mesh, first, second)
        how = "leaves the body at"
        if crossing is None:  # both ends on the boundary (a chamber's wall, say): the segment's middle tells
            middles = (first + second) / 2
            out = np.flatnonzero(~inside(mesh, middles, snapping=True))  # as near the surface as embed() allows
            crossing, how = (int(out[0]), middles[out[0]]) if len(out) else None, "runs outside the body at its middle"
        if crossing is not None:
            s, x = crossing
            ends = " to ".join(str([round(float(v), 6) for v in end[s]]) for end in (first, second))
            raise PneumaInputError(
                f"{self.what}: its segment from {ends} {how} {[round(float(v), 6) for v in x]} (through a chamber or "
                f"out of the body between two of its sample points; spacing {spacing:.6g}): give a smaller spacing or "
                f"move the fiber"
            )
        rest_length = np.linalg.norm(at_rest[segments[:, 1]] - at_rest[segments[:, 0]], axis=1)
        kept = rest_length > 1e-12 * float(np.ptp(mesh.vertices, axis=0).max())
        stiffness = np.full(int(kept.sum()), self.E * area)
        return [Cords(config, nodes, weights, segments[kept], stiffness, rest_length[kept])]
