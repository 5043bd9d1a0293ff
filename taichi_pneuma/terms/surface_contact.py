"""Contact of the body's surface with itself, 2D and 3D: IPC barriers between any two of its pieces that share no
node, by the IPC Toolkit (ipctk, Zachary Ferguson et al.; the [3d] extra).

The surface is the body's boundary as straight pieces (fem/self_intersection.py surface_pieces: the outer surface and
every chamber wall; a quadratic facet split at its midside nodes): triangles and their edges in 3D, segments in 2D.
The contact pairs are the point-triangle and edge-edge pairs in 3D, point-segment in 2D, of pieces that share no
node and lie closer than dhat; ipctk finds them by a broad phase (a bounding-volume hierarchy, LBVH) at every state
the solver evaluates, so the cost grows with the surface, not its square. Their distances d_k give the energy

    E = kappa sum_k w_k b(d_k^2) / dhat^3,   b(s) = -(s - dhat^2)^2 ln(s / dhat^2)  for s < dhat^2, else 0,

ipctk's barrier on squared distances scaled by 1 / dhat^3 ("physical": b / dhat^3 is a length, of order dhat), w_k
the pair's share of the surface (area weighting: half the incident facets' areas at a vertex, in 3D; half the
incident segments' lengths in 2D). So kappa is a pressure: the contact pressure at gap d is about kappa |b'|
(4.3 kappa at d = dhat / 2), and the energy converges as the mesh is refined. The barrier is C2 at dhat and
infinite as d -> 0: the energy forbids touching. Its gradient and Hessian are ipctk's; the PSD one projects each
pair's Hessian onto its non-negative eigenvalues (ipctk's PSDProjectionMethod.CLAMP).

max_step(dx) is ipctk's continuous collision check (Tight Inclusion CCD) along the straight path from x to x + dx,
which keeps every pair's distance positive over the step; the solver steps at most 0.9 of it.

The pairs change with the state, and so does the Hessian's pattern (Term.dynamic): hessian_pattern() is that of
the last hessian_values(). Every quantity is computed once per state (the displacements compared with the last).

Friction between the surface's pieces (SurfaceFriction, mu > 0): IPC's smoothed lagged Coulomb friction, ipctk's
FrictionPotential, as terms/friction.py's against obstacles. At the last equilibrium x^0 (advance) the pairs within
dhat, their normal force magnitudes lambda_k (the barrier's) and their tangent bases T_k are lagged; over an
increment each pair's relative slip u_k = T_k^T (Gamma_k (x - x^0)) (Gamma_k the pair's relative-motion map at its
lagged closest points) gives the energy D = sum_k mu lambda_k f0(|u_k|), f0 IPC's (f0' = f1, f1(y) = 2 y / eps -
y^2 / eps^2 below the slip eps, 1 above): static friction a stiff spring up to mu lambda, kinetic friction mu lambda
against the slip.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import PneumaInputError
from .base import Term, vertex_dofs


def ipctk_module():
    """The ipctk module, or PneumaInputError saying how to install it."""
    try:
        import ipctk
    except ImportError:  # pragma: no cover - the [3d] extra installs it where it has wheels
        raise PneumaInputError(
            "surface_contact needs the IPC Toolkit: pip install 'taichi-pneuma[3d]' (ipctk has wheels for Linux "
            "x86_64, macOS and Windows)"
        ) from None
    return ipctk


def fortran(array: np.ndarray, dtype=np.float64) -> np.ndarray:
    """A column-major copy (ipctk reads its matrices so)."""
    return np.asfortranarray(array, dtype=dtype)


def on_body(config, surface: np.ndarray, flat: np.ndarray) -> np.ndarray:
    """A gradient over the collision mesh's vertices (flat, surface's order) as one over the body's nodes (n, d)."""
    gradient = np.zeros_like(config.u)
    gradient[surface] = flat.reshape(-1, config.dim)
    return gradient


def triplets(surface: np.ndarray, dim: int, hessian) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(rows, cols, values) on the body's DOFs of a Hessian (sparse) over the collision mesh's DOFs."""
    coo = hessian.tocoo()
    dofs = vertex_dofs(surface, dim)
    return dofs[coo.row], dofs[coo.col], coo.data


class SurfaceContact(Term):
    """IPC barriers (threshold dhat, stiffness kappa, a pressure) between the pieces of the body's surface that
    share no node (module docstring)."""

    name = "surface_contact"
    reports_contact = True
    dynamic = True

    def __init__(self, config, pieces: np.ndarray, dhat: float, stiffness: float):
        """pieces: the surface as straight pieces (surface_pieces: triangles (f, 3); in 2D segments as (a, b, b))."""
        ipctk = ipctk_module()
        self.ipctk = ipctk
        self.config = config
        self.dhat, self.kappa = float(dhat), float(stiffness)
        n, d = config.rest.shape
        pieces = np.asarray(pieces, dtype=np.int32)
        if d == 3:
            faces = pieces
            edges = ipctk.edges(fortran(faces, np.int32))
        else:
            faces = np.zeros((0, 3), dtype=np.int32)
            edges = np.unique(np.sort(pieces[:, :2], axis=1), axis=0)
        include = np.zeros(n, dtype=bool)
        include[pieces.ravel()] = True
        self.mesh = ipctk.CollisionMesh(
            include.tolist(), [False] * n, fortran(config.rest), fortran(edges, np.int32), fortran(faces, np.int32)
        )
        self.surface = np.flatnonzero(include)  # the collision mesh's vertices, in its order
        self.potential = ipctk.BarrierPotential(self.dhat, self.kappa, True)
        self.broad_phase = ipctk.LBVH()
        self._state: np.ndarray | None = None
        self._rows = self._cols = np.zeros(0, dtype=np.int64)

    def positions(self, u: np.ndarray) -> np.ndarray:
        """The collision mesh's vertex positions (m, d) at displacements u (n, d)."""
        return fortran(self.config.rest[self.surface] + u[self.surface])

    def pairs_at(self, x: np.ndarray):
        """The contact pairs (area-weighted) at the collision mesh's positions x."""
        collisions = self.ipctk.NormalCollisions()
        collisions.use_area_weighting = True
        collisions.build(self.mesh, x, self.dhat, broad_phase=self.broad_phase)
        return collisions

    def _collisions(self):
        """The contact pairs at the current state (built once per state)."""
        u = self.config.u
        if self._state is None or not np.array_equal(self._state, u):
            self._state = u.copy()
            self._x = self.positions(u)
            self.collisions = self.pairs_at(self._x)
        return self.collisions

    def pairs(self) -> int:
        """The number of contact pairs (closer than dhat) at the current state."""
        return len(self._collisions())

    def min_distance(self) -> float:
        """The smallest distance between two pieces that share no node, among those closer than dhat (inf if none)."""
        collisions = self._collisions()
        return math.sqrt(collisions.compute_minimum_distance(self.mesh, self._x)) if len(collisions) else math.inf

    def energy(self) -> float:
        if not self.min_distance() > 0:
            return math.inf
        return float(self.potential(self.collisions, self.mesh, self._x))

    def gradient(self) -> np.ndarray:
        collisions = self._collisions()
        return on_body(self.config, self.surface, self.potential.gradient(collisions, self.mesh, self._x))

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        project = self.ipctk.PSDProjectionMethod.CLAMP if psd_only else self.ipctk.PSDProjectionMethod.NONE
        hessian = self.potential.hessian(self._collisions(), self.mesh, self._x, project)
        self._rows, self._cols, values = triplets(self.surface, self.config.dim, hessian)
        return values

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._rows, self._cols

    def max_step(self, dx: np.ndarray) -> float:
        self._collisions()
        end = self.positions(self.config.u + dx)
        step = self.ipctk.compute_collision_free_stepsize(self.mesh, self._x, end, broad_phase=self.broad_phase)
        return math.inf if step >= 1.0 else float(step)

    def fault(self) -> str | None:
        if self.energy() < math.inf:
            return None
        return "two pieces of the body's surface touch (surface_contact's barrier is infinite there)"


class SurfaceFriction(Term):
    """Smoothed Coulomb friction (coefficient mu, slip eps) between the pieces of the body's surface, lagged at the
    last equilibrium (module docstring); named 'surface_contact.friction', beside the contact's force."""

    name = "surface_contact.friction"
    reports_contact = True
    dynamic = True

    def __init__(self, contact: SurfaceContact, mu: float, eps: float):
        self.contact, self.config = contact, contact.config
        self.mu = float(mu)
        self.potential = contact.ipctk.FrictionPotential(float(eps))
        self._rows = self._cols = np.zeros(0, dtype=np.int64)
        self.advance(self.config.u)

    def advance(self, u: np.ndarray) -> None:
        """Lag the pairs, their normal forces and tangent bases at u, for the next increment."""
        contact = self.contact
        self.start = contact.positions(u)
        self.pairs = contact.ipctk.TangentialCollisions()
        self.pairs.build(contact.mesh, self.start, contact.pairs_at(self.start), contact.potential, self.mu)

    def _slip(self) -> np.ndarray:
        """The surface's displacement since the lag (m, d), as ipctk's 'velocities'."""
        return fortran(self.contact.positions(self.config.u) - self.start)

    def energy(self) -> float:
        return float(self.potential(self.pairs, self.contact.mesh, self._slip())) if len(self.pairs) else 0.0

    def gradient(self) -> np.ndarray:
        flat = self.potential.gradient(self.pairs, self.contact.mesh, self._slip())
        return on_body(self.config, self.contact.surface, flat)

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        methods = self.contact.ipctk.PSDProjectionMethod
        project = methods.CLAMP if psd_only else methods.NONE
        hessian = self.potential.hessian(self.pairs, self.contact.mesh, self._slip(), project)
        self._rows, self._cols, values = triplets(self.contact.surface, self.config.dim, hessian)
        return values

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self._rows, self._cols
