"""The Triangle bindings (fem/triangulation.py) give the same meshes, and the same error where Triangle fails.

The reference counts (1601/2916, 1632/2976, 1633/2980) are checked by test_geometry.py on the default
binding; here each installed binding meshes the reference beams and a two-chamber scene, and where both
are installed their meshes must agree exactly (vertex coordinates bitwise, the same numbering).
"""

from pathlib import Path

import numpy as np
import pytest

from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem import triangulation
from taichi_pneuma.fem.planar import BeamGeometry, Geometry
from taichi_pneuma.fem.shapes import Ellipse, Rectangle
from taichi_pneuma.scene.scenefile import load_scene

INSTALLED = triangulation.installed()
SCENES = Path(__file__).resolve().parents[1] / "taichi_pneuma" / "scenes"
MESHES = {
    "cy=0": lambda: BeamGeometry(cy=0.0).mesh(),
    "cy=+0.15": lambda: BeamGeometry(cy=0.15).mesh(),
    "cy=-0.15": lambda: BeamGeometry(cy=-0.15).mesh(),
    "bidirectional": lambda: load_scene(SCENES / "bidirectional.toml").geometry.mesh(),
}
COUNTS = {"cy=0": (1601, 2916), "cy=+0.15": (1632, 2976), "cy=-0.15": (1633, 2980)}


def mesh_with(binding, make, monkeypatch):
    monkeypatch.setenv(triangulation.CHOICE_VARIABLE, binding)
    return make()


@pytest.mark.parametrize("binding", INSTALLED)
@pytest.mark.parametrize("name", COUNTS)
def test_each_binding_gives_the_reference_counts(binding, name, monkeypatch):
    mesh = mesh_with(binding, MESHES[name], monkeypatch)
    assert (mesh.n_vertices, mesh.n_triangles) == COUNTS[name]


@pytest.mark.skipif(len(INSTALLED) < 2, reason=f"one Triangle binding installed ({', '.join(INSTALLED)})")
@pytest.mark.parametrize("name", MESHES)
def test_bindings_give_identical_meshes(name, monkeypatch):
    first, second = (mesh_with(binding, MESHES[name], monkeypatch) for binding in INSTALLED[:2])
    assert np.array_equal(first.vertices, second.vertices)  # bitwise, and in the same order
    assert np.array_equal(first.triangles, second.triangles)
    assert all(np.array_equal(a, b) for a, b in zip(first.chambers, second.chambers, strict=True))
    assert np.array_equal(first.boundary, second.boundary) and np.array_equal(first.pinned, second.pinned)


@pytest.mark.parametrize("binding", [b for b in INSTALLED if b == "triangle"])
def test_out_of_precision_is_one_input_error_on_each_binding(binding, monkeypatch):
    """A chamber 1e-17 of the body's size: Triangle's refinement runs out of precision (the `triangle` package
    raises; meshpy's Triangle ends the process, which no test can catch: that binding is left out)."""
    geometry = Geometry(Rectangle((0.0, 0.0), (1e17, 1e17)), (("main", Ellipse((0.0, 0.15), (0.85, 0.22), 128)),), 1e33)
    with pytest.raises(PneumaInputError, match="Triangle could not mesh the geometry"):
        mesh_with(binding, geometry.mesh, monkeypatch)


def test_an_unknown_binding_is_named(monkeypatch):
    monkeypatch.setenv(triangulation.CHOICE_VARIABLE, "gmsh")
    with pytest.raises(ImportError, match="PNEUMA_TRIANGLE='gmsh' is not one of triangle, meshpy"):
        triangulation.default_binding()
