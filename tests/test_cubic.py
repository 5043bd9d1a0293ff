"""Cubic (P3) triangles, the family added through the registry alone: derivatives against finite differences, the
cubic wall's enclosed area exact, the mesh's curved boundary and interior nodes, and the convergence order on the
Lame thick ring's closed form (against P1 and P2 on the same uniformly refined meshes)."""

import numpy as np
import pytest
from fd import dense_hessian, fd_hessian
from scenes import grounded_beam
from test_curved_boundaries import INNER, LOAD, NU, OUTER
from test_terms import assert_gradient_matches_finite_differences, assert_max_step_stops_before_inversion

import taichi_pneuma as tp
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.elements import TRIANGLE_P3, family_for
from taichi_pneuma.fem.planar import Geometry, jacobians
from taichi_pneuma.fem.shapes import Ellipse
from taichi_pneuma.fem.supports import Roller
from taichi_pneuma.materials import lame_parameters
from taichi_pneuma.scene.build import ChamberControl, Material, Scene
from taichi_pneuma.scene.schedule import ChamberSchedule
from taichi_pneuma.terms.chambers import PressureControl
from taichi_pneuma.terms.model import Configuration


@pytest.fixture(scope="module")
def coarse_p3():
    """A coarse cubic beam on the ground under gravity, chamber commanded to 1.5x, in a random state."""
    return grounded_beam(3, 0.08, 3)


@pytest.mark.parametrize("name", ["elastic", "chamber:main", "clamp", "gravity", "ground"])
def test_gradient_matches_finite_differences(coarse_p3, name):
    built, u = coarse_p3
    assert built.mesh.family is TRIANGLE_P3
    assert_gradient_matches_finite_differences(built, name, u)


def test_full_hessian_matches_finite_differences(coarse_p3):
    built, u = coarse_p3
    model = built.model
    model.set_displacements(u)
    hessian = dense_hessian(model.n_dofs, model.terms, psd_only=False)
    h_fd = fd_hessian(model, model.terms, u)
    assert np.linalg.norm(hessian - h_fd) / np.linalg.norm(h_fd) < 1e-6


def test_max_step_keeps_every_quadrature_point_uninverted(coarse_p3):
    assert_max_step_stops_before_inversion(coarse_p3[0])


def test_cubic_wall_area_is_exact_under_a_cubic_curve():
    """The loop (0, 0) -> (1, 0) -> (1, 1) straight, then back to (0, 0) along y = x^3 (nodes at x = 1, 2/3, 1/3: the
    cubic edge is that curve) runs counter-clockwise around the area under the curve, int_0^1 x^3 dx = 1/4, exactly
    (the area form's weights are exact rationals and its integrand a polynomial)."""
    t = np.array([0.0, 1 / 3, 2 / 3])
    bottom = np.column_stack([t, np.zeros(3)])
    up = np.column_stack([np.ones(3), t])
    curve = np.column_stack([1 - t, (1 - t) ** 3])
    nodes = np.vstack([bottom, up, curve])  # corner, two edge nodes, corner, ...: 3 cubic edges
    chamber = PressureControl().term(Configuration(nodes), np.arange(9), "main", order=3)
    assert chamber.rest_area == pytest.approx(0.25, abs=1e-15)


def test_cubic_mesh_puts_boundary_nodes_on_the_circle_and_interior_nodes_where_the_boundary_says():
    """Every node of the walls lies on its circle; each element's interior node is the quadratic map's value at
    its centre (ElementFamily.interior_weights: 1/4 the six edge nodes minus 1/6 the three corners, which is the
    centroid of a straight-sided triangle); no element is folded; the drawing splits each element in 9."""
    mesh = ring(8, 3).mesh()
    x, t = mesh.vertices, mesh.elements
    assert t.shape[1] == 10 and mesh.family is TRIANGLE_P3
    r = np.linalg.norm(x, axis=1)
    assert np.allclose(r[mesh.chambers[0]], INNER, atol=1e-14) and np.allclose(r[mesh.boundary], OUTER, atol=1e-14)
    assert len(mesh.chambers[0]) == 3 * 8  # corner, two edge nodes, next corner: 8 cubic edges
    expected = 0.25 * x[t[:, 3:9]].sum(axis=1) - x[t[:, :3]].sum(axis=1) / 6
    assert np.allclose(x[t[:, 9]], expected, atol=1e-15)
    straight = ~np.isin(t, np.concatenate([mesh.chambers[0], mesh.boundary])).any(axis=1)
    assert np.allclose(x[t[straight, 9]], x[t[straight, :3]].mean(axis=1), atol=1e-15)
    assert jacobians(x, t, TRIANGLE_P3.reference_nodes).min() > 0
    assert len(mesh.display_triangles()) == 9 * mesh.n_elements


def test_orders_without_a_family_are_refused_in_one_line():
    with pytest.raises(PneumaInputError, match=r"order = 3 must be one of 1 \(P1 tetrahedron\), 2 \(P2 tetrahedron\)"):
        family_for(3, 3)
    with pytest.raises(PneumaInputError, match=r"order = 4 must be one of 1 \(P1 triangle\), 2 .*, 3 \(P3 triangle\)"):
        ring(8, 4)


def ring(n: int, order: int, base: int = 8) -> Geometry:
    """The ring INNER <= r <= OUTER meshed at `base` points on the inner circle (2 base on the outer one, max area
    (2 pi / base)^2) and refined uniformly to n (h = 2 pi / n: nested meshes, boundary nodes on the circles);
    rollers on the axes hold the rigid motions."""
    circles = [Ellipse((0.0, 0.0), (r, r), k) for r, k in ((OUTER, 2 * base), (INNER, base))]
    return Geometry(
        circles[0],
        (("c", circles[1]),),
        (2 * np.pi / base) ** 2,
        None,
        order=order,
        refinements=int(np.log2(n // base)),
        rollers=(Roller((0.0, 1.0), (0.0, 0.0)), Roller((1.0, 0.0), (0.0, 0.0))),
    )


def lame_l2_error(geometry: Geometry) -> tuple[float, int]:
    """(relative L2 error of the displacement, DOFs) against Lame's plane-strain solution u = (A r + B / r) e_r under
    internal pressure p = LOAD mu (test_curved_boundaries.lame_errors), over the mapped elements with a degree-8 rule.
    The linear response is (u(p) - u(-p)) / 2: the geometric nonlinearity's O(p^2) part cancels, leaving O(p^3)."""
    mu, lam = lame_parameters(1.0, NU)
    p, a2, b2 = LOAD * mu, INNER**2, OUTER**2
    A, B = p * a2 / (2 * lam * (b2 - a2)), p * a2 * b2 / (2 * mu * (b2 - a2))
    runs = []
    for sign in (1, -1):
        kind = ChamberSchedule(PressureControl(allow_vacuum=True), ((1, sign * p),))
        result = tp.simulate(Scene(geometry, (ChamberControl(kind),), 1, Material(1.0, NU)), tol=1e-9)
        assert result.converged
        runs.append(result.displacements[-1])
    mesh, u = result.mesh, 0.5 * (runs[0] - runs[1])
    family = mesh.family
    rule = family.cell.rule(8)
    _, weights = family.quadrature(mesh.vertices, mesh.elements, rule)
    shape = family.shape_functions(rule[0])
    x = np.einsum("qa,mad->mqd", shape, mesh.vertices[mesh.elements])
    uh = np.einsum("qa,mad->mqd", shape, u[mesh.elements])
    r = np.linalg.norm(x, axis=2, keepdims=True)
    exact = (A * r + B / r) * x / r
    squared = lambda f: np.sum(weights * np.sum(f**2, axis=2))
    return float(np.sqrt(squared(uh - exact) / squared(exact))), 2 * mesh.n_vertices


def test_cubic_ring_converges_at_fourth_order_and_beats_quadratic_at_fewer_dofs():
    """Measured (h = 2 pi / n, n = 8, 16, 32, 64; nested meshes): P2 2.8, 2.9, 3.0 (3.3e-5 at n = 64, 6528 DOFs),
    P3 3.4, 3.75, 3.9 (1.4e-5 at n = 32, 3744 DOFs; 9.4e-7 at n = 64). With the interior node left at the straight
    centroid the P3 order stays near 3.4: curved elements need it where their boundary puts it."""
    cubic = [lame_l2_error(ring(n, 3)) for n in (16, 32, 64)]
    errors = np.array([e for e, _ in cubic])
    orders = np.log2(errors[:-1] / errors[1:])
    assert orders[-1] > 3.6 and orders.min() > 3.3
    quadratic, dofs = lame_l2_error(ring(64, 2))
    assert cubic[1][1] < dofs and cubic[1][0] < quadratic / 2  # P3 at n = 32 beats P2 at n = 64 on fewer DOFs


def test_cubic_cells_are_written_as_vtk_lagrange_triangles(tmp_path):
    """The VTU names the cells VTK_LAGRANGE_TRIANGLE (69), 10 nodes in VTK's order: meshio reads them back with the
    nodes at their places (edge node 3 a third of the way from corner 0 to 1 on a straight edge)."""
    import meshio

    from taichi_pneuma.io.vtk import vtu_text

    mesh = ring(8, 3).mesh()
    points = np.column_stack([mesh.vertices, np.zeros(mesh.n_vertices)])
    path = tmp_path / "p3.vtu"
    path.write_text(vtu_text(points, [(mesh.family, mesh.elements)], {}, {}, {}))
    grid = meshio.read(path)
    assert [(c.type, c.data.shape) for c in grid.cells] == [("VTK_LAGRANGE_TRIANGLE", (mesh.n_elements, 10))]
    assert np.array_equal(grid.cells[0].data, mesh.elements)
    x, t = mesh.vertices, mesh.elements
    straight = ~np.isin(t[:, 3], np.concatenate([mesh.chambers[0], mesh.boundary]))
    assert np.allclose(x[t[straight, 3]], (2 * x[t[straight, 0]] + x[t[straight, 1]]) / 3, atol=1e-15)


def test_the_quality_ladder_leaves_a_cubic_scene_its_mesh():
    """--quality's 2D ladder is of linear and quadratic meshes: a cubic scene keeps its area and order at every rung
    (only the Newton tolerance changes), where a quadratic one moves up and down the ladder."""
    from taichi_pneuma.apps.quality import QUALITY_STEPS, planar_preset

    assert all(planar_preset(q, 0.01, 3) == (0.01, 3) for q in QUALITY_STEPS)
    assert planar_preset("draft", 0.01, 2)[0] > 0.01 and planar_preset("draft", 0.01, 1)[0] > 0.01
