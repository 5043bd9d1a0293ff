"""3D frames: the camera's projection and orbit, the NumPy z-buffer rasteriser against exact coverage and
depth order, GGUI's scene against it, the frame layout on a synthetic deforming body, video, the
interactive window's slider and orbit logic."""

import dataclasses

import imageio.v3 as iio
import numpy as np
import pytest
from scipy.spatial import ConvexHull
from test_render import xvfb_display  # noqa: F401  (the virtual display fixture)

from taichi_pneuma.backend import has_ggui
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.realtime import interactive3d
from taichi_pneuma.realtime.interactive3d import Slider, commands_from, dragged, explore_3d
from taichi_pneuma.render.camera import MAX_ELEVATION, Camera
from taichi_pneuma.render.frames3d import CHAMBER, FrameRenderer3D, Track3D, body_colormap, open_view, render_video_3d
from taichi_pneuma.render.ggui3d import BLANK_RETRIES
from taichi_pneuma.render.surface import AMBIENT, BACK_FACE, SPECULAR, NumpyView, rasterise, shade_faces
from taichi_pneuma.render.text import LINE_PX

CUBE = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)


def box_surface(lo, hi, k: int):
    """The surface of the box lo..hi, k x k squares per side, two triangles each, oriented outward."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    vertices, faces = [], []
    t = np.linspace(0, 1, k + 1)
    for axis in range(3):
        u, v = [a for a in range(3) if a != axis]
        for side in (0, 1):
            grid = np.zeros((k + 1, k + 1, 3))
            grid[..., axis] = (lo, hi)[side][axis]
            grid[..., u] = lo[u] + (hi[u] - lo[u]) * t[:, None]
            grid[..., v] = lo[v] + (hi[v] - lo[v]) * t[None, :]
            base = len(vertices) and sum(len(p) for p in vertices)
            vertices.append(grid.reshape(-1, 3))
            i, j = np.meshgrid(np.arange(k), np.arange(k), indexing="ij")
            a, b, c, d = (base + (i + di) * (k + 1) + j + dj for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)))
            quads = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
            faces.append(quads)
    vertices, faces = np.concatenate(vertices), np.concatenate(faces)
    x = vertices[faces]
    normal = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    inward = np.sum(normal * (x.mean(axis=1) - (lo + hi) / 2), axis=1) < 0
    faces[inward] = faces[inward][:, ::-1]
    return vertices, faces


@pytest.fixture(scope="module")
def finger():
    """A 4 x 0.8 x 0.8 block with a box chamber inside, bent down about z by a growing curvature (the left end
    fixed): a synthetic ramp of 4 steps; colour: each node's displacement magnitude."""
    outer, outer_faces = box_surface((-2, -0.4, -0.4), (2, 0.4, 0.4), 8)
    inner, inner_faces = box_surface((-1.2, -0.1, -0.2), (1.2, 0.25, 0.2), 4)
    rest = np.concatenate([outer, inner])
    chamber = inner_faces + len(outer)
    states = []
    for kappa in (0.0, 0.15, 0.3, 0.45):
        if kappa == 0:
            states.append(rest.copy())
            continue
        s, r = rest[:, 0] + 2, 1 / kappa + rest[:, 1]
        states.append(np.column_stack([-2 + r * np.sin(kappa * s), r * np.cos(kappa * s) - 1 / kappa, rest[:, 2]]))
    positions = np.array(states)
    color = np.linalg.norm(positions - rest, axis=2)
    captions = tuple((f"step {i}/3",) for i in range(4))
    trace = (
        ("curvature", np.array([0.0, 0.15, 0.3, 0.45])),
        ("tip y", positions[:, rest[:, 0] > 1.99, 1].mean(axis=1)),
    )
    return Track3D(
        positions,
        outer_faces,
        (chamber,),
        color=color,
        color_label="|u|",
        title="bent block",
        captions=captions,
        trace=trace,
    )


def test_camera_basis_projection_and_orbit():
    camera = Camera(target=(1.0, 2.0, 3.0), distance=4.0, azimuth=30.0, elevation=20.0)
    assert np.linalg.norm(camera.eye - camera.target) == pytest.approx(4.0)
    basis = camera.basis()
    assert np.allclose(basis @ basis.T, np.eye(3)) and np.allclose(np.cross(basis[0], basis[1]), -basis[2])
    assert basis[1][1] > 0  # the picture's up has the world's up in it
    pixels, depth = camera.project(np.array([camera.target]), 200, 100)
    assert np.allclose(pixels, [[100, 50]]) and depth == pytest.approx([4.0])
    # a point one unit right of the target at the depth of the target: F / 4 pixels right, F = 50 / tan(fov / 2)
    right, _ = camera.project(np.array(camera.target) + basis[0], 200, 100)
    assert right[0] - 100 == pytest.approx(50 / np.tan(np.radians(35) / 2) / 4)
    turned = camera.orbit(350.0, 100.0)
    assert turned.azimuth == pytest.approx(20.0) and turned.elevation == MAX_ELEVATION
    assert np.linalg.norm(turned.eye - turned.target) == pytest.approx(4.0)


def test_fitted_camera_frames_the_box_tightly():
    """Every corner projects inside the frame less its margin, and one touches that margin."""
    points = CUBE * [4.0, 0.8, 0.8]
    camera = Camera(azimuth=40, elevation=30).fitted(points, 320, 200, margin=0.1)
    pixels, depth = camera.project(points, 320, 200)
    assert np.all(depth > 0)
    slack = np.min(np.concatenate([pixels[:, 0] - 32, 288 - pixels[:, 0], pixels[:, 1] - 20, 180 - pixels[:, 1]]))
    assert -1e-9 <= slack < 1e-6


def test_rasterised_cube_covers_its_projected_silhouette():
    """The pixels a unit cube covers number its projected outline's area (the convex hull of its projected
    corners) to within the pixels its outline crosses."""
    camera = Camera(azimuth=30, elevation=25).fitted(CUBE, 640, 480)
    pixels, depth = camera.project(CUBE, 640, 480)
    faces = ConvexHull(CUBE).simplices
    image = rasterise(pixels[faces], depth[faces], np.zeros((len(faces), 3)), 640, 480)
    covered = np.count_nonzero(image[..., 0] < 0.5)
    outline = ConvexHull(pixels)
    assert abs(covered - outline.volume) < 0.5 * outline.area  # hull .volume is the area, .area the perimeter
    assert abs(covered - outline.volume) < 0.001 * outline.volume


def test_nearest_triangle_wins_whatever_the_order():
    camera = Camera(azimuth=0, elevation=0, distance=5.0)
    square = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, -1, 0], [1, 1, 0], [-1, 1, 0]], float).reshape(2, 3, 3)
    near, far = square + [0.3, 0, 1.0], square  # near: 1 closer to the eye (on +z), shifted right
    red, blue = np.array([1.0, 0, 0]), np.array([0, 0, 1.0])
    for order in ((near, far), (far, near)):
        corners = np.concatenate(order)
        colors = np.repeat([red if t is near else blue for t in order], 2, axis=0)
        image = NumpyView(200, 200).render(corners, colors, camera, (1, 1, 1))
        pixels, _ = camera.project(np.array([[0.0, 0, 1.0], [-0.9, 0.0, 0.0]]), 200, 200)
        (c0, r0), (c1, r1) = np.round(pixels - 0.5).astype(int)
        assert np.allclose(image[r0, c0], red) and np.allclose(image[r1, c1], blue)


def test_colours_are_interpolated_perspective_correctly():
    """On a slanted triangle the colour at the projection of an edge's world midpoint is the mean of that
    edge's corner colours (screen-space interpolation would be off where the depth varies)."""
    camera = Camera(azimuth=0, elevation=0, distance=3.0)
    corners = np.array([[[-1.0, -1.0, 1.5], [1.0, -1.0, -3.0], [0.0, 1.0, 0.0]]])
    colors = np.array([[[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]]])
    image = NumpyView(400, 400).render(corners, colors, camera, (1, 1, 1))
    midpoint = corners[0, :2].mean(axis=0) + [0.0, 0.02, 0.0]  # just inside the triangle
    ((c, r),) = np.floor(camera.project(midpoint[None], 400, 400)[0]).astype(int)
    assert np.allclose(image[r, c], [0.5, 0.02, 0.48], atol=0.03)


def test_shading_lights_a_face_towards_the_eye_and_darkens_its_back():
    camera = Camera(azimuth=0, elevation=0, distance=5.0)
    towards = np.array([[[-1.0, -1, 0], [1, -1, 0], [0, 1, 0]]])  # normal +z, towards the eye
    (front,), (highlight,) = shade_faces(towards, camera)
    (back,), (no_highlight,) = shade_faces(towards[:, ::-1], camera)
    assert AMBIENT < front <= 1 and back == pytest.approx(BACK_FACE * front)
    assert 0 < highlight <= SPECULAR and no_highlight == 0


def ggui_or_skip(width, height):
    try:
        return open_view("ggui", width, height, log=lambda _: None)
    except PneumaInputError as exc:
        pytest.skip(str(exc))


def test_ggui_scene_draws_what_the_rasteriser_draws(finger):
    """The same shaded triangles and camera on both views: the same silhouette and colours, up to edge pixels."""
    renderer = FrameRenderer3D(finger, 640, 400, backend="numpy", trace=False)
    corners, colors = renderer.triangles(2)
    ggui = ggui_or_skip(renderer.canvas.width, renderer.canvas.height)
    try:
        a = renderer.canvas.render(corners, colors, renderer.camera, (1, 1, 1))
        b = ggui.render(corners, colors, renderer.camera, (1, 1, 1))
    finally:
        ggui.close()
    drawn_a, drawn_b = np.any(a < 0.99, axis=2), np.any(b < 0.99, axis=2)
    assert np.count_nonzero(drawn_a ^ drawn_b) < 0.01 * np.count_nonzero(drawn_a)
    both = drawn_a & drawn_b
    assert np.median(np.abs(a[both] - b[both])) < 2 / 255 and np.mean(np.abs(a[both] - b[both]) > 0.05) < 0.03


def test_a_frame_ggui_gives_back_blank_is_drawn_again_then_by_the_rasteriser(finger, monkeypatch):
    """GGUI handing back only background (seen under load) for a frame with the body in view: drawn again, and
    after the retries by the NumPy rasteriser, counted; never a picture without its body."""
    renderer = FrameRenderer3D(finger, 640, 400, backend="numpy", trace=False)
    corners, colors = renderer.triangles(2)
    expected = renderer.canvas.render(corners, colors, renderer.camera, (1, 1, 1))
    ggui = ggui_or_skip(renderer.canvas.width, renderer.canvas.height)
    reads = []
    blank = np.ones((ggui.width, ggui.height, 4), np.float32)  # (GGUI's buffer is column-major: rotated back)
    monkeypatch.setattr(ggui.window, "get_image_buffer_as_numpy", lambda: reads.append(1) or blank)
    try:
        image = ggui.render(corners, colors, renderer.camera, (1, 1, 1))
        empty = ggui.render(corners[:0], colors[:0], renderer.camera, (1, 1, 1))  # nothing in view: blank is right
    finally:
        ggui.close()
    assert len(reads) == 1 + BLANK_RETRIES + 1 and ggui.blank_frames == 1
    assert np.array_equal(image, expected) and np.all(empty == 1.0)


def view_of(renderer, image):
    return image[renderer.header_px :, : renderer.canvas.width]


def test_frames_show_the_chambers_through_the_section_and_never_crop_the_body(finger):
    """With the section the chamber's blue shows inside the body; without it the closed body hides it. The
    camera fitted to every state keeps the body off the view's border in every frame."""

    def chamber_blue(v):
        return np.count_nonzero((v[..., 2] > v[..., 0] + 40.0) & (v[..., 2] > v[..., 1] + 20.0))

    plain = dataclasses.replace(finger, color=None)  # light green: no blue in the body
    cut = FrameRenderer3D(plain, 640, 360, backend="numpy", trace=False, guides=False)  # no blue z axis
    whole = FrameRenderer3D(plain, 640, 360, backend="numpy", trace=False, section=False, guides=False)
    for i in range(cut.frames):
        view = view_of(cut, cut.frame(i))
        assert chamber_blue(view) > 500 and chamber_blue(view_of(whole, whole.frame(i))) == 0
        border = np.concatenate([view[0], view[-1], view[:, 0], view[:, -1]])
        assert np.all(border == 255)


def test_colour_field_and_colour_bar(finger):
    """Coloured per node on one scale for all steps: the rest state is all the colour map's low end (|u| = 0);
    a bent state shows high values; the colour bar spans the map (lightened as the body's)."""
    renderer = FrameRenderer3D(finger, 640, 360, backend="numpy", trace=False)
    lo, hi = renderer.range
    assert lo == 0.0 and hi == pytest.approx(finger.color.max())
    (rest, rest_colors), (bent, bent_colors) = (renderer.triangles(i) for i in (0, 3))
    low, high = body_colormap(np.array([lo, hi]), lo, hi)
    n_body, n_walls = len(renderer.section.surface), len(renderer.section.walls)

    def unshaded(corners, colors):
        factor, highlight = shade_faces(corners, renderer.camera)
        return (colors - highlight[:, None, None]) / factor[:, None, None]

    assert np.allclose(unshaded(rest, rest_colors)[:n_body], low)
    assert np.allclose(unshaded(rest, rest_colors)[n_body : n_body + n_walls], CHAMBER)
    assert np.any(np.all(np.isclose(unshaded(bent, bent_colors)[:n_body], high, atol=0.02), axis=-1))  # the top
    image = renderer.frame(3)
    x0 = renderer.canvas.width + 8
    strip = image[renderer.header_px + LINE_PX + 6 : renderer.height - 18, x0 + 7]
    assert np.allclose(strip[0] / 255, high, atol=0.03) and np.allclose(strip[-1] / 255, low, atol=0.03)


def test_header_and_trace_cursor(finger):
    renderer = FrameRenderer3D(finger, 800, 360, backend="numpy")
    frames = [renderer.frame(i) for i in range(renderer.frames)]
    assert all(np.any(f[: renderer.header_px, :200] < 128) for f in frames)  # title and caption text
    columns = renderer._trace.columns
    assert columns == sorted(columns) and len(set(columns)) == renderer.frames
    panel = [f[:, renderer.width - renderer.trace_px :] for f in frames]
    for i, p in enumerate(panel):
        rows = slice(*renderer._trace.rows)
        assert np.all(p[rows, columns[i]][5:-5] == 60)  # the cursor: a grey column across the plot box


def test_video_has_every_frame(finger, tmp_path):
    export = render_video_3d(
        finger, tmp_path / "ramp.mp4", tmp_path / "last.png", size=(480, 272), backend="numpy", log=lambda _: None
    )
    frames = list(iio.imiter(tmp_path / "ramp.mp4"))
    assert export.frames == 4 == len(frames) and frames[0].shape == (272, 480, 3)
    assert iio.imread(tmp_path / "last.png").shape == (272, 480, 3)
    assert export.renderer == NumpyView.name and export.ms_per_frame > 0


def test_bad_track_and_view_are_named():
    x = np.zeros((2, 5, 3))
    with pytest.raises(PneumaInputError, match=r"positions must be \(steps, nodes, 3\)"):
        Track3D(np.zeros((5, 3)), np.zeros((1, 3), int))
    with pytest.raises(PneumaInputError, match=r"triangles must be \(k, 3\) node indices in 0..4"):
        Track3D(x, np.array([[0, 1, 5]]))
    with pytest.raises(PneumaInputError, match=r"color must be \(steps, boundary faces\)"):
        Track3D(x, np.array([[0, 1, 2]]), color=np.zeros((2, 4)))
    with pytest.raises(PneumaInputError, match="renderer = 'vulkan' is not one of auto, numpy, ggui"):
        open_view("vulkan", 100, 100)


def test_slider_commands_and_drag_orbit():
    sliders = [Slider("c1", 0.0, 1000.0, 0.0), Slider("c2", 1.0, 2.0, 1.0)]
    shown = np.array([0.0, 1.0])
    assert commands_from(sliders, shown, [np.float32(0.0), np.float32(1.0)]) is None
    moved = commands_from(sliders, shown, [np.float32(250.5), np.float32(3.0)])
    assert np.allclose(moved, [250.5, 2.0])  # clamped to c2's range
    camera = Camera(azimuth=10.0, elevation=20.0)
    turned = dragged(camera, (0.5, 0.5), (0.75, 0.4))
    assert turned.azimuth == pytest.approx(10.0 - 90.0 + 360.0) and turned.elevation == pytest.approx(38.0)
    with pytest.raises(PneumaInputError, match="slider 'c1'"):
        Slider("c1", 1.0, 0.0, 0.5)


@pytest.mark.skipif(not has_ggui(), reason="the live 3D window is GGUI's, which this backend lacks")
def test_interactive_window_resolves_on_slider_moves_and_spins(xvfb_display, finger, monkeypatch):  # noqa: F811
    """Under a virtual display: solve runs every frame at the commands on screen, a changed slider value counts
    as a move, the camera spins."""
    import taichi as ti

    try:
        ti.ui.check_ggui_availability()
    except Exception as exc:  # no Vulkan: GGUI cannot open a window
        pytest.skip(str(exc))
    script = iter([[0.0], [0.0], [0.5], [0.5], [1.0]])
    monkeypatch.setattr(
        interactive3d,
        "commands_from",
        lambda sliders, shown, values, real=commands_from: real(sliders, shown, next(script)),
    )
    calls = []

    def solve(commands):
        calls.append(commands.tolist())
        return finger.positions[int(round(3 * commands[0]))], [f"command {commands[0]:.2f}"]

    summary = explore_3d(
        solve,
        [Slider("c", 0.0, 1.0, 0.0)],
        finger.positions[0],
        finger.boundary,
        finger.chambers,
        size=(320, 240),
        spin=5.0,
        max_frames=5,
    )
    assert calls == [[0.0], [0.0], [0.0], [0.5], [0.5], [1.0]]  # solve: every frame, at the commands on screen
    assert summary["solves"] == 3 and summary["frames"] == 5
    assert summary["azimuth"] == pytest.approx(30.0 + 25.0)


def test_an_offscreen_ggui_view_leaves_no_imgui_ini_in_the_current_folder(tmp_path, monkeypatch):
    """imgui writes its settings (imgui.ini) into the current folder when a window closes: an offscreen view
    removes it, and keeps one that was there before."""
    monkeypatch.chdir(tmp_path)
    view = ggui_or_skip(64, 64)
    view.render(np.array([[[-1.0, -1, 0], [1, -1, 0], [0, 1, 0]]]), np.ones((1, 3, 3)), Camera(), (1, 1, 1))
    view.close()
    assert not (tmp_path / "imgui.ini").exists()
    (tmp_path / "imgui.ini").write_text("[Window][mine]\n")
    view = ggui_or_skip(64, 64)
    view.close()
    assert (tmp_path / "imgui.ini").exists()  # the user's own, not removed (imgui may rewrite it)
