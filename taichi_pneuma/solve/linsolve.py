"""Sparse linear solves for Newton: a fixed CSR pattern, swappable factorisation backends,
and the Woodbury identity for the low-rank (chamber) parts kept out of the factorised matrix:

    (S + U C U^T)^-1 b = y - Z (C^-1 + U^T Z)^-1 U^T y,   y = S^-1 b,  Z = S^-1 U.
"""

import importlib.util
import os
import sys
from contextlib import contextmanager

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .. import runtime
from ..backend import ti


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


class FactorizationError(RuntimeError):
    """The matrix could not be factorised (singular, or not positive definite for a Cholesky backend)."""


class ScipySuperLU:
    """SciPy's SuperLU (general LU) on the symmetric matrix, minimum-degree ordering on A^T + A."""

    name = "scipy"

    def factorize(self, matrix: sp.csr_matrix) -> None:
        try:
            self._lu = spla.splu(matrix.tocsc(), permc_spec="MMD_AT_PLUS_A")
        except RuntimeError as exc:
            raise FactorizationError(str(exc)) from None

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        return self._lu.solve(rhs)


@contextmanager
def silenced_stdout():
    """Send the process's file descriptor 1 to /dev/null (CHOLMOD prints its warnings there directly)."""
    sys.stdout.flush()
    saved = os.dup(1)
    with open(os.devnull, "w") as null:
        os.dup2(null.fileno(), 1)
        try:
            yield
        finally:
            os.dup2(saved, 1)
            os.close(saved)


class CholespyCholesky:
    """Supernodal sparse Cholesky (CHOLMOD inside the cholespy wheel); refuses indefinite matrices.

    CHOLMOD prints its own warning for a matrix that is not positive definite; that is silenced,
    and FactorizationError raised instead (Newton then falls back to the PSD Hessian)."""

    name = "cholespy"

    def factorize(self, matrix: sp.csr_matrix) -> None:
        from cholespy import CholeskySolverD, MatrixType

        try:
            with silenced_stdout():
                self._factor = CholeskySolverD(matrix.shape[0], matrix.indptr.astype(np.int32),
                                               matrix.indices.astype(np.int32), matrix.data, MatrixType.CSR)
        except ValueError as exc:
            raise FactorizationError(str(exc)) from None

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        rhs = np.ascontiguousarray(rhs, dtype=np.float64)
        x = np.zeros_like(rhs)
        self._factor.solve(rhs, x)
        return x


@ti.kernel
def _fill_builder(builder: ti.types.sparse_matrix_builder(), rows: ti.types.ndarray(), cols: ti.types.ndarray(),
                  vals: ti.types.ndarray()):
    for i in range(rows.shape[0]):
        builder[rows[i], cols[i]] += vals[i]


class TaichiLLT:
    """Taichi's SparseSolver (Eigen's simplicial LLT on the CPU); the pattern is analysed once.

    Eigen's LLT reads the lower triangle only, so only the entries with row >= col are handed over
    (about half the triplets to build); their indices are converted once per pattern (FixedPattern
    hands out the same index arrays for every matrix)."""

    name = "taichi"

    def __init__(self):
        self._solver = None
        self._indptr = None

    def factorize(self, matrix: sp.csr_matrix) -> None:
        n = matrix.shape[0]
        if matrix.indptr is not self._indptr:
            self._indptr = matrix.indptr
            rows = np.repeat(np.arange(n, dtype=np.int32), np.diff(matrix.indptr))
            self._lower = rows >= matrix.indices
            self._rows, self._cols = rows[self._lower], matrix.indices[self._lower].astype(np.int32)
            self._solver = None
        builder = ti.linalg.SparseMatrixBuilder(n, n, max_num_triplets=len(self._rows), dtype=ti.f64)
        _fill_builder(builder, self._rows, self._cols, np.ascontiguousarray(matrix.data[self._lower]))
        sparse = builder.build()
        if self._solver is None:
            self._solver = ti.linalg.SparseSolver(dtype=ti.f64, solver_type="LLT")
            self._solver.analyze_pattern(sparse)
        self._solver.factorize(sparse)
        if not self._solver.info():
            raise FactorizationError("Taichi LLT factorisation failed (matrix not positive definite)")

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        if rhs.ndim == 2:
            return np.column_stack([self.solve(column) for column in rhs.T])
        return self._solver.solve(np.ascontiguousarray(rhs, dtype=np.float64))


BACKENDS = {"cholespy": CholespyCholesky, "scipy": ScipySuperLU, "taichi": TaichiLLT}


def make_backend(name: str):
    """A fresh linear-solver backend by name: one of BACKENDS, or "auto": Taichi's LLT when Taichi runs on
    the CPU, CHOLMOD otherwise (Taichi's sparse solvers are float32-only on CUDA; the solve stays float64),
    or SciPy's SuperLU where cholespy is not installed (it has no wheel for Linux aarch64)."""
    if name == "auto":
        name = "taichi" if runtime.current_arch() in (None, "cpu") else \
            "cholespy" if importlib.util.find_spec("cholespy") else "scipy"
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
