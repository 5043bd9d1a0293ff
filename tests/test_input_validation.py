"""Every user-facing constructor refuses bad values with one PneumaInputError naming the value."""

import pytest

from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.planar import BeamGeometry
from taichi_pneuma.io.output import prepare_directory
from taichi_pneuma.scene.build import Material, reference_scene
from taichi_pneuma.scene.schedule import area_ramp
from taichi_pneuma.solve.newton import NewtonOptions
from taichi_pneuma.terms.chambers import AreaControl

INF, NAN = float("inf"), float("nan")


@pytest.mark.parametrize(
    "make, pattern",
    [
        (lambda: Material(poisson_ratio=0.5), r"nu = 0.5 must lie in \(-1, 0.5\)"),
        (lambda: Material(poisson_ratio=-1.0), r"nu = -1.0 must lie"),
        (lambda: Material(youngs_modulus=0.0), r"E = 0.0 must be > 0"),
        (lambda: Material(youngs_modulus=INF), r"E = inf must be a finite number"),
        (lambda: Material(poisson_ratio=NAN), r"nu = nan must be a finite number"),
        (lambda: reference_scene(chamber_stiffness=0.0), r"k = 0.0 must be > 0"),
        (lambda: AreaControl(stiffness=-1e5), r"k = -100000.0 must be > 0"),
        (lambda: AreaControl(stiffness=NAN), r"stiffness = nan"),
        (lambda: BeamGeometry(cy=NAN), r"cy = nan"),
        (lambda: BeamGeometry(cy=0.2), r"escapes the beam vertically"),
        (lambda: BeamGeometry(chamber_points=3), r"chamber_points = 3"),
        (lambda: area_ramp(0.0, 36), r"growth = 0.0 must be > 0"),
        (lambda: area_ramp(-2.0, 36), r"growth = -2.0 must be > 0"),
        (lambda: area_ramp(INF, 36), r"growth = inf must be a finite number"),
        (lambda: area_ramp(3.5, 0), r"steps = 0 must be an integer >= 2"),
        (lambda: area_ramp(3.5, 1), r"steps = 1 must be an integer >= 2"),
        (lambda: area_ramp(3.5, 2.5), r"steps = 2.5 must be an integer"),
        (lambda: NewtonOptions(tol=NAN), r"tol = nan"),
        (lambda: NewtonOptions(tol=0.0), r"tol = 0.0 must be > 0"),
        (lambda: NewtonOptions(max_iterations=0), r"max_iterations = 0"),
    ],
)
def test_python_api_refuses(make, pattern):
    with pytest.raises(PneumaInputError, match=pattern):
        make()


def test_unwritable_output_directory_is_named(tmp_path):
    blocker = tmp_path / "plain_file"
    blocker.write_text("")
    with pytest.raises(PneumaInputError, match="plain_file/out.*not writable"):
        prepare_directory(blocker / "out")
