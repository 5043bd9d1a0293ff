"""Contact of the sides and faces of the body's surface with a rigid obstacle: the obstacle's features (its centre,
axis, corners or edges) against the body's straight surface pieces, so that no piece passes into the obstacle
between its nodes (the nodes against the obstacle's surface: terms/obstacles.py ObstacleContact).

Each convex obstacle O is the set of points within R of a feature set F (Shape.features, terms/obstacle_shapes.py):

    sphere                        F = its centre c, R its radius (2D: a disc)
    capsule                       F = its axis, the segment c -+ h a, R its radius (2D along z: a disc)
    box                           F = its corners and edges, R = 0 (2D: its 4 corners)
    cylinder, 2D                  along z a disc (F = {c}, R); along x or y a rectangle (its 4 corners)

A straight piece P of the surface (a triangle; 2D a segment) that moves from outside O into it first touches O where
a node of P meets O's surface (the node barrier), or where dist(F, P) = R: a feature point against the triangle
(2D: against the segment), or, in 3D, a feature edge against a side of the triangle (for two convex polytopes the
first contact is vertex-face or edge-edge). This term keeps every such pair apart: with d_k the pair's distance
(from its squared distance s_k, IPC Toolkit's point-triangle and edge-edge distances in 3D, this project's
point-segment distance in 2D: terms/contact.py) and g_k = d_k - R,

    E = kappa sum_k b(g_k),

b the log barrier of the node term (threshold dhat, stiffness kappa: terms/contact.py). Its gradient is
b'(g) grad d with grad d = grad s / (2 d); its Hessian b''(g) grad d grad d^T (PSD, always) plus, when exact,
b'(g) (Hess s / (2 d) - grad s grad s^T / (4 d^3)). A pair whose nearest point is a node of P repeats that node's
barrier, so the contact is stiffer there; E stays continuous, and the equilibrium force is the mechanics'.

The pairs change with the state (Term.dynamic): those of the pieces within dhat of the obstacle, by the least
signed distance m over each piece (obstacle_distance.obstacle_reach; no pair of a farther piece is nearer than m).
max_step(dx): conservative advancement of each piece that could reach the obstacle in the step (m below its fastest
node's motion v): t += m(t) / v (m falls no faster than v), stopped at 1e-3 of its starting m, so short of the
contact, as ObstacleContact.max_step is.

A plane needs no such term (a piece's nearest point to a plane is a node), and a 3D cylinder has none yet: its
rims and flat caps are not a feature set within one R. Its contact holds the nodes only, and the overlap check
(ObstacleContact.overlap) refuses a state in which a piece enters it.
"""

import math

import numpy as np

from ..backend import kernel, ti
from .base import Scalars, Table, Term, Triples, Vec2s, block_pattern, int32s
from .contact import barrier, squared_distance
from .obstacle_distance import obstacle_reach

ADVANCES = 100  # 2D conservative advancement: at most this many advances


@kernel
def point_segment_pairs(rest: Vec2s, u: Vec2s, pairs: Triples, s: Scalars, g: Table, H: Table):
    """s[q], g[q] (6), H[q] (36, row-major) of 2D pair q = (p, a, b): the squared distance of point p from segment ab
    and its derivatives over (p, a, b) (contact.squared_distance)."""
    for q in range(pairs.shape[0]):
        sq, gq, Hq = squared_distance(rest, u, pairs, q)
        s[q] = sq
        for i in ti.static(range(6)):
            g[q, i] = gq[i]
            for j in ti.static(range(6)):
                H[q, 6 * i + j] = Hq[i, j]


@kernel
def barriers(d: Scalars, dhat: ti.f64, kappa: ti.f64, out: Table):
    """out[k] = (b, b', b'') of the log barrier at d[k] > 0 (contact.barrier)."""
    for k in range(d.shape[0]):
        b, db, ddb = barrier(d[k], dhat, kappa)
        out[k, 0], out[k, 1], out[k, 2] = b, db, ddb


def ipctk_or_none():
    """The ipctk module, or None where it is not installed (Linux aarch64, or without the [3d] extra)."""
    try:
        import ipctk
    except ImportError:  # pragma: no cover - the [3d] extra installs it where it has wheels
        return None
    return ipctk


class ObstacleEdges(Term):
    """Barriers between an obstacle's features and the pieces of the body's surface (module docstring), the
    obstacle being the ObstacleContact `contact` (its shape, offset, dhat and kappa); named '<obstacle>.edges'."""

    reports_contact = True
    dynamic = True

    def __init__(self, contact, pieces: np.ndarray, ipctk=None):
        """pieces: the body's surface as straight pieces (surface_pieces: triangles; 2D segments as (a, b, b));
        ipctk: the module, for a 3D body."""
        self.contact, self.config = contact, contact.config
        self.name = f"{contact.name}.edges"
        self.dim = contact.config.dim
        self.ipctk = ipctk
        self.pieces = int32s(pieces)
        self._key: tuple | None = None
        self._state: list = []
        self._derived: tuple | None = None  # _barriers(True) at the state of _key
        self._rows = self._cols = np.zeros(0, dtype=np.int64)

    @staticmethod
    def needed(shape, dim: int) -> bool:
        """Whether an obstacle of the shape has features to keep the pieces from (module docstring)."""
        return len(shape.features(np.zeros(3), dim)[0]) > 0

    @property
    def reported_as(self) -> str:
        """The obstacle's name: the history's contact force on it is its nodes' and its edges' together."""
        return self.contact.name

    def feature_set(self) -> tuple[np.ndarray, np.ndarray, float]:
        """The obstacle's feature set where it is now (Shape.features at its moved position)."""
        return self.contact.shape.features(self.contact.parameters[:3], self.dim)

    def reach(self, corners: np.ndarray) -> np.ndarray:
        """The least signed distance of the obstacle over each piece given by its corners (k, 3, d)
        (obstacle_distance.obstacle_reach)."""
        k = len(corners)
        out = np.empty((k, 4))
        if k:
            where = np.ascontiguousarray(corners.reshape(-1, self.dim))
            facets = int32s(np.arange(3 * k).reshape(k, 3))
            obstacle_reach(where, np.zeros_like(where), facets, self.contact.kind, self.contact.parameters, out)
        return out[:, 0]

    def _pairs(self) -> list:
        """At the current state (computed once per state and obstacle position), per kind of pair: (its body nodes
        (k, 3 or 2), its feature's points (k, j, d), squared distances s (k,)) over the pieces within dhat of the
        obstacle (reach: no pair of a farther piece is nearer)."""
        u, p = self.config.u, self.contact.parameters
        if self._key is not None and np.array_equal(self._key[0], u) and np.array_equal(self._key[1], p):
            return self._state
        x = self.config.rest + u
        near = self.pieces[self.reach(x[self.pieces]) < self.contact.dhat]
        points, edges, _ = self.feature_set()
        groups = []
        if self.dim == 2:
            segments = np.unique(np.sort(near[:, :2], axis=1), axis=0)
            i, j = np.divmod(np.arange(len(points) * len(segments)), len(segments))
            nodes, held = segments[j], points[i][:, None]
            groups.append((nodes, held, self._point_segment(x, held[:, 0], nodes)[0]))
        else:
            sides = np.unique(np.sort(np.vstack([near[:, [0, 1]], near[:, [1, 2]], near[:, [2, 0]]]), axis=1), axis=0)
            for bodies, held in ((near, points[:, None]), (sides, edges)):
                i, j = np.divmod(np.arange(len(held) * len(bodies)), len(bodies))
                nodes, held = bodies[j].astype(np.int64), held[i]
                which = "point_triangle" if nodes.shape[1] == 3 else "edge_edge"
                distance = getattr(self.ipctk, f"{which}_distance")
                s = np.array([distance(*f, *x[n]) for f, n in zip(held, nodes)])
                groups.append((nodes, held, s))
        self._key, self._state, self._derived = (u.copy(), p.copy()), groups, None
        return groups

    def _point_segment(self, x: np.ndarray, points: np.ndarray, nodes: np.ndarray):
        """(s, grad s (k, 4), Hess s (k, 4, 4)) over the segments' two nodes, by contact.squared_distance with the
        feature points appended to the positions."""
        k = len(points)
        if k == 0:
            return np.zeros(0), np.zeros((0, 4)), np.zeros((0, 4, 4))
        n = len(x)
        where = np.ascontiguousarray(np.vstack([x, points]))
        pairs = int32s(np.column_stack([n + np.arange(k), nodes]))
        s, g, H = np.empty(k), np.empty((k, 6)), np.empty((k, 36))
        point_segment_pairs(where, np.zeros_like(where), pairs, s, g, H)
        return s, g[:, 2:], H.reshape(k, 6, 6)[:, 2:, 2:]

    def _derivatives(self, nodes: np.ndarray, held: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(grad s, Hess s) over the body's nodes of the pairs (nodes, feature points held)."""
        x = self.config.rest + self.config.u
        if self.dim == 2:
            return self._point_segment(x, held[:, 0], nodes)[1:]
        width = 3 * nodes.shape[1]
        which = "point_triangle" if nodes.shape[1] == 3 else "edge_edge"
        gradient = getattr(self.ipctk, f"{which}_distance_gradient")
        hessian = getattr(self.ipctk, f"{which}_distance_hessian")
        skip = 3 * held.shape[1]  # the feature's coordinates come first
        g, H = np.zeros((len(nodes), width)), np.zeros((len(nodes), width, width))
        for q, (f, n) in enumerate(zip(held, nodes)):
            g[q] = gradient(*f, *x[n])[skip:]
            H[q] = hessian(*f, *x[n])[skip:, skip:]
        return g, H

    def _barriers(self, derivatives: bool) -> tuple[list, float]:
        """(per kind of pair (nodes, d, b, b', b'', grad s, Hess s) of its pairs within dhat (no derivatives
        unless asked), the least g = d - R over all); with derivatives, computed once per state (the gradient and
        the Hessian share them)."""
        groups = self._pairs()
        if derivatives and self._derived is not None:
            return self._derived
        radius, dhat, kappa = self.feature_set()[2], self.contact.dhat, self.contact.kappa
        out, least = [], math.inf
        for nodes, held, s in groups:
            d = np.sqrt(np.maximum(s, 0.0))
            gap = d - radius
            least = min(least, float(gap.min(initial=math.inf)))
            active = gap < dhat
            values = np.zeros((int(active.sum()), 3))
            barriers(np.ascontiguousarray(np.maximum(gap[active], 1e-300)), dhat, kappa, values)
            parts = self._derivatives(nodes[active], held[active]) if derivatives else (None, None)
            out.append((nodes[active], d[active], *values.T, *parts))
        if derivatives:
            self._derived = (out, least)
        return out, least

    def min_gap(self) -> float:
        """The least g = d - R over the pairs within dhat (inf: none)."""
        return self._barriers(False)[1]

    def energy(self) -> float:
        groups, least = self._barriers(False)
        if not least > 0:
            return math.inf
        return float(sum(b.sum() for _, _, b, *_ in groups))

    def gradient(self) -> np.ndarray:
        gradient = np.zeros_like(self.config.u)
        groups, least = self._barriers(True)
        if not least > 0:  # a piece inside the obstacle: no finite force (fault() says why)
            return gradient + np.nan
        for nodes, d, _, db, _, g, _ in groups:
            forces = (db / (2.0 * d))[:, None] * g
            np.add.at(gradient, nodes, forces.reshape(*nodes.shape, self.dim))
        return gradient

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        rows, cols, values = [], [], []
        for nodes, d, _, db, ddb, g, H in self._barriers(True)[0]:
            grad_d = g / (2.0 * d)[:, None]
            blocks = ddb[:, None, None] * grad_d[:, :, None] * grad_d[:, None, :]
            if not psd_only:
                curvature = H / (2.0 * d)[:, None, None] - g[:, :, None] * g[:, None, :] / (4.0 * d**3)[:, None, None]
                blocks += db[:, None, None] * curvature
            r, c = block_pattern(nodes, self.dim)
            rows.append(r)
            cols.append(c)
            values.append(blocks.ravel())
        self._rows = np.concatenate([np.zeros(0, dtype=np.int64), *rows])
        self._cols = np.concatenate([np.zeros(0, dtype=np.int64), *cols])
        return np.concatenate([np.zeros(0), *values])

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._rows, self._cols

    def max_step(self, dx: np.ndarray) -> float:
        """The least t in [0, 1] at which a piece moving along dx reaches the obstacle, by conservative advancement
        of each piece that could (its least distance m below its fastest node's motion): t += m(t) / v, v that
        node's speed (m falls no faster), stopped at 1e-3 of its starting m (inf: none by t = 1)."""
        x = self.config.rest + self.config.u
        corners, moves = x[self.pieces], dx[self.pieces]
        speed = np.max(np.linalg.norm(moves, axis=2), axis=1)
        start = self.reach(corners)
        could = (speed > 0) & (start < speed)
        corners, moves, speed, start = corners[could], moves[could], speed[could], start[could]
        t, gap = np.zeros(len(start)), start.copy()
        for _ in range(ADVANCES):
            going = (gap > 1e-3 * start) & (t <= 1.0)
            if not going.any():
                break
            t[going] += gap[going] / speed[going]
            gap[going] = self.reach(corners[going] + t[going, None, None] * moves[going])
        reached = t <= 1.0
        return float(t[reached].min()) if reached.any() else math.inf

    def fault(self) -> str | None:
        if self.min_gap() > 0:
            return None
        return (
            f"a side or face of the body's surface touches {self.contact.name!r}{self.contact.moved} "
            f"(its edge barrier is infinite there)"
        )
