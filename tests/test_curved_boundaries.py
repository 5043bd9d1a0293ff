"""Curved boundaries of quadratic (and refined) 2D meshes: every boundary node of an ellipse or a rounded corner
lies on the exact curve, so the isoparametric P2 triangles converge at their full order against closed forms
(the Lame thick ring, an ellipse's area) where straight-sided ones stay at second order."""

import numpy as np
import pytest

import taichi_pneuma as tp
from taichi_pneuma.fem.elements import TRIANGLE_P2
from taichi_pneuma.fem.planar import Geometry, onto_curves
from taichi_pneuma.fem.shapes import Ellipse, Polygon, Rectangle, RoundedRectangle
from taichi_pneuma.fem.supports import PointSet, Roller
from taichi_pneuma.materials import lame_parameters
from taichi_pneuma.scene.build import ChamberControl, Material, Scene
from taichi_pneuma.scene.schedule import ChamberSchedule
from taichi_pneuma.terms.chambers import PressureControl
from taichi_pneuma.terms.model import Configuration

INNER, OUTER, NU, LOAD = 1.0, 2.0, 0.3, 1e-6


def ring(n: int, curved: bool = True) -> Geometry:
    """The ring INNER <= r <= OUTER, n points on the inner circle and 2 n on the outer one (segments of about
    h = 2 pi / n), max area h^2, quadratic triangles; curved False gives the same circles as straight-sided
    polygons (Polygon has no curve: the meshes before curved boundaries). Rollers on the axes hold the
    rigid motions (the symmetric solution does not move across them)."""
    circles = [Ellipse((0.0, 0.0), (r, r), k) for r, k in ((OUTER, 2 * n), (INNER, n))]
    body, hole = circles if curved else [Polygon(tuple(map(tuple, c.polygon()))) for c in circles]
    return Geometry(
        body,
        (("c", hole),),
        (2 * np.pi / n) ** 2,
        None,
        order=2,
        rollers=(Roller((0.0, 1.0), (0.0, 0.0)), Roller((1.0, 0.0), (0.0, 0.0))),
    )


def lame_errors(geometries) -> np.ndarray:
    """Relative error of the mean radial displacement of the inner and of the outer boundary nodes under
    internal pressure p = LOAD mu, against Lame's plane-strain solution of linear elasticity

        u(r) = A r + B / r,   A = p a^2 / (2 (lam' + G) (b^2 - a^2)),   B = p a^2 b^2 / (2 G (b^2 - a^2)),

    (sigma_rr = 2 (lam' + G) A - 2 G B / r^2 is -p at a and 0 at b) with the stable neo-Hookean law's
    linearised moduli G = mu, lam' = lam - mu. p / mu = 1e-6 keeps the geometric nonlinearity below the
    errors measured."""
    mu, lam = lame_parameters(1.0, NU)
    p, a2, b2 = LOAD * mu, INNER**2, OUTER**2
    A, B = p * a2 / (2 * lam * (b2 - a2)), p * a2 * b2 / (2 * mu * (b2 - a2))  # lam' + G = lam
    errors = []
    for geometry in geometries:
        scene = Scene(geometry, (ChamberControl(ChamberSchedule("pressure", ((1, p),))),), 1, Material(1.0, NU))
        result = tp.simulate(scene, tol=1e-9)
        assert result.converged and result.history["min_det"].min() > 0
        x = result.mesh.vertices
        r = np.linalg.norm(x, axis=1)
        radial = np.einsum("ij,ij->i", result.displacements[-1], x / r[:, None])
        errors.append([abs(radial[np.abs(r - R) < 1e-12].mean() / (A * R + B / R) - 1) for R in (INNER, OUTER)])
    return np.array(errors)


def test_quadratic_ring_converges_to_lame_at_third_order_with_curved_boundaries():
    """Curved P2: observed orders 2.9 (inner) and 3.0-3.3 (outer), 2.3e-4 at n = 32 (1656 DOFs); the same mesh
    with straight sides: order 2.0, 8.3e-3 (35x more; 2.0e-3 at 4x the DOFs)."""
    curved = lame_errors([ring(n) for n in (8, 16, 32)])
    orders = np.log2(curved[:-1] / curved[1:])
    assert np.all(orders > 2.6) and curved[-1].max() < 5e-4
    straight = lame_errors([ring(n, curved=False) for n in (16, 32)])
    assert np.all(np.log2(straight[0] / straight[1]) < 2.3)
    assert np.all(curved[-1] < straight[-1] / 10)


def wall_area(mesh, chamber: int = 0) -> float:
    """The area the chamber's quadratic wall encloses (parabolic arcs through its nodes)."""
    return (
        PressureControl()
        .term(Configuration(mesh.vertices), mesh.chambers[chamber], "c", 2, mesh.wall_origins[chamber])
        .rest_area
    )


def test_chamber_and_body_areas_converge_at_fourth_order_to_the_ellipse():
    """The parabola through three points of a smooth curve is off it by O(h^3), alternating in sign along the
    edge: the enclosed area converges at order 4 (observed 3.98-4.02), against 2 for the inscribed polygon."""
    a, b = 1.0, 0.6
    exact_hole = np.pi * a * b
    errors = []
    for n in (8, 16, 32):
        mesh = Geometry(
            Rectangle((0.0, 0.0), (4.0, 4.0)), (("c", Ellipse((0.1, 0.05), (a, b), n)),), (2 * np.pi / n) ** 2, order=2
        ).mesh()
        errors.append([abs(wall_area(mesh) / exact_hole - 1), abs(mesh.area / (16.0 - exact_hole) - 1)])
    errors = np.array(errors)
    assert np.all(np.log2(errors[:-1] / errors[1:]) > 3.7)
    polygon = Ellipse((0.1, 0.05), (a, b), 32).polygon()
    assert (
        errors[-1, 0]
        < abs(
            0.5
            * np.sum(polygon[:, 0] * np.roll(polygon[:, 1], -1) - np.roll(polygon[:, 0], -1) * polygon[:, 1])
            / exact_hole
            - 1
        )
        / 500
    )


def on_rounded_rectangle(points, center, size, radius) -> np.ndarray:
    """Distance of points from the outline of a rounded rectangle: the box of its corner circles' centres
    grown by radius (a signed-distance closed form)."""
    q = np.abs(points - center) - (np.array(size) / 2 - radius)
    return np.abs(np.linalg.norm(np.maximum(q, 0.0), axis=1) + np.minimum(q.max(axis=1), 0.0) - radius)


@pytest.mark.parametrize("order, refinements", [(2, 0), (2, 1), (1, 2)])
def test_boundary_nodes_lie_on_the_exact_curves_and_interior_edges_stay_straight(order, refinements):
    """An ellipse body with a rounded-rectangle chamber and an ellipse chamber, coarse (16 points per ellipse,
    Triangle adds points on the chord segments): every boundary node lies on its shape's curve, straight
    sides stay straight, every interior midside node is its edge's middle, and no element is folded (the
    isoparametric Jacobian positive at every node)."""
    body = Ellipse((0.0, 0.0), (2.0, 1.0), 16)
    box = RoundedRectangle((-0.8, 0.0), (0.6, 0.8), 0.2, 3)
    hole = Ellipse((0.8, 0.0), (0.4, 0.3), 16)
    mesh = Geometry(body, (("box", box), ("hole", hole)), 0.02, order=order, refinements=refinements).mesh()
    x = mesh.vertices
    assert np.allclose(np.hypot(x[mesh.boundary, 0] / 2.0, x[mesh.boundary, 1]), 1.0, atol=1e-14)
    assert on_rounded_rectangle(x[mesh.chambers[0]], (-0.8, 0.0), (0.6, 0.8), 0.2).max() < 1e-14
    assert np.allclose(np.hypot((x[mesh.chambers[1], 0] - 0.8) / 0.4, x[mesh.chambers[1], 1] / 0.3), 1.0, atol=1e-14)
    assert len(mesh.boundary) > 16 * 2**refinements * order  # Triangle split the body's chords
    if order == 2:
        t = mesh.triangles
        walls = np.concatenate([mesh.boundary, *mesh.chambers])
        for i, j, m in ((0, 1, 3), (1, 2, 4), (2, 0, 5)):
            interior = ~np.isin(t[:, m], walls)
            assert np.allclose(x[t[interior, m]], 0.5 * (x[t[interior, i]] + x[t[interior, j]]), atol=1e-15)
        dn = TRIANGLE_P2.shape_gradients(TRIANGLE_P2.reference_nodes)
        assert np.linalg.det(np.einsum("mai,paj->mpij", x[t], dn)).min() > 0


def test_straight_sides_of_a_rounded_rectangle_keep_their_midside_nodes_at_the_middle():
    box = RoundedRectangle((0.0, 0.0), (1.0, 0.6), 0.1, 4)
    mesh = Geometry(Rectangle((0.0, 0.0), (2.0, 1.2)), (("c", box),), 0.01, order=2).mesh()
    wall = mesh.vertices[mesh.chambers[0]]
    corners, mids = wall[0::2], wall[1::2]
    middles = 0.5 * (corners + np.roll(corners, -1, axis=0))
    side = (np.abs(np.abs(middles[:, 0]) - 0.5) < 1e-12) | (np.abs(np.abs(middles[:, 1]) - 0.3) < 1e-12)
    assert side.sum() >= 4 and np.allclose(mids[side], middles[side], atol=1e-15)
    assert np.all(np.linalg.norm(mids[~side] - middles[~side], axis=1) > 1e-4)  # the arcs' bulge


def test_half_model_wall_cut_by_the_symmetry_line_is_curved_up_to_the_line():
    """The half beam's notched chamber: its open wall's nodes on the ellipse, its ends on the line, and its
    area (closed by the flat cap) half the ellipse's, to the fourth-order error of the parabolic arcs."""
    mesh = Geometry(
        Rectangle((0.0, 0.2), (3.5, 0.4)),
        (("main", Ellipse((0.0, 0.0), (0.85, 0.22), 32)),),
        0.01,
        PointSet("left"),
        order=2,
        rollers=(Roller((0.0, 1.0), (0.0, 0.0)),),
    ).mesh()
    wall = mesh.vertices[mesh.chambers[0]]
    assert np.allclose(np.hypot(wall[:, 0] / 0.85, wall[:, 1] / 0.22), 1.0, atol=1e-14)
    assert wall[0, 1] == wall[-1, 1] == 0.0
    assert wall_area(mesh) == pytest.approx(np.pi * 0.85 * 0.22 / 2, rel=2e-5)  # the polygon's: 6.4e-3 off


def test_a_midside_node_that_would_fold_its_triangle_stays_at_the_middle():
    """A triangle whose side 01 is a chord of a unit-circle hole, its corner 2 on the chord's bisector: moving
    the midside node by d (into the triangle) gives dX/dxi = J0 + 4 d (grad L0 L1)^T, whose determinant at corner 0
    is det J0 (1 + 4 d . grad_X L1) = det J0 (1 - 2 s / H) for a move s along the bisector of height H: folded
    past half the height. With corner 2 at (0.8, 0.8) the arc's midpoint (0.707, 0.707) is 0.69 of the way
    (s = 0.29, H = 0.42): that edge stays straight; with it at (2, 2) (0.14 of the way) it is curved."""
    hole = Ellipse((0.0, 0.0), (1.0, 1.0), 8)
    for corner, curved in ((0.8, False), (2.0, True)):
        vertices = np.array(
            [
                [1.0, 0.0],
                [0.0, 1.0],
                [corner, corner],
                [0.5, 0.5],
                [0.5 * (1 + corner), 0.5 * corner],
                [0.5 * corner, 0.5 * (1 + corner)],
            ]
        )
        triangles = np.array([[1, 0, 2, 3, 4, 5]])
        moved = onto_curves(vertices, np.array([[1, 3], [3, 0]]), np.array([2, 2]), {2: hole.project}, triangles)
        assert np.allclose(moved[3], [np.sqrt(0.5)] * 2 if curved else [0.5, 0.5], atol=1e-15)
        assert np.allclose(moved[[0, 1, 2, 4, 5]], vertices[[0, 1, 2, 4, 5]], atol=1e-15)


def test_a_corner_on_a_chord_that_would_fold_its_linear_triangles_stays():
    """A node Triangle put on a chord of a unit-circle hole, (0.5, 0.5), with a vertex at (c, c) beyond it: moved
    to the arc (0.707, 0.707) it passes that vertex for c = 0.6 (both triangles turn clockwise), so it stays;
    for c = 2 it moves."""
    hole = Ellipse((0.0, 0.0), (1.0, 1.0), 8)
    for corner, curved in ((0.6, False), (2.0, True)):
        vertices = np.array([[1.0, 0.0], [0.0, 1.0], [0.5, 0.5], [corner, corner]])
        triangles = np.array([[0, 3, 2], [2, 3, 1]])
        moved = onto_curves(vertices, np.array([[0, 2], [2, 1]]), np.array([2, 2]), {2: hole.project}, triangles)
        assert np.allclose(moved[2], [np.sqrt(0.5)] * 2 if curved else [0.5, 0.5], atol=1e-15)
