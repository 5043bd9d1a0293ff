"""Proper orthogonal decomposition: the basis V (N, r) of the leading left singular vectors of the snapshot
matrix S = [u_1 ... u_S] (N, S), all DOFs (the clamp is a penalty term, so its DOFs are free ones).

    S = U Sigma W^T,   V = U[:, :r],   kept energy  sum_{i<r} sigma_i^2 / sum_i sigma_i^2;

r is given, or the smallest r whose kept energy reaches the fraction asked for. V^T V = I, and V V^T u_s is the
best rank-r approximation of the snapshots in the Euclidean norm.
"""

from __future__ import annotations

import numpy as np

from ..errors import require


def pod_basis(
    displacements: np.ndarray, modes: int | None = None, energy: float | None = None
) -> tuple[np.ndarray, np.ndarray, float]:
    """(V (N, r), the singular values (all), the kept energy fraction) of the snapshots displacements (S, N): r =
    modes, or the fewest modes keeping `energy` of sum sigma^2 (one of the two, never both)."""
    require((modes is None) != (energy is None), "give either a number of modes or an energy fraction, not both")
    u, sigma, _ = np.linalg.svd(np.asarray(displacements, dtype=np.float64).T, full_matrices=False)
    cumulative = np.cumsum(sigma**2) / np.sum(sigma**2)
    nonzero = int(np.sum(sigma > sigma[0] * 1e-13))
    if energy is not None:
        require(0 < energy < 1, f"--energy = {energy!r} must lie in (0, 1)")
        count = min(int(np.searchsorted(cumulative, float(energy))) + 1, nonzero)
    elif modes is not None:
        count = modes
    require(
        1 <= count <= nonzero,
        f"--modes = {count!r} must lie in [1, {nonzero}]: the snapshots span {nonzero} independent displacements",
    )
    return np.ascontiguousarray(u[:, :count]), sigma, float(cumulative[count - 1])
