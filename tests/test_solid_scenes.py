"""3D scenes from shapes end to end: the scene format's 3D bodies and chambers (read, written, meshed by gmsh),
material regions by volume group, the resource guard before and after meshing, the shipped 3D scenes from the
command line, and the pictures of a 3D run (both views, the video, the live window)."""

import json
import sys

import imageio.v3 as iio
import numpy as np
import pytest
from test_render import xvfb_display  # noqa: F401  (the virtual display fixture)

import taichi_pneuma as tp
from taichi_pneuma.apps.inflate import main as inflate
from taichi_pneuma.backend import has_ggui
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem import sizing
from taichi_pneuma.io.tomltext import parse_toml
from taichi_pneuma.limits import Budget
from taichi_pneuma.render.frames3d import FrameRenderer3D, Track3D
from taichi_pneuma.scene.dotted_edits import set_key
from taichi_pneuma.scene.scenefile import read_scene, scene_data

pytest.importorskip("gmsh", reason="gmsh is not installed (pip install 'taichi-pneuma[3d]')")

# a 3.5 x 0.8 x 0.8 beam extruded from a 2D union, five chambers of the five 3D chamber shapes
SHAPES = """
[body]
shape = "extrusion"
depth = 0.8
[body.profile]
shape = "union"
rectangles = [{ center = [-1.0, 0.0], size = [1.5, 0.8] }, { center = [0.75, 0.0], size = [2.0, 0.8] }]
[mesh]
size = 0.3
near_chambers = 0.1
[clamp]
side = "left"
[[chambers]]
name = "ellipsoid"
shape = "ellipsoid"
center = [-1.3, 0.1, 0.0]
semi_axes = [0.25, 0.15, 0.2]
keyframes = [[1, 1.2]]
[[chambers]]
name = "box"
shape = "box"
center = [-0.6, 0.1, 0.0]
size = [0.3, 0.3, 0.4]
keyframes = [[1, 1.2]]
[[chambers]]
name = "rounded"
shape = "rounded_box"
center = [0.0, 0.1, 0.0]
size = [0.4, 0.3, 0.4]
radius = 0.05
keyframes = [[1, 1.2]]
[[chambers]]
name = "cylinder"
shape = "cylinder"
center = [0.6, 0.1, 0.0]
radius = 0.12
length = 0.4
keyframes = [[1, 1.2]]
[[chambers]]
name = "prism"
shape = "extrusion"
depth = 0.4
profile = { shape = "polygon", points = [[1.0, 0.0], [1.4, 0.0], [1.2, 0.3]] }
keyframes = [[1, 1.2]]
[schedule]
increments = 1
"""
FLAT = {"box": 0.3 * 0.3 * 0.4, "prism": 0.5 * 0.4 * 0.3 * 0.4}  # flat-faced: meshed exactly


DELETE = object()


def scene_of(text: str, name: str = "s"):
    return read_scene(parse_toml(text, name), name)


def beam(size: float = 0.5, increments: int = 2, order: int = 1):
    """The shipped 3D reference beam from shapes on a coarse mesh, a short ramp."""
    return tp.load_scene("beam_3d_ellipsoid").with_values(
        {
            "mesh.size": size,
            "mesh.near_chambers": size,
            "mesh.distance": size,
            "mesh.order": order,
            "schedule.increments": increments,
            "chambers[0].keyframes": [[0, 1.0], [increments, 1.5]],
        }
    )


@pytest.fixture(scope="module")
def tiny_run():
    return tp.simulate(beam())


def test_every_3d_shape_reads_writes_back_and_meshes_to_its_volume():
    """The scene file's 3D keys make the solids.py shapes, the scene writes back to itself, and the meshed
    chambers enclose the shapes' volumes: the flat-faced ones exactly, the curved ones within their walls'
    faceting (below their closed forms by under 15 % at edge 0.1 on walls of curvature radius 0.12 to 0.05)."""
    scene = scene_of(SHAPES)
    assert scene_of(scene.to_toml()) == scene
    built = scene.build()
    volumes = {c.chamber_name: c.rest_area for c in built.chambers}
    for name, exact in FLAT.items():
        assert volumes[name] == pytest.approx(exact, rel=1e-9)
    p, q, r, radius = 0.3, 0.2, 0.3, 0.05  # the rounded box's inner box (size - 2 radius), swept by the ball
    curved = {
        "ellipsoid": 4 / 3 * np.pi * 0.25 * 0.15 * 0.2,
        "cylinder": np.pi * 0.12**2 * 0.4,
        "rounded": p * q * r
        + 2 * (p * q + q * r + r * p) * radius
        + np.pi * (p + q + r) * radius**2
        + 4 / 3 * np.pi * radius**3,
    }
    for name, exact in curved.items():
        assert 0.85 * exact < volumes[name] < exact
    mesh = built.mesh
    assert mesh.volume == pytest.approx(3.5 * 0.8 * 0.8 - sum(volumes.values()), rel=1e-9)
    assert np.allclose(mesh.vertices[mesh.pinned, 0], -1.75)


def test_quadratic_order_adds_midside_nodes_on_the_curved_chamber_wall_and_straight_ones_elsewhere():
    """The reference beam's chamber is the ellipsoid (x / 0.85)^2 + ((y - 0.15) / 0.22)^2 + (z / 0.25)^2 = 1: its
    wall's midside nodes lie on it (all but those whose move would fold an element), every other one at its
    edge's middle; with mesh.curved = false every one at its edge's middle."""
    straight = beam(order=2).with_values({"mesh.curved": False}).build().mesh
    mesh = beam(order=2).build().mesh
    assert mesh.elements.shape[1] == 10 and np.array_equal(mesh.elements, straight.elements)
    ellipsoid = lambda x: (((x - [0.0, 0.15, 0.0]) / [0.85, 0.22, 0.25]) ** 2).sum(axis=1)
    wall = np.unique(mesh.chambers[0][:, 3:])
    assert np.all(ellipsoid(straight.vertices[wall]) < 1 - 1e-6)  # the chords' middles lie inside
    on = np.abs(ellipsoid(mesh.vertices[wall]) - 1) < 1e-6
    assert on.mean() > 0.95
    moved = np.flatnonzero(np.any(mesh.vertices != straight.vertices, axis=1))
    assert set(moved.tolist()) == set(wall[on].tolist())
    corners, middles = straight.vertices[straight.elements[:, [0, 1]]], straight.vertices[straight.elements[:, 4]]
    assert np.allclose(middles, corners.mean(axis=1))


def test_pneunet_layer_is_its_volume_group_and_stiffer():
    """pneunet_3d's region { group = "layer" } gives E = 5e4 to exactly the tetrahedra of the bottom slab (their
    centroids within `layer` of the bottom), E = 1e4 to the rest."""
    scene = tp.load_scene("pneunet_3d").with_values({"mesh.size": 0.5, "mesh.near_chambers": 0.5, "mesh.order": 1})
    mesh = scene.build().mesh
    _, parameters = scene.element_material(mesh)
    stiff = parameters[:, 0] > parameters[:, 0].min()
    centroid_y = mesh.vertices[mesh.elements].mean(axis=1)[:, 1]
    bottom = mesh.vertices[:, 1].min()
    assert stiff.any() and np.array_equal(stiff, centroid_y < bottom + scene.geometry.body.layer)
    with pytest.raises(
        PneumaInputError, match=r"group = 'floor': the mesh has no such volume group \(its groups: layer\)"
    ):
        scene.with_value("material.regions[0].group", "floor").build()


@pytest.mark.parametrize(
    "change, message",
    [
        ({"mesh.max_area": 0.01}, "mesh.max_area: a 3D body from shapes takes mesh.size"),
        ({"mesh.size": DELETE}, "missing key 'mesh.size'"),
        ({"mesh.size": -0.1}, "size = -0.1 must be > 0"),
        ({"mesh.near_chambers": 0.0}, r"near_chambers = 0.0 must be > 0"),
        (
            {"chambers[0].shape": "ellipse", "chambers[0].center": [0, 0.15], "chambers[0].semi_axes": [0.8, 0.2]},
            "chamber 'main': a 3D body's chambers are 3D shapes",
        ),
        ({"chambers[0].semi_axes": [0.85, 0.22]}, r"semi_axes = \(0.85, 0.22\) must be three numbers"),
    ],
)
def test_bad_3d_keys_are_one_error_naming_them(change, message):
    data = scene_data(beam())
    for key, value in change.items():
        if value is DELETE:
            del data["mesh"][key.split(".")[1]]
        else:
            set_key(data, key, value)
    with pytest.raises(PneumaInputError, match=message):
        read_scene(data, "s")


def test_pneunet_chambers_are_its_groups():
    scene = tp.load_scene("pneunet_3d")
    with pytest.raises(PneumaInputError, match=r"chambers\[0\].*group = 'c9' is none of the pneunet's chambers c1, c2"):
        scene.with_value("chambers[0].group", "c9")
    with pytest.raises(PneumaInputError, match="chamber name '=c1' cannot start with ="):
        scene.with_value("chambers[0].name", "=c1")
    data = scene_data(scene)
    data["chambers"][0] = {**data["chambers"][0], "shape": "box", "center": [0, 0, 0], "size": [0.1] * 3}
    del data["chambers"][0]["group"]
    with pytest.raises(PneumaInputError, match="a pneunet body makes its own chambers c1 .. c6"):
        read_scene(data, "s")
    with pytest.raises(PneumaInputError, match=r"mesh.max_area: a 2D body takes|mesh.size: a 2D body takes"):
        tp.load_scene("reference_beam").with_value("mesh.size", 0.1)


def test_without_gmsh_one_error_names_the_install_command(monkeypatch):
    scene = beam()  # reading the scene needs no gmsh
    monkeypatch.setitem(sys.modules, "gmsh", None)
    with pytest.raises(PneumaInputError, match=r"gmsh, which is not installed: pip install 'taichi-pneuma\[3d\]'"):
        sizing.check_scene(scene)
    with pytest.raises(PneumaInputError, match=r"pip install 'taichi-pneuma\[3d\]'"):
        scene.build()


def test_resource_guard_estimates_before_meshing_and_caps_gmsh():
    """A fine mesh is refused from its estimate (volume / regular tetrahedron, before meshing); a mesh whose
    estimate passes a small budget but whose gmsh output does not is refused after meshing, quadratic
    tetrahedra counted 8 times."""
    fine = beam(size=0.01)
    with pytest.raises(
        PneumaInputError,
        match=r"the mesh would have about \S+ tetrahedra and need about .* GB; the limit is "
        r"200000 elements \(--max-triangles raises it\)",
    ):
        sizing.check_scene(fine)
    estimate = beam(size=0.3).geometry.size_estimate()
    tets, nodes = estimate.elements, estimate.nodes
    assert 500 < tets < 3000 and 0 < nodes < tets
    coarse = beam(size=0.5)  # its ellipsoid meshed by the curvature fallback: ~10 times the estimate
    assert coarse.geometry.size_estimate().elements < 300
    with pytest.raises(PneumaInputError, match=r"the mesh has \d+ tetrahedra; the limit is 400 "):
        coarse.build(Budget(400))
    with pytest.raises(PneumaInputError, match=r"the mesh has \d+ tetrahedra; the limit is 300 "):
        coarse.with_value("mesh.order", 2).build(Budget(8 * 300))


def test_pneunet_from_the_command_line_curls_towards_its_layer(tmp_path):
    """The shipped PneuNet on a coarse mesh: inflated, the finger curls down (towards the stiff layer), and
    deflated it returns to rest."""
    ramps = [arg for i in range(6) for arg in ("--set", f"chambers[{i}].keyframes=[[0, 0.0], [3, 900.0], [6, 0.0]]")]
    code = inflate(
        [
            "--scene",
            "pneunet_3d",
            "--set",
            "mesh.size=0.5",
            "--set",
            "mesh.near_chambers=0.5",
            "--set",
            "mesh.order=1",
            "--set",
            "schedule.increments=6",
            *ramps,
            "--no-video",
            "--quiet",
            "--out",
            str(tmp_path),
        ]
    )
    assert code == 0
    (stem,) = [p.name[: -len("_summary.json")] for p in tmp_path.glob("pneunet_3d_*_summary.json")]  # the hash
    states = np.load(tmp_path / f"{stem}_states.npz")
    tip_dy = (states["positions"][:, states["tip"], 1] - states["rest"][states["tip"], 1]).mean(axis=1)
    assert tip_dy[3] < -0.05 and abs(tip_dy[-1]) < 1e-6
    summary = json.loads((tmp_path / f"{stem}_summary.json").read_text())
    assert summary["tetrahedra"] > 0 and summary["all_converged"]


def body_pixels(renderer, image):
    """The 3D view's pixels that are not the white background."""
    view = image[renderer.header_px :, : renderer.canvas.width]
    return np.any(view < 250, axis=2)


def projected_box(renderer, positions):
    pixels, _ = renderer.camera.project(positions, renderer.canvas.width, renderer.canvas.height)
    return pixels.min(axis=0), pixels.max(axis=0)


@pytest.mark.parametrize("view", ["numpy", "ggui"])
def test_frames_of_a_3d_run_show_the_body_where_it_is(tiny_run, view):
    """Both views draw each step's body inside the projection of its nodes, covering most of that box's
    width and height, with the chamber's blue seen through the section (no guides: the ghost and axes lie
    outside the body)."""
    track = Track3D.from_result(tiny_run, "stretch")
    try:
        renderer = FrameRenderer3D(track, 480, 320, backend=view, trace=False, log=lambda _: None, guides=False)
    except PneumaInputError as exc:
        pytest.skip(str(exc))
    try:
        for i in (0, len(track.positions) - 1):
            image = renderer.compose(i)[0]  # the shapes, without the text
            drawn = body_pixels(renderer, image)
            rows, columns = np.nonzero(drawn)
            lo, hi = projected_box(renderer, track.positions[i])
            assert columns.min() >= lo[0] - 2 and columns.max() <= hi[0] + 2
            assert rows.min() >= lo[1] - 2 and rows.max() <= hi[1] + 2
            assert np.ptp(columns) > 0.9 * (hi[0] - lo[0]) and np.ptp(rows) > 0.8 * (hi[1] - lo[1])
            view_image = image[renderer.header_px :, : renderer.canvas.width].astype(float)
            blue = (view_image[..., 2] > view_image[..., 0] + 40) & (view_image[..., 2] > view_image[..., 1] + 20)
            assert np.count_nonzero(blue) > 100
    finally:
        renderer.canvas.close()


def test_3d_frame_colours_are_the_tetrahedra_under_the_faces(tiny_run):
    """Coloured by the largest stretch: the rest state is all 1 (the colour map's low end); each face's value
    is its tetrahedron's."""
    from taichi_pneuma.fem.fields import ElementFields
    from taichi_pneuma.render.frames3d import surface_triangles

    track = Track3D.from_result(tiny_run, "stretch")
    assert np.allclose(track.color[0], 1.0)
    outer, walls, under = surface_triangles(tiny_run.mesh)
    mesh = tiny_run.mesh
    assert len(walls) == 1 and len(outer) + len(walls[0]) == len(mesh.surface)
    assert all(set(face) <= set(mesh.elements[t]) for face, t in zip(outer, under))
    fields = ElementFields(mesh.vertices, mesh.elements).at(tiny_run.positions[-1])["max_stretch"]
    assert np.array_equal(track.color[-1], fields[under]) and track.color[-1].max() > 1.01


def test_3d_video_from_the_command_line(tmp_path):
    """inflate on a 3D scene writes an mp4 of one 3D frame per step and the most deformed frame's PNG, with the
    chamber visible."""
    code = inflate(
        [
            "--scene",
            "beam_3d_ellipsoid",
            "--set",
            "mesh.size=0.5",
            "--set",
            "mesh.near_chambers=0.5",
            "--set",
            "mesh.order=1",
            "--set",
            "schedule.increments=2",
            "--set",
            "chambers[0].keyframes=[[0, 1.0], [2, 1.5]]",
            "--renderer",
            "pillow",
            "--size",
            "480x240",
            "--quiet",
            "--out",
            str(tmp_path),
        ]
    )
    assert code == 0
    (stem,) = [p.name[: -len(".mp4")] for p in tmp_path.glob("beam_3d_ellipsoid_*.mp4")]  # named by its hash
    frames = list(iio.imiter(tmp_path / f"{stem}.mp4"))
    assert len(frames) == 3 and frames[0].shape == (240, 480, 3)
    png = iio.imread(tmp_path / f"{stem}.png").astype(float)
    blue = (png[..., 2] > png[..., 0] + 40) & (png[..., 2] > png[..., 1] + 20)
    assert np.count_nonzero(blue) > 100
    summary = json.loads((tmp_path / f"{stem}_summary.json").read_text())
    assert summary["renderer"] == "NumPy z-buffer rasteriser" and summary["video_frames"] == 3


def test_api_video_and_plot_of_a_3d_run(tiny_run, tmp_path):
    export = tiny_run.video(tmp_path / "v.gif", tmp_path / "v.png", size=(320, 192), renderer="gui")
    assert export.frames == len(tiny_run.steps) and iio.imread(tmp_path / "v.png").shape == (192, 320, 3)
    figure = tiny_run.plot()
    assert "volume ratio V / V_rest" in [ax.get_xlabel() for ax in figure.axes]


@pytest.mark.skipif(not has_ggui(), reason="the live 3D window is GGUI's, which this backend lacks")
def test_interactive_3d_scene_resolves_per_chamber_slider(xvfb_display, monkeypatch):  # noqa: F811
    """--interactive's 3D window: a slider per chamber over its schedule's commands; each frame a Newton step
    toward the equilibrium at the slider's command, which a held slider reaches (all_converged)."""
    import taichi as ti

    from taichi_pneuma.realtime import interactive3d
    from taichi_pneuma.realtime.interactive import chamber_sliders, explore_solid

    try:
        ti.ui.check_ggui_availability()
    except Exception as exc:  # no Vulkan: GGUI cannot open a window
        pytest.skip(str(exc))
    scene = beam()
    (slider,) = chamber_sliders(scene)
    assert (slider.name, slider.low, slider.high, slider.value) == ("main", 1.0, 1.5, 1.0)
    script = iter([[1.0], [1.2], [1.2]] + [[1.4]] * 9)  # the last command held: the live loop converges
    real = interactive3d.commands_from
    monkeypatch.setattr(
        interactive3d, "commands_from", lambda sliders, shown, values: real(sliders, shown, next(script))
    )
    summary = explore_solid(scene, (320, 240), spin=10.0, max_frames=12)
    assert summary["solves"] == 3 and summary["frames"] == 12 and summary["all_converged"]
    assert summary["commands"] == pytest.approx([1.4], abs=1e-6)
