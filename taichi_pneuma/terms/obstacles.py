"""Rigid obstacles: contact of the body's outer boundary nodes with a shape given by its signed distance (with
friction > 0, Coulomb friction too: terms/friction.py).

Each shape is a signed distance d(x) (terms/obstacle_distance.py), 1-Lipschitz. The energy is that of the ground
(terms/contact.py): E = sum_i b(d_i) over the boundary nodes, the log barrier b of threshold dhat and stiffness
kappa; gradient b'(d_i) n_i (n = grad d, the unit normal); Hessian per node b''(d) n n^T (PSD, always) plus, when
not psd_only, b'(d) Hess d. Hess d is exact wherever the closest feature of the shape is

    a plane (a face, a cap, the plane itself)      0
    a point (a box corner, a sphere's or an end's centre)     (I - n n^T) / r
    a line (a box edge, the axis of a side)        (I - a a^T - n n^T) / r
    a circle (the rim of a cylinder, radius R)     (I - n n^T - (R / rho) b b^T) / r

with r the distance to the feature, a the line's direction, b the circle's tangent and rho the distance to the
axis; all four are implemented, as one formula (I - n n^T - s t t^T) / r (s = 0, 1, R / rho).

max_step(dx): for each node, the largest alpha at which x + alpha dx has not crossed the surface, by conservative
advancement (t += d(x + t dx) / |dx|, never past the first contact since d is 1-Lipschitz), stopped when d falls
below 1e-3 of its start (a bound just short of the contact) or t passes STEP_CAP (then inf: the solver never steps
past 1); exact, d / -(dx . n), for a shape whose d is affine in x (Shape.linear: the plane).

The shape's kind is a runtime integer and its parameters a small float array (PARAMETERS), so the kernels compile
once whatever the scene. A moving obstacle's translation from its placed position is set by set_offset.

overlap(): the barrier holds the nodes only, so whether the obstacle overlaps the body is checked geometrically:
the least d over every straight piece of the body's surface (obstacle_distance.obstacle_reach), and whether the
obstacle's centre lies inside the body (fem/self_intersection.py winding). A run checks it at every
equilibrium and sweeps a moving obstacle's motion in sub-steps of at most its sweep (BuiltScene.sweeps,
solve/simulate.py settle); Obstacle.terms refuses a rest scene that overlaps (docs/theory/contact.md).
"""

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..backend import kernel, ti
from ..errors import require, require_finite, shape_of
from ..fem.self_intersection import surface_pieces, winding
from ..io.output import MAX_NAME, STEM, check_heading
from ..io.units import FORCE, LENGTH, NODAL_STIFFNESS, given, si_default, unit
from .base import HUGE, Indices, Nodal, Scalars, Table, Term, block_pattern, int32s
from .contact import barrier
from .friction import frictional
from .held_object import HeldObject
from .obstacle_distance import obstacle_reach, point_of, row3, signed_distance
from .obstacle_edges import ObstacleEdges, ipctk_or_none
from .obstacle_shapes import Shape, vector

STEP_CAP = 4.0  # max_step's conservative advancement stops past this step fraction (inf)
ADVANCES = 100  # and after this many advances (the bound reached, short of the contact)
REACH = 10.0  # a keyframe offset's components are at most this many times the body's size
MAX_SWEEPS = 1000  # sub-steps of one increment's obstacle motion, at most (Obstacle.terms refuses more)


@kernel
def obstacle_energy(
    rest: Nodal, u: Nodal, verts: Indices, kind: ti.i32, p: Scalars, dhat: ti.f64, kappa: ti.f64
) -> tuple[ti.f64, ti.f64]:
    """(sum of the barriers over the listed vertices outside the obstacle, smallest signed distance)."""
    total = 0.0
    nearest = ti.math.inf
    for k in range(verts.shape[0]):
        d = signed_distance(point_of(rest, u, verts[k]), kind, p)[0]
        ti.atomic_min(nearest, d)
        if d > 0:
            total += barrier(d, dhat, kappa)[0]
    return total, nearest


@kernel
def obstacle_derivatives(
    rest: Nodal,
    u: Nodal,
    verts: Indices,
    kind: ti.i32,
    p: Scalars,
    dhat: ti.f64,
    kappa: ti.f64,
    exact: ti.i32,
    gradient: Nodal,
    hessian: Table,
) -> ti.f64:
    """gradient = dE/dx; hessian[k] = the 3 x 3 block of vertex k, row-major (its d x d corner is the node's);
    returns the smallest signed distance."""
    nearest = ti.math.inf
    for v, i in ti.ndrange(gradient.shape[0], gradient.shape[1]):
        gradient[v, i] = 0.0
    for k in range(verts.shape[0]):
        d, n, r, s, t = signed_distance(point_of(rest, u, verts[k]), kind, p)
        ti.atomic_min(nearest, d)
        H = ti.Matrix.zero(ti.f64, 3, 3)
        if d > 0 and d < dhat:
            _, db, ddb = barrier(d, dhat, kappa)
            for i in ti.static(range(3)):
                if i < gradient.shape[1]:
                    gradient[verts[k], i] = db * n[i]
            H = ddb * n.outer_product(n)
            if exact and r > 0:
                H += db / r * (ti.Matrix.identity(ti.f64, 3) - n.outer_product(n) - s * t.outer_product(t))
        for i, j in ti.static(ti.ndrange(3, 3)):
            hessian[k, 3 * i + j] = H[i, j]
    return nearest


@kernel
def obstacle_step(rest: Nodal, u: Nodal, dx: Nodal, verts: Indices, kind: ti.i32, p: Scalars, linear: ti.i32) -> ti.f64:
    """Largest alpha (a bound short of the contact; inf past STEP_CAP) at which no listed vertex moving along dx
    has reached the obstacle; linear: its d is affine in x, d(x + t m) = d(x) + t (m . n), the bound exact."""
    bound = ti.math.inf
    for k in range(verts.shape[0]):
        x = point_of(rest, u, verts[k])
        m = row3(dx, verts[k])
        speed = m.norm()
        if speed > 0:
            d0, n, _, _, _ = signed_distance(x, kind, p)
            if linear:
                rate = m.dot(n)
                if rate < 0:
                    ti.atomic_min(bound, ti.max(d0, 0.0) / -rate)
            else:
                t, d, steps = 0.0, d0, 0
                while d > 1e-3 * d0 and t <= STEP_CAP and steps < ADVANCES:
                    t += d / speed
                    d = signed_distance(x + t * m, kind, p)[0]
                    steps += 1
                if t <= STEP_CAP:
                    ti.atomic_min(bound, ti.max(t, 0.0))
    return bound


class ObstacleContact(Term):
    """Barriers keeping the given vertices outside a rigid obstacle (a Shape), which set_offset translates."""

    reports_contact = True

    def __init__(
        self,
        config,
        vertices: np.ndarray,
        shape: Shape,
        name: str,
        dhat: float,
        stiffness: float,
        pieces: np.ndarray | None = None,
        sweep: float = math.inf,
    ):
        """pieces: the body's surface as straight pieces (surface_pieces), which overlap() tests; sweep: the
        farthest it moves between two equilibria (the sub-steps of a run: BuiltScene.sweeps)."""
        self.config = config
        self.name, self.shape, self.kind = name, shape, int(shape.kind)
        self.dhat, self.kappa, self.sweep = float(dhat), float(stiffness), float(sweep)
        self.placed = shape.parameters()
        self.parameters = self.placed.copy()
        self.verts = int32s(vertices)
        self.pieces = int32s(np.zeros((0, 3)) if pieces is None else pieces)
        self._rows, self._cols = block_pattern(np.asarray(vertices)[:, None], config.dim)

    @property
    def offset(self) -> np.ndarray:
        """The obstacle's translation from its placed position (3,)."""
        return self.parameters[:3] - self.placed[:3]

    def set_offset(self, offset) -> None:
        """Translate the obstacle by offset ([dx, dy] or [dx, dy, dz]) from its placed position."""
        self.parameters[:3] = self.placed[:3] + np.pad(np.asarray(offset, dtype=np.float64), (0, 3 - len(offset)))

    def _energy(self) -> tuple[float, float]:
        return obstacle_energy(
            self.config.rest, self.config.u, self.verts, self.kind, self.parameters, self.dhat, self.kappa
        )

    def nearest(self) -> float:
        """The smallest signed distance of a listed vertex to the obstacle (<= 0: one touches or is inside it)."""
        return float(self._energy()[1])

    def energy(self) -> float:
        total, nearest = self._energy()
        return total if nearest > 0 else np.inf

    def _derivatives(self, exact: bool) -> tuple[np.ndarray, np.ndarray]:
        d = self.config.dim
        gradient, hessian = np.empty_like(self.config.u), np.empty((len(self.verts), 9))
        nearest = obstacle_derivatives(
            self.config.rest,
            self.config.u,
            self.verts,
            self.kind,
            self.parameters,
            self.dhat,
            self.kappa,
            int(exact),
            gradient,
            hessian,
        )
        if not nearest > 0:  # inside the obstacle: no finite force (fault() says why)
            gradient[:] = np.nan
        return gradient, hessian.reshape(-1, 3, 3)[:, :d, :d].ravel()

    def gradient(self) -> np.ndarray:
        return self._derivatives(False)[0]

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._rows, self._cols

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        return self._derivatives(not psd_only)[1]

    def max_step(self, dx: np.ndarray) -> float:
        bound = obstacle_step(
            self.config.rest,
            self.config.u,
            np.ascontiguousarray(dx, dtype=np.float64),
            self.verts,
            self.kind,
            self.parameters,
            int(self.shape.linear),
        )
        return math.inf if bound >= HUGE else float(bound)  # Taichi's inf comes back as the largest double

    @property
    def moved(self) -> str:
        """', at its offset [dx, dy, dz]' where it has moved from its placed position, else ''."""
        return f", at its offset {np.round(self.offset, 6).tolist()}" if np.any(self.offset) else ""

    def fault(self) -> str | None:
        nearest = self.nearest()
        if nearest > 0:
            return None
        moved = self.moved
        return (
            f"{self.name!r} overlaps the body (a boundary node {-nearest:.3g} inside it{moved}): "
            f"it {'moved' if moved else 'reached'} too far for the body to give way"
        )

    def reach(self) -> tuple[float, np.ndarray]:
        """(m, x): the least signed distance m of the obstacle over the body's surface pieces (obstacle_reach: each
        straight segment or triangle searched, not only its corners) and a point x (3,) where it is taken."""
        out = np.empty((len(self.pieces), 4))
        obstacle_reach(self.config.rest, self.config.u, self.pieces, self.kind, self.parameters, out)
        k = int(np.argmin(out[:, 0]))
        return float(out[k, 0]), out[k, 1:]

    def overlap(self) -> str | None:
        """Where the obstacle overlaps the body in its current state, in words, or None. It does where m <= 0 (reach:
        a piece of the surface touches or enters it), or where its centre c (its parameters' position), inside it
        (d(c) < 0), lies inside the body: winding(c) = 1 (the obstacle wholly inside the body, its surface crossing
        no piece). A bounded convex obstacle meets the body's interior only so (its interior is connected); an
        unbounded one cannot lie wholly inside the body, so m <= 0 finds it (a plane's point is on it: d(c) = 0)."""
        d = self.config.dim
        m, x = self.reach()
        where = ", ".join(f"{v:.4g}" for v in x[:d])
        if m <= 0:
            return (
                f"obstacle {self.name!r} overlaps the body: the body's surface reaches {-m:.3g} into it at ({where})"
                f"{self.moved}"
            )
        centre = self.parameters[:3].copy()
        centre[d:] = 0.0  # a 2D scene's cross-section at z = 0: its point nearest the centre
        alone = (centre[None], np.zeros((1, 3)), int32s([0]))  # the centre as the one vertex of obstacle_energy
        inside_obstacle = obstacle_energy(*alone, self.kind, self.parameters, 1.0, 1.0)[1] < 0  # d(c) < 0
        if inside_obstacle and winding(self.config.rest + self.config.u, self.pieces, centre[:d]) > 0.5:
            where = ", ".join(f"{v:.4g}" for v in centre[:d])
            return (
                f"obstacle {self.name!r} overlaps the body: it lies inside the body (its centre ({where})){self.moved}"
            )
        return None


def check_friction(friction, slip) -> None:
    """Refuse a friction coefficient that is not >= 0 or a friction_slip (None: its default) that is not > 0."""
    require(require_finite("friction", friction) >= 0, f"friction = {friction!r} must be >= 0 (0: frictionless)")
    require(
        slip is None or require_finite("friction_slip", slip) > 0,
        f"friction_slip = {slip!r} must be > 0 (a length: the slip over which static friction reaches mu N)",
    )


@dataclass(frozen=True)
class Obstacle:
    """A rigid obstacle ([[obstacles]]): its name (heads its history columns), shape (a Shape), the barrier's
    threshold dhat and stiffness (as [effects.ground]'s), and keyframes ((step, [dx, dy(, dz)]), ...): its
    translation from its placed position, piecewise linear over the schedule's steps from 0 at step 0 and held
    after the last (as a chamber's commands, scene/schedule.py); none: a static obstacle; friction: the Coulomb
    coefficient mu (0: frictionless, no friction term) and friction_slip the slip eps over which static friction
    rises to mu times the normal force (None: dhat / 10, a length in the scene's units like dhat) (terms/friction.py,
    check_friction)."""

    name: str
    shape: Shape
    dhat: float | None = si_default(0.01, LENGTH, scaled=False)
    stiffness: float | None = si_default(1e3, NODAL_STIFFNESS, scaled=False)
    keyframes: tuple = field(default=())
    friction: float = 0.0
    friction_slip: float | None = field(default=None, metadata=unit(LENGTH))
    weight: float | None = field(default=None, metadata=unit(FORCE))
    release: int = 0

    def __post_init__(self):
        check_heading("obstacle name", self.name)  # a chamber's rule: it heads CSV columns
        require(
            isinstance(self.name, str) and len(self.name) <= MAX_NAME and STEM.fullmatch(self.name) is not None,
            f"obstacle name = {self.name!r} must be 1 to {MAX_NAME} letters, digits and _ + - . (not starting with "
            f"'.'): a plain name",
        )
        require(isinstance(self.shape, Shape), f"obstacle {self.name!r}: shape = {self.shape!r} is not a shape")
        for key in ("dhat", "stiffness"):
            value = getattr(self, key)
            require(value is None or require_finite(key, value) > 0, f"{key} = {value!r} must be > 0")
        check_friction(self.friction, self.friction_slip)
        require(
            self.weight is None or require_finite("weight", self.weight) > 0,
            f"obstacle {self.name!r}: weight = {self.weight!r} must be > 0 (none: it stays where it is placed)",
        )
        require(
            isinstance(self.release, int) and not isinstance(self.release, bool) and self.release >= 0,
            f"obstacle {self.name!r}: release = {self.release!r} must be a whole number of steps >= 0",
        )
        require(
            self.weight is None or not self.keyframes,
            f"obstacle {self.name!r}: an obstacle with a weight has no keyframes (it moves as the grip lets it)",
        )
        frames = self.keyframes
        require(
            isinstance(frames, (tuple, list))
            and all(isinstance(k, (tuple, list)) and len(k) == 2 and shape_of(k[1]) in ((2,), (3,)) for k in frames),
            f"obstacle {self.name!r}: keyframes = {frames!r} must be a list of [step, [dx, dy, dz]]",
        )
        steps = [require_finite("keyframes step", s) for s, _ in frames]
        for _, offset in frames:
            vector("keyframes offset", list(offset))
        require(
            all(float(s).is_integer() and s >= 0 for s in steps),
            f"obstacle {self.name!r}: keyframes steps {steps!r} must be whole numbers >= 0",
        )
        require(
            all(b > a for a, b in zip(steps, steps[1:])),
            f"obstacle {self.name!r}: keyframes steps {steps!r} must increase",
        )
        object.__setattr__(self, "keyframes", tuple((s, tuple(offset)) for s, offset in frames))

    @property
    def moving(self) -> bool:
        return bool(self.keyframes)

    @property
    def last_step(self) -> int:
        return int(self.keyframes[-1][0]) if self.keyframes else 0

    def frames(self) -> tuple[np.ndarray, np.ndarray]:
        """(steps (k,), translations (k, 3)): its keyframes after (0, 0) at step 0, unless one is at step 0."""
        steps = [0.0] + [float(s) for s, _ in self.keyframes]
        values = [(0.0, 0.0, 0.0)] + [vector("keyframes offset", list(v)) for _, v in self.keyframes]
        if len(steps) > 1 and steps[1] == 0.0:
            steps, values = steps[1:], values[1:]
        return np.array(steps), np.array(values)

    def offset(self, step: float) -> np.ndarray:
        """The translation (3,) at a (possibly fractional) step: linear between the keyframes, 0 at step 0."""
        steps, values = self.frames()
        return np.array([np.interp(step, steps, column) for column in values.T])

    def increment_motion(self) -> float:
        """The farthest it moves in one increment: the largest |v_k+1 - v_k| / (s_k+1 - s_k) over its frames."""
        steps, values = self.frames()
        return float(np.max(np.linalg.norm(np.diff(values, axis=0), axis=1) / np.diff(steps), initial=0.0))

    def terms(self, config, mesh, lumped_area, budget) -> list:
        """Its contact term on the body's outer boundary nodes, then the barrier on the sides and faces of the body's
        surface (obstacle_edges), then, with friction > 0, its friction term (friction.frictional) and, with a weight,
        its HeldObject; its overlap check on the body's surface pieces (surface_pieces). Refused: a 3D scene's
        point or vector of 2 numbers; a 2D scene's keyframe with a z offset; an offset component beyond REACH times
        the body's size (the diagonal of its bounding box); a motion per increment of more than MAX_SWEEPS sweeps
        (BuiltScene.sweeps; the sweep: half the smaller of dhat and the median length of the surface pieces' sides);
        an obstacle overlapping the rest body (overlap)."""
        flat = [key for key in self.shape.vectors if len(getattr(self.shape, key)) == 2]
        flat += ["keyframes"] if any(len(v) == 2 for _, v in self.keyframes) else []
        require(
            mesh.dim == 2 or not flat,
            f"obstacle {self.name!r}: {flat[0] if flat else ''} has 2 numbers; a 3D scene gives [x, y, z]",
        )
        size = float(np.linalg.norm(np.ptp(mesh.vertices, axis=0)))
        for step, offset in self.keyframes:
            v = np.array(vector("keyframes offset", list(offset)))
            require(
                mesh.dim == 3 or v[2] == 0.0,
                f"obstacle {self.name!r}: keyframes offset {list(offset)!r} at step {step:g} moves it along z; a 2D "
                f"scene's obstacle moves in its plane: give [dx, dy]",
            )
            require(
                float(np.max(np.abs(v))) <= REACH * size,
                f"obstacle {self.name!r}: keyframes offset {list(offset)!r} at step {step:g} must lie within "
                f"+-{REACH * size:.4g} in each component ({REACH:g} times the body's size)",
            )
        dhat, stiffness = float(given(self.dhat, "dhat")), float(given(self.stiffness, "stiffness"))
        pieces = surface_pieces(mesh)
        x = mesh.vertices[pieces]
        sides = np.linalg.norm(x - np.roll(x, 1, axis=1), axis=2)
        sweep = 0.5 * min(dhat, float(np.median(sides[sides > 0])))
        motion = self.increment_motion()
        require(
            motion <= MAX_SWEEPS * sweep,
            f"obstacle {self.name!r} moves {motion:.4g} in one increment: at most {MAX_SWEEPS} sweeps of {sweep:.3g} "
            f"(half the smaller of its dhat and the body's median surface edge), {MAX_SWEEPS * sweep:.4g}, are "
            f"allowed; spread its keyframes over more steps",
        )
        term = ObstacleContact(config, mesh.boundary, self.shape, self.name, dhat, stiffness, pieces, sweep)
        term.set_offset(self.offset(0.0))  # where it is at step 0 (a keyframe at step 0 moves it there)
        overlap = term.overlap()
        require(overlap is None, f"{overlap} at rest: place it clear of the body")
        edges = obstacle_edges(term, pieces)
        terms = frictional(term, self.friction, self.friction_slip, edges)
        if self.weight is None:
            return [term, *edges, *terms[1:]]
        friction = terms[1] if len(terms) > 1 else None
        return [term, *edges, *terms[1:], HeldObject(term, friction, self.weight, self.release, edges)]


def obstacle_edges(contact: ObstacleContact, pieces: np.ndarray) -> list:
    """[ObstacleEdges]: the barrier between the obstacle's features and the body's surface pieces (their sides and
    faces, terms/obstacle_edges.py) where its shape has a feature set; [] for a plane, a 3D cylinder, or a 3D body
    where the IPC Toolkit is not installed (its nodes then hold the contact alone, with a warning)."""
    if not ObstacleEdges.needed(contact.shape, contact.config.dim):
        return []
    ipctk = ipctk_or_none() if contact.config.dim == 3 else None
    if contact.config.dim == 3 and ipctk is None:  # pragma: no cover - the [3d] extra installs it where it can
        warnings.warn(
            f"obstacle {contact.name!r}: the IPC Toolkit (ipctk, the [3d] extra) is not installed, so only the "
            f"body's nodes are kept out of it (a state in which a face enters it is still refused)",
            stacklevel=2,
        )
        return []
    return [ObstacleEdges(contact, pieces, ipctk)]
