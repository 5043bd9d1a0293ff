"""The common shape of an energy term and the DOF numbering helper."""

from __future__ import annotations

import math

import numpy as np


def vertex_dofs(vertices: np.ndarray) -> np.ndarray:
    """Interleaved DOF indices [2v0, 2v0+1, 2v1, 2v1+1, ...] of the given vertices."""
    vertices = np.asarray(vertices, dtype=np.int64)
    return np.column_stack([2 * vertices, 2 * vertices + 1]).ravel()


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
