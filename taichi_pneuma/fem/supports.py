"""The rigid-body motions a body's supports leave free.

A support holds components of nodal displacements: rows (nodes, P), P a d x d symmetric projector (the clamp:
P = I; a roller of unit normal n: P = n n^T). The rigid motions of the body are u(X) = t + w x (X - c): d
translations t and the rotations w (2D: about z; 3D: about x, y and z), c the centroid of the vertices,
lengths measured in the body's size L. With R(X) the d x m matrix of these m = 3 (2D) or 6 (3D) modes at X,
the supports hold the energy 1/2 K a^T G a of a rigid motion of amplitudes a, with

    G = sum over rows, over their nodes i of  R(X_i)^T P R(X_i)     (m x m, symmetric positive semi-definite),

and leave free exactly its null space (eigenvalues below 1e-9 of the largest: G gains at least 1 per held
node of a held motion, and a rotation held by nodes a distance h apart about h^2 / L^2 of that). The free space
is named by its parts: the axes of the rotations in it (a free rotation about an axis off c carries a
translation along, which is not named again), and the translations free alone.
"""

from __future__ import annotations

import numpy as np

from ..errors import require

AXES = "xyz"
FREE = 1e-9  # an eigenvalue of G below this fraction of the largest: a free motion


def rigid_modes(vertices: np.ndarray) -> np.ndarray:
    """(n, d, m): the m rigid modes at each vertex, translations along the axes, then rotations about the
    axes (2D: z) through the centroid, of unit displacement at distance L (the body's size) from it."""
    n, d = vertices.shape
    x = (vertices - vertices.mean(axis=0)) / max(float(np.ptp(vertices, axis=0).max()), np.finfo(float).tiny)
    x3 = np.column_stack([x, np.zeros(n)]) if d == 2 else x
    rotations = [np.cross(np.eye(3)[a], x3)[:, :d] for a in ((2,) if d == 2 else (0, 1, 2))]
    return np.stack([np.broadcast_to(np.eye(d)[a], (n, d)) for a in range(d)] + rotations, axis=2)


def free_motions(vertices: np.ndarray, rows) -> list[str]:
    """The rigid motions the rows (nodes, P) leave free (module docstring), named: "translation along x",
    "rotation about z", or along (about) a direction [a, b, c] off the axes; [] when they hold every one."""
    d = vertices.shape[1]
    modes = rigid_modes(vertices)
    gram = np.zeros((modes.shape[2],) * 2)
    for nodes, projector in rows:
        at = modes[np.asarray(nodes, dtype=np.int64)]
        gram += np.einsum("kdm,de,ken->mn", at, np.asarray(projector, dtype=np.float64), at)
    values, vectors = np.linalg.eigh(gram)
    free = vectors[:, values <= FREE * max(values.max(), 0.0)]
    if free.shape[1] == 0:
        return []
    rotation = free[d:]
    u, s, vt = np.linalg.svd(rotation)
    rank = int(np.sum(s > 1e-6))
    translations = free[:d] @ vt[rank:].T  # the free motions without rotation
    rotation_axes = u[:, :rank]
    names = [f"translation along {name}" for name in directions(translations, AXES[:d])]
    return names + [f"rotation about {name}" for name in directions(rotation_axes, AXES[:3] if d == 3 else "z")]


def directions(basis: np.ndarray, axes: str) -> list[str]:
    """Names of the directions spanned by the columns of basis (k of them, independent): the axes themselves
    where the span is one of axes' coordinate subspaces, else a vector [a, b, c] per direction."""
    if basis.shape[1] == 0:
        return []
    q = np.linalg.qr(basis)[0]
    projector = q @ q.T
    if np.allclose(projector, np.diag(np.round(np.diag(projector))), atol=1e-6):
        return [axes[i] for i in np.flatnonzero(np.round(np.diag(projector)))]
    unit = q * np.sign(q[np.argmax(np.abs(q), axis=0), np.arange(q.shape[1])])  # largest component positive
    return [f"[{', '.join(f'{c:.3g}' for c in v)}]" for v in unit.T]


def require_held(vertices: np.ndarray, rows, supports: str) -> None:
    """Refuse (PneumaInputError naming them) supports, described by the text `supports`, that leave a rigid
    motion free."""
    free = free_motions(vertices, rows)
    require(not free, f"the supports ({supports}) leave free: {', '.join(free)}; a static body needs a [clamp] "
                      f"(side or box) or [[rollers]] that hold every rigid motion")
