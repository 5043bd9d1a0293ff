"""The linear-solver backends agree with each other on the Newton matrices, and the Cholesky ones refuse indefinite
ones."""

import numpy as np
import pytest
import scipy.sparse as sp

from taichi_pneuma.scene.build import reference_scene
from taichi_pneuma.solve.linsolve import BACKENDS, FactorizationError, FixedPattern, make_backend
from taichi_pneuma.solve.newton import NewtonOptions
from taichi_pneuma.solve.simulate import run_schedule


@pytest.fixture(scope="module")
def hessian():
    built = reference_scene(cy=0.15, max_area=0.01).build()
    built.model.set_displacements(0.05 * built.mesh.vertices)
    rows, cols = built.model.hessian_pattern()
    return FixedPattern(rows, cols, built.model.n_dofs).matrix(built.model.hessian_values(psd_only=True))


@pytest.mark.parametrize("name", sorted(BACKENDS))
def test_backend_matches_scipy_dense(hessian, name):
    rhs = np.random.default_rng(0).standard_normal((hessian.shape[0], 2))
    backend = make_backend(name)
    for scale in (1.0, 2.0):  # a second factorisation on the same pattern (reused symbolic analysis)
        backend.factorize((scale * hessian).tocsr())
        x = backend.solve(rhs)
        assert np.linalg.norm(scale * hessian @ x - rhs) < 1e-9 * np.linalg.norm(rhs)
        assert np.allclose(x, np.linalg.solve(scale * hessian.toarray(), rhs), rtol=1e-8, atol=1e-12)


@pytest.mark.parametrize("name", ["cholespy", "taichi"])
def test_cholesky_backends_refuse_indefinite(name):
    indefinite = sp.csr_matrix(np.array([[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]]))
    with pytest.raises(FactorizationError):
        make_backend(name).factorize(indefinite)


def test_ramp_is_the_same_with_every_backend():
    tips = []
    for name in sorted(BACKENDS):
        built = reference_scene(cy=0.15, growth=1.5, steps=3, max_area=0.01).build()
        result = run_schedule(built, options=NewtonOptions(linear_solver=name, tol=1e-9))
        assert all(s.converged for s in result.steps)
        tips.append(result.positions[-1])
    for state in tips[1:]:
        assert np.abs(state - tips[0]).max() < 1e-9
