"""Coulomb friction between the body and a rigid obstacle (or the ground): IPC's smoothed, lagged friction
(Li et al. 2020, "Incremental Potential Contact", sec. 5), quasistatic.

For each node k of the obstacle's contact term (terms/obstacles.py ObstacleContact) the lagged state holds its
normal force lambda_k = -b'(d_k) (the barrier's force, terms/contact.py, 0 beyond dhat; where the obstacle has an
edge barrier, terms/obstacle_edges.py, the magnitude of the two barriers' force on the node), its unit normal n_k
(the gradient of the shape's signed distance) and its position x_k^0, all taken at the last equilibrium (advance,
called with the displacements that end each increment; at construction, the rest state). The slip of the increment
is the node's tangential displacement relative to the obstacle,

    u_T = P_k (x_k - x_k^0 - (o - o^0)),   P_k = I - n_k n_k^T,

o - o^0 the obstacle's translation since the lag (its offset, ObstacleContact.set_offset). The energy is

    D = sum_k mu lambda_k f0(|u_T|),
    f1(y) = 2 y / eps - y^2 / eps^2 (y < eps), 1 (y >= eps),
    f0(y) = -y^3 / (3 eps^2) + y^2 / eps + eps / 3 (y < eps), y (y >= eps)   (f0' = f1, C2 at eps),

mu the friction coefficient and eps the slip over which the friction force mu lambda f1 rises from 0 to mu lambda:
static friction is a stiff spring (stiffness 2 mu lambda / eps at y = 0), kinetic friction the constant force
mu lambda against the slip. With y = |u_T| and t = u_T / y, the gradient is mu lambda (f1(y) / y) u_T and the
Hessian (lambda, n lagged: constants)

    mu lambda [ f1(y) / y (P - t t^T) + f1'(y) t t^T ],   f1 / y = 2 / eps - y / eps^2, f1' = 2 (eps - y) / eps^2
                                                          (y < eps);   1 / y and 0 (y >= eps),

exact, and PSD as it is: its eigenvalues are mu lambda f1 / y (across the slip, within the tangent plane),
mu lambda f1' >= 0 (along it) and 0 (along n), so psd_only changes nothing (IPC clamps the along-slip eigenvalue
of its own f1; this one's is never negative). At y = 0 it is mu lambda (2 / eps) P.

Lagging makes each increment a minimisation: lambda and n are those of the last equilibrium, so a node that first
comes within dhat during an increment has no friction until the next one. The energy is C2 and smooth everywhere
(f0 ~ y^2 / eps near 0), so the term is no kinked one; it bounds no step.
"""

import numpy as np

from ..backend import kernel, ti
from .base import Indices, Nodal, Scalars, Table, Term
from .contact import barrier
from .obstacle_distance import point_of, signed_distance

LAGGED = 7  # per node: lambda, n (3), x^0 (3)


@ti.func
def smoothed(y, eps):
    """(f0(y), f1(y) / y, f1'(y)) of IPC's smoothed friction (f1(y) / y taken as its limit 2 / eps at y = 0)."""
    f0, f1y, df1 = y, 1.0 / ti.max(y, eps), 0.0
    if y < eps:
        f0 = -y * y * y / (3.0 * eps * eps) + y * y / eps + eps / 3.0
        f1y = 2.0 / eps - y / (eps * eps)
        df1 = 2.0 * (eps - y) / (eps * eps)
    return f0, f1y, df1


@ti.func
def slip(rest: ti.template(), u: ti.template(), verts: ti.template(), lagged: ti.template(), shift, k):
    """(lambda, n, u_T) of listed vertex k: its lagged normal force and normal, and its slip u_T."""
    n = ti.Vector([lagged[k, 1], lagged[k, 2], lagged[k, 3]])
    start = ti.Vector([lagged[k, 4], lagged[k, 5], lagged[k, 6]])
    moved = point_of(rest, u, verts[k]) - start - shift
    return lagged[k, 0], n, moved - moved.dot(n) * n


@kernel
def friction_lag(
    rest: Nodal, u: Nodal, verts: Indices, kind: ti.i32, p: Scalars, dhat: ti.f64, kappa: ti.f64, lagged: Table
):
    """lagged[k] = (lambda, n, x) of listed vertex k at u: lambda = -b'(d) (0 at d >= dhat or d <= 0)."""
    for k in range(verts.shape[0]):
        x = point_of(rest, u, verts[k])
        d, n, _, _, _ = signed_distance(x, kind, p)
        force = 0.0
        if d > 0:
            force = -barrier(d, dhat, kappa)[1]
        lagged[k, 0] = force
        for i in ti.static(range(3)):
            lagged[k, 1 + i] = n[i]
            lagged[k, 4 + i] = x[i]


@kernel
def friction_energy(
    rest: Nodal, u: Nodal, verts: Indices, lagged: Table, offset: Scalars, mu: ti.f64, eps: ti.f64
) -> ti.f64:
    """sum_k mu lambda_k f0(|u_T|) over the listed vertices (offset: the obstacle's translation since the lag)."""
    shift = ti.Vector([offset[0], offset[1], offset[2]])
    total = 0.0
    for k in range(verts.shape[0]):
        force, _, tangential = slip(rest, u, verts, lagged, shift, k)
        if force > 0:
            total += mu * force * smoothed(tangential.norm(), eps)[0]
    return total


@kernel
def friction_derivatives(
    rest: Nodal,
    u: Nodal,
    verts: Indices,
    lagged: Table,
    offset: Scalars,
    mu: ti.f64,
    eps: ti.f64,
    gradient: Nodal,
    hessian: Table,
):
    """gradient = dD/dx; hessian[k] = the 3 x 3 block of listed vertex k, row-major (its d x d corner is the
    node's)."""
    shift = ti.Vector([offset[0], offset[1], offset[2]])
    for v, i in ti.ndrange(gradient.shape[0], gradient.shape[1]):
        gradient[v, i] = 0.0
    for k in range(verts.shape[0]):
        force, n, tangential = slip(rest, u, verts, lagged, shift, k)
        H = ti.Matrix.zero(ti.f64, 3, 3)
        if force > 0:
            y = tangential.norm()
            _, f1y, df1 = smoothed(y, eps)
            scale = mu * force
            for i in ti.static(range(3)):
                if i < gradient.shape[1]:
                    gradient[verts[k], i] = scale * f1y * tangential[i]
            t = tangential / ti.max(y, 1e-300)
            H = scale * (f1y * (ti.Matrix.identity(ti.f64, 3) - n.outer_product(n)) + (df1 - f1y) * t.outer_product(t))
        for i, j in ti.static(ti.ndrange(3, 3)):
            hessian[k, 3 * i + j] = H[i, j]


class ObstacleFriction(Term):
    """Smoothed Coulomb friction (coefficient mu, slip eps) on the nodes of an obstacle's contact term, lagged at the
    last equilibrium; named '<obstacle>.friction', so that the history reports its force beside the normal one."""

    reports_contact = True

    def __init__(self, contact, mu: float, eps: float, edges: list | None = None):
        """contact: the obstacle's ObstacleContact (its nodes, shape, barrier and offset, read live); edges: its
        barrier on the sides and faces of the body (terms/obstacle_edges.py), if any, whose normal force joins the
        nodes' lambda."""
        self.config, self.contact, self.edges = contact.config, contact, list(edges or [])
        self.name = f"{contact.name}.friction"
        self.mu, self.eps = float(mu), float(eps)
        self.lagged = np.zeros((len(contact.verts), LAGGED))
        self.origin = np.zeros(3)  # the obstacle's offset at the lag
        self.advance(self.config.u)

    def advance(self, u: np.ndarray) -> None:
        """Lag lambda, n and x at u (the obstacle where it is now) for the next increment."""
        c = self.contact
        friction_lag(self.config.rest, u, c.verts, c.kind, c.parameters, c.dhat, c.kappa, self.lagged)
        if self.edges:  # lambda_k: the whole contact force on the node, its barrier's and the edges' part
            kept = self.config.u.copy()
            self.config.u[:] = u
            push = sum(term.gradient() for term in (c, *self.edges))[c.verts]
            self.config.u[:] = kept
            self.lagged[:, 0] = np.linalg.norm(push, axis=1)
        self.origin = c.offset.copy()

    def _arguments(self) -> tuple:
        return (self.config.rest, self.config.u, self.contact.verts, self.lagged, self.contact.offset - self.origin)

    def energy(self) -> float:
        return float(friction_energy(*self._arguments(), self.mu, self.eps))

    def _derivatives(self) -> tuple[np.ndarray, np.ndarray]:
        d = self.config.dim
        gradient, hessian = np.empty_like(self.config.u), np.empty((len(self.contact.verts), 9))
        friction_derivatives(*self._arguments(), self.mu, self.eps, gradient, hessian)
        return gradient, hessian.reshape(-1, 3, 3)[:, :d, :d].ravel()

    def gradient(self) -> np.ndarray:
        return self._derivatives()[0]

    def hessian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return self.contact.hessian_pattern()

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        """The exact Hessian, PSD as it is (the module's docstring): psd_only changes nothing."""
        return self._derivatives()[1]

    def fault(self) -> str | None:
        """Where every node it holds (lambda > 0) slides (its friction force at mu lambda: |u_T| >= eps), that the
        body slides on the obstacle: a load along it beyond mu N has no quasistatic equilibrium."""
        held = self.lagged[:, 0] > 0
        force = np.linalg.norm(self.gradient()[self.contact.verts[held]], axis=1)
        limit = self.mu * self.lagged[held, 0]
        if not held.any() or not np.all(force >= (1 - 1e-9) * limit):
            return None
        return (
            f"the body slides on {self.contact.name!r}: every node in contact slips more than friction_slip = "
            f"{self.eps:.3g} in the increment, its friction at its limit mu N = {limit.sum():.4g}; a load along it "
            f"beyond that has no equilibrium (quasistatic friction holds or slides)"
        )


def frictional(contact, mu: float, slip: float | None, edges: list | None = None) -> list:
    """The terms of a contact with friction coefficient mu: the contact alone where mu = 0 (no friction term at all),
    else with its ObstacleFriction of slip eps (None: dhat / 10) on the normal force of the contact and its edges."""
    if mu == 0:
        return [contact]
    return [contact, ObstacleFriction(contact, mu, slip_length(slip, contact.dhat), edges)]


def slip_length(slip: float | None, dhat: float) -> float:
    """The slip eps over which static friction rises to mu N: the one given, or (None) a tenth of the contact's
    dhat."""
    return dhat / 10 if slip is None else slip
