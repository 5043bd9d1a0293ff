import numpy as np
import pytest

from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.planar import BeamGeometry
from taichi_pneuma.fem.polygons import signed_area


@pytest.mark.parametrize("cy, vertices, triangles", [(0.0, 1601, 2916), (0.15, 1632, 2976), (-0.15, 1633, 2980)])
def test_reference_mesh_sizes(cy, vertices, triangles):
    """Triangle with 'pqa0.0012' gives the reference implementation's meshes."""
    mesh = BeamGeometry(cy=cy).mesh()
    assert (mesh.n_vertices, mesh.n_triangles) == (vertices, triangles)


def test_chamber_loop_is_the_ellipse_counter_clockwise():
    geometry = BeamGeometry(cy=0.15)
    mesh = geometry.mesh()
    chamber_loop = mesh.chambers[0]
    loop = mesh.vertices[chamber_loop]
    assert len(chamber_loop) == len(set(chamber_loop.tolist()))
    assert signed_area(loop) == pytest.approx(0.587, abs=5e-4)
    # every wall vertex lies on the ellipse
    r = ((loop[:, 0] - geometry.cx) / geometry.a) ** 2 + ((loop[:, 1] - geometry.cy) / geometry.b) ** 2
    assert np.allclose(r, 1.0, atol=1e-9)
    # consecutive loop vertices are mesh edges
    edges = {tuple(sorted(e)) for t in mesh.triangles for e in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}
    assert all(tuple(sorted((a, b))) in edges for a, b in zip(chamber_loop, np.roll(chamber_loop, -1)))


def test_triangles_are_counter_clockwise_and_cover_beam_minus_chamber():
    geometry = BeamGeometry()
    mesh = geometry.mesh()
    p0, p1, p2 = (mesh.vertices[mesh.triangles[:, i]] for i in range(3))
    e1, e2 = p1 - p0, p2 - p0
    assert np.all(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] > 0)
    polygon_area = signed_area(geometry.general().chambers[0][1].polygon())
    assert mesh.area == pytest.approx(3.5 * 0.8 - polygon_area, rel=1e-12)


def test_named_vertex_sets():
    mesh = BeamGeometry().mesh()
    x = mesh.vertices[:, 0]
    assert np.allclose(x[mesh.pinned], -1.75) and np.allclose(x[mesh.tip], 1.75)
    ys = np.sort(mesh.vertices[mesh.pinned, 1])
    assert ys[0] == pytest.approx(-0.4) and ys[-1] == pytest.approx(0.4)


@pytest.mark.parametrize(
    "kwargs, word",
    [
        (dict(cy=0.5), "cy = 0.5"),
        (dict(cy=-0.18), "vertically"),
        (dict(cx=1.0), "horizontally"),
        (dict(a=-1.0), "a = -1.0"),
        (dict(max_area=float("nan")), "max_area"),
    ],
)
def test_chamber_outside_the_beam_is_refused(kwargs, word):
    with pytest.raises(PneumaInputError, match=word):
        BeamGeometry(**kwargs)


@pytest.mark.parametrize("max_area", [1e-4, 2e-5])
def test_small_max_area_is_honoured(max_area):
    """Triangle's switch takes no exponent notation: 2e-05 must not be read as 2 (a coarse mesh)."""
    mesh = BeamGeometry(max_area=max_area).mesh()
    p0, p1, p2 = (mesh.vertices[mesh.triangles[:, i]] for i in range(3))
    e1, e2 = p1 - p0, p2 - p0
    areas = 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    assert areas.max() <= max_area * (1 + 1e-9)
    assert mesh.n_vertices > 0.8 * (3.5 * 0.8 - 0.587) / max_area / 2  # about two triangles per vertex
