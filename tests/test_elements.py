"""Element families: shape functions (interpolation, partition of unity, gradients by finite differences),
quadrature rules exact to their degree and no further, the quadrature of a mesh, and boundary facets."""

import math
from itertools import product

import numpy as np
import pytest
from solid_meshes import shell_octant

from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.elements import (
    FAMILIES,
    SEGMENTS,
    TET_P1,
    TET_P2,
    TRIANGLE_P1,
    TRIANGLE_P2,
    boundary_facets,
    family_of,
)
from taichi_pneuma.fem.lagrange import conical_rule
from taichi_pneuma.scene.build import reference_scene

RNG = np.random.default_rng(7)


def random_reference_points(dim, count=20):
    """Points inside the reference simplex (uniform barycentric weights, last one dropped)."""
    weights = RNG.dirichlet(np.ones(dim + 1), size=count)
    return weights[:, 1:]


@pytest.mark.parametrize("family", FAMILIES + SEGMENTS, ids=lambda f: f.name)
def test_shape_functions_interpolate_and_sum_to_one(family):
    assert family.n_nodes == len(family.reference_nodes)
    assert np.allclose(family.shape_functions(family.reference_nodes), np.eye(family.n_nodes), atol=1e-15)
    points = random_reference_points(family.dim)
    assert np.allclose(family.shape_functions(points).sum(axis=1), 1.0, atol=1e-14)
    assert np.allclose(family.shape_gradients(points).sum(axis=1), 0.0, atol=1e-13)
    # order p reproduces polynomials of degree p: sum_a N_a(x) f(X_a) = f(x) for f = x^i y^j, i + j <= order
    for powers in product(range(family.order + 1), repeat=family.dim):
        if sum(powers) <= family.order:
            nodal = np.prod(family.reference_nodes ** np.array(powers), axis=1)
            exact = np.prod(points ** np.array(powers), axis=1)
            assert np.allclose(family.shape_functions(points) @ nodal, exact, atol=1e-14)


@pytest.mark.parametrize("family", FAMILIES + SEGMENTS, ids=lambda f: f.name)
def test_shape_gradients_match_finite_differences(family):
    points, h = random_reference_points(family.dim), 1e-6
    gradients = family.shape_gradients(points)
    for i in range(family.dim):
        step = h * np.eye(family.dim)[i]
        fd = (family.shape_functions(points + step) - family.shape_functions(points - step)) / (2 * h)
        assert np.abs(gradients[:, :, i] - fd).max() < 1e-8


def monomial_mean(powers):
    """The mean of prod x_i^p_i over the reference simplex: (prod p_i!) d! / (sum p_i + d)!."""
    d = len(powers)
    return math.prod(math.factorial(p) for p in powers) * math.factorial(d) / math.factorial(sum(powers) + d)


@pytest.mark.parametrize("family", FAMILIES, ids=lambda f: f.name)
def test_each_rule_is_exact_to_its_degree_and_no_further(family):
    for degree, (points, weights) in family.cell.rules.items():
        errors = {}
        for powers in product(range(degree + 2), repeat=family.dim):
            if sum(powers) <= degree + 1:
                value = weights @ np.prod(points ** np.array(powers), axis=1)
                errors[powers] = abs(value - monomial_mean(powers))
        assert max(e for p, e in errors.items() if sum(p) <= degree) < 1e-15
        assert max(e for p, e in errors.items() if sum(p) == degree + 1) > 1e-4


@pytest.mark.parametrize("dim, degree", [(1, 4), (2, 5), (2, 7), (3, 5)])
def test_conical_rules_are_exact_to_their_degree(dim, degree):
    """Simplex.rule's fallback for a degree without a fixed rule (the P3 triangle's nodal measures: degree 7) is
    exact for every monomial of that degree, against the closed form of its mean over the simplex."""
    points, weights = conical_rule(dim, degree)
    assert weights.sum() == pytest.approx(1.0, abs=1e-15) and np.all(points >= 0) and np.all(points.sum(axis=1) <= 1)
    for powers in product(range(degree + 1), repeat=dim):
        if sum(powers) <= degree:
            value = weights @ np.prod(points ** np.array(powers), axis=1)
            assert value == pytest.approx(monomial_mean(powers), abs=1e-15)


def body(order, dim):
    """A coarse mesh: the reference beam (2D) or an octant of a spherical shell (3D)."""
    if dim == 3:
        return shell_octant(3, 2, order)
    return reference_scene(cy=0.15, max_area=0.02, chamber_points=32, order=order).build().mesh


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("order", [1, 2])
def test_mesh_quadrature_weighs_the_measure_and_differentiates_linear_fields_exactly(order, dim):
    mesh = body(order, dim)
    family = family_of(mesh.elements, dim)
    assert family is {(2, 1): TRIANGLE_P1, (2, 2): TRIANGLE_P2, (3, 1): TET_P1, (3, 2): TET_P2}[dim, order]
    gradients, weights = family.quadrature(mesh.vertices, mesh.elements)
    assert weights.shape == (mesh.n_elements, len(family.rule[1])) and np.all(weights > 0)
    assert weights.sum() == pytest.approx(mesh.measure, rel=1e-12)
    A = np.arange(1.0, dim * dim + 1).reshape(dim, dim) / 3 - np.eye(dim)  # f(X) = A X has gradient A everywhere
    assert np.allclose(np.einsum("mai,mqaj->mqij", (mesh.vertices @ A.T)[mesh.elements], gradients), A, atol=1e-11)


def test_curved_quadratic_tetrahedron_weighs_its_curved_volume():
    """The reference tetrahedron with the midside node of edge 01 moved by b along z: the map is X = xi + b N_m e_z,
    N_m = 4 (1 - xi_x - xi_y - xi_z) xi_x, so det dX/dxi = 1 + b dN_m/dxi_z = 1 - 4 b xi_x (linear, integrated
    exactly by the degree-2 rule) and the volume is (1 - b) / 6, where the corners alone would give 1/6."""
    corners = np.vstack([np.zeros(3), np.eye(3)])
    nodes = np.vstack([corners] + [0.5 * (corners[i] + corners[j]) for i, j in TET_P2.edges])
    nodes[4, 2] += 0.3
    _, weights = TET_P2.quadrature(nodes, np.arange(10)[None])
    assert weights.sum() == pytest.approx(0.7 / 6, rel=1e-14)


def test_unknown_element_table_names_the_families():
    with pytest.raises(PneumaInputError, match="4 nodes in 2D.*P1 triangle"):
        family_of(np.zeros((3, 4), dtype=int), 2)


@pytest.mark.parametrize("order", [1, 2])
def test_boundary_facets_are_the_mesh_boundary_traversed_with_the_body_on_the_left(order):
    mesh = reference_scene(cy=0.0, max_area=0.05, chamber_points=16, order=order).build().mesh
    facets = boundary_facets(family_of(mesh.triangles, 2), mesh.triangles)
    chamber_nodes = np.concatenate(mesh.chambers)
    assert set(np.unique(facets)) == set(mesh.boundary) | set(chamber_nodes)
    # each facet's corners run counter-clockwise around the body and clockwise around a hole (the outward
    # normal lies to the right): the shoelace sum over the facets is the body's area, over the parabolas through
    # corner, midside node and corner for quadratic ones (their boundary nodes lie on the exact curves):
    # 1/2 a x b per straight facet, 1/6 (4 a x m + 4 m x b - a x b) per parabolic one
    a, b = mesh.vertices[facets[:, 0]], mesh.vertices[facets[:, 1]]
    cross = lambda p, q: p[:, 0] * q[:, 1] - p[:, 1] * q[:, 0]
    if order == 1:
        assert 0.5 * np.sum(cross(a, b)) == pytest.approx(mesh.area, rel=1e-12)
    else:
        m = mesh.vertices[facets[:, 2]]  # the facet's midside node: near the middle of its chord
        assert np.all(np.linalg.norm(m - 0.5 * (a + b), axis=1) < 0.25 * np.linalg.norm(b - a, axis=1))
        assert np.sum(4 * cross(a, m) + 4 * cross(m, b) - cross(a, b)) / 6 == pytest.approx(mesh.area, rel=1e-12)
