"""Every term's gradient and Hessian against central finite differences, and the chamber as a pressure load."""

import numpy as np
import pytest
import scipy.sparse as sp
from fd import dense_hessian, fd_gradient, fd_hessian, random_state

from taichi_pneuma.scene.build import reference_scene
from taichi_pneuma.solve.linsolve import FixedPattern, make_backend, solve_low_rank_updated


@pytest.fixture(scope="module")
def coarse():
    """A coarse beam (few DOFs, so dense finite differences are cheap) with the chamber commanded to 1.5x."""
    built = reference_scene(cy=0.15, chamber_points=32, max_area=0.02).build()
    built.set_commands([1.5])
    return built


@pytest.mark.parametrize("index", [0, 1, 2], ids=["elastic", "chamber", "clamp"])
def test_gradient_matches_finite_differences(coarse, index):
    model = coarse.model
    term = model.terms[index]
    u = random_state(coarse)
    model.set_displacements(u)
    g = term.gradient().ravel()
    g_fd = fd_gradient(model, term, u)
    assert np.linalg.norm(g - g_fd) / np.linalg.norm(g) < 1e-5


def test_full_hessian_matches_finite_differences(coarse):
    """The assembled Hessian with the indefinite parts kept (elastic unprojected, chamber load stiffness)."""
    model = coarse.model
    u = random_state(coarse)
    model.set_displacements(u)
    hessian = dense_hessian(model.n_dofs, model.terms, psd_only=False)
    h_fd = fd_hessian(model, model.terms, u)
    assert np.linalg.norm(hessian - h_fd) / np.linalg.norm(h_fd) < 1e-6
    assert np.allclose(hessian, hessian.T, atol=1e-9 * np.abs(hessian).max())


def test_projected_elastic_hessian_is_exact_where_no_projection_is_active(coarse):
    """Under uniform stretch (J > 1) every element's d2psi/dF2 is PSD, so projecting changes nothing."""
    model = coarse.model
    elastic = coarse.elastic
    u = 0.05 * coarse.mesh.vertices
    model.set_displacements(u)
    hessian = dense_hessian(model.n_dofs, [elastic], psd_only=True)
    h_fd = fd_hessian(model, [elastic], u)
    assert np.linalg.norm(hessian - h_fd) / np.linalg.norm(h_fd) < 1e-6


def test_projected_hessian_is_psd_and_differs_under_compression(coarse):
    model = coarse.model
    u = random_state(coarse, scale=0.03, seed=1)
    model.set_displacements(u)
    projected = dense_hessian(model.n_dofs, model.terms, psd_only=True)
    exact = dense_hessian(model.n_dofs, model.terms, psd_only=False)
    eigenvalues = np.linalg.eigvalsh(projected)
    assert eigenvalues.min() > -1e-9 * eigenvalues.max()
    assert np.linalg.eigvalsh(exact).min() < -1e-6 * eigenvalues.max()  # so the projection did something


def test_chamber_force_is_a_pressure_load():
    """For the centred chamber the net chamber force vanishes at any state: a closed loop's normals sum to zero."""
    built = reference_scene(cy=0.0, chamber_points=32, max_area=0.02).build()
    built.set_commands([2.0])
    chamber = built.chambers[0]
    for seed in range(3):
        built.model.set_displacements(random_state(built, seed=seed))
        force = -chamber.gradient()
        assert np.abs(force.sum(axis=0)).max() < 1e-12 * np.abs(force).sum()
        # and it is the pressure times the wall's area gradient, pushing outward (p > 0 when A < A*)
        assert chamber.pressure() > 0


def test_rest_area_and_pressure_sign():
    built = reference_scene().build()
    chamber = built.chambers[0]
    assert chamber.rest_area == pytest.approx(0.587, abs=5e-4)
    built.model.set_displacements(np.zeros_like(built.mesh.vertices))
    assert chamber.area() == pytest.approx(chamber.rest_area, rel=1e-14)
    built.set_commands([1.1])
    assert chamber.pressure() == pytest.approx(1e5 * 0.1 * chamber.rest_area)


def test_fixed_pattern_and_woodbury_solve(coarse):
    model = coarse.model
    model.set_displacements(0.05 * coarse.mesh.vertices)
    rows, cols = model.hessian_pattern()
    pattern = FixedPattern(rows, cols, model.n_dofs)
    values = model.hessian_values(psd_only=True)
    sparse = pattern.matrix(values)
    reference = sp.coo_matrix((values, (rows, cols)), shape=sparse.shape).toarray()
    assert np.array_equal(sparse.toarray(), reference)
    backend = make_backend("scipy")
    backend.factorize(sparse)
    rhs = np.random.default_rng(2).standard_normal(model.n_dofs)
    d = solve_low_rank_updated(backend, rhs, model.low_rank())
    dense = dense_hessian(model.n_dofs, model.terms, psd_only=True)
    assert np.linalg.norm(dense @ d - rhs) < 1e-8 * np.linalg.norm(rhs)


def assert_max_step_stops_before_inversion(built):
    """A random step: at 0.999 of max_step no element is inverted anywhere, at 1.001 one is."""
    elastic = built.elastic
    built.model.set_displacements(np.zeros_like(built.mesh.vertices))
    dx = 0.2 * np.random.default_rng(3).standard_normal(built.mesh.vertices.shape)
    alpha = elastic.max_step(dx)
    assert 0 < alpha < np.inf
    built.model.set_displacements(0.999 * alpha * dx)
    assert elastic.min_determinant() > 0
    built.model.set_displacements(1.001 * alpha * dx)
    assert elastic.min_determinant() < 0


def assert_gradient_matches_finite_differences(built, name, u):
    term = next(t for t in built.model.terms if t.name == name)
    built.model.set_displacements(u)
    g = term.gradient().ravel()
    assert np.linalg.norm(g) > 0
    assert np.linalg.norm(g - fd_gradient(built.model, term, u)) / np.linalg.norm(g) < 1e-5


def test_max_step_stops_before_inversion(coarse):
    assert_max_step_stops_before_inversion(coarse)


def test_projected_element_blocks_equal_eigen_clamped_blocks(coarse):
    """The analytic eigensystem of d2psi/dF2 against NumPy's eigh: W D^T [M]_+ D per quadrature point, M
    built from the formula in NumPy, its negative eigenvalues clamped; under a random, partly compressive state."""
    elastic = coarse.elastic
    u = random_state(coarse, scale=0.05, seed=4)
    coarse.model.set_displacements(u)
    x = coarse.mesh.vertices + u
    G = elastic.grads[:, 0]  # (m, k, 2) dN_a/dX at the one quadrature point of each linear triangle
    F = np.einsum("qai,qaj->qij", x[elastic.nodes], G)
    J = np.linalg.det(F)
    w, (mu, lam) = elastic.weights[:, 0], elastic.parameters.T
    g = np.stack([F[:, 1, 1], -F[:, 1, 0], -F[:, 0, 1], F[:, 0, 0]], axis=1)
    hj = np.array([[0, 0, 0, 1], [0, 0, -1, 0], [0, -1, 0, 0], [1, 0, 0, 0]], dtype=float)
    M = (
        mu[:, None, None] * np.eye(4)
        + lam[:, None, None] * g[:, :, None] * g[:, None, :]
        - (mu + lam * (1 - J))[:, None, None] * hj
    )
    values, vectors = np.linalg.eigh(M)
    assert (values < 0).any(axis=1).mean() > 0.5  # most elements need the projection
    clamped = vectors @ (np.maximum(values, 0)[:, :, None] * vectors.transpose(0, 2, 1))
    k = G.shape[1]
    D = np.zeros((len(G), 4, 2 * k))  # D[2i + j, 2a + i] = G[a, j]: dvec(F)/dx
    for i in range(2):
        for j in range(2):
            D[:, 2 * i + j, i::2] = G[:, :, j]
    for psd_only, inner in ((True, clamped), (False, M)):
        expected = w[:, None, None] * D.transpose(0, 2, 1) @ inner @ D
        blocks = elastic.hessian_values(psd_only).reshape(-1, 2 * k, 2 * k)
        assert np.abs(blocks - expected).max() < 1e-9 * np.abs(expected).max()
