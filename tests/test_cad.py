"""Bodies and chambers from CAD files (fem/cad.py): the shipped STEP actuator (drawn by build123d, not gmsh) meshed to
its closed-form volumes, its units, and every refusal."""

import numpy as np
import pytest

from taichi_pneuma.api import load_scene, simulate
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.cad import StepPart
from taichi_pneuma.fem.gmsh_mesher import MeshSizes, Solid, mesh_solid
from taichi_pneuma.fem.solid_geometry import SolidGeometry
from taichi_pneuma.fem.solids import Box
from taichi_pneuma.fem.supports import PointSet
from taichi_pneuma.io.units import UNITS
from taichi_pneuma.scene.build import ChamberControl, Scene
from taichi_pneuma.scene.schedule import area_ramp
from taichi_pneuma.scene.shipped import find

gmsh = pytest.importorskip("gmsh", reason="gmsh is not installed (pip install 'taichi-pneuma[3d]')")

MM = 1e-3
# examples/cad_fiber_actuator_step.py's actuator: a half-round bar of radius 8 on a 2 mm base, 100 mm long; its
# half-round chamber of radius 6, 94 mm long
BODY_VOLUME = np.pi * 8.0**2 / 2 * 100.0 + 2.0 * 16.0 * 100.0
CHAMBER_VOLUME = np.pi * 6.0**2 / 2 * 94.0


def actuator_file() -> str:
    return str(find("fiber_actuator", ".step", "CAD file"))


def actuator(metre: float = MM, order: int = 2) -> SolidGeometry:
    path = actuator_file()
    return SolidGeometry(
        StepPart(path, "body", metre),
        (("chamber", StepPart(path, "chamber", metre)),),
        MeshSizes(5.0 * MM / metre, distance=4.0 * MM / metre, through_wall=0.5),
        order=order,
        clamp=PointSet("left"),
    )


def test_the_step_actuator_meshes_to_the_closed_form_volumes_of_its_rubber_and_chamber():
    """Curved quadratic tetrahedra hold the rubber's volume (body less chamber) and the cavity's (the chamber
    term's rest volume, on its curved wall) to 0.1 %."""
    geometry = actuator()
    mesh = geometry.mesh()
    assert mesh.measure == pytest.approx(BODY_VOLUME - CHAMBER_VOLUME, rel=1e-3)
    chamber = Scene(geometry, (ChamberControl(area_ramp(1.5, 2, 1.0)),), 1, units=UNITS["mm-kPa"]).build().chambers[0]
    assert chamber.rest_area == pytest.approx(CHAMBER_VOLUME, rel=1e-3)
    x = mesh.vertices[:, 0]
    assert x.min() == pytest.approx(0.0, abs=1e-9) and x.max() == pytest.approx(100.0)


def test_the_file_states_millimetres_and_a_scene_in_metres_reads_them_as_metres():
    """The same file in a scene of metres: every length a thousandth, the volume 1e-9 times."""
    mesh = actuator(metre=1.0, order=1).mesh()
    assert mesh.vertices[:, 0].max() == pytest.approx(0.1, rel=1e-9)
    assert mesh.measure == pytest.approx((BODY_VOLUME - CHAMBER_VOLUME) * 1e-9, rel=2e-2)


def gmsh_step(path, boxes: int, surface_only: bool = False) -> str:
    """A STEP file of `boxes` unit boxes side by side (or a lone rectangle: no solid), written by gmsh (in metres,
    its solids named by the translator, not by a label)."""
    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        if surface_only:
            gmsh.model.occ.addRectangle(0, 0, 0, 1, 1)
        for k in range(boxes):
            gmsh.model.occ.addBox(2 * k, 0, 0, 1, 1, 1)
        gmsh.model.occ.synchronize()
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return str(path)


def solid_of(part: StepPart):
    """The part meshed as a body with a small box chamber at (0.5, 0.5, 0.5)."""
    return mesh_solid(Solid(part, (("c", Box((0.5, 0.5, 0.5), (0.2, 0.2, 0.2))),)), MeshSizes(0.25), max_tets=20_000)


def test_every_unusable_cad_file_is_one_clear_line(tmp_path):
    path = actuator_file()
    with pytest.raises(
        PneumaInputError, match=r"solid = 'lid': CAD file .* has no solid of that name \(body, chamber\)"
    ):
        solid_of(StepPart(path, "lid", MM))
    with pytest.raises(
        PneumaInputError, match=r"has 2 solids \(body, chamber\): name the one meant \(solid = \.\.\.\)"
    ):
        solid_of(StepPart(path, None, MM))
    two = gmsh_step(tmp_path / "two.step", 2)
    with pytest.raises(PneumaInputError, match=r"two.step' has 2 solids \(.*\): name the one meant"):
        solid_of(StepPart(two, None, 1.0))
    flat = gmsh_step(tmp_path / "flat.step", 0, surface_only=True)
    with pytest.raises(PneumaInputError, match=r"has no closed solid \(only surfaces or curves"):
        solid_of(StepPart(flat, None, 1.0))
    (tmp_path / "junk.step").write_text("ISO-10303-21;\nthis is not STEP\n")
    with pytest.raises(PneumaInputError, match=r"junk.step.*(cannot be read by OpenCASCADE|has no closed solid)"):
        solid_of(StepPart(str(tmp_path / "junk.step"), None, MM))
    with pytest.raises(PneumaInputError, match=r"a CAD part is read from a \.step, \.stp, \.iges, \.igs file"):
        StepPart(str(tmp_path / "part.stl"), None, MM)
    with pytest.raises(PneumaInputError, match=r"missing.step' cannot be read \(No such file or directory\)"):
        StepPart(str(tmp_path / "missing.step"), None, MM)
    with pytest.raises(PneumaInputError, match=r"give the scene units"):
        solid_of(StepPart(path, "body", None))
    assert not gmsh.isInitialized()


def test_one_unnamed_solid_is_the_part_and_the_cache_keys_its_content(tmp_path):
    """A file of one box needs no name; an edited file (two boxes) is a different part, not the cached one."""
    one = gmsh_step(tmp_path / "box.step", 1)
    part = StepPart(one, None, 1.0)
    meshed = solid_of(part)
    x = meshed.vertices[meshed.tets]
    assert np.linalg.det(x[:, 1:] - x[:, :1]).sum() / 6 == pytest.approx(1.0 - 0.2**3, rel=1e-9)
    gmsh_step(tmp_path / "box.step", 2)
    assert StepPart(one, None, 1.0).content != part.content


def test_the_shipped_step_scene_reads_its_parts_in_millimetres_and_refuses_a_scene_without_units(tmp_path):
    """fiber_bending_step: the body and chamber of the STEP file, the chamber's rest volume the half-round cavity's
    (0.1 %); the same file in a scene without units is refused when meshed, naming the file."""
    scene = load_scene("fiber_bending_step")
    assert isinstance(scene.geometry.body, StepPart) and scene.geometry.body.metre == MM
    assert scene.build().chambers[0].rest_area == pytest.approx(CHAMBER_VOLUME, rel=1e-3)
    text = (find("fiber_bending_step", ".toml")).read_text().replace('units = "mm-kPa"\n', "")
    text = text.replace('preset = "elastosil_m4601"', "E = 1.0\nnu = 0.45").replace('volumetric = "mixed"', "")
    text = text.replace('file = "fiber_actuator.step"', f'file = "{actuator_file()}"')
    (tmp_path / "unitless.toml").write_text(text)
    with pytest.raises(PneumaInputError, match=r"fiber_actuator.step'?: a CAD file's lengths have units; give the"):
        load_scene(tmp_path / "unitless.toml").build()


@pytest.mark.slow
def test_the_step_actuator_bends_as_the_parametric_one():
    """fiber_bending_step against fiber_bending_3d on a short ramp (2 increments to 40 kPa): the same tip rotation to
    1 % (the two meshes differ: gmsh meshes the file's solids, not the parametric shapes)."""
    short = {"chambers[0].keyframes": [[0, 0.0], [2, 40.0]], "schedule.increments": 2}
    angles = [
        simulate(load_scene(name).with_values(short)).history["tip_rotation"][-1]
        for name in ("fiber_bending_3d", "fiber_bending_step")
    ]
    assert angles[0] < -5.0 and angles[1] == pytest.approx(angles[0], rel=1e-2)
