"""Sparse linear solves for Newton: a fixed CSR pattern, swappable factorisation backends,
and the Woodbury identity for the low-rank (chamber) parts kept out of the factorised matrix:

    (S + U C U^T)^-1 b = y - Z (C^-1 + U^T Z)^-1 U^T y,   y = S^-1 b,  Z = S^-1 U.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .errors import PneumaInputError


class FixedPattern:
    """The CSR structure of a sum of triplets whose (row, col) never change.

    matrix(vals) sums duplicate entries into the precomputed CSR data array with one bincount.
    """

    def __init__(self, rows: np.ndarray, cols: np.ndarray, n: int):
        keys = np.asarray(rows, dtype=np.int64) * n + np.asarray(cols, dtype=np.int64)
        unique, self._slot = np.unique(keys, return_inverse=True)
        self._indices = (unique % n).astype(np.int32)
        self._indptr = np.searchsorted(unique // n, np.arange(n + 1)).astype(np.int32)
        self.n = n
        self.nnz = len(unique)

    def matrix(self, vals: np.ndarray) -> sp.csr_matrix:
        data = np.bincount(self._slot, weights=vals, minlength=self.nnz)
        return sp.csr_matrix((data, self._indices, self._indptr), shape=(self.n, self.n))


class ScipySuperLU:
    """SciPy's SuperLU on the symmetric matrix (minimum-degree ordering on A^T + A)."""

    name = "scipy"

    def factorize(self, matrix: sp.csr_matrix) -> None:
        self._lu = spla.splu(matrix.tocsc(), permc_spec="MMD_AT_PLUS_A")

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        return self._lu.solve(rhs)


BACKENDS = {"scipy": ScipySuperLU}


def make_backend(name: str):
    """A fresh linear-solver backend by name."""
    if name not in BACKENDS:
        raise PneumaInputError(f"linear solver = {name!r} is not one of {', '.join(BACKENDS)}")
    return BACKENDS[name]()


def solve_low_rank_updated(backend, rhs: np.ndarray, low_rank: list[tuple[np.ndarray, np.ndarray, float]]):
    """Solve (S + sum_j c_j u_j u_j^T) d = rhs with S already factorised in `backend`."""
    y = backend.solve(rhs)
    if not low_rank:
        return y
    U = np.zeros((len(rhs), len(low_rank)))
    for j, (dofs, u, _) in enumerate(low_rank):
        U[dofs, j] = u
    Z = backend.solve(U)
    capacitance = np.diag([1.0 / c for _, _, c in low_rank]) + U.T @ Z
    return y - Z @ np.linalg.solve(capacitance, U.T @ y)
