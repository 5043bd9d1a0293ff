"""The thinnest rubber around the chambers (fem/wall_thickness.py, wall_thickness.thinnest_wall) against the distances
the shapes give by hand, and mesh.through_wall, the mesh size it sets."""

import tomllib
from importlib.resources import files

import numpy as np
import pytest

from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.gmsh_mesher import Solid
from taichi_pneuma.fem.pneunet import PneuNet
from taichi_pneuma.fem.solids import Box, Cylinder, Ellipsoid, HalfCylinder
from taichi_pneuma.fem.wall_thickness import point_triangle_distances, thinnest_wall
from taichi_pneuma.scene.scenefile import read_scene

gmsh = pytest.importorskip("gmsh", reason="gmsh is not installed (pip install 'taichi-pneuma[3d]')")

BODY = Box((0.0, 0.0, 0.0), (1.6, 0.8, 0.8))


def test_point_triangle_distance_is_the_least_over_the_triangle():
    """Against the least distance to 200k points spread over each triangle (barycentric grid): never below it, and
    above it by no more than the grid's spacing; and three cases by hand (above the face, past an edge, past a
    corner)."""
    rng = np.random.default_rng(7)
    triangles = rng.normal(size=(20, 3, 3))
    points = rng.normal(size=(20, 3)) * 2
    n = 450
    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
    keep = i + j <= n
    u, v = i[keep] / n, j[keep] / n
    for point, (a, b, c) in zip(points, triangles):
        samples = a + np.outer(u, b - a) + np.outer(v, c - a)
        brute = np.linalg.norm(samples - point, axis=1).min()
        exact = point_triangle_distances(point[None], np.array([[[a, b, c]]]))[0, 0]
        spacing = max(np.linalg.norm(b - a), np.linalg.norm(c - a), np.linalg.norm(c - b)) / n
        assert brute - spacing <= exact <= brute + 1e-12
    unit = np.array([[[[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]]])
    for point, expected in (([0.2, 0.2, 0.5], 0.5), ([0.5, -0.3, 0.4], 0.5), ([-0.3, -0.4, 0.0], 0.5)):
        assert point_triangle_distances(np.array([point]), unit)[0, 0] == pytest.approx(expected, rel=1e-14)


@pytest.mark.parametrize(
    "chambers, body, expected",
    [
        # a box: 0.2 to the sides z = +-0.4 (0.25 in y, 0.4 and 0.6 to the ends)
        ([Box((0.1, 0.0, 0.0), (0.6, 0.3, 0.4))], BODY, 0.2),
        # a cylinder of radius 0.25 along x in the 0.8-square box: 0.15 to each side; its ends 0.3 from the body's
        ([Cylinder((0.0, 0.0, 0.0), 0.25, 1.0, "x")], BODY, 0.15),
        # an ellipsoid off centre: its top at y = 0.3, 0.1 below the body's top (0.2 to the sides z = +-0.4)
        ([Ellipsoid((0.0, 0.05, 0.0), (0.5, 0.25, 0.2))], BODY, 0.1),
        # two boxes 0.05 apart: the wall between them
        ([Box((-0.3, 0.0, 0.0), (0.5, 0.3, 0.3)), Box((0.3, 0.0, 0.0), (0.6, 0.3, 0.3))], BODY, 0.05),
        # half a model: the ellipsoid's open wall ends on the body's face z = 0, which it touches and which does not
        # count; 0.1 to the top as in the whole model
        ([Ellipsoid((0.0, 0.05, 0.0), (0.5, 0.25, 0.2))], Box((0.0, 0.0, 0.2), (1.6, 0.8, 0.4)), 0.1),
        # the bending actuator's section, curved: round walls 0.8 - 0.55 = 0.25 thick (chords 5 % inside a surface
        # this coarse: the exact projection corrects them), a 0.3 base under the chamber's flat floor, 0.3 end caps
        (
            [HalfCylinder((0.0, 0.0, 0.0), 0.55, 3.4, "x")],
            HalfCylinder((0.0, 0.0, 0.0), 0.8, 4.0, "x", base=0.3),
            0.25,
        ),
    ],
    ids=["box", "cylinder", "ellipsoid", "two_chambers", "half_model", "half_cylinder"],
)
def test_thinnest_wall_is_the_shapes_least_distance(chambers, body, expected):
    solid = Solid(body, tuple((f"c{k}", shape) for k, shape in enumerate(chambers)))
    assert thinnest_wall(solid) == pytest.approx(expected, rel=1e-6)


def test_thinnest_wall_of_a_pneunet_is_its_generators_thinnest_rubber():
    body = PneuNet()
    assert thinnest_wall(body.solid()) == pytest.approx(body.thinnest, rel=1e-6)


def actuator(**mesh) -> dict:
    """The shipped bending actuator's scene data with its [mesh] keys replaced."""
    data = tomllib.loads(files("taichi_pneuma").joinpath("scenes/fiber_bending_3d.toml").read_text())
    data["mesh"] = {"size": 4.0, "distance": 3.0, "order": 2, **mesh}
    return data


def test_through_wall_makes_the_edge_length_near_the_chambers_the_wall_over_it():
    """The actuator's walls are 2 mm (its chamber of radius 6 in a body of radius 8, its 2 mm base): 0.5 through the
    wall is 4 mm near the chambers, 2 is 1 mm; the scene file keeps through_wall, and --quality scales it."""
    scene = read_scene(actuator(through_wall=2.0), "a")
    assert scene.geometry.wall == pytest.approx(2.0, rel=1e-9)
    assert scene.geometry.mesh_sizes.near == pytest.approx(1.0, rel=1e-9)
    assert scene.with_values({"mesh.through_wall": 0.5}).geometry.mesh_sizes.near == pytest.approx(4.0, rel=1e-9)
    written = tomllib.loads(scene.to_toml())["mesh"]
    assert written["through_wall"] == 2.0 and "near_chambers" not in written
    coarse, fine = (
        read_scene(actuator(through_wall=2.0), "a")
        .with_values({"mesh.through_wall": t})
        .geometry.size_estimate()
        .elements
        for t in (0.5, 2.0)
    )
    assert fine > 4 * coarse


def test_through_wall_and_near_chambers_are_one_or_the_other():
    """A scene file gives one of them; setting one (--set, with_values) replaces the other."""
    scene = read_scene(actuator(through_wall=0.5), "a").with_values({"mesh.near_chambers": 3.0})
    assert (scene.geometry.sizes.near_chambers, scene.geometry.sizes.through_wall) == (3.0, None)
    back = scene.with_values({"mesh.through_wall": 1.0}).geometry
    assert (back.sizes.near_chambers, back.mesh_sizes.near) == (None, pytest.approx(2.0, rel=1e-9))
    with pytest.raises(PneumaInputError, match=r"near_chambers = 3.0 and through_wall = 1.0: give one of them"):
        read_scene(actuator(near_chambers=3.0, through_wall=1.0), "a")
    with pytest.raises(PneumaInputError, match=r"through_wall = -1.0 must be > 0"):
        read_scene(actuator(through_wall=-1.0), "a")


@pytest.mark.parametrize(
    "quality, expected",
    [  # (size, edges through the 2 mm wall, order) from the scene's 4 mm, 0.5 through the wall (4 mm near it)
        ("draft", (6.0, 2 / 6, 1)),  # uniform at 1.5 times the size: 6 mm through a 2 mm wall is 1/3 of an edge
        ("default", (6.0, 0.5 / 1.5, 2)),
        ("high", (4.0, 0.5 / 0.75, 2)),  # the walls' presets: finer through the wall, the bulk the scene's
        ("accurate", (4.0, 0.5 * 2, 2)),
    ],
)
def test_a_quality_preset_scales_the_edges_through_the_wall(tmp_path, quality, expected):
    """A body sized through its walls takes the walls' presets (apps/quality.py QUALITY_WALL)."""
    from taichi_pneuma.apps.cli import scene_of_flags
    from taichi_pneuma.apps.inflate import parser
    from taichi_pneuma.io.tomltext import dumps

    path = tmp_path / "actuator.toml"
    path.write_text(dumps(actuator(through_wall=0.5)))
    geometry = scene_of_flags(parser().parse_args(["--scene", str(path), "--quality", quality])).geometry
    size, through, order = expected
    assert (geometry.sizes.size, geometry.order) == (size, order)
    assert geometry.sizes.through_wall == pytest.approx(through, rel=1e-9)
    assert geometry.mesh_sizes.near == pytest.approx(min(2.0 / through, size), rel=1e-9)
