"""Each obstacle shape's one triangulated surface (Shape.surface), which ParaView's files and the 3D frames both
draw: every point on the shape, the surface closed and wound outwards, its area and enclosed volume the closed
forms', the outlined edges the box's and the square's sides."""

import numpy as np
import pytest

from taichi_pneuma.render.guides3d import obstacle_triangles
from taichi_pneuma.render.paraview_parts import obstacle_cells
from taichi_pneuma.terms.obstacle_shapes import Box, Capsule, Cylinder, Plane, Sphere

C = np.array([1.0, 2.0, 3.0])
SOLIDS = [
    Sphere(center=tuple(C), radius=2.0),
    Box(center=tuple(C), size=(2.0, 4.0, 6.0)),
    *(Cylinder(center=tuple(C), radius=1.5, length=4.0, axis=a) for a in "xyz"),
    *(Capsule(center=tuple(C), radius=1.5, length=4.0, axis=a) for a in "xyz"),
]
# (area, volume) in closed form: a sphere of radius 2; the 2 x 4 x 6 box; radius 1.5, length 4 (a capsule's segment)
EXACT = {
    "Sphere": (4 * np.pi * 4, 4 / 3 * np.pi * 8),
    "Box": (2 * (8 + 12 + 24), 48.0),
    "Cylinder": (2 * np.pi * 1.5 * 4 + 2 * np.pi * 1.5**2, np.pi * 1.5**2 * 4),
    "Capsule": (2 * np.pi * 1.5 * 4 + 4 * np.pi * 1.5**2, np.pi * 1.5**2 * 4 + 4 / 3 * np.pi * 1.5**3),
}
ids = lambda s: f"{type(s).__name__}-{getattr(s, 'axis', '')}"  # noqa: E731


@pytest.mark.parametrize("shape", SOLIDS, ids=ids)
def test_a_solids_surface_lies_on_it_closes_and_faces_out_with_its_area_and_volume(shape):
    """Every point on the boundary; each triangle's sides in one other triangle, run the other way (closed); each
    triangle facing away from the centre (each shape is convex about it); the area to 0.5 % and the enclosed volume
    to 1 % of the closed forms (48 points round, 12 rings a quarter circle: the polygons' chords fall short)."""
    points, triangles, edges = shape.surface(5.0, np.array([3.0, 3.0, 3.0]))
    name = type(shape).__name__
    if name == "Sphere":
        assert np.linalg.norm(points - C, axis=1) == pytest.approx(2.0, rel=1e-12)
    elif name == "Box":
        assert np.abs((points - C) / (1.0, 2.0, 3.0)).max(axis=1) == pytest.approx(1.0, rel=1e-12)
    else:
        axis = np.eye(3)["xyz".index(shape.axis)]
        along = (points - C) @ axis
        radial = np.linalg.norm(points - C - np.outer(along, axis), axis=1)
        if name == "Capsule":
            assert np.hypot(radial, along - np.clip(along, -2.0, 2.0)) == pytest.approx(1.5, rel=1e-12)
        else:
            on_side = np.isclose(radial, 1.5, rtol=1e-12) & (np.abs(along) <= 2.0 + 1e-12)
            on_cap = np.isclose(np.abs(along), 2.0, rtol=1e-12) & (radial <= 1.5 + 1e-12)
            assert np.all(on_side | on_cap)
    sides = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    assert len({tuple(e) for e in sides}) == len(sides)
    assert {tuple(e) for e in sides} == {tuple(e) for e in sides[:, ::-1]}
    a, b, c = (points[triangles[:, i]] - C for i in range(3))
    normals = np.cross(b - a, c - a)
    assert np.all(np.einsum("fi,fi->f", normals, a + b + c) > 0)
    area, volume = EXACT[name]
    assert 0.5 * np.linalg.norm(normals, axis=1).sum() == pytest.approx(area, rel=0.005)
    assert np.einsum("fi,fi->f", a, np.cross(b, c)).sum() / 6 == pytest.approx(volume, rel=0.01)
    if name == "Box":  # its 12 edges: 4 along each axis, as long as the box is along it
        lengths = np.abs(points[edges[:, 1]] - points[edges[:, 0]])
        assert sorted(lengths.max(axis=1)) == [2.0] * 4 + [4.0] * 4 + [6.0] * 4
        assert np.all(np.sort(lengths, axis=1)[:, :2] == 0)
    else:
        assert len(edges) == 0


def test_a_planes_square_lies_in_it_about_the_point_nearest_the_centre_facing_the_body():
    """A plane's patch: its 4 corners in the plane, 2 reach apart along its sides (its 4 edges), centred on the
    point of the plane nearest the given centre, its 2 triangles facing the normal's side."""
    shape = Plane(point=(0.0, 1.0, 0.0), normal=(1.0, 2.0, 2.0))
    n, centre = np.array([1.0, 2.0, 2.0]) / 3.0, np.array([3.0, 3.0, 3.0])
    points, triangles, edges = shape.surface(5.0, centre)
    assert np.abs((points - (0.0, 1.0, 0.0)) @ n).max() < 1e-12
    np.testing.assert_allclose(points.mean(axis=0), centre - ((centre - (0.0, 1.0, 0.0)) @ n) * n, atol=1e-12)
    assert np.linalg.norm(points[edges[:, 1]] - points[edges[:, 0]], axis=1) == pytest.approx([10.0] * 4)
    assert sorted(np.bincount(edges.ravel())) == [2, 2, 2, 2]  # a loop through the 4 corners
    a, b, c = (points[triangles[:, i]] for i in range(3))
    assert np.all(np.cross(b - a, c - a) @ n > 0)


@pytest.mark.parametrize("shape", [*SOLIDS, Plane(point=tuple(C), normal=(0.0, 0.0, 1.0))], ids=ids)
def test_paraview_and_the_3d_frames_draw_the_same_triangles(shape):
    """ParaView's cells and the frames' triangles are the one surface's (a plane's patch about its point)."""
    points, _, cells = obstacle_cells(shape, 3, 5.0, C)
    triangles, edges = obstacle_triangles(shape, 5.0)
    np.testing.assert_array_equal(points[cells], triangles)
    assert edges.shape == (len(shape.surface(5.0, C).edges), 2, 3)
