"""What the 2D pictures show: the history plot draws only panels with something to say (no command plotted
against itself, no constant curve, each chamber named), a frame keeps every step's body in its panel with a
scale bar in the scene's unit, and pneuma-steer's captions say what each run's tip did."""

from __future__ import annotations

import json
import re
from dataclasses import replace

import numpy as np
import pytest
from renderers import SOFTWARE
from scenes import small_run

import taichi_pneuma as tp
from taichi_pneuma.apps import steer
from taichi_pneuma.render.colours import GHOST
from taichi_pneuma.render.frames import FrameRenderer, Track
from taichi_pneuma.render.plots import history_figure
from taichi_pneuma.render.view2d import view_bounds


@pytest.fixture(scope="module")
def area_run():
    """A short coarse reference ramp under area control (the mesh other tests use: Taichi's kernel cache)."""
    return small_run()


@pytest.fixture(scope="module")
def pressure_run():
    scene = tp.reference_scene(cy=0.15, steps=3, max_area=0.01).with_values(
        {"chambers[0].control": "pressure", "chambers[0].keyframes": [[0, 0.0], [2, 300.0]]}
    )
    return tp.simulate(scene)


@pytest.fixture(scope="module")
def two_chamber_run():
    """bidirectional, coarse and short: the top chamber inflated and let down, then the bottom one."""
    scene = tp.load_scene("bidirectional").with_values(
        {
            "mesh.max_area": 0.02,
            "schedule.increments": 4,
            "chambers[0].keyframes": [[0, 1.0], [1, 1.6], [2, 1.0]],
            "chambers[1].keyframes": [[2, 1.0], [4, 1.6]],
        }
    )
    return tp.simulate(scene)


def near(a, b) -> bool:
    """Equal to 5 % (a coarse mesh's area ratio is its command to 1.3 %, measured)."""
    return len(a) == len(b) and np.allclose(np.asarray(a, float), np.asarray(b, float), rtol=0.05, atol=1e-6)


@pytest.mark.parametrize("run", ["area_run", "pressure_run", "two_chamber_run"])
def test_the_plot_draws_no_command_against_itself_and_no_constant_curve(run, request):
    """No line has the command (any chamber's column, or the area ratio it makes an area-controlled chamber take)
    on y against the command or the step on x, no line is flat, and no axes is empty."""
    result = request.getfixturevalue(run)
    steps = np.arange(len(result.steps))
    figure = history_figure(result)
    lines = [line for ax in figure.axes for line in ax.lines]
    assert all(ax.lines for ax in figure.axes) and len(figure.axes) >= 4
    for line in lines:
        x, y = line.get_xdata(), line.get_ydata()
        assert np.ptp(y) > 1e-9, line.get_label()
        for k, command in enumerate(result.command.T):
            assert not (near(y, command) and (near(x, command) or near(x, steps))), (line.get_label(), k)


def test_the_responses_are_against_the_driving_pressure_or_else_the_step(pressure_run, two_chamber_run):
    tip = lambda fig: next(ax for ax in fig.axes if ax.get_title().startswith("tip deflection"))
    one = tip(history_figure(pressure_run)).lines[0]
    assert np.array_equal(one.get_xdata(), pressure_run.pressure[:, 0])
    assert np.array_equal(one.get_ydata(), pressure_run.history["tip_dy"])
    two = tip(history_figure(two_chamber_run))
    assert two.get_xlabel() == "step" and np.array_equal(two.lines[0].get_xdata(), np.arange(5))


def test_a_two_chamber_plot_names_both_chambers_in_their_own_colours(two_chamber_run):
    figure = history_figure(two_chamber_run)
    pressure = next(ax for ax in figure.axes if ax.get_title() == "chamber pressure")
    legend = [t.get_text() for t in pressure.get_legend().get_texts()]
    assert legend == ["top", "bottom"]
    assert pressure.lines[0].get_color() != pressure.lines[1].get_color()
    for line, k in zip(pressure.lines, (0, 1)):
        assert np.array_equal(line.get_ydata(), two_chamber_run.pressure[:, k])


def curled(mesh, degrees: float = 150.0, steps: int = 6) -> np.ndarray:
    """States (steps, n, 2) of the body turned rigidly about its left end by 0 .. degrees: the tip sweeps far
    outside the rest shape's box (up and back over the clamp)."""
    pivot = np.array([mesh.vertices[:, 0].min(), 0.0])
    states = []
    for angle in np.radians(np.linspace(0.0, degrees, steps)):
        turn = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
        states.append(pivot + (mesh.vertices - pivot) @ turn.T)
    return np.array(states)


def curled_track(mesh, units=("", "", "")) -> Track:
    states = curled(mesh)
    steps = len(states)
    ones = np.ones((steps, 1))
    tip = states[:, mesh.tip, 1].mean(axis=1) - states[0, mesh.tip, 1].mean()
    return Track(mesh, states, ones, ones * np.linspace(0, 75.2, steps)[:, None], tip, units=units, area=ones * 12.5)


def pixels(renderer, points: np.ndarray) -> np.ndarray:
    """World points -> pixel coordinates (origin top-left, y down), as the image is indexed."""
    return renderer.to_canvas(0, points) * (renderer.width, -renderer.height) + (0, renderer.height)


@pytest.mark.parametrize("size", [(960, 384), (384, 160)])
def test_every_steps_body_is_inside_its_panel_below_the_header(area_run, size):
    track = curled_track(area_run.mesh)
    renderer = FrameRenderer([track], *size, backend=SOFTWARE)
    x0, x1 = (v * size[0] for v in renderer.panels[0])
    for state in track.states:
        px = pixels(renderer, state)
        assert px[:, 0].min() >= x0 and px[:, 0].max() <= x1
        assert px[:, 1].min() >= renderer.header_px - 1e-9 and px[:, 1].max() <= size[1]


@pytest.mark.parametrize("units, unit", [(("", "", ""), ""), ((" mm", " mm^2", " kPa"), " mm")])
def test_the_scale_bar_is_a_round_length_in_the_scenes_unit_where_no_step_is(area_run, units, unit):
    track = curled_track(area_run.mesh, units)
    renderer = FrameRenderer([track], 960, 384, backend=SOFTWARE)
    length, label, (left, top, right, bottom) = renderer.scale_bar
    mantissa = length / 10 ** np.floor(np.log10(length))
    assert np.isclose(mantissa, 1) or np.isclose(mantissa, 2) or np.isclose(mantissa, 5)
    assert label == f"{length:g}{unit}"
    panel_world = (renderer.panels[0][1] - renderer.panels[0][0]) * 960 / renderer._scale
    assert 0.08 * panel_world < length <= 0.2 * panel_world  # 1-2-5 steps: within a factor 2.5 of a fifth
    for state in track.states:
        px = pixels(renderer, state)
        assert not np.any((px[:, 0] >= left) & (px[:, 0] <= right) & (px[:, 1] >= top) & (px[:, 1] <= bottom))
    image = renderer.frame(len(track.states) - 1)
    ends = pixels(renderer, np.array([[0.0, 0.0], [length, 0.0]]))  # the bar is `length` long at the view's scale
    row = (
        image[int(bottom) - 6 : int(bottom) - 1, int(left) : int(right)].min(axis=(0, 2)) < 200
    )  # drawn, not background
    assert abs(np.count_nonzero(row) - (ends[1, 0] - ends[0, 0])) <= 3
    assert label in [text.text for text in renderer.draw(0)]


def test_chambers_at_one_pressure_over_the_run_show_it_once_in_the_header(area_run):
    """Three chambers at one pressure all run: 'p = 75.2 kPa (all 3)'; once one differs at any step, each its own."""
    track = curled_track(area_run.mesh, (" mm", " mm^2", " kPa"))
    ramp = np.linspace(0, 75.2, len(track.states))[:, None]
    shared = replace(track, pressure=np.hstack([ramp] * 3), area_ratio=np.ones((len(ramp), 3)), area=None)
    assert shared.header(5)[1].startswith("p = 75.2 kPa (all 3)   tip dy")
    apart = replace(shared, pressure=np.hstack([ramp, ramp, ramp * (1 + 1e-6 * (ramp > 30))]))
    assert apart.header(5)[1].startswith("p = 75.2, 75.2, 75.2 kPa   tip dy")
    ten = replace(  # ten chambers: ranges, so that the line stays short of the trace panel
        apart,
        pressure=np.hstack([ramp * (1 + 0.01 * k) for k in range(10)]),
        area_ratio=np.hstack([1 + ramp / 100 * (1 + 0.01 * k) for k in range(10)]),
    )
    step, pressures = ten.header(5)
    assert step == "step 5/5   area x1.75 .. x1.82 (10)" and pressures.startswith("p = 75.2 .. 82.0 kPa (10)   tip")


def test_a_header_with_units_says_them_and_the_rest_shape_is_a_ghost(area_run):
    track = curled_track(area_run.mesh, (" mm", " mm^2", " kPa"))
    assert track.header(5) == ["step 5/5   area 12.5 mm^2", f"p = 75.2 kPa   tip dy = {track.tip_dy[5]:+.4g} mm"]
    renderer = FrameRenderer([track], 960, 384, trace=False, backend=SOFTWARE)
    image = renderer.frame(5).astype(int)
    mesh = area_run.mesh
    right = mesh.vertices[:, 0].max()
    end = mesh.vertices[np.abs(mesh.vertices[:, 0] - right) < 1e-9]  # the rest shape's right side, left by step 5
    x, y = pixels(renderer, end.mean(axis=0, keepdims=True))[0].astype(int)
    patch = image[y - 2 : y + 3, x - 2 : x + 3].reshape(-1, 3)
    assert np.min(np.abs(patch - np.round(np.array(GHOST) * 255)).max(axis=1)) < 25


def test_a_tip_that_rises_then_falls_is_told_so_and_a_still_one_stays():
    rise_fall = np.array([0.0, 0.1, 0.26, 0.2, 0.0, -0.15, -0.28])
    assert steer.tip_story(rise_fall, 0.28) == "tip up to +0.26 (step 2), then down to -0.28 (step 6)"
    assert steer.tip_story(-np.abs(rise_fall), 0.28) == "tip down to -0.28 (step 6)"
    assert steer.tip_story(np.array([0.0, 0.004, -0.0061]), 0.28) == "tip stays within +-0.01"


def test_steer_captions_give_each_runs_tip_extremes(tmp_path, capsys):
    """A short coarse steer run (no video): each caption's numbers are its run's largest and smallest tip
    deflection and their steps, read from the summary's tip histories; the high chamber's tip rises first."""
    flags = ["--max-area", "0.01", "--steps", "8", "--no-video", "--quiet", "--out", str(tmp_path)]
    assert steer.main(flags) == 0
    (written,) = tmp_path.glob("steer*_summary.json")  # named after the flags that change the scenes
    summary = json.loads(written.read_text())
    printed = capsys.readouterr().out
    for key, caption in summary["caption"].items():
        tip = np.array(summary["tip_history"][key])
        assert caption in printed and f"(cy = {key})" in caption
        told = {
            word: (float(value), int(step))
            for word, value, step in re.findall(r"(up|down) to ([-+.\d]+) \(step (\d+)\)", caption)
        }
        if "up" in told:
            assert told["up"] == (round(tip.max(), 2), int(np.argmax(tip)))
        if "down" in told:
            assert told["down"] == (round(tip.min(), 2), int(np.argmin(tip)))
    high = np.array(summary["tip_history"]["+0.15"])
    assert high.max() > 0.1 and high[-1] < -0.1 and np.argmax(high) < np.argmin(high)  # rises, then falls
    assert re.search(r"tip up to .*, then down to ", summary["caption"]["+0.15"])
    assert re.search(r"^chamber low .*: tip down to .*, then up to ", summary["caption"]["-0.15"])
    assert "tip stays within +-" in summary["caption"]["+0.00"]


def test_the_view_takes_in_the_obstacles_near_the_body_and_no_far_one(area_run):
    """view_bounds: a closed obstacle that comes within a tenth of the body's size is in view at every step's
    offset; one far away, and a plane's long line, are not."""
    mesh = area_run.mesh
    lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
    square = np.array([[0.0, 0.0], [0.2, 0.0], [0.2, 0.2], [0.0, 0.2]])
    near = (square + (hi[0] + 0.1, 0.0), True, np.array([[0.0, 0.0], [0.0, 0.3]]))  # 0.1 right of the tip, rising
    far = (square + (hi[0] + 10.0, 0.0), True, np.zeros((2, 2)))
    plane = (np.array([[-50.0, lo[1] - 0.05], [50.0, lo[1] - 0.05]]), False, np.zeros((2, 2)))
    states = np.array([mesh.vertices, mesh.vertices])
    track = Track(mesh, states, np.ones((2, 1)), np.zeros((2, 1)), np.zeros(2), obstacles=(near, far, plane))
    view_lo, view_hi = view_bounds([track])
    assert np.allclose(view_lo, lo) and np.allclose(view_hi, [hi[0] + 0.3, max(hi[1], 0.5)])
