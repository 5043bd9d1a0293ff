"""Branch sweeps by a low-rank update of the held factorisation (solve/branch_update.py): the update is the Hessian
difference of the cord segments that change branch, and a ramp solved with it reaches the states of one that
factorises every sweep, with fewer factorisations."""

import numpy as np
import pytest
import scipy.sparse as sp
from solid_meshes import box_with_cavity, scene_of
from test_fibers import CASES, perturbed

from taichi_pneuma import runtime
from taichi_pneuma.fem.fiber_paths import Crossed
from taichi_pneuma.scene.build import Material
from taichi_pneuma.scene.schedule import ChamberSchedule
from taichi_pneuma.solve.branch_update import branch_update
from taichi_pneuma.solve.newton import NewtonOptions
from taichi_pneuma.solve.simulate import run_schedule
from taichi_pneuma.terms.fibers import Fiber


@pytest.fixture(scope="module", autouse=True)
def taichi():
    runtime.ensure_initialised()


def dense(pattern, values, n: int) -> np.ndarray:
    return sp.coo_matrix((values, pattern), shape=(n, n)).toarray()


@pytest.mark.parametrize("case", CASES)
def test_the_update_is_the_hessian_difference_of_the_segments_that_change_branch(case):
    mesh, config, term, dx = perturbed(case)
    pattern, n = term.hessian_pattern(), config.u.size
    base = term.hessian_values()
    changed = term.choose_branches(dx)
    new = term.hessian_values()
    update = branch_update([pattern], [base], [new], max_rank=10**6)
    assert update is not None and 0 < len(update) <= mesh.dim * changed  # rank <= d per segment
    updated = dense(pattern, base, n)
    for dofs, v, eigenvalue in update:
        updated[np.ix_(dofs, dofs)] += eigenvalue * np.outer(v, v)
    expected = dense(pattern, new, n)
    assert np.allclose(updated, expected, rtol=0, atol=1e-12 * np.abs(expected).max())
    assert branch_update([pattern], [base], [new], max_rank=len(update) - 1) is None
    assert branch_update([None], [base], [new], max_rank=0) == []  # a smooth part is never compared


def test_a_ramp_with_updated_sweeps_reaches_the_states_of_one_that_factorises_every_sweep():
    """A crossed pair of stiff cords (E A 3000 times the rubber's E times the wall's section) round the cavity of a
    quadratic box: the same equilibria to the tolerance's size, with fewer factorisations."""
    crossed = Fiber(Crossed((-1.7, -0.2, 0.0), 0.15, 2.0, "x", angle=40.0), 3e6, area=1e-4)
    built = scene_of(
        box_with_cavity(2), [ChamberSchedule("pressure", ((2, 1000.0),))], 2, Material(1e4, 0.3), fibers=(crossed,)
    ).build()
    runs = {}
    for updates in (False, True):
        runs[updates] = run_schedule(built, options=NewtonOptions(tol=1e-9, sweep_updates=updates))
        assert runs[updates].converged
    old, new = runs[False], runs[True]
    scale = np.abs(old.positions[-1] - old.positions[0]).max()
    assert np.abs(new.positions - old.positions).max() < 1e-6 * scale
    assert new.newton["factorizations"] < old.newton["factorizations"]
