"""A branch sweep's Hessian as a low-rank update of the factorisation held (solve/newton.py's branch sweeps).

A sweep re-solves the Newton direction at the same u with the kinked terms' pieces on other branches: only the
Hessian blocks of the pieces that changed branch differ from those of the factorised matrix S (a tension-only cord
segment going taut adds c c^T (x) (k n n^T + k (l - L0) / l (I - n n^T)), rank <= d, over its 2 (d + 1) nodes; one
going slack removes it). Their difference D = H_new - S is symmetric and nonzero only on the few DOFs T those
pieces touch, so its eigendecomposition there,

    D = sum_j lambda_j v_j v_j^T    (v_j over T, |lambda_j| > EIGEN_CUTOFF max |lambda|),

gives H_new = S + V Lambda V^T, which the Woodbury identity (linsolve.solve_low_rank_updated) solves with the held
factor: one extra right-hand side per rank instead of a new factorisation. That pays only while the rank is small
(a solve with the quadratic bending actuator's factor costs about 6 ms a right-hand side, its factorisation with
assembly about 125 ms): past max_rank the sweep factorises H_new instead. The direction is the same as the one
solved with the new factorisation, to round-off.
"""

from __future__ import annotations

import numpy as np

EIGEN_CUTOFF = 1e-12  # eigenvalues of D below this fraction of its largest are round-off of a zero block


def branch_update(
    patterns: list[tuple[np.ndarray, np.ndarray] | None],
    base: list[np.ndarray],
    values: list[np.ndarray],
    max_rank: int,
) -> list[tuple[np.ndarray, np.ndarray, float]] | None:
    """The rank-1 parts (dofs, v, lambda) of D = H(values) - H(base), the terms' Hessian parts in the model's pattern
    order, over the parts whose pattern (rows, cols) is given (the kinked terms'; None: a part that is the same in
    both); None where its rank exceeds max_rank."""
    rows, cols, deltas = [], [], []
    for pattern, old, new in zip(patterns, base, values, strict=True):
        if pattern is None or new is old:
            continue
        changed = np.flatnonzero(new != old)
        rows.append(pattern[0][changed])
        cols.append(pattern[1][changed])
        deltas.append(new[changed] - old[changed])
    if not deltas or not sum(len(delta) for delta in deltas):
        return []
    row, col, delta = np.concatenate(rows), np.concatenate(cols), np.concatenate(deltas)
    dofs, index = np.unique(np.concatenate([row, col]), return_inverse=True)
    if len(dofs) > 8 * max_rank:  # more DOFs than a block of max_rank pieces spans: refactorise without looking
        return None
    dense = np.zeros((len(dofs), len(dofs)))
    np.add.at(dense, (index[: len(row)], index[len(row) :]), delta)
    eigenvalues, vectors = np.linalg.eigh(0.5 * (dense + dense.T))
    kept = np.flatnonzero(np.abs(eigenvalues) > EIGEN_CUTOFF * np.abs(eigenvalues).max())
    if len(kept) > max_rank:
        return None
    return [(dofs, vectors[:, j], float(eigenvalues[j])) for j in kept]
