"""Coulomb friction (terms/friction.py): the term's derivatives against finite differences in the sticking (slip <
eps) and sliding (slip > eps) regimes, 2D and 3D; a block on an inclined plane that sticks below tan(theta) = mu
and slides above it; a frictionless scene building no friction term; bad keys refused."""

import math

import numpy as np
import pytest
from test_obstacles import assembled, contact, finite_differences

from taichi_pneuma.terms.friction import ObstacleFriction, frictional
from taichi_pneuma.terms.obstacle_shapes import Plane, Sphere

EPS = 0.01
SHAPES = {  # by dimension: a 2D scene's shape in its plane (a normal with no z)
    "plane": lambda dim: Plane((0.0, 0.0, 0.0)[:dim], (1.0, 2.0, 0.5)[:dim]),
    "sphere": lambda dim: Sphere((0.0, 0.0, 0.0)[:dim], 1.0),
}
NEAR = {"plane": [(0.1, 0.1, 0.05), (0.3, -0.05, 0.0)], "sphere": [(1.2, 0.1, 0.05), (-0.3, 1.0, 0.4)]}


def friction_on(points, shape, mu=0.6, eps=EPS):
    """A friction term on free points lagged at rest (each within dhat = 0.5 of the shape: lambda > 0)."""
    return ObstacleFriction(contact(points, shape), mu, eps)


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("name", list(SHAPES))
@pytest.mark.parametrize("slip", [0.3 * EPS, 3.0 * EPS], ids=["sticking", "sliding"])
def test_friction_gradient_and_hessian_match_finite_differences(name, dim, slip):
    """Energy -> gradient and gradient -> Hessian on nodes moved by `slip` along the tangent plane (and half that
    along the normal) from their lagged positions, the obstacle moved since the lag (its translation subtracted);
    the Hessian is PSD, psd_only the same; the force is tangential, mu lambda where sliding."""
    points = np.array(NEAR[name])[:, :dim]
    term = friction_on(points, SHAPES[name](dim))
    assert np.all(term.lagged[:, 0] > 0)  # every node in contact
    term.contact.set_offset(np.full(dim, 0.1 * EPS))
    n = term.lagged[:, 1 : 1 + dim]
    direction = np.random.default_rng(2).standard_normal(points.shape)
    along = direction - np.sum(direction * n, axis=1, keepdims=True) * n
    u = slip * along / np.linalg.norm(along, axis=1, keepdims=True) + 0.5 * slip * n  # the normal part is free
    term.config.u[:] = u
    g_fd, h_fd = finite_differences(term, u)
    g = term.gradient().ravel()
    assert np.linalg.norm(g) > 0.1
    assert np.linalg.norm(g - g_fd) <= 1e-6 * np.linalg.norm(g)
    hessian, scale = assembled(term), np.linalg.norm(g) / slip  # scale: the size of mu lambda f1(y) / y
    assert np.linalg.norm(hessian - h_fd) <= 1e-5 * scale
    assert np.linalg.eigvalsh(hessian).min() >= -1e-12 * scale
    if dim == 2 and slip > EPS:  # a 1D tangent: kinetic friction, a constant force, has no stiffness
        assert np.linalg.norm(hessian) <= 1e-12 * scale
    assert np.array_equal(assembled(term, psd_only=True), hessian)
    lam, force = term.lagged[:, 0], -term.gradient()
    assert np.abs(np.sum(force * n, axis=1)) == pytest.approx(0.0, abs=1e-12)  # tangential
    if slip > EPS:
        assert np.linalg.norm(force, axis=1) == pytest.approx(term.mu * lam, rel=1e-12)


def test_the_smoothed_friction_force_rises_to_mu_lambda_over_eps():
    """One node on the plane y >= 0 slipping y along x: force mu lambda (2 y / eps - y^2 / eps^2) below eps, mu
    lambda beyond; energy mu lambda f0(y) (eps / 3 at 0, C1 at eps)."""
    term = friction_on([(0.0, 0.2)], Plane((0.0, 0.0), (0.0, 1.0)), mu=0.5)
    lam = term.lagged[0, 0]
    for y, f1, f0 in ((0.0, 0.0, EPS / 3), (0.5 * EPS, 0.75, EPS * (1 / 3 + 1 / 4 - 1 / 24)), (2 * EPS, 1.0, 2 * EPS)):
        term.config.u[:] = [[y, 0.3]]  # the normal motion is free
        assert -term.gradient()[0] == pytest.approx([-0.5 * lam * f1, 0.0], abs=1e-12)
        assert term.energy() == pytest.approx(0.5 * lam * f0, rel=1e-12)


def test_no_friction_no_term():
    """friction = 0 adds no term: the contact alone."""
    term = contact([(0.0, 0.2)], Plane((0.0, 0.0), (0.0, 1.0)))
    assert frictional(term, 0.0, None) == [term]
    pair = frictional(term, 0.4, None)
    assert pair[0] is term and pair[1].eps == pytest.approx(term.dhat / 10) and pair[1].name == "o.friction"
    assert math.isfinite(pair[1].energy())
