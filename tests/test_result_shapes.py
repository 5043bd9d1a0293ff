"""The shapes Result's docstring states for its arrays are the shapes a 2D and a 3D run (on quadratic tetrahedra)
have: each "name (shape)" the docstring writes is read off it, its symbols replaced by the run's counts (d by the
dimension the test asks for, n by the nodes its elements use, counted here), and compared with the array."""

import functools
import inspect
import re

import numpy as np
import pytest

import taichi_pneuma as tp

# "positions (steps, n, d)", "command, area, area_ratio, pressure (steps, chambers)", "obstacle_positions() (...)"
STATED = re.compile(r"((?:[\w.]+(?:\(\))?, )*[\w.]+(?:\(\))?) \(((?:\w+, )*\w+)\)")


def stated_shapes() -> dict[str, tuple[str, ...]]:
    """Each array attribute Result's docstring gives a shape -> that shape's symbols."""
    doc = inspect.getdoc(tp.Result)
    return {
        name: tuple(shape.split(", "))
        for names, shape in STATED.findall(" ".join(doc.split()))
        if "," in shape
        for name in names.split(", ")
    }


def value_of(result, name: str):
    value = functools.reduce(getattr, name.removesuffix("()").split("."), result)
    return value() if name.endswith("()") else value


def tiny_2d():
    return tp.simulate(tp.reference_scene(max_area=0.02, growth=1.2, steps=2)), 2


def tiny_3d_quadratic():
    pytest.importorskip("gmsh", reason="gmsh is not installed (pip install 'taichi-pneuma[3d]')")
    size = 0.5
    scene = tp.load_scene("beam_3d_ellipsoid").with_values(
        {
            "mesh.size": size,
            "mesh.near_chambers": size,
            "mesh.distance": size,
            "mesh.order": 2,
            "schedule.increments": 1,
            "chambers[0].keyframes": [[0, 1.0], [1, 1.2]],
        }
    )
    return tp.simulate(scene), 3


def test_the_docstring_states_the_arrays_shapes_with_symbols():
    shapes = stated_shapes()
    assert shapes["positions"] == shapes["displacements"] == ("steps", "n", "d")
    assert {"contact_forces", "pressure", "area_ratio", "mesh.vertices", "obstacle_positions()"} <= set(shapes)


@pytest.mark.parametrize("make", [tiny_2d, tiny_3d_quadratic], ids=["2d", "3d_quadratic"])
def test_every_stated_array_shape_is_the_runs(make):
    result, d = make()
    mesh = result.mesh
    nodes = len(np.unique(mesh.elements))  # every node of the mesh, corners and (quadratic) midside nodes
    if d == 3:
        assert mesh.order == 2 and nodes > len(np.unique(mesh.elements[:, :4]))  # midside nodes counted in n
    counts = {
        "steps": len(result.steps),
        "n": nodes,
        "d": d,
        "chambers": len(result.chamber_names),
        "obstacles": len(result.scene.obstacles),
    }
    checked = []
    for name, shape in stated_shapes().items():
        value = value_of(result, name)
        if value is None:  # contact_forces without contact
            continue
        expected = tuple(counts[s] if s in counts else int(s) for s in shape)
        assert np.shape(value) == expected, f"{name}: stated {shape}"
        checked.append(name)
    assert {"positions", "displacements", "pressure", "mesh.vertices", "obstacle_positions()"} <= set(checked)
