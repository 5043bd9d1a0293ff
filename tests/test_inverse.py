"""Inverse control: twin tests (commands drawn at random inside the bounds, solved forward, recovered
from the tip they produced), unreachable targets and targets that need a bound, bad input."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from taichi_pneuma.control.inverse import Reacher, ReachOptions, body_length, command_bounds
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.tip import tip_measures
from taichi_pneuma.scene.build import ChamberControl, reference_scene
from taichi_pneuma.scene.scenefile import load_scene
from taichi_pneuma.scene.schedule import ChamberSchedule
from taichi_pneuma.scene.targets import Target
from taichi_pneuma.solve.newton import NewtonOptions, NewtonSolver
from taichi_pneuma.solve.simulate import settle

SCENES = Path(__file__).resolve().parent.parent / "taichi_pneuma" / "scenes"
TIGHT = NewtonOptions(tol=1e-9)


def pressure_bidirectional():
    """bidirectional.toml with both chambers under pressure control, 0 .. 700."""
    scene = load_scene(SCENES / "bidirectional.toml")
    control = ChamberControl(ChamberSchedule("pressure", ((8, 700.0),)), bounds=(0.0, 700.0))
    return dataclasses.replace(scene, controls=(control, control))


SCENE = {
    "reference": lambda: reference_scene(max_area=0.01, chamber_points=64),  # 1 area chamber, ratio 1 .. 3.5
    "bidirectional": lambda: load_scene(SCENES / "bidirectional.toml"),  # 2 area chambers, 1 .. 2.5
    "bidirectional_pressure": pressure_bidirectional,  # 2 pressure chambers, 0 .. 700
    "pneunet_finger": lambda: load_scene(SCENES / "pneunet_finger.toml"),  # 6 pressure chambers, 0 .. 900
}


@pytest.fixture(scope="module")
def built():
    cache = {}
    return lambda name: cache.setdefault(name, SCENE[name]().build())


def forward(built, commands):
    """The tip point and rotation at the equilibrium of `commands`, solved from rest (not by the code under test)."""
    solver = NewtonSolver(built.model, TIGHT)
    rest = built.scene.schedule.rest_commands
    u, *_ = settle(built, solver, rest, np.zeros_like(built.mesh.vertices), np.asarray(commands, float))
    (dx, dy), rotation = tip_measures(built.mesh, u)
    return built.mesh.vertices[built.mesh.tip].mean(axis=0) + (dx, dy), rotation


def drawn_commands(built, seed):
    lo, hi = command_bounds(built.scene)
    return lo + np.random.default_rng(seed).uniform(0.05, 0.95, len(lo)) * (hi - lo)


@pytest.mark.parametrize(
    "name, angle",
    [("reference", False), ("bidirectional", False), ("bidirectional", True), ("bidirectional_pressure", False)],
)
@pytest.mark.parametrize("seed", [1, 2])
def test_twin_commands_are_recovered_where_unique(built, name, angle, seed):
    built = built(name)
    commands = drawn_commands(built, seed)
    tip, rotation = forward(built, commands)
    target = Target(tuple(tip), rotation if angle else None)
    length = body_length(built)
    loose = Reacher(built, newton=TIGHT).reach(target)  # the default tolerance, 1e-3 of the body length
    assert loose.reached and loose.error <= 1e-3 * length
    assert np.hypot(*(loose.pose.tip - tip)) == pytest.approx(loose.error, abs=1e-12)
    tight = Reacher(built, options=ReachOptions(tol=1e-7), newton=TIGHT).reach(target)
    assert tight.reached and tight.error <= 1e-7 * length
    assert np.abs(tight.pose.commands - commands).max() <= 1e-4 * np.abs(commands).max()
    assert tight.pose.tip == pytest.approx(forward(built, tight.pose.commands)[0], abs=1e-7)  # Newton tol 1e-9


@pytest.mark.parametrize("seed", [1, 2])
def test_twin_with_redundant_chambers_reaches_the_tip_inside_the_bounds(built, seed):
    built = built("pneunet_finger")
    commands = drawn_commands(built, seed)
    tip, rotation = forward(built, commands)
    for target in (Target(tuple(tip)), Target(tuple(tip), rotation)):
        result = Reacher(built).reach(target)
        assert result.reached and result.error <= 1e-3 * body_length(built)
        assert target.angle is None or result.angle_error <= 0.5
        assert np.all((result.pose.commands >= 0) & (result.pose.commands <= 900))
        assert np.hypot(*(forward(built, result.pose.commands)[0] - target.tip)) <= 1e-3 * body_length(built)


def test_unreachable_target_stops_at_the_closest_pose_and_names_the_bounds(built):
    built = built("bidirectional")
    target = Target((1.7, -1.0))  # far below anything the beam can curl to
    result = Reacher(built).reach(target)
    assert not result.reached
    assert result.active == [("top", "max", "area ratio", 2.5), ("bottom", "min", "area ratio", 1.0)]
    assert np.array_equal(result.pose.commands, [2.5, 1.0])
    line = result.summary_line()
    assert line.startswith("unreachable: closest tip error ")
    assert "chamber 'top' at its max area ratio 2.5; chamber 'bottom' at its min area ratio 1" in line
    # the closest pose: no commands inside the bounds put the tip nearer (a grid of forward solves)
    grid = [forward(built, (top, bottom))[0] for top in (2.0, 2.25, 2.5) for bottom in (1.0, 1.25)]
    assert result.error <= min(np.hypot(*(p - target.tip)) for p in grid) + 1e-6  # Newton tol 1e-6 vs 1e-9


def test_target_that_needs_a_bound(built):
    """Commands with one chamber at its bound are recovered; with that chamber's other bound tightened
    past what the target needs, it becomes unreachable, the bound named, and no command passes it."""
    built = built("bidirectional")
    tip, _ = forward(built, [2.2, 1.0])
    result = Reacher(built, options=ReachOptions(tol=1e-7)).reach(Target(tuple(tip)))
    assert result.reached and result.pose.commands == pytest.approx([2.2, 1.0], rel=1e-4)
    assert np.all(result.pose.commands >= 1.0)
    tighter = Reacher(built, bounds=([1.0, 1.0], [2.0, 2.5])).reach(Target(tuple(tip)))
    assert not tighter.reached and ("top", "max", "area ratio", 2.0) in tighter.active
    assert all(np.all((p.commands >= [1.0, 1.0]) & (p.commands <= [2.0, 2.5])) for p in tighter.path)
    assert "chamber 'top' at its max area ratio 2" in tighter.summary_line()


def test_bounds_from_the_scene_file_and_defaults(tmp_path):
    text = (
        (SCENES / "bidirectional.toml")
        .read_text()
        .replace(
            "keyframes = [[0, 1.0], [8, 2.5], [16, 1.0]]",
            "keyframes = [[0, 1.0], [8, 2.5], [16, 1.0]]\nbounds = [1.2, 2.0]",
        )
    )
    (tmp_path / "b.toml").write_text(text + "\n[[targets]]\ntip = [1.8, -0.1]\nangle = -3.0\nweights = [1, 2, 0.5]\n")
    scene = load_scene(tmp_path / "b.toml")
    lo, hi = command_bounds(scene)
    assert lo.tolist() == [1.2, 1.0] and hi.tolist() == [2.0, 2.5]  # top from the file; bottom from its keyframes
    assert scene.targets[3:] == (Target((1.8, -0.1), -3.0, (1.0, 2.0, 0.5)),)  # after the shipped file's three
    assert command_bounds(load_scene(SCENES / "pneunet_finger.toml"))[1].tolist() == [900.0] * 6


@pytest.mark.parametrize(
    "make, pattern",
    [
        (lambda: Target((float("nan"), 0.0)), "target tip = nan"),
        (lambda: Target((1.0, 0.0), float("inf")), "target angle = inf"),
        (
            lambda: Target(
                (1.0,),
            ),
            r"target tip = \[1.0\] must be \[x, y\]",
        ),
        (lambda: Target((1.0, 0.0), None, (0.0, 0.0, 1.0)), "w_x or w_y > 0"),
        (
            lambda: ChamberControl(ChamberSchedule("pressure", ((1, 10.0),)), bounds=(900.0, 0.0)),
            "min 900 must be < max 0",
        ),
        (
            lambda: ChamberControl(ChamberSchedule("area", ((1, 2.0),)), bounds=(0.0, 2.0)),
            r"bounds = \[0.0, 2.0\]: area ratio 0.0 must lie in \(0, 1000\]",
        ),
        (
            lambda: ChamberControl(ChamberSchedule("pressure", ((1, 10.0),)), bounds=(-5.0, 2.0)),
            "pressure -5.0 is negative; set allow_vacuum",
        ),
        (lambda: ReachOptions(tol=0.0), "tol = 0.0 must be > 0"),
        (lambda: ReachOptions(restarts=-1), "restarts = -1 must be an integer >= 0"),
    ],
)
def test_bad_input_is_refused(make, pattern):
    with pytest.raises(PneumaInputError, match=pattern):
        make()


def test_trajectory_with_newtons_factor_reused_reaches_every_target(built):
    """follow() warm-starts each target from the last; with reuse_factor (live mode) the Jacobian comes from
    Newton's last exact factorisation: every target is still reached, each in a few forward solves."""
    built = built("bidirectional")
    path = [(1.5, 1.2), (1.6, 1.25), (1.7, 1.3), (1.8, 1.3)]
    targets = [Target(tuple(forward(built, q)[0])) for q in path]
    reacher = Reacher(built, options=ReachOptions(restarts=0, reuse_factor=True))
    results = reacher.follow(targets)
    assert all(r.reached and r.error <= 1e-3 * body_length(built) for r in results)
    assert all(r.forward_solves <= 3 for r in results[1:])
    assert results[-1].pose.commands == pytest.approx(path[-1], rel=1e-2)  # unique, but only to tol 1e-3 L
