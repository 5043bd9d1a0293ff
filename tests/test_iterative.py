"""The iterative backend (CG with smoothed-aggregation multigrid) on 3D elastic systems: its near-null space, its
residual, its Newton runs against a direct solver's, and its fall-back when CG does not converge."""

import numpy as np
import pytest
import scipy.sparse as sp
from solid_meshes import box_with_cavity, scene_of

from taichi_pneuma.scene.schedule import area_ramp
from taichi_pneuma.solve import linsolve
from taichi_pneuma.solve.linsolve import (
    AMG_MIN_DOFS,
    AmgConjugateGradient,
    FixedPattern,
    NotConverged,
    make_backend,
    rigid_body_modes,
    solve_low_rank_updated,
)
from taichi_pneuma.solve.newton import FORCING_MAX, NewtonOptions, NewtonSolver, forcing_term
from taichi_pneuma.solve.simulate import run_schedule

pytest.importorskip("pyamg")  # the multigrid library, not installed where it has no wheel (Linux aarch64)


def beam(increments: int = 2):
    """The clamped 3.5 x 0.8 x 0.8 box with its closed cavity (936 tetrahedra), the cavity's volume to 1.3x."""
    return scene_of(box_with_cavity(), [area_ramp(1.3, increments + 1, 1e5)], increments).build()


def hessian_at(built, scale: float):
    """The projected Hessian, its low-rank parts and the gradient at a bent state u = scale (0, x^2, 0)."""
    model = built.model
    x = model.config.rest
    model.set_displacements(scale * np.column_stack([0 * x[:, 0], (x[:, 0] + 1.75) ** 2, 0 * x[:, 0]]))
    matrix = FixedPattern(*model.hessian_pattern(), model.n_dofs).matrix(model.hessian_values(psd_only=True))
    return matrix, model.low_rank(), model.gradient()[0]


def test_rigid_body_modes_are_the_null_space_of_a_free_elastic_hessian():
    """Without the clamp and the chamber, the elastic Hessian at rest maps the 3 translations and the 3 rotations
    to zero (to round-off against its norm), and nothing else: the modes span a 6-dimensional space."""
    built = beam()
    elastic = built.elastic
    matrix = FixedPattern(*elastic.hessian_pattern(), built.model.n_dofs).matrix(elastic.hessian_values())
    modes = rigid_body_modes(built.model.config.rest)
    assert modes.shape == (built.model.n_dofs, 6)
    assert np.linalg.matrix_rank(modes) == 6
    scale = np.abs(matrix).max() * np.abs(modes).max()
    assert np.abs(matrix @ modes).max() < 1e-9 * scale
    assert np.abs(matrix @ np.random.default_rng(1).standard_normal(built.model.n_dofs)).max() > 1e-3 * scale


@pytest.mark.parametrize("rtol", [1e-3, 1e-8])
def test_cg_reaches_its_tolerance_on_a_3d_elastic_system_with_its_chamber(rtol):
    """(S + c u u^T) x = b to the relative residual asked, checked with the full matrix (the chamber's rank-1
    part included); at 1e-8 the solution is the direct one (SciPy's LU with the Woodbury identity)."""
    built = beam()
    matrix, low_rank, g = hessian_at(built, 0.02)
    assert low_rank  # the volume-controlled chamber's rank-1 part
    backend = make_backend("amg", built.model.config.rest)
    backend.factorize(matrix)
    x = solve_low_rank_updated(backend, -g, low_rank, rtol)
    full = matrix.toarray()
    for dofs, u, c in low_rank:
        full[np.ix_(dofs, dofs)] += c * np.outer(u, u)
    assert np.linalg.norm(full @ x + g) <= 10 * rtol * np.linalg.norm(g)
    assert backend.iterations < 100
    if rtol == 1e-8:
        direct = make_backend("scipy")
        direct.factorize(matrix)
        exact = solve_low_rank_updated(direct, -g, low_rank)
        assert np.linalg.norm(x - exact) < 1e-6 * np.linalg.norm(exact)


def test_a_3d_ramp_with_cg_ends_at_the_direct_solvers_tip():
    """The volume ramp solved with CG (inexact Newton) and with SciPy's LU: the same tip to 1e-7 of its
    deflection, in no more Newton iterations (the forcing term keeps the convergence quadratic)."""
    tips, iterations = {}, {}
    for name in ("amg", "scipy"):
        result = run_schedule(beam(), options=NewtonOptions(linear_solver=name, tol=1e-9))
        assert all(step.converged for step in result.steps)
        tips[name] = result.positions[-1]
        iterations[name] = int(result.history["iterations"].sum())
    deflection = np.abs(tips["scipy"] - beam().mesh.vertices).max()
    assert deflection > 0.02
    assert np.abs(tips["amg"] - tips["scipy"]).max() < 1e-7 * deflection
    assert iterations["amg"] <= iterations["scipy"] + 1


def test_newton_falls_back_to_the_direct_backend_when_cg_does_not_converge():
    """CG allowed one iteration cannot reach the forcing term: NotConverged, and Newton's direction comes from the
    PSD Hessian factorised by the direct backend, which takes every later Hessian of the solver (CG is not tried
    again); the equilibrium is the direct solver's."""
    built = beam(1)
    matrix, low_rank, g = hessian_at(built, 0.02)
    backend = AmgConjugateGradient(built.model.config.rest)
    backend.MAX_ITERATIONS = 1
    backend.factorize(matrix)
    with pytest.raises(NotConverged, match="CG reached a relative residual"):
        backend.solve(-g, low_rank, 1e-8)
    built = beam(1)
    solver = NewtonSolver(built.model, NewtonOptions(linear_solver="amg", tol=1e-9))
    solver.backend.MAX_ITERATIONS = 1
    cg_calls = []
    factorize = solver.backend.factorize
    solver.backend.factorize = lambda matrix: cg_calls.append(1) or factorize(matrix)
    built.set_commands(np.array([1.3]))
    u, record = solver.solve(built.model.config.u)
    assert record.converged and record.psd_fallbacks >= 1 and solver.factored_by is solver.direct_backend
    assert solver.cg_failed and record.iterations > 2 and len(cg_calls) <= 2  # an exact H, then the PSD one: no more
    reference = run_schedule(beam(1), options=NewtonOptions(linear_solver="scipy", tol=1e-9)).positions[-1]
    assert np.abs(built.mesh.vertices + u - reference).max() < 1e-7


def test_a_hierarchy_built_on_an_indefinite_matrix_does_not_precondition_the_next_one():
    """An exact Hessian may be indefinite (a chamber's load stiffness at the jumped pressure of an increment's
    start): CG fails on it, and the projected Hessian that Newton takes next (the same sparsity pattern) gets a
    hierarchy of its own, not the indefinite one's, and converges (on the stale hierarchy CG ended 300
    iterations at a relative residual of 0.8)."""
    built = beam(1)
    matrix, low_rank, g = hessian_at(built, 0.02)
    shifted = matrix.copy()
    shifted.setdiag(matrix.diagonal() - 0.1 * np.median(matrix.diagonal()))
    indefinite = sp.csr_matrix((shifted.data, matrix.indices, matrix.indptr), shape=matrix.shape)
    backend = AmgConjugateGradient(built.model.config.rest)
    backend.factorize(indefinite)
    with pytest.raises(NotConverged):
        solve_low_rank_updated(backend, -g, low_rank, 1e-6)
    backend.factorize(matrix)  # the same pattern (indptr): reuse would be the default
    x = solve_low_rank_updated(backend, -g, low_rank, 1e-6)
    assert backend.iterations < 60
    direct = make_backend("scipy")
    direct.factorize(matrix)
    exact = solve_low_rank_updated(direct, -g, low_rank)
    assert np.linalg.norm(x - exact) < 1e-4 * np.linalg.norm(exact)


def test_forcing_term_tightens_with_the_residual_down_to_what_the_tolerance_needs():
    assert forcing_term(1.0, 1e-6) == FORCING_MAX
    assert forcing_term(1e-3, 1e-6) == 1e-3  # eta = r: quadratic convergence
    assert forcing_term(1e-6 * 1.5, 1e-6) == pytest.approx(0.1 / 1.5)  # near tol: only what lands below it
    for r in np.logspace(-6, 0, 13):
        eta = forcing_term(r, 1e-6)
        assert 0 < eta <= 0.1 and eta * r <= max(r * r, 0.1 * 1e-6) * 1.0000001


def test_auto_takes_cg_for_large_3d_systems_only(monkeypatch):
    assert make_backend("auto", np.zeros((AMG_MIN_DOFS, 2))).name != "amg"
    assert make_backend("auto").name != "amg"
    monkeypatch.setattr(linsolve, "installed", lambda module: module != "cvxopt")  # without CHOLMOD
    assert make_backend("auto", np.zeros((-(-AMG_MIN_DOFS // 3), 3))).name == "amg"
    assert make_backend("auto", np.zeros(((AMG_MIN_DOFS - 1) // 3, 3))).name != "amg"
