"""What a new user meets in the first hour: the API's obvious calls, the shipped scenes by name, the apps'
--help, output that matches the flags, and the pictures (tip path, trace panel, clamp markers, the
frame PNG, the sweep plot)."""

import dataclasses
import fnmatch
import inspect
import json
import math
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import imageio.v3 as iio
import imageio_ffmpeg
import numpy as np
import pytest
from renderers import SOFTWARE
from scenes import SMALL_FLAGS, small_run

import taichi_pneuma as tp
from taichi_pneuma.apps import bench, inflate, optimize, reach, serve, steer, sweep
from taichi_pneuma.render.colours import TIP_PATH
from taichi_pneuma.render.frames import PIN_HALF_PX, FrameRenderer, Track
from taichi_pneuma.render.text import label_box
from taichi_pneuma.scene.shipped import SHIPPED
from taichi_pneuma.study import parse_vary, study_figure

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def small():
    return small_run()


# --- the API ---------------------------------------------------------------------------------------


def test_reference_scene_and_with_value_take_the_command_lines_short_names():
    short = tp.reference_scene(E=2e4, nu=0.4, k=2e5, max_area=0.01)
    long = tp.reference_scene(youngs_modulus=2e4, poisson_ratio=0.4, chamber_stiffness=2e5, max_area=0.01)
    assert short == long
    assert (short.material.youngs_modulus, short.material.poisson_ratio) == (2e4, 0.4)
    assert short.controls[0].kind.stiffness == 2e5
    with pytest.raises(TypeError, match="youngs"):
        tp.reference_scene(youngs=1.0)
    base = tp.reference_scene(max_area=0.01)
    assert base.with_value("E", 3e4) == base.with_value("material.E", 3e4)
    assert base.with_values({"cy": -0.1, "nu": 0.3}) == base.with_values(
        {"chambers[0].center[1]": -0.1, "material.nu": 0.3}
    )
    with pytest.raises(tp.PneumaInputError, match="material.nu"):
        base.with_value("nu", 0.5)  # the error names the key the short name stands for


def test_progress_true_shows_a_bar_and_a_function_is_still_called(capsys):
    scene = tp.reference_scene(growth=1.2, steps=3, max_area=0.02)
    tp.simulate(scene, progress=True)
    bar = capsys.readouterr().err
    assert scene.name in bar and "/3 [" in bar  # tqdm's bar over the 3 steps (rest state included)
    seen = []
    tp.simulate(scene, progress=lambda step, positions, force: seen.append(step.step))
    assert seen == [0, 1, 2]


def test_tip_rotation_is_the_tip_vertices_least_squares_rotation(small):
    """An independent formula: the angle of the rigid rotation that best maps the rest tip vertices (about
    their mean) onto the deformed ones, atan2(sum of cross products, sum of dot products)."""
    tip = small.mesh.tip
    rest = small.mesh.vertices[tip] - small.mesh.vertices[tip].mean(axis=0)
    now = small.positions[-1][tip] - small.positions[-1][tip].mean(axis=0)
    angle = math.degrees(math.atan2(np.sum(rest[:, 0] * now[:, 1] - rest[:, 1] * now[:, 0]), np.sum(rest * now)))
    assert small.tip_rotation == pytest.approx(angle, abs=1e-9) and abs(angle) > 0.5


def test_version_stop_and_ramp_interrupted_are_exported():
    assert re.fullmatch(r"\d+\.\d+\.\d+", tp.__version__)
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert pyproject["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "taichi_pneuma.__version__"}
    assert set(tp.__all__) <= set(dir(tp))
    with pytest.raises(tp.RampInterrupted) as stopped:
        tp.simulate(tp.reference_scene(growth=1.2, steps=4, max_area=0.02), stop=lambda: True)
    assert len(stopped.value.result.steps) == 1  # stopped after the rest step


def test_every_public_result_attribute_is_documented():
    doc = "\n".join(inspect.getdoc(cls) or "" for cls in tp.Result.__mro__)  # its own and its records' (Run)
    fields = {f.name for f in dataclasses.fields(tp.Result)}
    for name in dir(tp.Result):
        if name.startswith("_"):
            continue
        if name in fields:
            assert re.search(rf"\b{name}\b", doc), f"field {name} is not described in Result's docstring"
        else:
            assert inspect.getdoc(inspect.getattr_static(tp.Result, name)), f"Result.{name} has no docstring"


def test_video_takes_a_size_string_and_creates_its_directories(small, tmp_path):
    export = small.video(tmp_path / "new" / "sub" / "a.mp4", png=tmp_path / "pngs" / "a.png", size="480x192")
    assert (export.width, export.height) == (480, 192)
    assert iio.imread(tmp_path / "new" / "sub" / "a.mp4", index=0).shape == (192, 480, 3)
    assert iio.imread(tmp_path / "pngs" / "a.png").shape == (192, 480, 3)
    for bad in ("480x19", "480", (480,), "wide"):
        with pytest.raises(tp.PneumaInputError, match=r"^size = "):
            small.video(tmp_path / "b.mp4", size=bad)


def test_the_frame_png_is_the_most_deformed_step(tmp_path):
    """A ramp up to 2x and back to rest: the PNG is the frame at the peak (step 2), pixel for pixel."""
    scene = tp.reference_scene(max_area=0.02).with_values(
        {"schedule.increments": 4, "chambers[0].keyframes": [[2, 2.0], [4, 1.0]]}
    )
    result = tp.simulate(scene)
    assert result.peak_step() == 2
    result.video(tmp_path / "v.mp4", png=tmp_path / "v.png", size=(320, 160), renderer=SOFTWARE)
    renderer = FrameRenderer([Track.from_result(result, color="stretch")], 320, 160, backend=SOFTWARE)
    assert np.array_equal(iio.imread(tmp_path / "v.png"), renderer.frame(2))
    assert not np.array_equal(renderer.frame(2), renderer.frame(4))


# --- shipped scenes ----------------------------------------------------------------------------------


def test_shipped_scenes_load_by_name_from_anywhere(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert tp.load_scene("pneunet_finger") == tp.load_scene(SHIPPED / "pneunet_finger.toml")
    assert tp.load_scene("pneunet_finger.toml").name == "pneunet_finger"
    assert len(tp.load_scene("bidirectional").targets) == 3  # a scene with [[targets]] ships
    (tmp_path / "pneunet_finger.toml").write_text(tp.load_scene("bidirectional").to_toml())
    assert tp.load_scene("pneunet_finger").name == "bidirectional"  # a file that exists is read first
    with pytest.raises(tp.PneumaInputError, match=r"'nosuch' cannot be read .*bidirectional, blocked_force_3d"):
        tp.load_scene("nosuch")


def test_every_shipped_file_is_package_data():
    """pyproject's package-data patterns take every file of taichi_pneuma/scenes into the wheel."""
    patterns = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]
    shipped = [p.relative_to(ROOT / "taichi_pneuma").as_posix() for p in SHIPPED.rglob("*") if p.is_file()]
    assert len(shipped) >= 5
    for name in shipped:
        assert any(fnmatch.fnmatch(name, pattern) for pattern in patterns["taichi_pneuma"]), name


# --- the apps: --help, flags and output --------------------------------------------------------------

APPS = {
    "inflate": inflate,
    "reach": reach,
    "steer": steer,
    "sweep": sweep,
    "optimize": optimize,
    "bench": bench,
    "serve": serve,
}


def test_help_is_complete_and_starts_without_taichi():
    """Each app's description is the whole first paragraph of its docstring (not cut mid-sentence), and
    building every parser imports neither Taichi nor the solver (so --help prints no Taichi banner)."""
    for name, module in APPS.items():
        description = module.parser().description
        assert description == " ".join(module.__doc__.split("\n\n")[0].split()) and description.endswith("."), name
    code = (
        "import sys\nfrom taichi_pneuma.apps import inflate, reach, steer, sweep, optimize, bench, serve\n"
        "[m.parser().format_help() for m in (inflate, reach, steer, sweep, optimize, bench, serve)]\n"
        "print(sorted(m for m in ('taichi', 'scipy', 'triangle', 'matplotlib') if m in sys.modules))"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert proc.stdout.strip() == "[]"
    helped = subprocess.run(
        [sys.executable, "-m", "taichi_pneuma.apps.inflate", "--help"], capture_output=True, text=True, check=True
    )
    assert "[Taichi]" not in helped.stdout + helped.stderr and "--no-video" in helped.stdout


def test_bench_writes_to_a_scratch_directory_by_default():
    assert bench.parser().parse_args([]).out == "out/bench"


def test_set_takes_short_names(tmp_path):
    assert inflate.main([*SMALL_FLAGS, "--no-video", "--set", "E=2e4", "--set", "cy=-0.1", "--out", str(tmp_path)]) == 0
    scene = tp.load_scene(tmp_path / "inflate_cy+0.15_growth2_steps3_max_area0.01_E2e4_cy-0.1_scene.toml")
    assert scene.material.youngs_modulus == 2e4 and scene.geometry.chambers[0][1].center[1] == -0.1


def test_video_in_a_new_directory_is_made_and_an_unwritable_one_fails_before_solving(tmp_path, capsys):
    assert (
        inflate.main(
            [
                *SMALL_FLAGS,
                "--size",
                "320x160",
                "--video",
                str(tmp_path / "a" / "b" / "v.mp4"),
                "--out",
                str(tmp_path / "out"),
            ]
        )
        == 0
    )
    assert imageio_ffmpeg.count_frames_and_secs(str(tmp_path / "a" / "b" / "v.mp4"))[0] == 3
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    capsys.readouterr()
    assert inflate.main([*SMALL_FLAGS, "--video", str(blocker / "v.mp4"), "--out", str(tmp_path / "out2")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not writable" in err[0]
    assert not list((tmp_path / "out2").glob("*_history.csv"))  # nothing was solved


def test_no_video_writes_no_picture_and_everything_else(tmp_path):
    assert inflate.main([*SMALL_FLAGS, "--no-video", "--out", str(tmp_path)]) == 0
    written = sorted(p.name for p in tmp_path.iterdir())
    assert not [n for n in written if n.endswith((".png", ".mp4", ".gif"))]  # as --help and the README say
    assert {
        "inflate_cy+0.15_growth2_steps3_max_area0.01_history.csv",
        "inflate_cy+0.15_growth2_steps3_max_area0.01_states.npz",
        "inflate_cy+0.15_growth2_steps3_max_area0.01_summary.json",
        "inflate_cy+0.15_growth2_steps3_max_area0.01_scene.toml",
        "inflate_cy+0.15_growth2_steps3_max_area0.01.pvd",
    } <= set(written)


def test_reach_has_no_bar_in_a_piped_log_and_follows_color(tmp_path, capsys):
    """Two targets (the bar's case), output to a stream that is not a terminal (as a pipe or a log file):
    no bar text, no carriage returns. --color changes the picture."""
    built = tp.reference_scene(max_area=0.01).build()
    tips = [
        tp.simulate(tp.reference_scene(max_area=0.01, growth=g, steps=2)).positions[-1][built.mesh.tip].mean(axis=0)
        for g in (2.0, 3.0)
    ]
    csv = tmp_path / "t.csv"
    csv.write_text("x,y\n" + "".join(f"{float(x)!r},{float(y)!r}\n" for x, y in tips))
    pngs = []
    for color in ("stretch", "detF"):
        out = tmp_path / color
        code = reach.main(
            ["--max-area", "0.01", "--targets", str(csv), "--color", color, "--size", "320x160", "--out", str(out)]
        )
        printed = capsys.readouterr()
        assert code == 0, printed.err
        assert "\r" not in printed.out + printed.err and "reaching" not in printed.out + printed.err
        pngs.append(iio.imread(out / "reach_cy+0.15_max_area0.01.png"))
    assert not np.array_equal(*pngs)


# --- pictures ----------------------------------------------------------------------------------------


def boxes_overlap(a, b) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


@pytest.mark.parametrize("size", [(960, 384), (480, 192), (320, 128), (256, 96)])
def test_small_frames_keep_labels_apart_and_markers_inside(small, size):
    track = Track.from_result(small, color="stretch")
    renderer = FrameRenderer([track], *size, backend=SOFTWARE)
    labels = renderer.draw(2)
    steps = [label_box(label) for label in labels if label.anchor == "mt" and label.text.isdigit()]
    assert all(not boxes_overlap(a, b) for k, a in enumerate(steps) for b in steps[k + 1 :])
    if renderer.trace:  # the left axis' numbers too
        left = [label_box(label) for label in labels if label.anchor == "rm"]
        assert len(left) >= 2 and all(not boxes_overlap(a, b) for k, a in enumerate(left) for b in left[k + 1 :])
    else:
        assert size[0] * size[1] <= 320 * 128  # left out only where its plot would be too small
    pins = renderer.to_canvas(0, track.states[2][track.mesh.pinned]) * size
    half = PIN_HALF_PX
    x0, x1 = (v * size[0] for v in renderer.panels[0])
    assert pins[:, 0].min() - half >= x0 and pins[:, 0].max() + half <= x1
    assert pins[:, 1].min() - half >= 0 and pins[:, 1].max() + half <= size[1]


def test_several_chambers_have_their_own_colours_and_names_in_the_trace():
    scene = tp.load_scene("bidirectional").with_value("mesh.max_area", 0.02)
    result = tp.simulate(scene)
    renderer = FrameRenderer([Track.from_result(result)], 960, 384, backend=SOFTWARE)
    colors = renderer.chamber_colors()
    labels = renderer.draw(0)
    image = renderer.frame(0)
    named = {label.text: label.color for label in labels if label.text in scene.chamber_names}
    assert named == {"top": colors[0], "bottom": colors[1]} and colors[0] != colors[1]
    spec = renderer.trace_axes()
    left, top, right, bottom = spec["box"]
    lo, hi, _ = spec["area"]
    step = 8  # the top chamber at x2.5, the bottom one at rest: their area curves far apart
    x = left + (right - left) * step / (len(result.steps) - 1)
    for k in (0, 1):
        y = bottom + (top - bottom) * (result.area_ratio[step, k] - lo) / (hi - lo)
        patch = image[int(y) - 2 : int(y) + 3, int(x) - 2 : int(x) + 3].reshape(-1, 3).astype(float)
        assert np.min(np.abs(patch - np.round(np.array(colors[k]) * 255)).max(axis=1)) < 40, k


def test_the_tip_path_is_not_joined_across_a_restart():
    """Frames 0-1 pursue target 0 (reached at frame 1), frame 2 is a restart far away, frame 3 steps on:
    the reached tip is a marker, the restart's jump is no line, the current descent's iterates are dots."""
    built = tp.reference_scene(max_area=0.02).build()
    mesh = built.mesh
    shift = lambda dx, dy: mesh.vertices + np.array([dx, dy])
    states = np.array([shift(0, 0), shift(0, -0.2), shift(0, 0.6), shift(0, 0.3)])
    tip = states[:, mesh.tip].mean(axis=1)
    track = Track(
        mesh,
        states,
        np.ones((4, 1)),
        np.zeros((4, 1)),
        tip[:, 1] - tip[0, 1],
        targets=np.tile(tip[1] + (0, 0.05), (4, 1)),
        target_index=np.array([0, 0, 1, 1]),
        descent=np.array([0, 0, 1, 1]),
    )
    renderer = FrameRenderer([track], 480, 320, trace=False, backend=SOFTWARE)
    image = renderer.frame(3)
    px = lambda p: (renderer.to_canvas(0, np.array([p]))[0] * (480, 320)) * (1, -1) + (0, 320)
    orange = np.round(np.array(TIP_PATH) * 255)
    near = lambda p: np.min(
        np.abs(
            image[int(px(p)[1]) - 2 : int(px(p)[1]) + 3, int(px(p)[0]) - 2 : int(px(p)[0]) + 3].reshape(-1, 3) - orange
        ).max(axis=1)
    )
    assert near(tip[1]) < 30  # where target 0 was reached
    assert near(tip[2]) < 30  # the current descent's earlier iterate: a dot
    assert near((tip[1] + tip[2]) / 2) > 100  # no line across the restart's jump


def test_sweep_plot_labels_the_short_name_and_draws_no_failed_run_as_data():
    axis = parse_vary("cy=-0.1,0.1,0.35")
    assert axis.key == "chambers[0].center[1]" and axis.label == "cy"
    rows = [{axis.key: cy, "tip_dy": -cy, "tip_dx": 0.05, "error": None} for cy in (-0.1, 0.1)]
    rows.append({axis.key: 0.35, "error": "chamber 'main' is not inside the body"})
    ax = study_figure(rows, [axis.key], labels=[axis.label]).axes[0]
    assert ax.get_xlabel() == "cy"
    for line in ax.lines:
        if line.get_label().startswith("tip"):
            assert 0.35 not in list(line.get_xdata())  # the failed run is no point of a data curve
    failed = [line for line in ax.lines if line.get_label().startswith("failed")]
    assert len(failed) == 1 and list(failed[0].get_xdata()) == [0.35, 0.35]
    assert failed[0].get_transform() != ax.transData  # spans the axes' height, not a value of y


def test_sweep_prints_rows_under_the_short_name(tmp_path, capsys):
    assert (
        sweep.main(
            [
                "--vary",
                "cy=0.1,0.35",
                "--max-area",
                "0.02",
                "--growth",
                "1.2",
                "--steps",
                "2",
                "--workers",
                "1",
                "--out",
                str(tmp_path),
                "--name",
                "s",
            ]
        )
        == 0
    )
    printed = capsys.readouterr().out
    assert "full grid over cy)" in printed and "  cy = 0.35: error:" in printed
    assert json.loads((tmp_path / "s.json").read_text())["keys"] == ["chambers[0].center[1]"]  # the CSV keeps keys
