"""Rigid obstacles: the shapes' signed distances against closed forms, the contact term's derivatives against finite
differences, its step bound against hand-computed hit times, and in runs: the clamp's reaction balancing the
contact and the loads, a moving obstacle pushing the tip, and bad input refused."""

import math

import numpy as np
import pytest

from taichi_pneuma import runtime
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.terms.model import Configuration
from taichi_pneuma.terms.obstacles import Box, Capsule, Cylinder, Obstacle, ObstacleContact, Plane, Sphere

H = 1e-6


def contact(points, shape, dhat=0.5, stiffness=10.0):
    """An obstacle term on free points (rest = the points, u = 0)."""
    runtime.ensure_initialised()
    config = Configuration(np.asarray(points, dtype=float))
    return ObstacleContact(config, np.arange(len(points)), shape, "o", dhat, stiffness)


def distances(points, shape):
    """The signed distance of each point (one term per point: nearest() of one vertex)."""
    return [contact([p], shape).nearest() for p in points]


def test_signed_distances_match_closed_forms():
    """Hand-computed distances: outside each shape on faces, edges, corners, rims and ends, and inside."""
    plane = Plane((0.0, 1.0), (0.0, 2.0))  # y >= 1
    assert distances([(3.0, 1.5), (0.0, 0.25)], plane) == pytest.approx([0.5, -0.75])
    sphere = Sphere((1.0, 0.0, 0.0), 0.5)
    assert distances([(4.0, 4.0, 0.0), (1.0, 0.1, 0.0)], sphere) == pytest.approx([4.5, -0.4])
    box = Box((0.0, 0.0, 0.0), (2.0, 4.0, 6.0))  # half sizes 1, 2, 3
    face, edge, corner, inside = (1.5, 0.0, 0.0), (2.0, 3.0, 0.0), (2.0, 4.0, 5.0), (0.5, 0.0, 0.0)
    assert distances([face, edge, corner, inside], box) == pytest.approx([0.5, math.sqrt(2), 3.0, -0.5])
    assert distances([(0.0, 3.0)], Box((0.0, 0.0), (2.0, 4.0))) == pytest.approx([1.0])  # 2D: no z extent
    cylinder = Cylinder((0.0, 0.0, 0.0), 1.0, 4.0, "x")  # |x| <= 2, y^2 + z^2 <= 1
    side, cap, rim = (0.5, 0.0, 3.0), (2.5, 0.3, 0.0), (5.0, 0.0, 5.0)
    assert distances([side, cap, rim], cylinder) == pytest.approx([2.0, 0.5, 5.0])
    assert distances([(3.0, 4.0)], Cylinder((0.0, 0.0), 1.0, 1.0, "z")) == pytest.approx([4.0])  # 2D: a circle
    capsule = Capsule((0.0, 0.0, 0.0), 0.5, 2.0, "y")  # segment y in [-1, 1]
    assert distances([(3.0, 0.5, 0.0), (0.0, 4.0, 4.0), (0.0, 1.2, 0.0)], capsule) == pytest.approx([2.5, 4.5, -0.3])


SHAPES = {
    "plane": Plane((0.0, 0.0, 0.0), (1.0, 2.0, 0.5)),
    "sphere": Sphere((0.0, 0.0, 0.0), 1.0),
    "box": Box((0.0, 0.0, 0.0), (2.0, 2.0, 2.0)),
    "cylinder": Cylinder((0.0, 0.0, 0.0), 1.0, 2.0, "y"),
    "capsule": Capsule((0.0, 0.0, 0.0), 1.0, 2.0, "z"),
}
# points within dhat = 0.5 of each shape, on every kind of closest feature (face, edge, corner; side, cap, rim; end)
NEAR = {
    "plane": [(0.1, 0.1, 0.05), (0.3, -0.05, 0.0)],
    "sphere": [(1.2, 0.1, 0.05), (-0.3, 1.0, 0.4)],
    "box": [(1.2, 0.3, -0.2), (1.15, 1.2, 0.4), (-1.1, 1.25, -1.2)],
    "cylinder": [(1.1, 0.3, 0.4), (0.2, 1.3, -0.1), (0.95, -1.2, 0.5)],
    "capsule": [(1.2, 0.1, 0.4), (0.3, -0.4, 1.9)],
}


def finite_differences(term, u):
    """The central-difference gradient of the energy and Hessian (from the gradient) at u."""
    n = u.size
    g, columns = np.zeros(n), []
    for i in range(n):
        step = np.zeros(n)
        step[i] = H
        term.config.u[:] = (u.ravel() + step).reshape(u.shape)
        e_plus, g_plus = term.energy(), term.gradient().ravel()
        term.config.u[:] = (u.ravel() - step).reshape(u.shape)
        g[i] = (e_plus - term.energy()) / (2 * H)
        columns.append((g_plus - term.gradient().ravel()) / (2 * H))
    term.config.u[:] = u
    return g, np.array(columns).T


def assembled(term, psd_only=False):
    n = term.config.u.size
    matrix = np.zeros((n, n))
    np.add.at(matrix, term.hessian_pattern(), term.hessian_values(psd_only))
    return matrix


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("name", list(SHAPES))
def test_gradient_and_exact_hessian_match_finite_differences(name, dim):
    """Energy -> gradient and gradient -> exact Hessian (b'' n n^T + b' Hess d) on nodes within dhat of each shape
    (2D: the same shapes at z = 0); the PSD Hessian is positive semi-definite."""
    points = np.array(NEAR[name])[:, :dim]
    if dim == 2:
        points = np.array([p for p in points if 0 < distances([p], SHAPES[name])[0] < 0.5])
    term = contact(points, SHAPES[name])
    u = 0.01 * np.random.default_rng(1).standard_normal(points.shape)
    term.config.u[:] = u
    g_fd, h_fd = finite_differences(term, u)
    g = term.gradient().ravel()
    assert np.linalg.norm(g) > 1.0  # the contact is active
    assert np.linalg.norm(g - g_fd) <= 1e-6 * np.linalg.norm(g)
    hessian = assembled(term)
    assert np.linalg.norm(hessian - h_fd) <= 1e-5 * np.linalg.norm(hessian)
    assert np.linalg.eigvalsh(assembled(term, psd_only=True)).min() >= -1e-9 * np.linalg.norm(hessian)


@pytest.mark.parametrize(
    ("shape", "start", "direction", "hit"),
    [
        (Plane((0.0, -1.0), (0.0, 1.0)), (0.3, 0.5), (0.5, -3.0), 0.5),  # y = 0.5 - 3 t reaches -1 at t = 0.5
        (Sphere((2.0, 0.0), 1.0), (-1.0, 0.0), (1.0, 0.0), 2.0),  # x = -1 + t reaches 1 at t = 2
        (Sphere((0.0, 0.0, 0.0), 1.0), (0.6, -3.0, 0.0), (0.0, 1.0, 0.0), 2.2),  # y = -0.8 on the sphere
        (Box((0.0, 0.0), (2.0, 1.0)), (3.0, 0.2), (-4.0, 0.0), 0.5),  # x = 3 - 4 t reaches 1 at t = 0.5
        (Box((0.0, 0.0, 0.0), (2.0, 2.0, 2.0)), (3.0, 2.5, 0.3), (-1.0, -1.0, 0.0), 2.0),  # the face x = 1 at y = 0.5
    ],
    ids=["plane", "circle", "sphere-offset", "box", "box-3d"],
)
def test_max_step_stops_a_node_just_before_the_surface(shape, start, direction, hit):
    """A node moving straight at a shape: max_step within 1e-3 of the hand-computed hit time, never past it."""
    term = contact([start], shape)
    alpha = term.max_step(np.array([direction], dtype=float))
    assert hit * (1 - 1e-3) <= alpha <= hit
    assert term.max_step(-np.array([direction], dtype=float)) == math.inf  # moving away
