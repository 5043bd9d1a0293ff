"""The common shape of an energy term, the DOF numbering helper, and the kernel argument types.

Kernels are module-level functions of arrays: mesh data, per-element parameters, the rest positions
X and the displacements u arrive as `ti.types.ndarray` arguments (NumPy arrays on the caller's side),
scalars as runtime arguments. Taichi's compile key holds an ndarray's dtype and ndim, not its shape,
so a kernel is compiled once per process whatever the mesh, material or scene. The argument types are TypeAliases
so that a type checker reads them as annotations it cannot see into (Any), not as variables.
"""

import math
from typing import Any, TypeAlias

import numpy as np

from ..backend import ti

Nodal: TypeAlias = ti.types.ndarray(dtype=ti.f64, ndim=2)  # (n, d) float64: positions, displacements, forces, any d
Scalars: TypeAlias = ti.types.ndarray(dtype=ti.f64, ndim=1)  # (m,) float64
Table: TypeAlias = ti.types.ndarray(dtype=ti.f64, ndim=2)  # (m, k) float64: per-element Hessian blocks
Indices: TypeAlias = ti.types.ndarray(dtype=ti.i32, ndim=1)  # (m,) int32 vertex indices
Triples: TypeAlias = ti.types.ndarray(dtype=ti.types.vector(3, ti.i32), ndim=1)  # (m, 3) int32 vertex triples
HUGE = 1e300  # a finite stand-in for infinity in comparisons (smallest_positive_cubic_root)


def vectors(d: int):
    """The kernel argument type of (n, d) float64 nodal data as n d-vectors (a Taichi vector has a fixed size)."""
    return ti.types.ndarray(dtype=ti.types.vector(d, ti.f64), ndim=1)


Vec2s: TypeAlias = vectors(2)  # (n, 2) float64, for the planar terms' kernels


def vertex_dofs(vertices: np.ndarray, d: int) -> np.ndarray:
    """Interleaved DOF indices [d v0, d v0 + 1, ..., d v0 + d - 1, d v1, ...] of the given vertices in dimension d."""
    vertices = np.asarray(vertices, dtype=np.int64)
    return (d * vertices[:, None] + np.arange(d)).ravel()


def block_pattern(blocks: np.ndarray, d: int) -> tuple[np.ndarray, np.ndarray]:
    """(rows, cols) of dense dk x dk Hessian blocks, one per row of `blocks` (m, k) vertex indices in dimension
    d, each block stored row-major: entry dk i + j of block e is (dof i, dof j) of its vertices' DOFs."""
    m, k = blocks.shape
    dofs = vertex_dofs(blocks.ravel(), d).reshape(m, d * k)
    return np.repeat(dofs, d * k, axis=1).ravel(), np.tile(dofs, (1, d * k)).ravel()


def int32s(values) -> np.ndarray:
    """A contiguous int32 copy of index data, as the kernels take it."""
    return np.ascontiguousarray(values, dtype=np.int32)


@ti.func
def position(rest: ti.template(), u: ti.template(), i):
    """Current position x_i = X_i + u_i."""
    return rest[i] + u[i]


@ti.func
def edge(rest: ti.template(), u: ti.template(), i, j):
    """x_j - x_i, formed from rest and displacement differences so short edges keep their digits."""
    return (rest[j] - rest[i]) + (u[j] - u[i])


@ti.func
def quadratic_roots(c0, c1, c2):
    """Real roots of c0 + c1 t + c2 t^2 as a 2-vector, inf where there is none.

    Uses q = -(c1 + sign(c1) sqrt(disc)) / 2, roots q / c2 and c0 / q (no cancellation); a c2 below
    1e-14 of the other coefficients is treated as zero (one root, -c0 / c1)."""
    roots = ti.Vector([ti.math.inf, ti.math.inf])
    if ti.abs(c2) <= 1e-14 * (ti.abs(c1) + ti.abs(c0)):
        if c1 != 0:
            roots[0] = -c0 / c1
    else:
        disc = c1 * c1 - 4.0 * c2 * c0
        if disc >= 0:
            sq = ti.sqrt(disc)
            q = -0.5 * (c1 + ti.select(c1 >= 0, sq, -sq))
            roots[0] = q / c2
            if q != 0:
                roots[1] = c0 / q
    return roots


@ti.func
def smallest_positive_root(c0, c1, c2):
    """The smallest root t > 0 of c0 + c1 t + c2 t^2 (inf if none)."""
    roots = quadratic_roots(c0, c1, c2)
    root = ti.math.inf
    for r in ti.static(range(2)):
        if roots[r] > 0:
            root = ti.min(root, roots[r])
    return root


@ti.func
def sign_of(x):
    return ti.select(x > 0, 1, ti.select(x < 0, -1, 0))


@ti.func
def cubic(c0, c1, c2, c3, t):
    return c0 + t * (c1 + t * (c2 + t * c3))


@ti.func
def smallest_positive_cubic_root(c0, c1, c2, c3):
    """The smallest root t > 0 of p(t) = c0 + c1 t + c2 t^2 + c3 t^3 (inf if none), by bisection on the
    pieces where p is monotone: from 0 to the positive roots of p' (quadratic_roots) and, past the last one,
    to a bracket found by doubling (up to HUGE). Any degree (c3, or more, may vanish). The result is the
    left end of the last bracket, within 1e-15 of the root relative to it and never past it.

    Taichi compiles with fast math, which may assume no value is infinite: a comparison with an infinite
    constant can be folded away, so the pieces' ends are compared with the finite HUGE instead."""
    critical = quadratic_roots(c1, 2.0 * c2, 3.0 * c3)
    ends = ti.Vector([ti.min(critical[0], critical[1]), ti.max(critical[0], critical[1]), HUGE])
    root = ti.math.inf
    found = False
    a = 0.0
    for i in ti.static(range(3)):
        b = ends[i]
        if not found and a < b and b <= HUGE:
            start = sign_of(cubic(c0, c1, c2, c3, a))
            if ti.static(i == 2):  # the last piece, unbounded: double until p changes sign
                b = ti.max(2.0 * a, 1.0)
                while sign_of(cubic(c0, c1, c2, c3, b)) == start and b < HUGE:
                    b *= 2.0
            if start == 0 and a > 0:
                root, found = a, True
            elif start != 0 and sign_of(cubic(c0, c1, c2, c3, b)) != start:
                lo, hi = a, b
                while hi - lo > 1e-15 * hi:
                    middle = 0.5 * (lo + hi)
                    if middle <= lo or middle >= hi:
                        break
                    if sign_of(cubic(c0, c1, c2, c3, middle)) == start:
                        lo = middle
                    else:
                        hi = middle
                root, found = lo, True
            a = b
    return root


class Term:
    """Defaults for the optional duties: no sparse Hessian, no rank-1 part, no step bound.

    A term holds the model's Configuration (config.rest, config.u: (n, d) NumPy arrays) and its own
    data as NumPy arrays, and evaluates itself by calling module-level kernels on them.
    reports_contact: whether -gradient() is a contact force the history reports, under reported_as (its name, or
    the name of the term it is a part of: an obstacle's edge barrier is reported with its node barrier).
    kinked: whether the term is piecewise smooth (see choose_branches).
    dynamic: whether its Hessian's pattern follows the state (a contact term's active pairs): hessian_pattern() is
    then that of its last hessian_values() call, and the model's fixed pattern leaves it out (EnergyModel.assemble).
    quadratic: whether its energy is a polynomial of degree <= 2 in u, the same at every command (a clamp, a roller,
    gravity): a reduced model projects it once (reduce/exact.py).
    piecewise: whether its energy is a sum over pieces, E = sum_p E_p (an element, a cord segment, a sheet's cell),
    each touching the nodes of its row of piece_nodes() only, with hessian_values() the pieces' dense blocks in piece
    order on block_pattern(piece_nodes()): restricted() takes a weighted subset of the pieces, as a reduced model's
    hyper-reduction samples them (reduce/ecsw.py).
    """

    name = "term"
    reports_contact = False
    kinked = False  # piecewise smooth: choose_branches may move pieces to other branches
    dynamic = False  # its Hessian's pattern changes with the state
    quadratic = False  # E(u) = E(0) + g(0).u + 1/2 u^T K u, K constant, whatever the commands
    piecewise = False  # E = sum_p E_p over pieces: piece_nodes(), restricted(), scale_pieces()
    config: Any  # the Configuration it is evaluated on (terms/model.py)
    vertices: np.ndarray  # a restricted term's: the numbers of its configuration's nodes in the whole one

    @property
    def reported_as(self) -> str:
        """The history's name for its contact force (reports_contact)."""
        return self.name

    def energy(self) -> float:
        """The term's energy at config.u (every term has one)."""
        raise NotImplementedError

    def gradient(self) -> np.ndarray:
        """dE/du (n, d) at config.u (every term has one)."""
        raise NotImplementedError

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        return np.zeros(0)

    def low_rank(self) -> list[tuple[np.ndarray, np.ndarray, float]]:
        return []

    def max_step(self, dx: np.ndarray) -> float:
        return math.inf

    def choose_branches(self, dx: np.ndarray | None) -> int:
        """A kinked term (piecewise smooth: each piece s on one of the smooth branches psi_s^b of its energy, the
        branch a function of the state, as a tension-only cord is taut or slack) makes hessian_values and
        branch_shift use, for every piece, the branch it is on at u + dx (dx (n, d); None: at u, the default) and
        returns how many pieces that moves to another branch than the one they used; a smooth term returns 0."""
        return 0

    def branch_shift(self) -> np.ndarray | None:
        """The gradient at u of the chosen branches' energies minus the true gradient, (n, d) (None: zero, as for
        every smooth term and for a kinked one whose pieces are on their own branches at u)."""
        return None

    def piece_nodes(self) -> np.ndarray:
        """(P, k) the nodes each piece's energy depends on, in the order of its Hessian block (a piecewise term)."""
        raise NotImplementedError

    @property
    def n_pieces(self) -> int:
        """The number of pieces P (a piecewise term)."""
        return len(self.piece_nodes())

    def on_pieces(self, config, pieces: np.ndarray, nodes: np.ndarray) -> "Term":
        """A term of the same class on config holding only `pieces` (indices), with nodes (len(pieces), k) their
        rows of piece_nodes() numbered in config (a piecewise term; restricted() calls it)."""
        raise NotImplementedError

    def scale_pieces(self, scale: np.ndarray) -> None:
        """Multiply each piece's energy by scale (P,) (a piecewise term)."""
        raise NotImplementedError

    def restricted(self, pieces: np.ndarray, scale: np.ndarray, apart: bool = False) -> "Term":
        """The term on `pieces` only, piece p's energy times scale[p]: E = sum_p scale_p E_p, on a configuration of
        its own holding those pieces' nodes alone, numbered afresh (apart: a copy of the nodes per piece, so that no
        two pieces share one and gradient() holds each piece's own forces). Its `vertices` are the numbers of its
        nodes in this term's configuration. For a piecewise term; a kinked one's pieces start on their own
        branches (choose_branches)."""
        pieces = np.asarray(pieces, dtype=np.int64)
        nodes = self.piece_nodes()[pieces]
        if apart:
            vertices, local = nodes.ravel(), np.arange(nodes.size)
        else:
            vertices, local = np.unique(nodes, return_inverse=True)
        config = type(self.config)(self.config.rest[vertices])  # a Configuration (terms/model.py) of those nodes
        term = self.on_pieces(config, pieces, local.reshape(nodes.shape))
        term.scale_pieces(np.asarray(scale, dtype=np.float64))
        term.vertices = vertices
        return term

    def fault(self) -> str | None:
        """Why no equilibrium can be found from the current state, in words, when this term is the cause (e.g. a
        material law that is unstable there), else None; asked when a Newton solve breaks down."""
        return None

    def columns(self) -> dict[str, float]:
        """History columns of its own, by name, at the current state (none by default)."""
        return {}

    def follow(self) -> None:
        """Called when the model's displacements are set, before any term is evaluated at them (a term whose state
        follows the body's, as a held object's height, updates it here)."""

    def advance(self, u: np.ndarray) -> None:
        """Called with the displacements that end each increment; time-dependent terms update their state."""
