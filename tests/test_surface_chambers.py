"""A surface body's chambers drawn as closed surface files of their own (fem/surface_import.py SurfaceChamber): the
cavities they enclose to their exact volumes, every misplaced chamber refused in one line, and a surface of more
facets than the budget holds refused before it is repaired or meshed."""

import time

import numpy as np
import pytest
from test_surface_import import BOX, cube, write_stl

from taichi_pneuma.api import load_scene
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem import sizing
from taichi_pneuma.fem.gmsh_mesher import MeshSizes
from taichi_pneuma.fem.solid_geometry import SolidGeometry
from taichi_pneuma.fem.solids import Box
from taichi_pneuma.fem.surface_clearance import closest_approach, triangle_gaps
from taichi_pneuma.fem.surface_import import Cavity, SurfaceBody, SurfaceChamber, SurfaceGeometry
from taichi_pneuma.limits import MAX_TRIANGLES, Budget
from taichi_pneuma.scene.build import ChamberControl, Scene
from taichi_pneuma.scene.schedule import area_ramp

pytest.importorskip("gmsh", reason="gmsh is not installed (pip install 'taichi-pneuma[3d]')")

SCENE = """
[body]
shape = "surface"
file = "body.stl"
scale = 1.0

[mesh]
size = 0.25
near_chambers = 0.1

[material]
E = 1e4
nu = 0.45

[clamp]
side = "left"

[[chambers]]
name = "a"
shape = "cavity"
inside = [0.2, 0.2, 0.2]
keyframes = [[0, 1.0], [1, 1.1]]

[[chambers]]
name = "b"
shape = "surface"
file = "chamber_mm.stl"
scale = 0.001
keyframes = [[0, 1.0], [1, 1.1]]

[schedule]
increments = 1
"""


def test_a_chamber_file_is_a_cavity_of_its_exact_volume(tmp_path):
    """A unit box with a cavity of its own (0.2^3, named by a point) and a chamber drawn in its own file in mm
    (0.4^3, half its facets turned over): the rubber is 1 - 0.2^3 - 0.4^3 and each chamber's rest volume its box's,
    to the binary STL's single precision; the scene file reads the chamber's file beside it at its own scale."""
    chamber = cube(500.0, 900.0, 3)
    chamber[::2] = chamber[::2, ::-1]
    write_stl(tmp_path / "body.stl", np.concatenate([BOX, cube(0.1, 0.3)[:, ::-1]]))
    write_stl(tmp_path / "chamber_mm.stl", chamber)
    (tmp_path / "s.toml").write_text(SCENE)
    built = load_scene(tmp_path / "s.toml").build()
    assert built.mesh.measure == pytest.approx(1 - 0.2**3 - 0.4**3, rel=1e-7)
    assert [c.rest_area for c in built.chambers] == pytest.approx([0.2**3, 0.4**3], rel=1e-6)
    without_scale = SurfaceChamber(str(tmp_path / "chamber_mm.stl"))  # the body's scale: 1, so 1000 times too large
    assert without_scale.scale is None
    with pytest.raises(PneumaInputError, match=r"chamber 'b': its surface lies outside the body"):
        geometry(tmp_path / "body.stl", (("a", Cavity((0.2, 0.2, 0.2))), ("b", without_scale))).mesh()


def geometry(body, chambers) -> SurfaceGeometry:
    return SurfaceGeometry(SurfaceBody(str(body), 1.0), tuple(chambers), MeshSizes(0.25, 0.1))


MISPLACED = [
    ("crossing", [cube(0.5, 1.2)], r"chamber 'c0': its surface touches or crosses the body's outer surface at \["),
    ("touching", [cube(0.3, 1.0)], r"chamber 'c0': its surface touches or crosses the body's outer surface at \["),
    ("outside", [cube(1.5, 2.0)], r"chamber 'c0': its surface lies outside the body$"),
    ("overlapping", [cube(0.1, 0.4), cube(0.35, 0.8)], r"chamber 'c1': its surface touches or crosses the cavity of "),
    ("face to face", [cube(0.1, 0.4), cube(0.4, 0.8)], r"chamber 'c1': its surface touches or crosses the cavity of "),
    ("nested", [cube(0.1, 0.6), cube(0.2, 0.3)], r"chamber 'c1': its surface lies inside the cavity of chamber 'c0'"),
    ("around", [cube(0.2, 0.3), cube(0.1, 0.6)], r"chamber 'c1': its surface encloses the cavity of chamber 'c0'"),
    ("about the body's cavity", [cube(0.6, 0.95)], r"chamber 'c0': its surface encloses the body's cavity about"),
]


@pytest.mark.parametrize("case, surfaces, message", MISPLACED, ids=[case[0] for case in MISPLACED])
def test_a_misplaced_chamber_file_is_one_line(tmp_path, case, surfaces, message):
    """Each chamber drawn where it cannot be a cavity of the body is refused before gmsh runs, naming it and the
    surface it meets or holds (the last case's body has a cavity of its own about [0.75, 0.75, 0.75])."""
    cavity = case == "about the body's cavity"
    body = write_stl(tmp_path / "body.stl", np.concatenate([BOX, cube(0.7, 0.8)]) if cavity else BOX)
    chambers = [(f"c{i}", SurfaceChamber(write_stl(tmp_path / f"c{i}.stl", s))) for i, s in enumerate(surfaces)]
    with pytest.raises(PneumaInputError, match=message):
        geometry(body, [("cavity", Cavity((0.75, 0.75, 0.75)))] * cavity + chambers).mesh()


def test_an_unusable_chamber_file_is_one_line(tmp_path):
    """A chamber file with a hole is refused as a body's is (its file named); one of two closed surfaces, a scale
    that is not positive, another format are refused too, and so is a chamber file in a body from shapes."""
    body = write_stl(tmp_path / "body.stl", BOX)
    holed = write_stl(tmp_path / "holed.stl", cube(0.3, 0.7)[1:])
    with pytest.raises(PneumaInputError, match=r"holed.stl' has a hole: \d+ edges of one triangle only"):
        geometry(body, [("c", SurfaceChamber(holed))]).mesh()
    two = write_stl(tmp_path / "two.stl", np.concatenate([cube(0.1, 0.3), cube(0.6, 0.8)]))
    with pytest.raises(PneumaInputError, match=r"two.stl' holds 2 closed surfaces; a chamber's file holds one"):
        geometry(body, [("c", SurfaceChamber(two))]).mesh()
    with pytest.raises(PneumaInputError, match=r"scale = 0.0 must be > 0 \(or left out: the body's\)"):
        SurfaceChamber(holed, 0.0)
    with pytest.raises(PneumaInputError, match=r"a surface is read from a \.stl, \.obj, \.ply, \.off file"):
        SurfaceChamber(str(tmp_path / "chamber.step"))
    with pytest.raises(PneumaInputError, match=r"chamber 'c': a 3D body's chambers are 3D shapes"):
        SolidGeometry(Box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0)), (("c", SurfaceChamber(holed)),), MeshSizes(0.25, 0.1))


def test_the_gap_between_two_triangles():
    """Triangles apart are measured at a corner-face pair (a corner 0.5 above the other's inside) or an edge-edge pair
    (an edge rising over the x axis, y = -0.4 .. 0.4 at z = 0.3 + 0.5 (y + 0.4): nearest it at y = -0.2, sqrt(0.2)
    away, outside the flat triangle); triangles that pierce each other, or share a corner, have gap 0."""
    flat = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]])
    above = np.array([[[0.25, 0.25, 0.5], [0.3, 0.25, 2.0], [0.25, 0.3, 2.0]]])
    rising = np.array([[[0.5, -0.4, 0.3], [0.5, 0.4, 0.7], [0.5, -0.4, 2.0]]])
    piercing = above - [0.0, 0.0, 1.0]
    touching = np.array([[[1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [2.0, 1.0, 0.0]]])
    gaps = triangle_gaps(np.repeat(flat, 4, axis=0), np.concatenate([above, rising, piercing, touching]))
    assert gaps == pytest.approx([0.5, np.sqrt(0.2), 0.0, 0.0])
    assert closest_approach(flat, above, 0.4) is None
    assert closest_approach(flat, above, 0.6)[0] == pytest.approx(0.5)


def test_a_surface_of_too_many_facets_is_refused_before_it_is_read_further(tmp_path):
    """A surface of 400,001 facets passes the default limit (200,000 triangles' worth, a facet half of one): the
    mesher and the scene's size check refuse it in one line, within seconds (reading it is all they do); a budget of
    1000 triangles refuses 2001 facets."""
    path = write_stl(tmp_path / "big.stl", np.random.default_rng(0).random((400_001, 3, 3)))
    body = geometry(path, [("main", Cavity((0.5, 0.5, 0.5)))])
    start = time.perf_counter()
    message = r"big.stl' has 400001 facets: about 2e\+05 triangles' worth, 0.8 GB; the limit is 200000 triangles"
    with pytest.raises(PneumaInputError, match=message):
        body.mesh(Budget(MAX_TRIANGLES))
    scene = Scene(body, (ChamberControl(area_ramp(1.5, 2, 1.0)),), 1)
    with pytest.raises(PneumaInputError, match=message):
        sizing.check_scene(scene)
    assert time.perf_counter() - start < 20  # an unbounded repair and mesh of it takes a minute or more
    small = write_stl(tmp_path / "small.stl", np.random.default_rng(1).random((2001, 3, 3)))
    with pytest.raises(PneumaInputError, match=r"has 2001 facets: .* the limit is 1000 triangles"):
        geometry(small, []).mesh(Budget(1000))
