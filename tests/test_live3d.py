"""The 3D live window's solve (realtime/equilibrium.py LiveEquilibrium): one Newton step per frame, the previous
frame's factorisation reused while a slider moves. A slider that comes to rest settles to the equilibrium a
full Newton solve finds at its final commands, and no frame on the way inverts a tetrahedron."""

import numpy as np
import pytest

from taichi_pneuma.realtime.equilibrium import LiveEquilibrium
from taichi_pneuma.scene.schedule import ChamberSchedule
from taichi_pneuma.solve.newton import NewtonOptions, NewtonSolver
from tests.solid_meshes import box_with_cavity, scene_of

TOL = 1e-6


@pytest.fixture(scope="module")
def built():
    """The box with a cavity under a pressure command (a softer body: the slider's top bends it visibly)."""
    from taichi_pneuma.scene.build import Material

    return scene_of(box_with_cavity(), [ChamberSchedule("pressure", ((1, 1.0),))], 1, Material(1e4, 0.45)).build()


def elastic(built):
    return next(t for t in built.model.terms if t.name == "elastic")


def drag(live, built, values, idle_frames):
    """Move the slider through `values` (one frame each), then rest for idle_frames; the smallest det F seen."""
    smallest = np.inf
    for value in list(values) + [values[-1]] * idle_frames:
        live.frame(np.array([value]))
        built.model.set_displacements(live.u)
        smallest = min(smallest, elastic(built).min_determinant())
    return smallest


def test_a_resting_slider_settles_to_the_full_newton_equilibrium_without_inverting(built):
    live = LiveEquilibrium(built, NewtonOptions(tol=TOL))
    smallest = drag(live, built, np.linspace(0.0, 2500.0, 12), idle_frames=10)
    assert live.converged and live.residual <= TOL
    assert smallest > 0  # no frame shows an inverted tetrahedron
    built.set_commands(np.array([2500.0]))
    full, record = NewtonSolver(built.model, NewtonOptions(tol=TOL)).solve(np.zeros_like(live.u))
    assert record.converged
    scale = np.abs(full).max()
    assert scale > 0.05  # a visible bend, not the rest state
    assert np.abs(live.u - full).max() <= 1e-4 * scale


def test_a_fast_slider_is_followed_by_single_steps_that_keep_every_tetrahedron_upright(built):
    """A slider swept to full pressure and back within a few frames: each frame one step (the line search
    keeps det F > 0), the state lags the commands, then settles at the end."""
    live = LiveEquilibrium(built, NewtonOptions(tol=TOL))
    smallest = drag(live, built, [0.0, 1500.0, 2500.0, 500.0, 2000.0], idle_frames=15)
    assert smallest > 0 and live.converged


def test_a_reused_factorisation_gives_a_descent_step_without_a_new_hessian(built):
    """solve(reuse_factor=True): the step at new commands solves with the factorisation of the previous ones
    (no Hessian assembled or factorised) and still lowers the energy and the residual."""
    solver = NewtonSolver(built.model, NewtonOptions(tol=TOL))
    built.set_commands(np.array([1000.0]))
    u, _ = solver.solve(np.zeros((len(built.mesh.vertices), 3)))
    built.set_commands(np.array([1200.0]))
    _, record = solver.solve(u, max_iterations=1, reuse_factor=True)
    assert record.iterations == 1 and "factorize" not in record.phase_seconds and "hessian" not in record.phase_seconds
    assert record.energies[-1] < record.energies[0] and record.residuals[-1] < record.residuals[0]
