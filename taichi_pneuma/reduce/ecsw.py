"""Energy-Conserving Sampling and Weighting (ECSW; Farhat, Avery, Chapman, Cortial 2014) of each piecewise term.

A piecewise term's energy is a sum over pieces (terms/base.py Term.piecewise: the elastic term's elements, a fibre's
segments, a sheet's cells), so its projected force is too, V^T f(u) = sum_e V_e^T f_e(u) (V_e: the rows of V at
piece e's DOFs). ECSW looks for weights w >= 0, most of them zero, with

    sum_e w_e c_se = b_s,   c_se = V_e^T f_e(u_s) / |b_s|,   b_s = sum_e c_se          (every snapshot s),

to a relative tolerance tau: |G w - b| <= tau |b|, G the (S r, m) matrix of the c_se, b its row sums (w = 1 solves
it exactly). Each snapshot's block is scaled by its own force |V^T f(u_s)| so that every snapshot counts alike
(a state where the term has no force, as the rest state, is left out: its projected force at most 1e-12 of the
largest of any term's, round-off; a term with no force in any snapshot, a sheet that never stretches, gets no
pieces). The greedy active-set method of Lawson and Hanson, stopped at the
tolerance, gives a sparse w: add the piece whose column has the largest positive correlation with the residual,
G_e^T (b - G w), solve the non-negative least squares problem on the pieces taken (scipy.optimize.nnls), drop
those it gives weight zero, and repeat. The residual decreases strictly, so at most m pieces are ever taken. As each
solve starts afresh, the pieces are added in batches that grow with the set (the len(taken) / BATCH most correlated
at once): a few more pieces than one at a time, at a fraction of the time (pneunet_finger, 36 modes, 83 snapshots:
97 s one at a time). Every piecewise term is sampled apart, with its own fit.

The per-piece forces f_e come from the whole term's own class and kernels, on nodes that no two pieces share
(Term.restricted, apart): piece e's node a is node k e + a of a copy of the nodes, so nothing is summed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import nnls

from ..terms.base import Term, vertex_dofs

BATCH = 10  # sparse_nnls takes the len(taken) // BATCH most correlated pieces at once (at least one)


def piecewise_terms(terms: list[Term]) -> dict[str, Term]:
    """The piecewise terms (Term.piecewise) by label: the term's name, the second and later of a name numbered
    (fibers, fibers_2, ...)."""
    labels: dict[str, Term] = {}
    for term in (t for t in terms if t.piecewise):
        count = sum(1 for other in labels.values() if other.name == term.name)
        labels[term.name if count == 0 else f"{term.name}_{count + 1}"] = term
    return labels


def piece_basis(term: Term, basis: np.ndarray) -> np.ndarray:
    """V_e (m, k d, r): the rows of the basis V at each piece's DOFs (term.piece_nodes()); term on V's nodes or on
    its own configuration with V the rows at its vertices."""
    nodes = term.piece_nodes()
    m, k = nodes.shape
    d = term.config.dim
    return basis[vertex_dofs(nodes.ravel(), d)].reshape(m, k * d, basis.shape[1])


def piece_forces(apart: Term, u: np.ndarray) -> np.ndarray:
    """f_e(u) (m, k d): every piece's nodal forces dE_e/dx at displacements u (n, d), its DOFs interleaved, from
    the term restricted to all its pieces apart (Term.restricted: nothing summed)."""
    d = apart.config.dim
    apart.config.u[:] = np.asarray(u).reshape(-1, d)[apart.vertices]
    return apart.gradient().reshape(apart.n_pieces, -1)


def projected_forces(term: Term, basis: np.ndarray, displacements: np.ndarray) -> np.ndarray:
    """C (S, r, m): c_se = V_e^T f_e(u_s) for the snapshots displacements (S, n d), unscaled."""
    ve = piece_basis(term, basis)
    m = term.n_pieces
    apart = term.restricted(np.arange(m), np.ones(m), apart=True)
    return np.stack([np.einsum("ekr,ek->re", ve, piece_forces(apart, u)) for u in displacements])


@dataclass
class Sampling:
    """The pieces taken (ids, ascending) and their weights (> 0); error: |G w - b| / |b| over the snapshots (0 for
    a term with no force in any of them)."""

    pieces: np.ndarray
    weights: np.ndarray
    error: float


def sparse_nnls(G: np.ndarray, b: np.ndarray, tol: float) -> np.ndarray:
    """w >= 0 with |G w - b| <= tol |b|, few of them non-zero: the greedy active-set method (module docstring);
    stops short of the tolerance only where no piece correlates positively with the residual."""
    w = np.zeros(G.shape[1])
    taken: list[int] = []
    residual = b.copy()
    target = tol * np.linalg.norm(b)
    while np.linalg.norm(residual) > target and len(taken) < G.shape[1]:
        correlation = G.T @ residual
        correlation[taken] = -np.inf
        best = np.argsort(correlation)[::-1][: max(1, len(taken) // BATCH)]
        best = best[correlation[best] > 0]
        if not len(best):
            break
        taken += best.tolist()
        values, _ = nnls(G[:, taken], b)
        w[:] = 0.0
        w[taken] = values
        taken = [e for e in taken if w[e] > 0]
        residual = b - G[:, taken] @ w[taken]
    return w


def fit(C: np.ndarray, tol: float, floor: float = 0.0) -> Sampling:
    """The ECSW sampling (module docstring) of projected piece forces C (S, r, m) to the relative tolerance tol; a
    snapshot whose projected force |V^T f(u_s)| is at most `floor` (or 1e-12 of the largest) has none."""
    norms = np.linalg.norm(C.sum(axis=2), axis=1)  # |V^T f(u_s)|
    loaded = norms > max(floor, 1e-12 * norms.max(initial=0.0))
    if not loaded.any():
        return Sampling(np.zeros(0, dtype=np.int64), np.zeros(0), 0.0)
    G = (C[loaded] / norms[loaded, None, None]).reshape(-1, C.shape[2])
    b = G.sum(axis=1)
    w = sparse_nnls(G, b, tol)
    pieces = np.flatnonzero(w > 0)
    error = float(np.linalg.norm(G @ w - b) / np.linalg.norm(b))
    return Sampling(pieces, w[pieces], error)


def sample_terms(terms: list[Term], basis: np.ndarray, displacements: np.ndarray, tol: float) -> dict[str, Sampling]:
    """The ECSW sampling of every piecewise term of `terms`, by label (piecewise_terms). A term's projected force
    in a snapshot counts as none (round-off) at or below 1e-12 of the largest of any term's in any snapshot."""
    forces = {label: projected_forces(t, basis, displacements) for label, t in piecewise_terms(terms).items()}
    largest = max((float(np.linalg.norm(C.sum(axis=2), axis=1).max(initial=0.0)) for C in forces.values()), default=0.0)
    return {label: fit(C, tol, 1e-12 * largest) for label, C in forces.items()}
