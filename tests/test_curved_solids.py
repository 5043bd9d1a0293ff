"""Quadratic tetrahedra on gmsh's curved shapes (fem/curving.py): a midside node on a curved surface moved onto it,
unless the move folds its element; and the tube's inner wall against the closed form, straight against curved.

The tube: a quarter (x, y >= 0) of a slice of the thick tube of radii A = 1 and B = 2 between the planes
z = -+L / 2, rollers on all four planes (plane strain), pressure p on the inner wall, p / mu = 1e-5 (geometric
nonlinearity far below the errors measured). Linear elasticity's plane-strain Lame solution, with the stable
neo-Hookean law's linearised moduli G = mu and Lame constant lam' = lam - mu (as tests/test_solid_verification.py):

    u_r(r) = p A^2 / (B^2 - A^2) [r / (2 (lam' + G)) + B^2 / (2 G r)].

Measured (gmsh 4.15.2; relative error of the inner wall's mean radial displacement over its corner nodes):

    size 0.25 ( 526 tets): straight -7.8e-3, curved -2.0e-4
    size 0.125 (3142 tets): straight -2.4e-3, curved -9.9e-6   (observed orders 1.7 and 4.3)
"""

import numpy as np
import pytest
from solid_meshes import scene_of

import taichi_pneuma as tp
from taichi_pneuma.fem.curving import FLOOR, curve, jacobian_ratios
from taichi_pneuma.fem.elements import TET_P2
from taichi_pneuma.fem.gmsh_mesher import MeshSizes
from taichi_pneuma.fem.solid_geometry import SolidGeometry
from taichi_pneuma.fem.solids import Box, Cut, Cylinder
from taichi_pneuma.fem.supports import Roller
from taichi_pneuma.materials import lame_parameters
from taichi_pneuma.scene.build import Material
from taichi_pneuma.scene.schedule import ChamberSchedule

A, B, L, NU = 1.0, 2.0, 0.5, 0.3
PLANES = (((1, 0, 0), (0, 0, 0)), ((0, 1, 0), (0, 0, 0)), ((0, 0, 1), (0, 0, -L / 2)), ((0, 0, 1), (0, 0, L / 2)))
ROLLERS = tuple(Roller(n, p) for n, p in PLANES)
QUARTER = Cut(
    Cylinder((0, 0, 0), B, L, "z"), (Box((-B, 0, 0), (2 * B, 4 * B, 2 * L)), Box((0, -B, 0), (4 * B, 2 * B, 2 * L)))
)
BORE = Cylinder((0, 0, 0), A, 2 * L, "z")


def reference_tet() -> tuple[np.ndarray, np.ndarray]:
    """(vertices, elements) of the unit reference tetrahedron made quadratic (straight)."""
    corners = np.vstack([np.zeros(3), np.eye(3)])
    vertices, elements, _ = TET_P2.lift(corners, np.array([[0, 1, 2, 3]]))
    return vertices, elements


def test_a_straight_element_has_jacobian_ratio_one_and_a_bent_one_the_closed_form():
    """Moving edge 01's midside node by d along y: X = xi + 4 L0 L1 d e_y, det dX/dxi = 1 - 4 d xi_1, least at
    corner 1: 1 - 4 d."""
    vertices, elements = reference_tet()
    assert jacobian_ratios(vertices, elements, TET_P2) == pytest.approx([1.0], abs=1e-12)
    for d in (0.05, 0.1, -0.1):
        bent = vertices.copy()
        bent[elements[0, 4]] += [0.0, d, 0.0]
        assert jacobian_ratios(bent, elements, TET_P2) == pytest.approx([min(1 - 4 * d, 1.0)], abs=1e-12)


def test_a_move_that_would_fold_its_element_is_undone_and_a_mild_one_kept():
    vertices, elements = reference_tet()
    node = elements[:, 4]
    for d, kept in ((0.1, True), ((1 - FLOOR) / 4 + 0.01, False), (0.5, False)):
        target = vertices[node] + [0.0, d, 0.0]
        moved = curve(vertices, elements, TET_P2, node, target)
        assert np.array_equal(moved[node], target if kept else vertices[node])
        assert np.array_equal(np.delete(moved, node, axis=0), np.delete(vertices, node, axis=0))


def tube_errors(size: float) -> list[float]:
    """The relative errors of the inner wall's radial displacement, straight then curved (module docstring)."""
    mu, lam = lame_parameters(1.0, NU)
    p = 1e-5 * mu
    exact = p * A**2 / (B**2 - A**2) * (A / (2 * lam) + B**2 / (2 * mu * A))  # lam' + G = lam
    errors = []
    for curved in (False, True):
        geometry = SolidGeometry(QUARTER, (("main", BORE),), MeshSizes(size), 2, rollers=ROLLERS, curved=curved)
        mesh = geometry.mesh()
        result = tp.simulate(scene_of(mesh, [ChamberSchedule("pressure", ((1, p),))], 1, Material(1.0, NU)))
        assert result.converged
        X = mesh.vertices
        radius = np.hypot(X[:, 0], X[:, 1])
        corners = np.unique(mesh.elements[:, :4])
        inner = corners[np.abs(radius[corners] - A) < 1e-9]
        radial = np.einsum("ij,ij->i", result.displacements[-1][inner, :2], X[inner, :2]) / A
        errors.append(abs(radial.mean() / exact - 1))
    return errors


def test_a_tube_on_curved_quadratic_tetrahedra_converges_faster_than_on_straight_ones():
    pytest.importorskip("gmsh", reason="gmsh is not installed (pip install 'taichi-pneuma[3d]')")
    coarse, fine = np.array(tube_errors(0.25)), np.array(tube_errors(0.125))
    orders = np.log2(coarse / fine)
    assert fine[1] < fine[0] / 20 and coarse[1] < coarse[0] / 10  # 2.4e-3 against 9.9e-6
    assert orders[1] > 3.0 and orders[1] > orders[0] + 1  # 4.3 and 1.7
    assert fine[0] < 0.005 and fine[1] < 1e-4
