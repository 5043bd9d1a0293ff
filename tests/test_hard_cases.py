"""Hard cases stay numerically stable: every step converges (or the run says clearly that it did not),
no triangle inverts, nothing is NaN, the energy never rises within a Newton solve, and the physics is sane."""

import numpy as np
import pytest

from taichi_pneuma.fem.polygons import polygon_self_intersects
from taichi_pneuma.scene.build import reference_scene
from taichi_pneuma.solve.newton import NewtonOptions, NewtonSolver
from taichi_pneuma.solve.simulate import RampFailed, run_schedule

LENGTH = 3.5
REFERENCE_TIP = -0.279


def ramp(cy=0.15, growth=3.5, steps=36, k=1e5, E=1e4, nu=0.45, max_area=0.0012):
    built = reference_scene(
        cy=cy, growth=growth, steps=steps, youngs_modulus=E, poisson_ratio=nu, chamber_stiffness=k, max_area=max_area
    ).build()
    return built, run_schedule(built)


def assert_stable(built, result):
    """The checks every hard case must pass."""
    tol = NewtonOptions().tol
    for step, solve in zip(result.steps, result.solves):
        assert step.converged and step.residual <= tol, (step, solve.message)
        assert step.min_det > 0, step
        assert np.all(np.diff(solve.energies) <= built.model.energy_resolution), step
    assert np.all(np.isfinite(result.positions))


@pytest.fixture(scope="module")
def reference(reference_ramp):
    """The reference ramp, ramp() with its defaults (conftest's, shared)."""
    return reference_ramp(0.15)


@pytest.mark.slow
@pytest.mark.parametrize("growth", [6.0, 8.0])
def test_large_growth_balloons_and_keeps_curling(growth):
    built, result = ramp(growth=growth, steps=int(10 * growth) + 1)
    assert_stable(built, result)
    assert result.steps[-1].chambers["main"].area_ratio == pytest.approx(growth, rel=0.01)
    tips = result.history["tip_dy"]
    assert tips[-1] < -0.9 and np.all(np.diff(tips[len(tips) // 2 :]) < 0)  # curls further as it balloons


@pytest.mark.slow
@pytest.mark.parametrize("nu", [0.49, 0.499])
def test_near_incompressible(nu):
    built, result = ramp(nu=nu)
    assert_stable(built, result)
    # still curls down, by an amount of the same order as for nu = 0.45
    assert -0.5 < result.tip_deflection < -0.2


@pytest.mark.slow
def test_thin_wall_chamber_0p01_from_the_top():
    built, result = ramp(cy=0.4 - 0.22 - 0.01)
    assert_stable(built, result)
    assert result.tip_deflection < REFERENCE_TIP  # the chamber further from the axis bends the beam more


def test_single_increment_reaches_the_ramp_equilibrium(reference):
    built, result = ramp(steps=2)
    assert_stable(built, result)
    assert np.abs(result.positions[-1] - reference[1].positions[-1]).max() < 1e-6 * LENGTH


def test_cut_back_increments_reach_the_ramp_equilibrium(reference):
    """With 5 Newton iterations allowed, the single 1x -> 3.5x increment must be cut to get there."""
    built = reference_scene(cy=0.15, steps=2).build()
    result = run_schedule(built, options=NewtonOptions(max_iterations=5))
    assert_stable(built, result)
    assert result.steps[-1].cuts >= 1 and result.steps[-1].substeps >= 2
    assert np.abs(result.positions[-1] - reference[1].positions[-1]).max() < 1e-6 * LENGTH


def test_too_few_cuts_fail_clearly_and_keep_the_steps_done():
    built = reference_scene(cy=0.15, steps=2).build()
    five_iterations = NewtonOptions(max_iterations=5)
    with pytest.raises(RampFailed, match=r"step 1: no equilibrium at commanded area 2\.055.* after 0 cuts; residual"):
        run_schedule(built, options=five_iterations, max_cuts=0)
    try:
        run_schedule(built, options=five_iterations, max_cuts=0)
    except RampFailed as failure:
        assert len(failure.result.steps) == 1 and failure.result.positions.shape == (1, built.mesh.n_vertices, 2)


def test_cut_backs_stop_once_the_residual_stalls_near_the_tolerance_and_say_what_to_try():
    """A tolerance below the residual's round-off floor (about 1.6e-10 here, 16 times the 1e-11 asked): every solve
    ends near it whatever the increment, so the cuts stop after 3 (not the 8 allowed), saying so and what to try."""
    built = reference_scene(cy=0.15, steps=2).build()
    with pytest.raises(RampFailed, match=r"after 3 cuts; residual .*stalled at .* times the tolerance") as failure:
        run_schedule(built, options=NewtonOptions(tol=1e-11))
    assert "try a looser --tol, more --max-iterations, a finer mesh or quadratic elements" in str(failure.value)


@pytest.mark.slow
@pytest.mark.parametrize("k", [1e8, 1e3])
def test_chamber_stiffness_extremes(k):
    built, result = ramp(k=k)
    assert_stable(built, result)
    final = result.steps[-1].chambers["main"]
    area_error = final.area_ratio / final.command - 1
    if k == 1e8:  # a stiff chamber meets its commanded area
        assert abs(area_error) < 1e-5
        assert result.tip_deflection == pytest.approx(REFERENCE_TIP, abs=0.01)
    else:  # a soft chamber falls short by p / k
        assert area_error == pytest.approx(
            -final.pressure / (k * final.command * built.chambers[0].rest_area), rel=1e-9
        )
        assert area_error < -0.05


@pytest.mark.slow
def test_mesh_density_coarse_and_fine(reference):
    """Triangles of 0.01 (374 vertices) and 0.0004 (4508; the reference mesh has 1632)."""
    tips = {}
    for max_area in (0.01, 0.0004):
        built, result = ramp(max_area=max_area)
        assert_stable(built, result)
        tips[max_area] = result.tip_deflection
    reference_tip = reference[1].tip_deflection
    # refining the mesh moves the answer less than coarsening it
    assert abs(tips[0.0004] - reference_tip) < abs(tips[0.01] - reference_tip)


@pytest.mark.slow
def test_stiff_material_same_chamber_stiffness():
    built, result = ramp(E=1e7)
    assert_stable(built, result)
    # the chamber cannot win against a 1000x stiffer body: the area falls far short, the pressure is huge
    assert result.steps[-1].chambers["main"].area_ratio < 2.0 and result.peak_pressure > 1e4


def test_deflation_below_rest_area_keeps_the_chamber_simple():
    built, result = ramp(growth=0.5, steps=11)
    assert_stable(built, result)
    assert result.steps[-1].chambers["main"].area_ratio == pytest.approx(0.5, abs=0.01)
    loop = built.mesh.chambers[0]
    assert not any(polygon_self_intersects(state[loop]) for state in result.positions)


def test_random_perturbation_returns_to_the_same_equilibrium(reference):
    built, result = reference
    solver = NewtonSolver(built.model)
    equilibrium = result.positions[-1] - built.mesh.vertices
    built.set_commands([result.steps[-1].chambers["main"].command])
    noise = 1e-3 * LENGTH * np.random.default_rng(0).standard_normal(equilibrium.shape)
    u, record = solver.solve(equilibrium + noise)
    assert record.converged and built.elastic.min_determinant() > 0
    assert np.abs(u - equilibrium).max() < 1e-6 * LENGTH
