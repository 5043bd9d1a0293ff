"""Constraints (terms/constraints.py) against finite differences, their node selection, and their scene-file keys."""

import numpy as np
import pytest

from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.planar import Geometry
from taichi_pneuma.fem.shapes import Ellipse, Rectangle
from taichi_pneuma.fem.supports import PointSet, Roller
from taichi_pneuma.scene.build import Scene, reference_scene
from taichi_pneuma.scene.scenefile import read_scene, scene_data
from taichi_pneuma.solve.simulate import run_schedule
from taichi_pneuma.terms.constraints import Clamp, NormalClamp
from taichi_pneuma.terms.model import Configuration

H = 1e-4  # the energies are quadratic: central differences are exact up to round-off


def terms(config):
    nodes = np.array([0, 2, 3, 5])
    return {
        "clamp": Clamp(config, nodes, 1e3),
        "roller y": NormalClamp(config, nodes, (0.0, 2.0), 1e3),
        "roller slanted": NormalClamp(config, nodes, (0.6, -0.8), 1e3),
    }


@pytest.mark.parametrize("name", ["clamp", "roller y", "roller slanted"])
def test_energy_gradient_and_hessian_match_finite_differences(name):
    rng = np.random.default_rng(3)
    config = Configuration(rng.standard_normal((7, 2)))
    term = terms(config)[name]
    u0 = 0.1 * rng.standard_normal(config.u.shape)
    n = u0.size

    def at(step):
        config.u[:] = u0 + step.reshape(-1, 2)
        return term.energy(), term.gradient().ravel()

    energy, gradient = at(np.zeros(n))
    hessian = np.zeros((n, n))
    np.add.at(hessian, term.hessian_pattern(), term.hessian_values())
    steps = H * np.eye(n)
    fd_gradient = [(at(s)[0] - at(-s)[0]) / (2 * H) for s in steps]
    fd_hessian = np.array([(at(s)[1] - at(-s)[1]) / (2 * H) for s in steps]).T
    assert np.allclose(gradient, fd_gradient, rtol=0, atol=1e-8 * np.abs(gradient).max())
    assert np.allclose(hessian, fd_hessian, rtol=0, atol=1e-9)
    assert energy == pytest.approx(0.5 * gradient @ u0.ravel(), rel=1e-12)  # quadratic: E = 1/2 u . grad E


def test_roller_holds_the_normal_component_only():
    config = Configuration(np.zeros((4, 2)))
    roller = NormalClamp(config, [1, 2], (3.0, 4.0), 10.0)
    config.u[:] = [[5.0, 5.0], [-0.8, 0.6], [-1.6, 1.2], [0.0, 0.0]]  # tangential on the held nodes
    assert roller.energy() == pytest.approx(0.0, abs=1e-14) and np.abs(roller.gradient()).max() < 1e-14
    config.u[:] = [[5.0, 5.0], [0.6, 0.8], [0.0, 0.0], [0.0, 0.0]]  # a unit normal displacement of node 1
    assert roller.energy() == pytest.approx(5.0) and roller.gradient()[1] == pytest.approx([6.0, 8.0])
    y_roller = NormalClamp(config, [1, 2], (0.0, 1.0), 10.0)
    assert y_roller.hessian_pattern()[0].tolist() == [3, 5]  # one entry per node: its y DOF


def test_roller_selects_a_line_or_a_box():
    vertices = np.array([[0.0, 0.0], [1.0, 5e-7], [2.0, 2e-6], [1.0, 1.0]])
    assert Roller((0.0, -3.0), (7.0, 0.0)).select(vertices).tolist() == [0, 1]
    assert Roller((1.0, 0.0), box=(0.5, -1, 1.5, 2)).select(vertices).tolist() == [1, 3]
    with pytest.raises(PneumaInputError, match="holds no mesh vertex"):
        Roller((1.0, 0.0), (5.0, 0.0)).select(vertices)
    # a plane through the body between its nodes: the message says why and what to do instead
    with pytest.raises(PneumaInputError, match="its plane cuts through the body, where the mesher puts nodes only by"):
        Roller((1.0, 0.0), (0.5, 0.0)).select(vertices)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(normal=(0, 0), point=(0, 0)), "must not be zero"),
        (dict(normal=(0, 1)), "exactly one of 'point'"),
        (dict(normal=(0, 1), point=(0, 0), box=(0, 0, 1, 1)), "exactly one of 'point'"),
        (dict(normal=(0, 1), point=(0, 0), tolerance=0.0), "tolerance"),
        (dict(normal=(0, 1), box=(1, 0, 0, 1)), "x0 < x1"),
    ],
)
def test_bad_roller_is_refused(kwargs, message):
    with pytest.raises(PneumaInputError, match=message):
        Roller(**kwargs)


def test_roller_and_tip_keys_round_trip_through_the_scene_file():
    scene = reference_scene(max_area=0.02, chamber_points=32)
    data = scene_data(scene)
    assert data["tip"] == {"side": "right"}
    data["tip"] = {"box": [1.7, -0.1, 1.8, 0.1]}
    data["rollers"] = [
        {"normal": [1.0, 0.0], "point": [1.75, 0.0]},
        {"normal": [0.0, 1.0], "box": [1.7, -0.5, 1.8, 0.5], "tolerance": 1e-3},
    ]
    scene = read_scene(data, "s")
    assert scene.geometry.tip == PointSet(box=(1.7, -0.1, 1.8, 0.1))
    assert scene.geometry.rollers[1] == Roller((0.0, 1.0), box=(1.7, -0.5, 1.8, 0.5), tolerance=1e-3)
    assert read_scene(scene_data(scene), "s") == scene
    assert scene.build().model.term_names() == ["elastic", "chamber:main", "clamp", "roller", "roller"]
    data["rollers"][0]["side"] = "left"
    with pytest.raises(PneumaInputError, match=r"unknown key 'rollers\[0\].side'"):
        read_scene(data, "s")


def test_roller_wall_at_the_right_end_holds_it_horizontally():
    """The docs' worked example: a roller wall at x = 1.75 keeps the inflated beam's end face on the wall (tip dx
    and rotation held, to the penalty's reaction / K) while it slides along it (tip dy free, if smaller than a
    free end's)."""
    geometry = Geometry(
        Rectangle((0.0, 0.0), (3.5, 0.8)),
        (("main", Ellipse((0.0, 0.15), (0.85, 0.22), 32)),),
        0.02,
        PointSet("left"),
        rollers=(Roller(normal=(1.0, 0.0), point=(1.75, 0.0)),),
    )
    free = reference_scene(max_area=0.02, chamber_points=32, steps=4)
    held = Scene(geometry, free.controls, free.increments)
    tips = [run_schedule(scene.build()).steps[-1] for scene in (free, held)]
    assert tips[0].tip_dx > 1e-2 and abs(tips[1].tip_dx) < 1e-6 * tips[0].tip_dx
    assert abs(tips[0].tip_rotation) > 10 and abs(tips[1].tip_rotation) < 1e-6 * abs(tips[0].tip_rotation)
    assert 1e-3 < abs(tips[1].tip_dy) < abs(tips[0].tip_dy)
