"""Surface contact (terms/surface_contact.py, ipctk's IPC barriers between pieces of the body's surface): its
derivatives against finite differences, its PSD Hessian, its continuous collision step bound, and whole runs in
which walls press on each other without crossing (fem/self_intersection.py surface_crossing, written independently
of ipctk, checks every state)."""

import numpy as np
import pytest

import taichi_pneuma as tp
from taichi_pneuma.fem.self_intersection import surface_crossing
from taichi_pneuma.terms.model import Configuration

ipctk = pytest.importorskip("ipctk")
from taichi_pneuma.terms.surface_contact import SurfaceContact, SurfaceFriction  # noqa: E402

DHAT = 0.1


def facing_pieces(dim: int):
    """Two pieces 0.05 apart (half of DHAT) that share no node: triangles in 3D (a corner of one above the face of
    the other, an edge of each crossing the other's above it), segments in 2D (a point above the other's middle);
    as (rest (n, d), pieces (2, 3))."""
    if dim == 3:
        rest = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.3, 0.3, 0.05], [0.2, 0.9, 0.8], [0.9, 0.1, 0.6]])
        return rest.astype(float), np.array([[0, 1, 2], [3, 4, 5]])
    rest = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, 0.05], [0.6, 0.9]])
    return rest, np.array([[0, 1, 1], [2, 3, 3]])


def term_at(dim: int, seed: int = 0):
    rest, pieces = facing_pieces(dim)
    config = Configuration(rest)
    term = SurfaceContact(config, pieces, DHAT, 10.0)
    u = 0.01 * np.random.default_rng(seed).standard_normal(rest.shape)
    config.u[:] = u
    return config, term, u


def at(config, term, u, what):
    config.u[:] = u
    return what()


def assembled(term, u: np.ndarray, psd_only: bool = False) -> np.ndarray:
    """The term's Hessian (u.size, u.size) at its state, dense."""
    values = term.hessian_values(psd_only)
    hessian = np.zeros((u.size, u.size))
    np.add.at(hessian, term.hessian_pattern(), values)
    return hessian


def derivatives_match(config, term, u: np.ndarray) -> None:
    """The term's gradient against central differences of its energy, its Hessian against those of its gradient."""
    config.u[:] = u
    g, hessian = term.gradient().ravel(), assembled(term, u)
    h = 1e-6
    g_fd, h_fd = np.zeros(u.size), np.zeros((u.size, u.size))
    for i in range(u.size):
        step = np.zeros(u.size)
        step[i] = h
        plus, minus = ((u.ravel() + s * step).reshape(u.shape) for s in (1, -1))
        g_fd[i] = (at(config, term, plus, term.energy) - at(config, term, minus, term.energy)) / (2 * h)
        h_fd[:, i] = (at(config, term, plus, term.gradient) - at(config, term, minus, term.gradient)).ravel() / (2 * h)
    assert np.linalg.norm(g) > 0
    assert np.linalg.norm(g - g_fd) <= 1e-6 * np.linalg.norm(g)
    # (+ a floor under round-off for a Hessian that vanishes: 2D kinetic friction's, f1 constant along the slip)
    assert np.linalg.norm(hessian - h_fd) <= 1e-5 * np.linalg.norm(hessian) + 1e-6 * np.linalg.norm(g)


@pytest.mark.parametrize("dim", [2, 3])
def test_gradient_and_hessian_match_finite_differences(dim):
    config, term, u = term_at(dim)
    assert term.pairs() > 0 and 0 < term.min_distance() < DHAT  # the barrier is active
    derivatives_match(config, term, u)


@pytest.mark.parametrize("slip", [0.3, 3.0], ids=["sticking", "sliding"])
@pytest.mark.parametrize("dim", [2, 3])
def test_friction_between_pieces_matches_finite_differences(dim, slip):
    """Friction lagged at a state in contact, then the upper piece moved along the lower one by slip times eps
    (below eps: the static branch; past it: kinetic): its gradient and Hessian against finite differences, and when
    sliding its force is mu times the lagged normal force."""
    config, contact, u = term_at(dim)
    eps, mu = 1e-3, 0.5
    friction = SurfaceFriction(contact, mu, eps)
    rest, pieces = facing_pieces(dim)
    moved = u.copy()
    moved[np.unique(pieces[1]), 0] += slip * eps
    derivatives_match(config, friction, moved)
    config.u[:] = moved
    upper = np.unique(pieces[1])
    force = np.linalg.norm(friction.gradient()[upper].sum(axis=0))  # the friction force on the upper piece
    config.u[:] = u
    normal = np.linalg.norm(contact.gradient()[upper].sum(axis=0))  # the lagged normal force on it
    assert force <= mu * normal * (1 + 1e-9)
    if slip > 1:
        assert force == pytest.approx(mu * normal, rel=1e-9)


@pytest.mark.parametrize("dim", [2, 3])
def test_psd_hessian_has_no_negative_eigenvalue(dim):
    config, term, u = term_at(dim, seed=1)
    eigenvalues = np.linalg.eigvalsh(assembled(term, u, psd_only=True))
    assert eigenvalues.max() > 0 and eigenvalues.min() >= -1e-9 * eigenvalues.max()


@pytest.mark.parametrize("dim", [2, 3])
def test_step_bound_stops_short_of_the_crossing(dim):
    """Pushing the upper piece straight through the lower one: the bound lies before the crossing (which a step of
    0.05 / 0.2 = 0.25 of dx reaches) and the state at the bound is apart, by the independent crossing test."""
    rest, pieces = facing_pieces(dim)
    config = Configuration(rest)
    term = SurfaceContact(config, pieces, DHAT, 10.0)
    dx = np.zeros_like(rest)
    upper = np.unique(pieces[1])
    dx[upper, dim - 1] = -0.2
    bound = term.max_step(dx)
    assert 0 < bound < 0.25
    assert surface_crossing(rest + bound * dx, pieces) is None
    assert surface_crossing(rest + 0.5 * dx, pieces) is not None  # the test would see a crossing


def test_a_finger_curling_onto_itself_never_crosses_itself():
    """The shipped finger_curl: with surface contact it curls 336 degrees, its base pressing on its tip, and no
    two pieces of its surface cross at any step (the crossing test, not ipctk, says so); the same scene without
    contact stops where they cross. The contact forces are internal: they press the two sides apart and sum to 0."""
    scene = tp.load_scene("finger_curl")
    result = tp.simulate(scene)
    assert len(result.steps) == scene.increments + 1
    pieces = result.built.surface_pieces
    assert all(surface_crossing(x, pieces) is None for x in result.positions)
    history = result.history
    assert history["tip_rotation"][-1] < -330.0
    pressing = history["surface_contact.magnitude"]
    assert pressing[0] == 0.0 and np.all(pressing[-3:] > 0.0) and np.all(np.diff(pressing[-3:]) > 0)
    forces = result.contact_forces[-1]
    assert np.abs(forces.sum(axis=0)).max() <= 1e-9 * np.abs(forces).sum()
    with pytest.raises(tp.RampFailed, match="passes through itself"):
        tp.simulate(scene.with_values({"effects": {}}))
