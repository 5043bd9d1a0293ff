"""An obstacle the body holds: after its release step the obstacle is free to move along y under a load W along -y
(its weight), held only by its contact with the body and the friction there.

Its height o (its offset along y from where it was placed) is not a degree of freedom of the model: for the body's
state x it takes the height that minimises the energy of its contact terms (the nodes' and the edges') and
friction term with the load's potential,

    o*(x) = argmin_o  phi(x, o),   phi = E_c(x, o) + E_f(x, o) + W o,

found by Newton's method on o alone (inner_solve; each term depends on x_k - o e_y only, so dphi/do = W - sum_k
g_k . e_y and d2phi/do2 = e^T H e, with g_k the terms' gradient at node k, H their Hessian and e the motion of every
node by 1 along y), its steps kept short of the contact (the contact terms' step bounds along the relative
motion). The model's energy is then E(x) = min_o phi(x, o) plus the body's own: by the envelope theorem its
gradient is the contact and friction terms' (at o*), and its Hessian theirs less the rank-1 Schur complement of the
eliminated height,

    H = H_xx - u u^T / h,   u = d2phi/dx do = -H e,   h = d2phi/do2,

given as a low-rank part (low_rank: (dofs, u, -1 / h)), with the terms' exact or PSD blocks as the solver asks. A
grip whose friction cannot carry W has no minimum: phi falls without bound as the object slides down. The object
slips where the inner solve finds no root of dphi/do within SLIP_LIMIT dhat of its height at the last equilibrium
(a slide of more than that in one increment: out of the grip, or into a new hold farther down); the energy is then
infinite, so that the increment finds no equilibrium and the ramp stops, saying that the object slips (fault).
"""

from __future__ import annotations

import math

import numpy as np

from .base import Term

INNER_ITERATIONS = 50
INNER_TOLERANCE = 1e-10  # |dphi/do| against W (and the contact forces' sum)
SLIP_LIMIT = 10.0  # the object slips where it would move this many times its dhat in one increment


class HeldObject(Term):
    """The release of an obstacle (its contact term `contact`, friction term `friction` or None) at step `release`,
    with load W along -y: the model's energy its contact's minimised over its height (module docstring)."""

    reports_contact = False

    def __init__(self, contact, friction, weight: float, release: int, edges: list | None = None):
        """edges: the obstacle's barrier on the sides and faces of the body (terms/obstacle_edges.py), if any."""
        self.contact, self.friction, self.edges = contact, friction, list(edges or [])
        self.config = contact.config
        self.name = f"{contact.name}.weight"
        self.weight, self.release = float(weight), int(release)
        self.step = 0  # the step being solved: the number of increments done (advance calls)
        self.axis = 1  # y
        self.slipped = False
        self.slips = 0
        self.settled = self._height()
        self._state: np.ndarray | None = None
        self._low_rank: list = []

    @property
    def free(self) -> bool:
        return self.step >= self.release

    @property
    def terms(self) -> list:
        return [t for t in (self.contact, *self.edges, self.friction) if t is not None]

    def advance(self, u: np.ndarray) -> None:
        self.step += 1
        self.settled = self._height()  # the height at the last equilibrium
        self.slips = 0  # inner solves that slipped in the increment being solved
        self._state = None  # released now, perhaps: solve again at the same state

    def follow(self) -> None:
        """At a new state: the inner solve where the object is free (before any term is evaluated there), from its
        last height or, where a node lies inside the object there (a state nearer the last equilibrium, as after
        a cut-back), from its height at the last equilibrium."""
        u = self.config.u
        if self._state is not None and np.array_equal(self._state, u):
            return
        self._state = u.copy()
        if not self.free:
            return
        if not math.isfinite(self._phi()):
            self._set_height(self.settled)
            if not math.isfinite(self._phi()):  # inside at both: the contact's energy is infinite, the state refused
                return
        self.inner_solve()

    def _height(self) -> float:
        return float(self.contact.offset[self.axis])

    def _set_height(self, height: float) -> None:
        offset = self.contact.offset.copy()
        offset[self.axis] = height
        self.contact.set_offset(offset)

    def _phi(self) -> float:
        return sum(t.energy() for t in self.terms) + self.weight * self._height()

    def _slope(self) -> tuple[float, float]:
        """(dphi/do, its scale: W plus the sum of the nodes' forces along y) at the current height."""
        along = np.sum([t.gradient()[:, self.axis] for t in self.terms], axis=0)
        return self.weight - float(along.sum()), self.weight + float(np.abs(along).sum())

    def _column(self, psd_only: bool) -> tuple[np.ndarray, np.ndarray]:
        """(dofs, H e): the terms' Hessians (of this flavour) times e, the unit motion of every node along y, on the
        dofs where it is not zero."""
        d = self.config.dim
        column = np.zeros(self.config.u.size)
        for term in self.terms:
            values = term.hessian_values(psd_only)
            rows, cols = term.hessian_pattern()
            along = cols % d == self.axis
            column += np.bincount(rows[along], values[along], minlength=column.size)
        dofs = np.flatnonzero(column)
        return dofs, column[dofs]

    def inner_solve(self) -> None:
        """Move the object to o*(x) (module docstring): Newton on o, each step kept short of the contact and
        backtracked until phi decreases; where that finds no root within SLIP_LIMIT dhat of its height at the last
        equilibrium (the grip cannot carry the load) or stalls off one, the object is put back and marked slipped."""
        start = self._height()
        reach = SLIP_LIMIT * self.contact.dhat
        self.slipped = True
        for _ in range(INNER_ITERATIONS):
            slope, scale = self._slope()
            if abs(slope) <= INNER_TOLERANCE * scale:
                self.slipped = False
                return
            dofs, column = self._column(False)
            curvature = float(column[dofs % self.config.dim == self.axis].sum())
            step = -slope / curvature if curvature > 0 else -math.copysign(reach, slope)
            step = max(-reach, min(reach, step))  # no farther than a slip in one Newton step
            here, phi = self._height(), self._phi()
            alpha = min(1.0, 0.9 * self._step_bound(step))
            while alpha > 1e-12:
                self._set_height(here + alpha * step)
                trial = self._phi()
                if trial <= phi + 1e-4 * alpha * step * slope or (
                    math.isfinite(trial) and abs(self._slope()[0]) <= (1 - 1e-4 * alpha) * abs(slope)
                ):  # phi decreases, or (its change lost in round-off near the minimum) its slope does
                    break
                alpha *= 0.5
            else:  # no decrease along the slope: round-off at the minimum, or nothing holds it
                self._set_height(here)
                self.slipped = abs(slope) > 1e-6 * scale
                break
            if abs(self._height() - self.settled) > reach:
                break
        if self.slipped:
            self.slips += 1
            self._set_height(start)

    def _step_bound(self, step: float) -> float:
        """The largest fraction of a height change `step` before the body reaches the object (the body moving by
        -step along y relative to it): its nodes, and the sides and faces of its surface."""
        dx = np.zeros_like(self.config.u)
        dx[:, self.axis] = -step
        return min(term.max_step(dx) for term in (self.contact, *self.edges))

    def energy(self) -> float:
        self.follow()
        if self.slipped:
            return math.inf
        return self.weight * self._height() if self.free else 0.0

    def gradient(self) -> np.ndarray:
        self.follow()
        return np.zeros_like(self.config.u)

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        """None of its own; the Schur complement of the height, from the terms' blocks of this flavour, is kept
        for low_rank."""
        self.follow()
        self._low_rank = []
        if self.free:
            dofs, column = self._column(psd_only)
            curvature = float(column[dofs % self.config.dim == self.axis].sum())
            if curvature > 0:
                self._low_rank = [(dofs, -column, -1.0 / curvature)]
        return np.zeros(0)

    def columns(self) -> dict[str, float]:
        """'<obstacle>.dy': its height from where it was placed."""
        return {f"{self.contact.name}.dy": self._height()}

    def low_rank(self) -> list:
        return self._low_rank

    def fault(self) -> str | None:
        """That the object slips out of the grip, where it did at a state of the increment being solved."""
        if not (self.free and self.slips):
            return None
        friction = self.friction
        held = 0.0 if friction is None else friction.mu * float(friction.lagged[:, 0].sum())
        return (
            f"{self.contact.name!r} slips out of the grip (it would slide more than {SLIP_LIMIT:g} dhat = "
            f"{SLIP_LIMIT * self.contact.dhat:.4g} in the increment): its weight {self.weight:.4g} is more than the "
            f"grip holds (the friction mu N = {held:.4g}, with the normal forces' own lift)"
        )
