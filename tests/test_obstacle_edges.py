"""The barrier between an obstacle's features and the sides and faces of the body's surface
(terms/obstacle_edges.py): its derivatives against finite differences for every shape that has one, 2D and 3D, and
its step bound against the first contact found independently (points sampled on the pieces against the shapes'
definitions). A whole run with a disc pressed between two nodes: tests/test_obstacles.py."""

import math

import numpy as np
import pytest

from taichi_pneuma.terms.model import Configuration
from taichi_pneuma.terms.obstacle_edges import ObstacleEdges
from taichi_pneuma.terms.obstacle_shapes import Box, Capsule, Cylinder, Sphere
from taichi_pneuma.terms.obstacles import ObstacleContact

DHAT = 0.1
FLOOR_3D = np.array([[0, 0, 0], [1, 0, 0], [0, 0, 1], [1, 0, 1]], dtype=float), np.array([[0, 1, 2], [1, 3, 2]])
FLOOR_2D = np.array([[0, 0], [1, 0], [2, 0.1]], dtype=float), np.array([[0, 1, 1], [1, 2, 2]])
SHAPES = {  # each just below the floor, nearer it than DHAT between its nodes (their first contact inside a piece)
    "sphere 3D": (FLOOR_3D, Sphere((0.4, -1.05, 0.3), 1.0)),
    "capsule 3D": (FLOOR_3D, Capsule((0.4, -1.05, 0.3), 1.0, 2.0, "x")),
    "box 3D": (FLOOR_3D, Box((0.4, -0.55, 0.45), (0.3, 1.0, 5.0))),
    "disc 2D": (FLOOR_2D, Sphere((0.4, -1.05), 1.0)),
    "capsule 2D": (FLOOR_2D, Capsule((1.1, -0.45), 0.2, 0.4, "y")),
    "rectangle 2D": (FLOOR_2D, Box((0.5, -0.55), (0.3, 1.0))),
    "cylinder 2D": (FLOOR_2D, Cylinder((0.5, -0.55), 0.15, 1.0, "y")),
}


def term_of(case: str, seed: int = 0):
    (rest, pieces), shape = SHAPES[case]
    config = Configuration(rest)
    contact = ObstacleContact(config, np.arange(len(rest)), shape, "o", DHAT, 10.0, pieces)
    ipctk = pytest.importorskip("ipctk") if rest.shape[1] == 3 else None
    term = ObstacleEdges(contact, pieces, ipctk)
    config.u[:] = 0.003 * np.random.default_rng(seed).standard_normal(rest.shape)
    return config, contact, term


def assembled(term, size: int) -> np.ndarray:
    values = term.hessian_values()
    hessian = np.zeros((size, size))
    np.add.at(hessian, term.hessian_pattern(), values)
    return hessian


@pytest.mark.parametrize("case", SHAPES)
def test_gradient_and_hessian_match_finite_differences(case):
    config, contact, term = term_of(case)
    u = config.u.copy()
    assert 0 < term.min_gap() < DHAT and term.min_gap() < contact.nearest()  # nearer between the nodes
    g, hessian = term.gradient().ravel(), assembled(term, u.size)
    h = 1e-6
    g_fd, h_fd = np.zeros(u.size), np.zeros((u.size, u.size))
    for i in range(u.size):
        step = np.zeros(u.size)
        step[i] = h
        ends = []
        for sign in (1, -1):
            config.u[:] = (u.ravel() + sign * step).reshape(u.shape)
            ends.append((term.energy(), term.gradient().ravel()))
        g_fd[i] = (ends[0][0] - ends[1][0]) / (2 * h)
        h_fd[:, i] = (ends[0][1] - ends[1][1]) / (2 * h)
    config.u[:] = u
    assert np.linalg.norm(g) > 0
    assert np.linalg.norm(g - g_fd) <= 1e-6 * np.linalg.norm(g)
    assert np.linalg.norm(hessian - h_fd) <= 1e-5 * np.linalg.norm(hessian)
    psd = np.zeros_like(hessian)
    np.add.at(psd, term.hessian_pattern(), term.hessian_values(psd_only=True))
    assert np.linalg.eigvalsh(psd).min() >= -1e-9 * np.abs(psd).max()


def inside(shape, points: np.ndarray) -> np.ndarray:
    """Whether each point (k, d) lies in the shape (closed), from its definition (not the project's distances)."""
    x = np.pad(points, ((0, 0), (0, 3 - points.shape[1])))
    c = np.array(tuple(shape.center) + (0.0,) * (3 - len(shape.center)))
    if isinstance(shape, Box):
        half = np.array(tuple(shape.size) + (np.inf,) * (3 - len(shape.size))) / 2
        return np.all(np.abs(x - c) <= half, axis=1)
    if isinstance(shape, Sphere):
        return np.linalg.norm(x - c, axis=1) <= shape.radius
    a = np.eye(3)["xyz".index(shape.axis)]
    t = (x - c) @ a
    if isinstance(shape, Capsule):
        nearest = np.clip(t, -shape.length / 2, shape.length / 2)[:, None] * a
        return np.linalg.norm(x - c - nearest, axis=1) <= shape.radius
    radial = np.linalg.norm(x - c - t[:, None] * a, axis=1)
    return (radial <= shape.radius) & (np.abs(t) <= shape.length / 2)


def samples(corners: np.ndarray, count: int = 80) -> np.ndarray:
    """Points on a grid over each piece (its corners (p, 3, d); a 2D segment as (a, b, b))."""
    s, t = (v.ravel() for v in np.meshgrid(np.linspace(0, 1, count), np.linspace(0, 1, count), indexing="ij"))
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    points = a[:, None] + s[None, :, None] * ((b - a)[:, None] + t[None, :, None] * (c - b)[:, None])
    return points.reshape(-1, corners.shape[2])


@pytest.mark.parametrize("case", SHAPES)
def test_the_step_bound_stops_short_of_the_first_contact(case):
    """The floor moved down (onto the obstacle) and sideways: the bound t (the edges' and the nodes' together) is at
    most the first time t* at which a point of a piece lies in the obstacle (bisection over points sampled on the
    pieces, against the shape's own definition) and at least 0.9 t*; a step away from it is not bounded."""
    config, contact, term = term_of(case)
    (rest, pieces), shape = SHAPES[case]
    u = config.u.copy()
    dx = np.zeros_like(u)
    dx[:, 1], dx[:, 0] = -1.0, 0.3
    bound = min(term.max_step(dx), contact.max_step(dx))
    lo, hi = 0.0, 1.0
    for _ in range(40):
        middle = 0.5 * (lo + hi)
        hit = inside(shape, samples((rest + u + middle * dx)[pieces])).any()
        lo, hi = (lo, middle) if hit else (middle, hi)
    assert 0.9 * lo <= bound <= hi
    assert term.max_step(-dx) == math.inf
