"""The common shape of an energy term and the DOF numbering helper."""

import math

import numpy as np
import taichi as ti


def vertex_dofs(vertices: np.ndarray) -> np.ndarray:
    """Interleaved DOF indices [2v0, 2v0+1, 2v1, 2v1+1, ...] of the given vertices."""
    vertices = np.asarray(vertices, dtype=np.int64)
    return np.column_stack([2 * vertices, 2 * vertices + 1]).ravel()


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


class Term:
    """Defaults for the optional duties: no sparse Hessian, no rank-1 part, no step bound.

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
