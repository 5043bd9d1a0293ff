"""Supports and named node sets: the clamp and the tip (PointSet), the rollers (Roller), the nodes each selects on a
mesh, and the rigid-body motions the supports leave free.

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

from dataclasses import dataclass

import numpy as np

from ..errors import require, require_finite, shape_of

AXES = "xyz"
SIDES = ("left", "right", "bottom", "top", "back", "front")  # pairs along x, y, z
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
    require(
        not free,
        f"the supports ({supports}) leave free: {', '.join(free)}; a static body needs a [clamp] "
        f"(side or box) or [[rollers]] that hold every rigid motion",
    )


@dataclass(frozen=True)
class PointSet:
    """Named mesh nodes (the clamp, the tip): a side of the body's bounding box (within 1e-6; back and front
    are the sides normal to z, in 3D) or those in a closed box [x0, y0, x1, y1] ([x0, y0, z0, x1, y1, z1] in 3D)."""

    side: str | None = None
    box: tuple | None = None

    def __post_init__(self):
        require((self.side is None) != (self.box is None), "give exactly one of 'side' and 'box'")
        if self.side is not None:
            require(self.side in SIDES, f"side = {self.side!r} is not one of {', '.join(SIDES)}")
        else:
            require_box("box", self.box)

    def select(self, vertices: np.ndarray, what: str) -> np.ndarray:
        """The indices of the chosen vertices; choosing none is a PneumaInputError naming `what` (e.g. 'tip')."""
        if self.side is not None:
            axis = SIDES.index(self.side) // 2
            require(axis < vertices.shape[1], f"{what}.side = {self.side!r} needs a 3D body")
            x = vertices[:, axis]
            chosen = x <= x.min() + 1e-6 if SIDES.index(self.side) % 2 == 0 else x >= x.max() - 1e-6
        else:
            chosen = in_box(vertices, self.box, what)
        nodes = np.flatnonzero(chosen)
        require(len(nodes) > 0, f"{what}.box = {self.box!r} selects no mesh vertex")
        return nodes


def clamped(clamp: PointSet | None, vertices: np.ndarray) -> np.ndarray:
    """The clamped vertices: those clamp selects, none when there is no clamp (None: a body held otherwise,
    e.g. by rollers on its symmetry planes)."""
    return np.zeros(0, dtype=np.int64) if clamp is None else clamp.select(vertices, "clamp")


def node_sets(clamp: PointSet | None, tip: PointSet, rollers, vertices: np.ndarray) -> tuple:
    """(pinned, tip, rollers) on a mesh of these vertices: the clamped nodes, the tip's nodes and per roller (its
    held nodes, its unit normal); a set that selects no vertex is a PneumaInputError naming it."""
    return (
        clamped(clamp, vertices),
        tip.select(vertices, "tip"),
        tuple((roller.select(vertices), roller.unit_normal) for roller in rollers),
    )


@dataclass(frozen=True)
class Roller:
    """A roller support: nodes whose displacement along `normal` is held, their tangential motion free.

    The nodes are those within `tolerance` of the line (the plane, in 3D) n . (X - point) = 0, or those in
    the closed box [x0, y0, x1, y1] ([x0, y0, z0, x1, y1, z1]). A roller line along an edge of the body is a
    symmetry line: a chamber may be cut by it (see Geometry), which is how half and quarter models of symmetric
    actuators are built; in 3D a roller plane holding a chamber's open rim closes that chamber (tetmesh.py)."""

    normal: tuple
    point: tuple | None = None
    box: tuple | None = None
    tolerance: float = 1e-6

    def __post_init__(self):
        normal = vector("normal", self.normal)
        require(any(normal), f"normal = {list(self.normal)!r} must not be zero")
        require(
            (self.point is None) != (self.box is None),
            "give exactly one of 'point' (the roller line through it) and 'box'",
        )
        if self.point is not None:
            require(
                len(vector("point", self.point)) == len(normal),
                f"point = {list(self.point)!r} must have as many components as normal = {list(self.normal)!r}",
            )
        else:
            require_box("box", self.box)
        require(require_finite("tolerance", self.tolerance) > 0, f"tolerance = {self.tolerance!r} must be > 0")

    @property
    def unit_normal(self) -> np.ndarray:
        n = np.asarray(self.normal, dtype=np.float64)
        return n / np.linalg.norm(n)

    def select(self, vertices: np.ndarray) -> np.ndarray:
        """The indices of the held vertices; holding none is a PneumaInputError."""
        if self.point is not None:
            where = f"point = {list(self.point)!r}"
        else:
            assert self.box is not None  # __post_init__: exactly one of point and box
            where = f"box = {list(self.box)!r}"
        what = f"roller (normal = {list(self.normal)!r}, {where})"
        require(
            len(self.normal) == vertices.shape[1],
            f"{what}: its normal must have {vertices.shape[1]} components on this {vertices.shape[1]}D body",
        )
        if self.point is not None:
            chosen = np.abs((vertices - np.asarray(self.point, dtype=np.float64)) @ self.unit_normal) <= self.tolerance
        else:
            chosen = in_box(vertices, self.box, what)
        nodes = np.flatnonzero(chosen)
        if self.point is not None and not len(nodes):
            side = (vertices - np.asarray(self.point, dtype=np.float64)) @ self.unit_normal
            require(
                not (side.min() < 0 < side.max()),
                f"{what} holds no mesh vertex: its plane cuts through the body, where the mesher puts nodes only by "
                f"chance (a 3D body from shapes is meshed with nodes on every roller plane, a mesh file's or a 2D "
                f"body's is not); model the part on one side of it, with the roller on the cut face (a half model: "
                f"docs/3d.md), or put the roller on a face of the body",
            )
        require(len(nodes) > 0, f"{what} holds no mesh vertex")
        return nodes


def vector(name: str, value) -> tuple[float, ...]:
    """A point or direction of 2 or 3 finite numbers (PneumaInputError naming it otherwise)."""
    require(shape_of(value) in ((2,), (3,)), f"{name} = {value!r} must be a list of 2 (2D) or 3 (3D) numbers")
    return tuple(require_finite(name, v) for v in value)


def require_box(name: str, box) -> None:
    """Refuse, naming it, a box that is not [x0, y0, x1, y1] (2D) or [x0, y0, z0, x1, y1, z1] (3D) of finite
    numbers with each lower bound below its upper one."""
    require(
        shape_of(box) in ((4,), (6,)), f"{name} = {box!r} must be [x0, y0, x1, y1] (or [x0, y0, z0, x1, y1, z1] in 3D)"
    )
    for v in box:
        require_finite(name, v)
    half = len(box) // 2
    require(
        all(box[i] < box[half + i] for i in range(half)),
        f"{name} = {list(box)!r} must have x0 < x1 and y0 < y1" + (" and z0 < z1" if half == 3 else ""),
    )


def in_box(points: np.ndarray, box, what: str = "box") -> np.ndarray:
    """Which points (k, d) lie in the closed box [x0, y0, (z0,) x1, y1, (z1)] of 2 d numbers."""
    d = points.shape[1]
    require(len(box) == 2 * d, f"{what}: box = {list(box)!r} must have {2 * d} numbers on this {d}D body")
    lower, upper = np.asarray(box[:d], dtype=np.float64), np.asarray(box[d:], dtype=np.float64)
    return np.all((points >= lower) & (points <= upper), axis=1)
