"""CHOLMOD with its symbolic analysis kept (solve/linsolve.py), the automatic choice of a linear solver, and
Newton's chord steps (solve/newton.py): each solves to the same equilibrium as a fresh factorisation."""

import numpy as np
import pytest
import scipy.sparse as sp
from solid_meshes import box_with_cavity, scene_of

from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.scene.build import Material
from taichi_pneuma.scene.schedule import ChamberSchedule
from taichi_pneuma.solve import linsolve
from taichi_pneuma.solve.linsolve import (
    DIRECT_MAX_DOFS_3D,
    FactorizationError,
    FixedPattern,
    make_backend,
    nested_dissection,
    solve_low_rank_updated,
)
from taichi_pneuma.solve.newton import NewtonOptions
from taichi_pneuma.solve.simulate import run_schedule

pytest.importorskip("cvxopt")


@pytest.fixture(scope="module")
def built():
    """The box with a cavity (quadratic tetrahedra) under a volume command to 1.6x in 4 increments."""
    scene = scene_of(box_with_cavity(order=2), [ChamberSchedule("area", ((4, 1.6),))], 4, Material(1e4, 0.45))
    return scene.build()


def hessians(built, count=2):
    """The model's pattern and its PSD Hessians at `count` random small displacements."""
    model = built.model
    pattern = FixedPattern(*model.hessian_pattern(), model.n_dofs)
    rng = np.random.default_rng(1)
    matrices = []
    for _ in range(count):
        model.set_displacements(1e-2 * rng.standard_normal(model.config.u.shape))
        matrices.append(pattern.matrix(model.hessian_parts(psd_only=True)))
    model.set_displacements(np.zeros_like(model.config.u))
    return matrices


def test_cholmod_keeps_its_analysis_and_solves_each_matrix_of_the_pattern(built):
    backend = make_backend("cholmod", built.model.config.rest)
    rhs = np.random.default_rng(0).standard_normal((built.model.n_dofs, 3))
    for matrix in hessians(built):
        backend.factorize(matrix)
        x = backend.solve(rhs)
        assert np.linalg.norm(matrix @ x - rhs) < 1e-10 * np.linalg.norm(rhs)
        assert np.allclose(backend.solve(rhs[:, 0]), x[:, 0], rtol=1e-12, atol=0)
    assert backend._indptr is matrix.indptr  # one symbolic analysis served both


def test_woodbury_with_cholmod_solves_the_rank_one_updated_system(built):
    matrix = hessians(built, 1)[0]
    backend = make_backend("cholmod", built.model.config.rest)
    backend.factorize(matrix)
    rng = np.random.default_rng(2)
    dofs = np.arange(0, built.model.n_dofs, 7)
    u, rhs = rng.standard_normal(len(dofs)), rng.standard_normal(built.model.n_dofs)
    x = solve_low_rank_updated(backend, rhs, [(dofs, u, 1e5)])
    full = matrix.toarray()
    full[np.ix_(dofs, dofs)] += 1e5 * np.outer(u, u)
    assert np.linalg.norm(full @ x - rhs) < 1e-9 * np.linalg.norm(rhs)


def test_nested_dissection_orders_every_dof_once_keeping_nodes_together(built):
    matrix = hessians(built, 1)[0]
    order = nested_dissection(matrix, 3)
    assert order is not None and np.array_equal(np.sort(order), np.arange(matrix.shape[0]))
    nodes = order.reshape(-1, 3)
    assert np.all(nodes % 3 == np.arange(3)) and np.all(nodes[:, 0] // 3 == nodes[:, 2] // 3)


def test_cholmod_refuses_an_indefinite_matrix():
    indefinite = sp.csr_matrix(np.array([[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]]))
    with pytest.raises(FactorizationError):
        make_backend("cholmod").factorize(indefinite)


def test_auto_takes_cholmod_in_3d_up_to_its_limit_and_multigrid_above():
    assert make_backend("auto", np.zeros((1000, 3))).name == "cholmod"
    assert make_backend("auto", np.zeros((DIRECT_MAX_DOFS_3D // 3, 3))).name == "cholmod"
    assert make_backend("auto", np.zeros((DIRECT_MAX_DOFS_3D // 3 + 1, 3))).name == "amg"
    assert make_backend("auto", np.zeros((5000, 2))).name == linsolve.direct_backend()


def test_cholmod_without_cvxopt_is_one_clear_error(monkeypatch):
    monkeypatch.setattr(linsolve, "installed", lambda module: module != "cvxopt")
    with pytest.raises(PneumaInputError, match="needs CVXOPT"):
        make_backend("cholmod")


def test_chord_steps_reach_the_same_equilibria_with_fewer_factorisations(built):
    """The ramp with chord steps (a held factorisation reused while it pays) against a fresh Hessian at every
    iteration: the same converged states (to the tolerance's size), fewer factorisations than iterations."""
    runs = {}
    for chord in (False, True):
        result = run_schedule(built, options=NewtonOptions(tol=1e-9, linear_solver="cholmod", chord_steps=chord))
        assert result.converged
        runs[chord] = result
    fresh, chorded = runs[False], runs[True]
    scale = np.abs(fresh.positions[-1] - fresh.positions[0]).max()
    assert np.abs(chorded.positions - fresh.positions).max() < 1e-6 * scale
    assert sum(r.chord_steps for r in chorded.solves) > 0 == sum(r.chord_steps for r in fresh.solves)
    assert all(np.all(np.diff(r.energies) <= built.model.energy_resolution) for r in chorded.solves)


def test_a_chord_step_that_needs_a_line_search_is_given_up_for_a_fresh_hessian():
    """The cavity to 2.2 times its volume in one increment, far from the rest state: a held factorisation is a poor
    model there, and a chord step taken with a line search (0141107's rule: four such steps, halved to 0.25-0.5) left
    the iterates off the path, twice the iterations of a fresh Hessian every time. Taken whole or not at all, chord
    steps need fewer factorisations than fresh Newton and at most half as many iterations more, to the same state."""
    scene = scene_of(box_with_cavity(order=2), [ChamberSchedule("area", ((1, 2.2),))], 1, Material(1e4, 0.45))
    built = scene.build()
    runs = [
        run_schedule(built, options=NewtonOptions(tol=1e-9, linear_solver="cholmod", chord_steps=chord))
        for chord in (False, True)
    ]
    (fresh,), (chorded,) = (run.solves[1:] for run in runs)
    assert chorded.converged and fresh.converged and chorded.chord_steps > 0
    assert chorded.iterations - chorded.chord_steps < fresh.iterations
    assert chorded.iterations <= 1.5 * fresh.iterations
    scale = np.abs(runs[0].positions[-1] - runs[0].positions[0]).max()
    assert np.abs(runs[1].positions[-1] - runs[0].positions[-1]).max() < 1e-6 * scale
