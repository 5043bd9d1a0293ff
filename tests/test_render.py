"""Offscreen frames, video files and the apps' rendering flags."""

import dataclasses
import json
import os
import subprocess
import sys

import imageio.v3 as iio
import imageio_ffmpeg
import numpy as np
import pytest
from renderers import SOFTWARE, needs_window
from scenes import SMALL_FLAGS, small_scene

from taichi_pneuma.apps import inflate, steer
from taichi_pneuma.backend import has_gui
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.render import canvases
from taichi_pneuma.render import frames as render_frames
from taichi_pneuma.render.colours import AREA_CURVE, BACKGROUND, CHAMBER_FILL, FACE, GROUND, PRESSURE_CURVE
from taichi_pneuma.render.frames import FrameRenderer, Track
from taichi_pneuma.render.text import label_box
from taichi_pneuma.render.video import write_video
from taichi_pneuma.scene.build import reference_scene
from taichi_pneuma.solve.simulate import run_schedule


@pytest.fixture(scope="module")
def ramp():
    built = small_scene().build()
    return built.mesh, run_schedule(built)


@pytest.fixture(scope="module")
def track(ramp):
    return Track.from_result(ramp[1])


def rgb8(color):
    return np.round(np.array(color) * 255)


def pixels_at(renderer, image, points):
    """Colours of the pixels under world points drawn in beam panel 0."""
    uv = renderer.to_canvas(0, points)
    cols = np.clip((uv[:, 0] * renderer.width).astype(int), 0, renderer.width - 1)
    rows = np.clip(((1 - uv[:, 1]) * renderer.height).astype(int), 0, renderer.height - 1)
    return image[rows, cols].astype(float)


@pytest.mark.parametrize("backend", ["gui", "ggui", "pillow"])
def test_frame_shows_the_mesh_and_the_filled_chamber(track, backend, capsys):
    try:
        renderer = FrameRenderer([track], 480, 192, trace=True, backend=backend)
    except PneumaInputError as exc:
        pytest.skip(str(exc))
    image = renderer.frame(2)
    assert image.shape == (192, 480, 3) and image.dtype == np.uint8
    x = track.states[2]
    tri = track.mesh.triangles
    centroids = x[tri].mean(axis=1)
    face = pixels_at(renderer, image, centroids)
    near_face = np.all(np.abs(face - rgb8(FACE)) < 40, axis=1)  # some centroids fall on a drawn edge
    assert near_face.mean() > 0.6
    chamber_centre = x[track.mesh.chambers[0]].mean(axis=0, keepdims=True)
    assert np.all(np.abs(pixels_at(renderer, image, chamber_centre) - rgb8(CHAMBER_FILL)) <= 3)
    below_beam = np.array([[x[:, 0].mean(), x[:, 1].min() - 0.05]])  # just under the bent beam: background
    assert np.all(np.abs(pixels_at(renderer, image, below_beam) - rgb8(BACKGROUND)) <= 3)
    # the pinned wall's square markers are dark
    assert pixels_at(renderer, image, x[track.mesh.pinned]).max(axis=1).mean() < 100
    assert f"renderer: {renderer.canvas.name}" in capsys.readouterr().out


def test_ground_line_is_drawn_where_the_ground_is(track):
    lowest = float(track.states[..., 1].min())
    grounded = dataclasses.replace(track, ground=lowest - 0.02)
    points = track.states.reshape(-1, 2)
    bounds = (points.min(axis=0) - 0.05, points.max(axis=0))
    renderer = FrameRenderer([grounded], 480, 192, trace=False, backend=SOFTWARE, bounds=bounds)
    image = renderer.frame(0)
    x_mid = float(track.states[0, :, 0].mean())
    on_line = pixels_at(renderer, image, np.array([[x_mid, lowest - 0.02]]))
    assert np.all(np.abs(on_line - rgb8(GROUND)) <= 3)
    no_ground = FrameRenderer([track], 480, 192, trace=False, backend=SOFTWARE, canvas=renderer.canvas, bounds=bounds)
    assert np.all(
        np.abs(pixels_at(no_ground, no_ground.frame(0), np.array([[x_mid, lowest - 0.02]])) - rgb8(BACKGROUND)) <= 3
    )


def test_view_frames_every_state(track):
    renderer = FrameRenderer([track, track], 480, 192, trace=False, backend=SOFTWARE)
    for panel, (x0, x1) in enumerate(renderer.panels):
        uv = renderer.to_canvas(panel, track.states.reshape(-1, 2))
        assert uv[:, 0].min() > x0 and uv[:, 0].max() < x1 and uv[:, 1].min() > 0 and uv[:, 1].max() < 1


@pytest.mark.parametrize("suffix", [".mp4", ".gif"])
def test_video_has_every_frame_at_its_size(tmp_path, suffix):
    frames = (np.full((64, 96, 3), 20 * i, np.uint8) for i in range(7))
    assert write_video(tmp_path / f"v{suffix}", frames, fps=7) == 7
    assert imageio_ffmpeg.count_frames_and_secs(str(tmp_path / f"v{suffix}"))[0] == 7
    assert iio.imread(tmp_path / f"v{suffix}", index=0).shape[:2] == (64, 96)


def test_interrupted_video_leaves_no_file(tmp_path):
    def frames():
        yield np.zeros((64, 64, 3), np.uint8)
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        write_video(tmp_path / "v.mp4", frames())
    assert os.listdir(tmp_path) == []


def test_unknown_video_extension_is_refused(tmp_path):
    with pytest.raises(PneumaInputError, match="v.avi"):
        write_video(tmp_path / "v.avi", iter([]))


def test_no_video_initialises_no_renderer_and_draws_no_picture(tmp_path, monkeypatch):
    def refuse(*args, **kwargs):
        raise AssertionError("a renderer was initialised")

    monkeypatch.setattr(render_frames, "open_canvas", refuse)
    assert inflate.main([*SMALL_FLAGS, "--no-video", "--out", str(tmp_path)]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        f"inflate_cy+0.15_growth2_steps3_max_area0.01{end}"
        for end in (".pvd", "_history.csv", "_scene.toml", "_states.npz", "_summary.json", "_vtk")
    ]


def test_inflate_renders_with_ti_gui_by_default_and_refuses_ggui_without_vulkan(tmp_path):
    """'auto' is ti.GUI (the faster renderer), so no Vulkan is needed (a backend without Taichi's GUIs,
    Quadrants, falls back to Pillow); asking for GGUI where Vulkan is missing is one error line before any solve."""
    env = dict(os.environ, VK_ICD_FILENAMES=str(tmp_path / "no_vulkan.json"))
    run = lambda *flags: subprocess.run(
        [
            sys.executable,
            "-m",
            "taichi_pneuma.apps.inflate",
            *SMALL_FLAGS,
            "--size",
            "320x160",
            "--out",
            str(tmp_path),
            *flags,
        ],
        capture_output=True,
        text=True,
        env=env,
    )
    proc = run()
    assert proc.returncode == 0, proc.stderr
    name = "ti.GUI (software)" if has_gui() else "Pillow (software)"
    assert f"renderer: {name}" in proc.stdout
    video = tmp_path / "inflate_cy+0.15_growth2_steps3_max_area0.01.mp4"
    assert imageio_ffmpeg.count_frames_and_secs(str(video))[0] == 3
    assert iio.imread(video, index=0).shape == (160, 320, 3)
    summary = json.loads((tmp_path / "inflate_cy+0.15_growth2_steps3_max_area0.01_summary.json").read_text())
    assert summary["renderer"] == name and summary["video_frames"] == 3
    assert iio.imread(tmp_path / "inflate_cy+0.15_growth2_steps3_max_area0.01.png").shape == (160, 320, 3)
    refused = run("--renderer", "ggui")
    errors = [line for line in refused.stderr.splitlines() if line.startswith("error:")]
    assert (
        refused.returncode == 2
        and len(errors) == 1
        and ("renderer = 'ggui' is unavailable" if has_gui() else "renderer = 'ggui' needs") in errors[0]
    )


def test_steer_plays_three_panels_in_one_video(tmp_path, capsys):
    flags = ["--max-area", "0.01", "--growth", "1.5", "--steps", "4", "--quiet"]
    assert steer.main([*flags, "--renderer", SOFTWARE, "--size", "384x128", "--out", str(tmp_path)]) == 0
    printed = capsys.readouterr().out
    assert all(f"cy = {cy}" in printed for cy in ("+0.15", "+0.00", "-0.15"))
    summary = json.loads((tmp_path / "steer_growth1.5_steps4_max_area0.01_summary.json").read_text())
    tips = summary["tip_deflection"]
    assert tips["+0.15"] == pytest.approx(-tips["-0.15"], rel=0.15)  # near mirror images (the meshes differ)
    assert imageio_ffmpeg.count_frames_and_secs(str(tmp_path / "steer_growth1.5_steps4_max_area0.01.mp4"))[0] == 4
    assert iio.imread(tmp_path / "steer_growth1.5_steps4_max_area0.01.png").shape == (128, 384, 3)


@pytest.mark.parametrize(
    "flags, word",
    [
        (["--size", "300"], "--size = '300'"),
        (["--size", "99x64"], "--size = '99x64'"),
        (["--fps", "0"], "fps = 0"),
        (["--video", "x.avi"], "x.avi"),
    ],
)
def test_bad_rendering_flags_exit_2(tmp_path, capsys, flags, word):
    assert inflate.main([*SMALL_FLAGS, *flags, "--out", str(tmp_path)]) == 2
    assert word in capsys.readouterr().err


def test_interactive_without_display_is_one_clear_error(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert inflate.main([*SMALL_FLAGS, "--interactive", "--out", str(tmp_path)]) == 2
    assert "--interactive needs a display" in capsys.readouterr().err


def test_without_taichi_gui_a_live_window_or_taichi_renderer_is_one_clear_error(tmp_path, capsys, monkeypatch):
    """Where the backend has neither ti.GUI nor GGUI (Quadrants; simulated here on Taichi), --interactive
    and --renderer gui/ggui are refused in one line naming what is missing; 'auto' draws with Pillow."""
    monkeypatch.setattr(canvases, "has_gui", lambda: False)
    monkeypatch.setattr(canvases, "has_ggui", lambda: False)
    monkeypatch.setenv("DISPLAY", ":0")
    assert inflate.main([*SMALL_FLAGS, "--interactive", "--out", str(tmp_path)]) == 2
    assert "a live window needs Taichi's GUI (ti.GUI or GGUI), which" in capsys.readouterr().err
    for backend in ("gui", "ggui"):
        with pytest.raises(PneumaInputError, match=f"renderer = '{backend}' needs Taichi's GUI .* --renderer pillow"):
            canvases.open_canvas(64, 64, backend)
    assert canvases.open_canvas(64, 64, "auto").name == "Pillow (software)"


def test_pillow_draws_the_picture_ggui_draws(track):
    """The same frame on GGUI (Vulkan) and on Pillow: averaged over 4 x 4 pixel blocks (Pillow's edges are
    anti-aliased, GGUI's are not) the two pictures agree within 24 of 255 levels at 99% of the blocks."""
    try:
        ggui = FrameRenderer([track], 480, 192, trace=True, backend="ggui", log=lambda *_: None).frame(2)
    except PneumaInputError as exc:
        pytest.skip(str(exc))
    pillow = FrameRenderer([track], 480, 192, trace=True, backend="pillow", log=lambda *_: None).frame(2)
    blocks = lambda image: image.reshape(48, 4, 120, 4, 3).mean(axis=(1, 3))
    assert np.mean(np.abs(blocks(ggui) - blocks(pillow)).max(axis=2) > 24) < 0.01


@pytest.fixture
def xvfb_display(monkeypatch):
    """A virtual X display on a free display number, ready when yielded (skips when Xvfb is not installed)."""
    import shutil

    if not shutil.which("Xvfb"):
        pytest.skip("Xvfb is not installed (apt-get install xvfb)")
    read_end, write_end = os.pipe()
    proc = subprocess.Popen(
        ["Xvfb", "-displayfd", str(write_end), "-screen", "0", "800x600x24"],
        pass_fds=(write_end,),
        stderr=subprocess.DEVNULL,
    )
    os.close(write_end)
    with os.fdopen(read_end) as ready:
        number = ready.readline().strip()  # Xvfb writes its display number once it accepts connections
    monkeypatch.setenv("DISPLAY", f":{number}")
    yield
    proc.terminate()
    proc.wait()


@needs_window
def test_interactive_window_resolves_when_the_slider_moves(xvfb_display, monkeypatch, capsys):
    from taichi_pneuma.realtime.interactive import explore

    moves = iter([1.0, 1.0, 1.3, 1.3, 1.6])  # the slider's values on successive frames
    monkeypatch.setattr(canvases.GUICanvas, "slider", lambda self, label, value, low, high: next(moves))
    scene = reference_scene(cy=0.15, max_area=0.01)
    assert explore(scene, 2.0, (320, 160), "gui", max_frames=5) == {"all_converged": True, "solves": 3}
    printed = capsys.readouterr().out
    assert "area x1.300" in printed and "area x1.600" in printed


def pixel(image, x, y):
    return image[int(round(y)), int(round(x))].astype(float)


def test_text_never_covers_the_body(track):
    """Three titled panels (the steering picture's layout): every label's box lies off the body's pixels
    in every frame."""
    titled = [dataclasses.replace(track, title=f"cy = +0.15: chamber high -> curls down {k}") for k in range(3)]
    renderer = FrameRenderer(titled, 1344, 320, trace=False, backend=SOFTWARE)
    for i in range(renderer.frames):
        boxes = np.array([label_box(label) for label in renderer.draw(i)])
        for p, t in enumerate(titled):
            uv = renderer.to_canvas(p, t.states[i])
            px = np.column_stack([uv[:, 0] * renderer.width, (1 - uv[:, 1]) * renderer.height])
            inside = (
                (px[:, None, 0] >= boxes[None, :, 0])
                & (px[:, None, 0] <= boxes[None, :, 2])
                & (px[:, None, 1] >= boxes[None, :, 1])
                & (px[:, None, 1] <= boxes[None, :, 3])
            )
            assert not inside.any()


def test_body_colours_follow_det_f_and_the_colour_bar_numbers(ramp):
    """Each triangle is drawn in viridis(det F) on the run's det F range, and each number of the colour
    bar sits beside the colour of its value."""
    import matplotlib

    mesh, result = ramp
    colored = Track.from_result(result, color="detF")

    def areas(x):
        a, b, c = (x[mesh.triangles[:, k]] for k in range(3))
        return (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0]

    det = np.array([areas(x) / areas(mesh.vertices) for x in result.positions])  # det F = area ratio
    assert colored.color == pytest.approx(det, rel=1e-10) and colored.color_label == "det F"
    renderer = FrameRenderer([colored], 480, 192, trace=False, backend=SOFTWARE)
    image = renderer.frame(2)
    lo, hi = det.min(), det.max()
    assert renderer.color_range == pytest.approx((lo, hi)) and hi - lo > 0.02
    viridis = lambda v: np.asarray(matplotlib.colormaps["viridis"]((np.asarray(v) - lo) / (hi - lo)))[..., :3] * 255
    centroids = result.positions[2][mesh.triangles].mean(axis=1)
    close = np.all(np.abs(pixels_at(renderer, image, centroids) - viridis(det[2])) < 20, axis=1)
    assert close.mean() > 0.6  # the rest fall on the drawn outline or the chamber wall
    ticks = [label for label in renderer.draw(2) if label.anchor == "lm"]
    assert len(ticks) >= 3
    for label in ticks:
        bar = pixel(image, label.x - 15, label.y)  # the bar's middle column, at the tick's height
        assert np.all(np.abs(bar - viridis(float(label.text))) < 12), label


def test_trace_axis_numbers_match_the_drawn_curves(track):
    """The numbers on the trace panel's axes put each curve where its values are: the pixel at (step, value)
    mapped through the tick labels is the curve's colour (where the two curves do not cross)."""
    renderer = FrameRenderer([track], 960, 384, trace=True, backend=SOFTWARE)
    labels = renderer.draw(0)
    image = renderer.frame(0)
    step_x = {float(l.text): l.x for l in labels if l.anchor == "mt" and l.text.replace(".", "").isdigit()}
    assert set(step_x) >= {0.0, 1.0, 2.0}
    y_of = {}
    for anchor, color, values in (
        ("rm", AREA_CURVE, track.area_ratio[:, 0]),
        ("lm", PRESSURE_CURVE, track.pressure[:, 0]),
    ):
        ticks = [(float(l.text), l.y) for l in labels if l.anchor == anchor and l.color == color]
        assert len(ticks) >= 3
        (v0, y0), (v1, y1) = ticks[0], ticks[-1]
        y_of[color] = y0 + (values - v0) * (y1 - y0) / (v1 - v0)
    checked = 0
    for color, other in ((AREA_CURVE, PRESSURE_CURVE), (PRESSURE_CURVE, AREA_CURVE)):
        for step in (0, 1, 2):
            y, x = y_of[color][step], step_x[float(step)]
            if abs(y - y_of[other][step]) < 8:
                continue  # the curves meet here
            patch = image[int(y) - 2 : int(y) + 3, int(x) - 2 : int(x) + 3].reshape(-1, 3)
            assert np.min(np.abs(patch - rgb8(color)).max(axis=1)) < 40, (color, step)
            checked += 1
    assert checked >= 2


def test_quadratic_elements_are_coloured_by_their_own_value():
    """Each P2 element's four display triangles take its value: the middle one's centroid shows it."""
    import matplotlib

    built = reference_scene(cy=0.15, growth=2.0, steps=3, max_area=0.02, order=2).build()
    result = run_schedule(built)
    colored = Track.from_result(result, color="stretch")
    renderer = FrameRenderer([colored], 480, 192, trace=False, backend=SOFTWARE)
    image = renderer.frame(2)
    lo, hi = renderer.color_range
    expected = np.asarray(matplotlib.colormaps["viridis"]((colored.color[2] - lo) / (hi - lo)))[:, :3] * 255
    middle = result.positions[2][built.mesh.triangles[:, 3:]].mean(axis=1)
    close = np.all(np.abs(pixels_at(renderer, image, middle) - expected) < 20, axis=1)
    assert close.mean() > 0.6


def test_a_printed_zero_is_never_signed():
    """'p = -0.0' on a frame or a progress line: a value that rounds to zero prints unsigned, padded ones keeping
    their width; other negatives keep their sign."""
    from taichi_pneuma.render.text import number

    assert [number(v, ".1f") for v in (-0.0, -0.01, -0.06, 0.04)] == ["0.0", "0.0", "-0.1", "0.0"]
    assert number(-1e-13, "8.2f") == "    0.00" and number(-2.5, "8.2f") == "   -2.50"
