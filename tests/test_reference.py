"""The reference ramp for the three chamber placements, against the reference figures (the ramps are
conftest's reference_ramp, shared with the other tests that need them)."""

import numpy as np
import pytest

from taichi_pneuma.solve.newton import NewtonOptions

pytestmark = pytest.mark.slow
TOL = NewtonOptions().tol


@pytest.fixture(scope="module")
def ramps(reference_ramp):
    return {cy: reference_ramp(cy) for cy in (0.15, 0.0, -0.15)}


@pytest.mark.parametrize("cy, tip", [(0.15, -0.278), (0.0, -0.001), (-0.15, 0.278)])
def test_tip_deflection(ramps, cy, tip):
    assert ramps[cy][1].tip_deflection == pytest.approx(tip, abs=0.003)


@pytest.mark.parametrize("cy", [0.15, 0.0, -0.15])
def test_area_ratio(ramps, cy):
    assert ramps[cy][1].steps[-1].chambers["main"].area_ratio == pytest.approx(3.49, abs=0.01)


def test_area_after_ramp_and_peak_pressure(ramps):
    built, result = ramps[0.15]
    assert result.steps[-1].chambers["main"].area == pytest.approx(2.052, abs=0.005)
    assert result.peak_pressure == pytest.approx(294.8, rel=0.01)


def test_the_summary_gives_the_mesh_terms_and_chamber_areas(ramps):
    """The figures the reference file's run reports (reference_beam.toml is this scene: test_scenes.py)."""
    summary = ramps[0.15][1].summary()
    assert summary["vertices"] == 1632 and summary["triangles"] == 2976
    assert summary["terms"] == ["elastic", "chamber:main", "clamp"]
    assert summary["chambers"]["main"]["rest_area"] == pytest.approx(0.587, abs=5e-4)
    assert summary["chambers"]["main"]["final_area"] == pytest.approx(2.052, abs=0.005)


def test_up_and_down_chambers_are_mirror_images(ramps):
    assert ramps[0.15][1].tip_deflection == pytest.approx(-ramps[-0.15][1].tip_deflection, abs=0.003)


@pytest.mark.parametrize("cy", [0.15, 0.0, -0.15])
def test_every_step_converges_without_inversion(ramps, cy):
    built, result = ramps[cy]
    for step, solve in zip(result.steps, result.solves):
        assert step.converged and step.residual <= TOL, (step, solve.message)
        assert step.min_det > 0
        assert np.all(np.isfinite(result.positions[step.step]))
        # the energy never increased within a Newton solve (up to float64 resolution)
        assert np.all(np.diff(solve.energies) <= built.model.energy_resolution)


def test_pressure_rises_monotonically_and_bend_direction(ramps):
    _, result = ramps[0.15]
    pressure = result.history["main.pressure"]
    assert np.all(np.diff(pressure) > 0)
    # a chamber above the neutral axis first lifts the tip slightly, then curls the beam down
    assert result.history["tip_dy"][-1] < 0
