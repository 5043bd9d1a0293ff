"""The common shape of an energy term, the DOF numbering helper, and the kernel argument types.

Kernels are module-level functions of arrays: mesh data, per-element parameters, the rest positions
X and the displacements u arrive as `ti.types.ndarray` arguments (NumPy arrays on the caller's side),
scalars as runtime arguments. Taichi's compile key holds an ndarray's dtype and ndim, not its shape,
so a kernel is compiled once per process whatever the mesh, material or scene.
"""

import math

import numpy as np

from ..backend import ti

Nodal = ti.types.ndarray(dtype=ti.f64, ndim=2)  # (n, d) float64: positions, displacements, forces, any d
Scalars = ti.types.ndarray(dtype=ti.f64, ndim=1)  # (m,) float64
Table = ti.types.ndarray(dtype=ti.f64, ndim=2)  # (m, k) float64: per-element Hessian blocks
Indices = ti.types.ndarray(dtype=ti.i32, ndim=1)  # (m,) int32 vertex indices
Triples = ti.types.ndarray(dtype=ti.types.vector(3, ti.i32), ndim=1)  # (m, 3) int32 vertex triples


def vectors(d: int):
    """The kernel argument type of (n, d) float64 nodal data as n d-vectors (a Taichi vector has a fixed size)."""
    return ti.types.ndarray(dtype=ti.types.vector(d, ti.f64), ndim=1)


Vec2s = vectors(2)  # (n, 2) float64, for the planar terms' kernels


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


class Term:
    """Defaults for the optional duties: no sparse Hessian, no rank-1 part, no step bound.

    A term holds the model's Configuration (config.rest, config.u: (n, d) NumPy arrays) and its own
    data as NumPy arrays, and evaluates itself by calling module-level kernels on them.
    reports_contact: whether -gradient() is a contact force the history reports.
    """

    name = "term"
    reports_contact = False

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        return np.zeros(0)

    def low_rank(self) -> list[tuple[np.ndarray, np.ndarray, float]]:
        return []

    def max_step(self, dx: np.ndarray) -> float:
        return math.inf

    def advance(self, u: np.ndarray) -> None:
        """Called with the displacements that end each increment; time-dependent terms update their state."""
