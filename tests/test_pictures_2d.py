"""What the 2D pictures show: the history plot draws only panels with something to say (no command plotted
against itself, no constant curve, each chamber named), a frame keeps every step's body in its panel with a
scale bar in the scene's unit, and pneuma-steer's captions say what each run's tip did."""

from __future__ import annotations

import numpy as np
import pytest

import taichi_pneuma as tp
from taichi_pneuma.render.plots import history_figure


@pytest.fixture(scope="module")
def area_run():
    """A short coarse reference ramp under area control (the mesh other tests use: Taichi's kernel cache)."""
    return tp.simulate(tp.reference_scene(cy=0.15, growth=2.0, steps=3, max_area=0.01))


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
