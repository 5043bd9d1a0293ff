"""The reach command as a user runs it: a target, a trajectory, an unreachable target, bad input, design."""

import dataclasses
import json
import subprocess
import sys

import imageio.v3 as iio
import imageio_ffmpeg
import numpy as np
import pytest
from renderers import SOFTWARE, needs_window
from scenes import SMALL_FLAGS, small_scene
from test_inverse import SCENES, forward
from test_render import xvfb_display  # noqa: F401 (a fixture)

from taichi_pneuma.apps.reach import main
from taichi_pneuma.render.colours import TARGET
from taichi_pneuma.render.frames import FrameRenderer, Track
from taichi_pneuma.scene.build import reference_scene
from taichi_pneuma.scene.scenefile import load_scene
from taichi_pneuma.solve.simulate import run_schedule

BIDIRECTIONAL = str(SCENES / "bidirectional.toml")
QUIET = ["--no-video", "--quiet"]


@pytest.fixture(scope="module")
def bidirectional():
    return load_scene(BIDIRECTIONAL).build()


def test_reach_prints_the_commands_and_writes_its_files(tmp_path, capsys, bidirectional):
    tip, _ = forward(bidirectional, [1.8, 1.3])
    assert main(["--scene", BIDIRECTIONAL, "--tip", *map(str, tip), "--out", str(tmp_path), *QUIET]) == 0
    printed = capsys.readouterr().out.splitlines()
    assert printed[-1].startswith("reached: tip (") and "tip error" in printed[-1]
    assert any(line.startswith("commands: top = ") and "bottom = " in line for line in printed)
    summary = json.loads((tmp_path / "reach_bidirectional_summary.json").read_text())
    assert summary["target"]["tip"] == pytest.approx(list(tip)) and summary["reached"]
    assert summary["tip_error"] <= 1e-3 * 3.5
    assert np.hypot(*(np.array(summary["tip"]) - tip)) == pytest.approx(summary["tip_error"], abs=1e-12)
    commands = [summary["commands"]["top"], summary["commands"]["bottom"]]
    assert np.hypot(*(forward(bidirectional, commands)[0] - tip)) <= 1e-3 * 3.5  # an independent forward solve
    history = np.genfromtxt(tmp_path / "reach_bidirectional_history.csv", delimiter=",", names=True, deletechars="")
    assert history["top.command"][-1] == pytest.approx(commands[0], abs=1e-12)
    assert history["tip_error"][-1] == pytest.approx(summary["tip_error"], abs=1e-12)
    assert np.load(tmp_path / "reach_bidirectional_states.npz")["positions"].shape[0] == len(history)


def test_unreachable_target_exits_1_with_one_line_and_keeps_the_closest_pose(tmp_path, capsys):
    assert main(["--scene", BIDIRECTIONAL, "--tip", "1.7", "-1.0", "--out", str(tmp_path), *QUIET]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("unreachable: closest tip error 0.72")
    assert "chamber 'top' at its max area ratio 2.5" in err[0]
    summary = json.loads((tmp_path / "reach_bidirectional_summary.json").read_text())
    assert not summary["reached"] and summary["commands"] == {"top": 2.5, "bottom": 1.0}
    assert (tmp_path / "reach_bidirectional_history.csv").exists()


def test_trajectory_from_scene_targets_and_csv_with_video(tmp_path, capsys, bidirectional):
    path = [(1.3, 1.0), (1.8, 1.2), (2.2, 1.5)]
    tips = [tuple(map(float, forward(bidirectional, q)[0])) for q in path]
    untargeted = dataclasses.replace(load_scene(BIDIRECTIONAL), targets=())  # the shipped scene's own targets left out
    text = untargeted.to_toml() + "".join(f"\n[[targets]]\ntip = [{x!r}, {y!r}]\n" for x, y in tips)
    (tmp_path / "traj.toml").write_text(text)
    (tmp_path / "traj.csv").write_text("x,y\n" + "".join(f"{x!r},{y!r}\n" for x, y in tips))
    out = tmp_path / "out"
    assert (
        main(
            [
                "--scene",
                str(tmp_path / "traj.toml"),
                "--out",
                str(out),
                "--renderer",
                SOFTWARE,
                "--size",
                "320x128",
                "--quiet",
            ]
        )
        == 0
    )
    assert capsys.readouterr().out.splitlines()[-1].startswith("reached: all 3 targets in order")
    history = np.genfromtxt(out / "reach_bidirectional_history.csv", delimiter=",", names=True, deletechars="")
    assert sorted(set(history["target"].astype(int))) == [0, 1, 2]
    for k, (x, y) in enumerate(tips):
        last = np.flatnonzero(history["target"] == k)[-1]
        assert (history["target_x"][last], history["target_y"][last]) == (x, y)
        assert history["tip_error"][last] <= 1e-3 * 3.5
    assert imageio_ffmpeg.count_frames_and_secs(str(out / "reach_bidirectional.mp4"))[0] == len(history)
    assert iio.imread(out / "reach_bidirectional.png").shape == (128, 320, 3)
    csv_out = tmp_path / "csv"
    assert main(["--scene", BIDIRECTIONAL, "--targets", str(tmp_path / "traj.csv"), "--out", str(csv_out), *QUIET]) == 0
    summary = json.loads((csv_out / "reach_bidirectional_summary.json").read_text())
    assert summary["targets"] == summary["targets_reached"] == 3 and summary["worst_tip_error"] <= 1e-3 * 3.5


def test_target_marker_is_drawn_at_the_target():
    built = reference_scene(max_area=0.01, chamber_points=64).build()
    states = built.mesh.vertices[None]
    target = np.array([[1.2, 0.6]])  # above the beam, on the background
    track = Track(built.mesh, states, np.ones((1, 1)), np.zeros((1, 1)), np.zeros(1), targets=target)
    renderer = FrameRenderer([track], 480, 192, trace=False, backend=SOFTWARE, log=lambda *_: None)
    image = renderer.frame(0)
    uv = renderer.to_canvas(0, target)[0]
    pixel = image[int((1 - uv[1]) * 192), int(uv[0] * 480)].astype(float)
    assert np.all(np.abs(pixel - np.round(np.array(TARGET) * 255)) <= 3)


POINTED = """
name = "pointed"
[body]
shape = "polygon"
points = [[-1.5, -0.3], [1.2, -0.3], [1.5, 0.0], [1.2, 0.3], [-1.5, 0.3]]
[mesh]
max_area = 0.01
[clamp]
side = "left"
[[chambers]]
name = "main"
shape = "ellipse"
center = [0.0, 0.1]
semi_axes = [0.5, 0.1]
keyframes = [[2, 2.0]]
[schedule]
increments = 2
"""


@pytest.mark.parametrize(
    "flags, word",
    [
        (["--tip", "nan", "0"], "target tip = nan"),
        (["--tip", "1.8", "0", "--weights", "0", "0", "1"], "w_x or w_y > 0"),
        (
            ["--tip", "1.8", "0", "--bounds", "top", "3", "2"],
            "--bounds top: bounds = [3.0, 2.0]: min 3 must be < max 2",
        ),
        (["--tip", "1.8", "0", "--bounds", "middle", "1", "2"], "unknown chamber 'middle' (chambers: top, bottom)"),
        (["--tip", "1.8", "0", "--bounds", "top", "0", "2"], "area ratio 0.0 must lie in (0, 1000]"),
        (["--angle", "5"], "--angle needs --tip"),
        (["--tip", "1.8", "0", "--targets", "t.csv"], "give --tip or --targets, not both"),
        (["--targets", "missing.csv"], "'missing.csv' cannot be read"),
        (["--scene", str(SCENES / "pneunet_finger.toml")], "no target: give --tip X Y"),  # a scene without [[targets]]
        (["--tip", "1.8", "0", "--tip-tol", "0"], "tol = 0.0 must be > 0"),
        (["--tip-dy", "-0.2"], "--tip-dy needs --design cy"),
    ],
)
def test_bad_input_is_one_error_line_and_exit_2(tmp_path, capsys, flags, word):
    assert main(["--scene", BIDIRECTIONAL, *flags, "--out", str(tmp_path / "out"), *QUIET]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and word in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_angle_needs_a_tip_with_two_vertices(tmp_path, capsys):
    (tmp_path / "pointed.toml").write_text(POINTED)
    assert (
        main(
            [
                "--scene",
                str(tmp_path / "pointed.toml"),
                "--tip",
                "1.4",
                "0",
                "--angle",
                "5",
                "--out",
                str(tmp_path),
                *QUIET,
            ]
        )
        == 2
    )
    assert "tip rotation needs at least 2 tip vertices (this mesh has 1)" in capsys.readouterr().err


def test_bad_input_from_the_shell_has_no_traceback(tmp_path):
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "taichi_pneuma.apps.reach",
            "--scene",
            BIDIRECTIONAL,
            "--tip",
            "1",
            "inf",
            "--out",
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
    )
    errors = [line for line in proc.stderr.splitlines() if line.strip() and not line.startswith("[Taichi]")]
    assert proc.returncode == 2 and errors == ["error: target tip = inf must be a finite number"]


def test_design_finds_the_chamber_height_for_a_tip_deflection(tmp_path, capsys):
    assert main(["--design", "cy", "--tip-dy", "-0.05", *SMALL_FLAGS, "--out", str(tmp_path)]) == 0
    assert capsys.readouterr().out.splitlines()[-1].startswith("reached: cy = +0.")
    summary = json.loads((tmp_path / "design_cy_tip_dy-0.05_growth2_steps3_max_area0.01_summary.json").read_text())
    assert summary["found"] and 0 < summary["cy"] < 0.179 and summary["evaluations"] == len(summary["history"])
    ramp = run_schedule(small_scene(summary["cy"]).build())
    assert ramp.tip_deflection == pytest.approx(summary["tip_dy"], abs=1e-9)  # an independent ramp at that cy
    assert abs(ramp.tip_deflection + 0.05) <= 2e-3


def test_design_out_of_range_is_unreachable(tmp_path, capsys):
    assert main(["--design", "cy", "--tip-dy", "-5", *SMALL_FLAGS, "--out", str(tmp_path)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("unreachable: tip dy -5 lies outside what cy in [")


@needs_window
def test_live_drag_resolves_on_every_move_and_sliders_command_directly(
    xvfb_display,  # noqa: F811 (the fixture, imported by name)
    monkeypatch,
    capsys,
    bidirectional,
):
    """Under Xvfb, in a real ti.GUI window; the canvas's mouse query is scripted (the button held at two
    target positions, then released) and on the last frame the 'top' slider returns a value the user set."""
    from taichi_pneuma.realtime.interactive import fixed_view, follow_mouse
    from taichi_pneuma.render.canvases import GUICanvas

    size = (480, 192)
    view = FrameRenderer(
        [Track(bidirectional.mesh, bidirectional.mesh.vertices[None], np.ones((1, 2)), np.zeros((1, 2)), np.zeros(1))],
        *size,
        trace=False,
        backend="gui",
        bounds=fixed_view(bidirectional.mesh),
        log=lambda *_: None,
    )
    tips = [forward(bidirectional, q)[0] for q in ([1.6, 1.2], [1.9, 1.3])]  # reachable targets
    at = [tuple(view.to_canvas(0, tip)) for tip in tips]
    script = iter([(*at[0], True), (*at[0], True), (*at[1], True), (*at[1], False), (0.5, 0.5, False)])
    top_calls = []

    def slider(self, label, value, low, high, row=0):
        if label == "top":
            top_calls.append(value)
            if len(top_calls) == 5:  # the last frame: the user has moved the top slider to 2.0
                return 2.0
        return value

    monkeypatch.setattr(GUICanvas, "mouse", lambda self: next(script))
    monkeypatch.setattr(GUICanvas, "slider", slider)
    result = follow_mouse(load_scene(BIDIRECTIONAL), ([1.0, 1.0], [2.5, 2.5]), size, "gui", max_frames=5)
    assert result["reaches"] == 2 and result["all_converged"]  # a reach per move, each within 1e-3 L
    assert result["target"] == pytest.approx(list(tips[1]), abs=1e-9)
    assert result["direct"] == 1 and result["commands"][0] == pytest.approx(2.0)
    assert top_calls[3] == pytest.approx(1.9, abs=0.01)  # the sliders follow the commands the drag found
    assert "2 reaches, 1 direct commands, 5 frames" in capsys.readouterr().out


def test_interactive_without_display_is_one_clear_error(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert main(["--scene", BIDIRECTIONAL, "--interactive", "--out", str(tmp_path)]) == 2
    assert "--interactive needs a display" in capsys.readouterr().err
