"""Energy-Conserving Sampling and Weighting (ECSW; Farhat, Avery, Chapman, Cortial 2014) of the elastic term.

The projected elastic force is a sum over the elements, V^T f(u) = sum_e V_e^T f_e(u) (V_e: the rows of V at
element e's DOFs). ECSW looks for weights w >= 0, most of them zero, with

    sum_e w_e c_se = b_s,   c_se = V_e^T f_e(u_s) / |b_s|,   b_s = sum_e c_se          (every snapshot s),

to a relative tolerance tau: |G w - b| <= tau |b|, G the (S r, m) matrix of the c_se, b its row sums (w = 1 solves
it exactly). Each snapshot's block is scaled by its own force |V^T f(u_s)| so that every snapshot counts alike
(the rest state, with no force, is left out). The greedy active-set method of Lawson and Hanson, stopped at the
tolerance, gives a sparse w: add the element whose column has the largest positive correlation with the residual,
G_e^T (b - G w), solve the non-negative least squares problem on the elements taken (scipy.optimize.nnls), drop
those it gives weight zero, and repeat. The residual decreases strictly, so at most m elements are ever taken. As each
solve starts afresh, the elements are added in batches that grow with the set (the len(taken) / BATCH most correlated
at once): a few more elements than one at a time, at a fraction of the time (pneunet_finger, 36 modes, 83 snapshots:
97 s one at a time).

The per-element forces f_e come from the whole term's own class and kernels, on a mesh whose elements share no node
(Elasticity.restricted, apart): element e's node a is node k e + a of a copy of the nodes, so nothing is summed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import nnls

from ..terms.base import vertex_dofs
from ..terms.elastic import Elasticity

BATCH = 10  # sparse_nnls takes the len(taken) // BATCH most correlated elements at once (at least one)


def element_forces(apart: Elasticity, u: np.ndarray) -> np.ndarray:
    """f_e(u) (m, k d): every element's nodal forces dE_e/dx at displacements u (n, d), its DOFs interleaved, from
    the term restricted to all its elements apart (Elasticity.restricted: nothing summed)."""
    apart.config.u[:] = np.asarray(u).reshape(-1, apart.dim)[apart.vertices]
    m, k = apart.nodes.shape
    return apart.gradient().reshape(m, k * apart.dim)


def element_basis(elastic: Elasticity, basis: np.ndarray) -> np.ndarray:
    """V_e (m, k d, r): the rows of the basis V (n d, r) at each element's DOFs."""
    m, k = elastic.nodes.shape
    return basis[vertex_dofs(elastic.nodes.ravel(), elastic.dim)].reshape(m, k * elastic.dim, basis.shape[1])


def projected_forces(elastic: Elasticity, basis: np.ndarray, displacements: np.ndarray) -> np.ndarray:
    """C (S, r, m): c_se = V_e^T f_e(u_s) for the snapshots displacements (S, n d), unscaled."""
    ve = element_basis(elastic, basis)
    m = len(elastic.nodes)
    apart = elastic.restricted(np.arange(m), np.ones(m), apart=True)
    return np.stack([np.einsum("ekr,ek->re", ve, element_forces(apart, u)) for u in displacements])


@dataclass
class Sampling:
    """The elements taken (ids, ascending) and their weights (> 0); error: |G w - b| / |b| over the snapshots."""

    elements: np.ndarray
    weights: np.ndarray
    error: float


def sparse_nnls(G: np.ndarray, b: np.ndarray, tol: float) -> np.ndarray:
    """w >= 0 with |G w - b| <= tol |b|, few of them non-zero: the greedy active-set method (module docstring);
    stops short of the tolerance only where no element correlates positively with the residual."""
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


def ecsw(elastic: Elasticity, basis: np.ndarray, displacements: np.ndarray, tol: float) -> Sampling:
    """The ECSW sampling (module docstring) of the elastic term for the basis V (n d, r) over the snapshots (S, n d),
    to the relative tolerance tol."""
    C = projected_forces(elastic, basis, displacements)
    totals = C.sum(axis=2)  # (S, r): V^T f(u_s)
    norms = np.linalg.norm(totals, axis=1)
    loaded = norms > 1e-12 * max(float(norms.max()), 1e-300)
    G = (C[loaded] / norms[loaded, None, None]).reshape(-1, C.shape[2])
    b = G.sum(axis=1)
    w = sparse_nnls(G, b, tol)
    elements = np.flatnonzero(w > 0)
    error = float(np.linalg.norm(G @ w - b) / np.linalg.norm(b))
    return Sampling(elements, w[elements], error)
