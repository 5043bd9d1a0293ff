"""Sparse linear solves for Newton: a fixed CSR pattern, swappable backends, and the low-rank (chamber)
parts U C U^T kept out of the sparse matrix S.

A direct backend factorises S and adds the low-rank parts by the Woodbury identity:

    (S + U C U^T)^-1 b = y - Z (C^-1 + U^T Z)^-1 U^T y,   y = S^-1 b,  Z = S^-1 U.

The iterative backend (AmgConjugateGradient) runs conjugate gradients on S + U C U^T itself, preconditioned
by an algebraic multigrid hierarchy of S, to a relative residual the caller gives (Newton's forcing term).
"""

import importlib.util
import itertools
import os
import sys
from collections.abc import Sequence
from contextlib import contextmanager
from typing import Any

import numpy as np
import scipy.sparse as sp

from .. import runtime
from ..backend import ti
from ..errors import require


def installed(module: str) -> bool:
    return importlib.util.find_spec(module) is not None


class FixedPattern:
    """The CSR structure of a sum of triplets whose (row, col) never change, plus extra triplets whose (row, col)
    may change from one matrix to the next (a contact term's active pairs: Term.dynamic).

    matrix(values, extra) sums duplicate entries into the precomputed CSR data array: values is the fixed
    triplets' values, or the list of them per term in the pattern's order (no concatenated copy), each summed with
    one bincount (or, shorter than the data array, np.add.at); extra is (rows, cols, values) of the changing ones.
    The structure only grows: an extra entry not in it is inserted (the fixed triplets' slots shifted past it) and
    kept, so a backend re-analyses the pattern (new index arrays) only when the contact pairs reach new nodes.
    """

    def __init__(self, rows: np.ndarray, cols: np.ndarray, n: int):
        keys = np.asarray(rows, dtype=np.int64) * n + np.asarray(cols, dtype=np.int64)
        self._keys, self._slot = np.unique(keys, return_inverse=True)
        self.n = n
        self._structure()

    def _structure(self) -> None:
        """The CSR index arrays of the sorted unique keys row n + col."""
        n = self.n
        self._indices = (self._keys % n).astype(np.int32)
        self._indptr = np.searchsorted(self._keys // n, np.arange(n + 1)).astype(np.int32)
        self.nnz = len(self._keys)

    def _extra_slots(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """The data slots of the extra triplets, inserting the keys the structure lacks (sorted insertion: each old
        key k moves up by the number of new keys below it)."""
        keys = np.asarray(rows, dtype=np.int64) * self.n + np.asarray(cols, dtype=np.int64)
        slots = np.searchsorted(self._keys, keys)
        missing = (slots == self.nnz) | (self._keys[np.minimum(slots, self.nnz - 1)] != keys)
        if np.any(missing):
            new = np.unique(keys[missing])
            shift = np.searchsorted(new, self._keys)
            self._slot = (self._slot + shift[self._slot]) if len(self._slot) else self._slot
            self._keys = np.insert(self._keys, np.searchsorted(self._keys, new), new)
            self._structure()
            slots = np.searchsorted(self._keys, keys)
        return slots

    def matrix(self, values: np.ndarray | list[np.ndarray], extra: tuple | None = None) -> sp.csr_matrix:
        changing = [] if extra is None else [(self._extra_slots(extra[0], extra[1]), extra[2])]  # may move _slot
        fixed = [values] if isinstance(values, np.ndarray) else values
        ends = np.cumsum([len(part) for part in fixed], dtype=np.int64)
        data = np.zeros(self.nnz)
        for slots, part in [(self._slot[end - len(part) : end], part) for part, end in zip(fixed, ends)] + changing:
            if len(part) > self.nnz:
                data += np.bincount(slots, weights=part, minlength=self.nnz)
            else:
                np.add.at(data, slots, part)
        return sp.csr_matrix((data, self._indices, self._indptr), shape=(self.n, self.n))


class FactorizationError(RuntimeError):
    """The matrix could not be factorised (singular, or not positive definite for a Cholesky backend)."""


class ScipySuperLU:
    """SciPy's SuperLU (general LU) on the symmetric matrix, minimum-degree ordering on A^T + A."""

    name = "scipy"

    def factorize(self, matrix: sp.csr_matrix) -> None:
        from scipy.sparse.linalg import splu  # (imported where used, as in _cg)

        try:
            self._lu = splu(matrix.tocsc(), permc_spec="MMD_AT_PLUS_A")
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
                self._factor = CholeskySolverD(
                    matrix.shape[0],
                    matrix.indptr.astype(np.int32),
                    matrix.indices.astype(np.int32),
                    matrix.data,
                    MatrixType.CSR,
                )
        except ValueError as exc:
            raise FactorizationError(str(exc)) from None

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        rhs = np.ascontiguousarray(rhs, dtype=np.float64)
        x = np.zeros_like(rhs)
        self._factor.solve(rhs, x)
        return x


def nested_dissection(matrix: sp.csr_matrix, block: int) -> np.ndarray | None:
    """A fill-reducing ordering of the DOFs of a matrix of block x block node blocks: METIS's nested dissection
    (pymetis) of the node graph, each node's DOFs kept together; None where pymetis is not installed. On the
    quadratic 3D beam's Hessians it leaves a Cholesky factor 7-33 % smaller, and 1.2-3x faster to compute,
    than CHOLMOD's own choice (AMD in CVXOPT's build): nested dissection suits 3D meshes, minimum degree 2D ones."""
    if not installed("pymetis"):
        return None
    import pymetis

    n = matrix.shape[0] // block
    rows = np.repeat(np.arange(matrix.shape[0]), np.diff(matrix.indptr))
    graph = sp.csr_matrix((np.ones(matrix.nnz), (rows // block, matrix.indices // block)), shape=(n, n))
    graph.setdiag(0)
    graph.eliminate_zeros()
    order, _ = pymetis.nested_dissection(pymetis.CSRAdjacency(graph.indptr, graph.indices))
    return (block * np.asarray(order, dtype=np.int64)[:, None] + np.arange(block)).ravel()


class CholmodCholesky:
    """Supernodal sparse Cholesky (CHOLMOD, through CVXOPT's binding): the symbolic analysis (fill-reducing
    ordering, supernodes) is done once per pattern and kept, so each Newton iteration pays only the numerical
    factorisation (0.07 s for the quadratic 3D beam's 12k DOFs, where CHOLMOD's simplicial one in cholespy takes
    0.6 s, and 1.1 s at 59k DOFs). The ordering: nested_dissection of the nodes (block: DOFs per node) where
    pymetis is installed. Refuses indefinite matrices (FactorizationError). CVXOPT is GPL-licensed: it comes with
    the [3d] extra, beside gmsh.

    The pattern's CSR arrays are read as the CSC arrays of the transpose: the matrix is symmetric, so its values
    in CSR order are those of the same matrix in CHOLMOD's column order, and only the lower triangle is read."""

    name = "cholmod"

    def __init__(self, block: int = 1):
        self._block = block
        self._indptr = None

    def factorize(self, matrix: sp.csr_matrix) -> None:
        import cvxopt
        from cvxopt import cholmod

        if matrix.indptr is not self._indptr:
            n = matrix.shape[0]
            rows = np.repeat(np.arange(n, dtype=np.int64), np.diff(matrix.indptr))
            self._matrix = cvxopt.spmatrix(
                cvxopt.matrix(matrix.data), cvxopt.matrix(matrix.indices.astype(np.int64)), cvxopt.matrix(rows), (n, n)
            )
            order = nested_dissection(matrix, self._block)
            self._symbolic = (
                cholmod.symbolic(self._matrix, uplo="L")
                if order is None
                else cholmod.symbolic(self._matrix, p=cvxopt.matrix(order.tolist(), tc="i"), uplo="L")
            )
            self._indptr = matrix.indptr
        self._matrix.V = cvxopt.matrix(matrix.data)
        try:
            cholmod.numeric(self._matrix, self._symbolic)
        except ArithmeticError as exc:
            raise FactorizationError(f"CHOLMOD: the matrix is not positive definite (column {exc})") from None

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        import cvxopt
        from cvxopt import cholmod

        x = cvxopt.matrix(np.asarray(rhs, dtype=np.float64))
        try:
            cholmod.solve(self._symbolic, x)
        except ArithmeticError as exc:  # a factor of a singular matrix (a free body sliding)
            raise FactorizationError(f"CHOLMOD: the solve failed ({exc})") from None
        return np.array(x).reshape(rhs.shape)


@ti.kernel
def _fill_builder(
    builder: ti.types.sparse_matrix_builder(),
    rows: ti.types.ndarray(),
    cols: ti.types.ndarray(),
    vals: ti.types.ndarray(),
):
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


def rigid_body_modes(rest: np.ndarray) -> np.ndarray:
    """The near-null space of elasticity at nodes (n, d), on interleaved DOFs, (d n, d (d + 1) / 2): the d
    translations and the d (d - 1) / 2 infinitesimal rotations about the centroid (in the (i, j) plane the
    field (-x_j, x_i)): an elastic Hessian maps them to (almost) zero, and multigrid must keep them on its
    coarse levels to converge independently of the mesh size."""
    n, d = rest.shape
    centred = rest - rest.mean(axis=0)
    modes = [np.tile(np.eye(d)[i], n) for i in range(d)]
    for i, j in itertools.combinations(range(d), 2):
        rotation = np.zeros((n, d))
        rotation[:, i], rotation[:, j] = -centred[:, j], centred[:, i]
        modes.append(rotation.ravel())
    return np.column_stack(modes)


class NotConverged(FactorizationError):
    """The iterative solver did not reach its tolerance in its iteration limit (the matrix is indefinite or too
    ill-conditioned for the preconditioner): the caller falls back as for a failed factorisation."""


class AmgConjugateGradient:
    """Conjugate gradients on S + U C U^T (scipy.sparse.linalg.cg), preconditioned by one V-cycle of pyamg's
    smoothed-aggregation multigrid of S, built with the rigid-body modes of the nodes as its near-null space
    (aggregates of whole nodes: S as d x d blocks). Needs a symmetric positive definite S + U C U^T (the
    projected Hessian is; the exact one may not be: NotConverged then).

    CG's memory is a few vectors and the hierarchy (about 1.5 times S), where a Cholesky factor of a 3D
    Hessian grows as n^(4/3); its time grows about linearly in n. factorize() builds the hierarchy only
    when the pattern is new or the last solve needed more than twice the iterations per decade of residual
    that the hierarchy's first solve did (it stays a good preconditioner of the nearby Hessians of the next
    Newton iterations and increments while it does); a solve that fails with a reused hierarchy is retried
    on a fresh one. rtol: the relative residual |(S + U C U^T) x - b| / |b| a solve reaches (Newton sets
    it per iteration; the default is a tight one for standalone use)."""

    name = "amg"
    MAX_ITERATIONS = 300
    # strength of connection |a_ij| >= 0.08 sqrt(|a_ii a_jj|) (of the node blocks' norms), not pyamg's 0: the dense
    # node graph of quadratic tetrahedra otherwise makes aggregates of ~30 nodes and a weak coarse level;
    # energy-minimising prolongation smoothing, not one Jacobi step. Measured on the quadratic 3D beam's
    # Hessians (32k DOFs): 3-10 CG iterations to 1e-2 where pyamg's defaults took 8-29 (docs/3d.md)
    OPTIONS = {"strength": ("symmetric", {"theta": 0.08}), "smooth": "energy"}
    STALE_FACTOR = 2.0

    def __init__(self, rest: np.ndarray | None = None):
        self._modes = None if rest is None else rigid_body_modes(np.asarray(rest, dtype=np.float64))
        self._block = 1 if rest is None else np.shape(rest)[1]
        self.rtol = 1e-10
        self.iterations = 0  # CG iterations of the last solve
        self._hierarchy: Any = None  # pyamg's multilevel solver
        self._indptr = None

    def factorize(self, matrix: sp.csr_matrix) -> None:
        self._matrix = matrix
        if self._hierarchy is None or matrix.indptr is not self._indptr or self._stale:
            self._setup()

    def _setup(self) -> None:
        import pyamg

        matrix = self._matrix
        blocks = matrix.tobsr(blocksize=(self._block, self._block)) if self._block > 1 else matrix
        self._hierarchy = pyamg.smoothed_aggregation_solver(blocks, B=self._modes, symmetry="hermitian", **self.OPTIONS)
        self._preconditioner = self._hierarchy.aspreconditioner(cycle="V")
        self._indptr = matrix.indptr
        self._fresh_rate: float | None = None  # iterations per decade of residual on this hierarchy's first solve
        self._stale = False

    def solve(
        self, rhs: np.ndarray, low_rank: Sequence[tuple[np.ndarray, np.ndarray, float]] = (), rtol: float | None = None
    ) -> np.ndarray:
        if rhs.ndim == 2:
            return np.column_stack([self.solve(column, low_rank, rtol) for column in rhs.T])
        rtol = self.rtol if rtol is None else rtol
        try:
            return self._cg(rhs, low_rank, rtol)
        except NotConverged:
            if self._fresh_rate is None:  # a fresh hierarchy: the matrix is at fault (indefinite), and so is its
                self._stale = True  # hierarchy, which must not precondition the next matrix of this pattern
                raise
            self._setup()
            return self._cg(rhs, low_rank, rtol)

    def _cg(self, rhs: np.ndarray, low_rank, rtol: float) -> np.ndarray:
        matrix = self._matrix

        def apply(x):
            y = matrix @ x
            for dofs, u, c in low_rank:
                y[dofs] += c * float(u @ x[dofs]) * u
            return y

        import scipy.sparse.linalg as spla  # (imported where used: 0.1 s of every run's start otherwise)

        operator = spla.LinearOperator(matrix.shape, matvec=apply, dtype=np.float64)
        count = itertools.count()
        x, info = spla.cg(
            operator,
            rhs,
            rtol=rtol,
            maxiter=self.MAX_ITERATIONS,
            M=self._preconditioner,
            callback=lambda _: next(count),
        )
        self.iterations = next(count)
        residual = float(np.linalg.norm(apply(x) - rhs) / max(np.linalg.norm(rhs), np.finfo(float).tiny))
        if info != 0 or not residual <= 10 * rtol:
            raise NotConverged(
                f"CG reached a relative residual of {residual:.2e}, not {rtol:.2e}, in {self.iterations} iterations"
            )
        rate = self.iterations / max(-np.log10(max(residual, 1e-16)), 1.0)
        if self._fresh_rate is None:
            self._fresh_rate = rate
        self._stale = rate > self.STALE_FACTOR * self._fresh_rate
        return x


BACKENDS = {
    "amg": AmgConjugateGradient,
    "cholespy": CholespyCholesky,
    "cholmod": CholmodCholesky,
    "scipy": ScipySuperLU,
    "taichi": TaichiLLT,
}
# auto in 3D: CHOLMOD up to this many DOFs, CG with multigrid above (a factor's memory grows as n^(4/3) and its
# time as n^2, multigrid's about as n). On the quadratic beam's Hessians (2 cores; docs/3d.md, "Linear solvers
# in 3D") CHOLMOD refactorises 59k DOFs in 1.1 s and 119k in 3.9 s, where multigrid's set-up and one solve to 1e-2
# take 3.0 s and 15 s, and each later solve 0.6 s and 5.4 s; the 250k bound itself is extrapolated (n^2), not
# measured
DIRECT_MAX_DOFS_3D = 250_000
# auto without CHOLMOD: CG with multigrid from this many DOFs on in 3D. bench.py's solid section: on the octant
# (nu = 0.45) it overtakes Taichi's LLT between 675 and 3,213 DOFs and is 3x faster at 12,675; at nu = 0.499
# multigrid is weaker (its near-null space misses the nearly incompressible modes) and only even with LLT at 3,213
AMG_MIN_DOFS = 10_000


def auto_backend(rest: np.ndarray | None) -> str:
    """The backend "auto" takes for the nodes at rest (n, d) (None: a matrix of unknown origin): in 3D, CHOLMOD
    (CVXOPT installed: the [3d] extra) up to DIRECT_MAX_DOFS_3D DOFs, CG with multigrid above them or, without
    CHOLMOD, from AMG_MIN_DOFS on; otherwise direct_backend()."""
    dofs = 0 if rest is None or rest.shape[1] != 3 else rest.size
    cholmod = installed("cvxopt")
    if installed("pyamg") and (dofs > DIRECT_MAX_DOFS_3D or (dofs >= AMG_MIN_DOFS and not cholmod)):
        return "amg"
    return "cholmod" if dofs and cholmod else direct_backend()


def make_backend(name: str, rest: np.ndarray | None = None):
    """A fresh linear-solver backend by name: one of BACKENDS, or "auto" (auto_backend). rest: the nodes'
    positions (n, d): the multigrid's near-null space, CHOLMOD's node blocks."""
    name = auto_backend(rest) if name == "auto" else name
    if name == "amg":
        require(
            installed("pyamg"),
            "linear solver 'amg' needs pyamg, which is not installed (pip install pyamg; it "
            "has no wheel for Linux aarch64): choose auto, cholmod, taichi, cholespy or scipy",
        )
        return AmgConjugateGradient(rest)
    if name == "cholmod":
        require(
            installed("cvxopt"),
            "linear solver 'cholmod' needs CVXOPT, which is not installed (pip install "
            "'taichi-pneuma[3d]'): choose auto, amg, taichi, cholespy or scipy",
        )
        return CholmodCholesky(1 if rest is None else rest.shape[1])
    return BACKENDS[name]()


def direct_backend() -> str:
    """The direct backend of a 2D model, or where CHOLMOD is not installed: Taichi's LLT when Taichi runs on the
    CPU, cholespy on the GPU arches (Taichi's sparse solvers are float32-only on CUDA; the solve stays float64),
    or SciPy's SuperLU where cholespy is not installed (no wheel for Linux aarch64)."""
    return "taichi" if runtime.current_arch() in (None, "cpu") else "cholespy" if installed("cholespy") else "scipy"


def solve_low_rank_updated(
    backend, rhs: np.ndarray, low_rank: list[tuple[np.ndarray, np.ndarray, float]], rtol: float | None = None
):
    """Solve (S + sum_j c_j u_j u_j^T) d = rhs with S factorised in `backend` (the iterative one: set up), to the
    relative residual rtol where the backend is iterative (a direct one solves exactly)."""
    if isinstance(backend, AmgConjugateGradient):
        return backend.solve(rhs, low_rank, rtol)
    if not low_rank:
        return backend.solve(rhs)
    U = np.zeros((len(rhs), len(low_rank)))
    for j, (dofs, u, _) in enumerate(low_rank):
        U[dofs, j] = u
    solved = backend.solve(np.column_stack([rhs, U]))  # one pass over the factor for all right-hand sides
    y, Z = solved[:, : -len(low_rank)].reshape(rhs.shape), solved[:, -len(low_rank) :]
    capacitance = np.diag([1.0 / c for _, _, c in low_rank]) + U.T @ Z
    return y - Z @ np.linalg.solve(capacitance, U.T @ y)
