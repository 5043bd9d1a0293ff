"""3D against closed forms and against 2D: plane strain (the reference beam extruded through a depth, rollers on
both faces normal to z) and the pressurised thick-walled sphere (Lame), with observed orders of convergence."""

from dataclasses import replace

import numpy as np
import pytest
from solid_meshes import DEPTH, extruded_beam, scene_of, shell_octant

import taichi_pneuma as tp
from taichi_pneuma.fem.shapes import Polygon
from taichi_pneuma.materials import StableNeoHookean, lame_parameters
from taichi_pneuma.scene.build import Material, reference_scene
from taichi_pneuma.scene.schedule import ChamberSchedule, area_ramp
from taichi_pneuma.terms import Elasticity
from taichi_pneuma.terms.chambers import AreaControl
from taichi_pneuma.terms.model import EnergyModel

CONVERGED_2D_TIP = (
    -0.25826
)  # the 2D reference ramp's converged tip deflection (P2, uniform refinement; docs/accuracy.md)


def test_extruded_p1_body_has_exactly_depth_times_the_plane_strain_energy_forces_and_area():
    """The matching discretisation: a z-independent displacement of the linear tetrahedra of the extruded beam
    (each prism split in three) has, exactly, depth x the 2D energy of the linear triangles, the forces of each
    node column sum to depth x the 2D nodal force, and the prism chamber encloses depth x the 2D area: every
    tetrahedron of a prism has the F of its triangle (F_zz = 1), so the 3D model restricted to such motions is
    the plane-strain one."""
    mesh, planar = extruded_beam(0.05, chamber_points=32)
    in_plane = 0.03 * np.random.default_rng(0).standard_normal(planar.vertices.shape)
    u = np.column_stack([np.tile(in_plane, (2, 1)), np.zeros(mesh.n_vertices)])
    energies, forces, measures = [], [], []
    for body, displacement in ((planar, in_plane), (mesh, u)):
        model = EnergyModel(body.vertices, 1.0, 1e-12)
        n = body.n_elements
        elastic = model.add(
            Elasticity(
                model.config,
                body.elements,
                StableNeoHookean,
                StableNeoHookean.parameters(np.full(n, 1e4), np.full(n, 0.45)),
            )
        )
        chamber = model.add(AreaControl(1.0).term(model.config, body.chambers[0], "c", 1, body.wall_origins[0]))
        model.set_displacements(displacement)
        energies.append(elastic.energy())
        forces.append(elastic.gradient())
        measures.append(chamber.area())
    assert energies[1] == pytest.approx(DEPTH * energies[0], rel=1e-12)
    columns = forces[1].reshape(2, -1, 3).sum(axis=0)
    assert np.abs(columns[:, :2] - DEPTH * forces[0]).max() < 1e-10 * np.abs(forces[0]).max()
    assert measures[1] == pytest.approx(DEPTH * measures[0], rel=1e-12)


@pytest.mark.parametrize("order", [1, 2])
def test_extruded_beam_bends_as_the_plane_strain_beam(order):
    """The reference ramp (area 1 -> 3.5x, chamber stiffness k / depth: the same energy per unit depth) on the 2D
    triangles and on the extruded tetrahedra of the same triangles (straight-sided in both: the chamber given as
    the polygon, whose quadratic triangles are not fitted to the ellipse). A linear tetrahedron of a split prism is not
    the plane-strain triangle (the prism's nodes may move differently at its two faces), so the two differ by a
    discretisation error; on equal footing it is a small part of their common error against the converged
    -0.2583: under a quarter of it (observed 1 % for P1, 17 % for P2 at this mesh). The z faces' rollers keep
    the motion planar (tip dz ~ 0) and the bend angle is the 2D tip rotation."""
    steps = 8
    scene = reference_scene(max_area=0.05, chamber_points=32, steps=steps, order=order)
    chamber = Polygon(tuple(map(tuple, scene.geometry.chambers[0][1].polygon())))  # no curve: straight P2 sides
    planar = tp.simulate(replace(scene, geometry=replace(scene.geometry, chambers=(("main", chamber),))))
    mesh, _ = extruded_beam(0.05, order, chamber_points=32)
    solid = tp.simulate(scene_of(mesh, [area_ramp(3.5, steps, 1e5 / DEPTH)], steps - 1, Material(1e4, 0.45)))
    assert planar.converged and solid.converged
    gap, error = abs(solid.tip_deflection - planar.tip_deflection), abs(planar.tip_deflection - CONVERGED_2D_TIP)
    assert gap < 0.25 * error
    assert solid.steps[-1].tip_rotation == pytest.approx(planar.steps[-1].tip_rotation, abs=0.25 * error / 0.01)
    assert abs(solid.steps[-1].tip[2]) < 1e-4
    assert solid.area_ratio[-1, 0] == pytest.approx(planar.area_ratio[-1, 0], rel=1e-4)


def lame_errors(meshes, nu=0.3, load=1e-5):
    """Relative error of the mean radial displacement of the inner and the outer surface nodes of each octant mesh
    (inner radius 1, outer 2) under pressure p = load x mu, against the Lame solution of linear elasticity

        u(r) = p a^3 / (b^3 - a^3) [r / (3 K) + b^3 / (4 G r^2)],

    with the stable neo-Hookean law's linearised moduli: shear G = mu and Lame constant lam - mu, so bulk
    K = (lam - mu) + 2 mu / 3 = lam - mu / 3. The load is small enough (p / mu = 1e-5) for the geometric
    nonlinearity to stay below the discretisation errors measured."""
    mu, lam = lame_parameters(1.0, nu)
    bulk, p = lam - mu / 3, load * mu
    exact = lambda r: p / 7 * (r / (3 * bulk) + 8 / (4 * mu * r**2))
    errors = []
    for mesh in meshes:
        result = tp.simulate(scene_of(mesh, [ChamberSchedule("pressure", ((1, p),))], 1, Material(1.0, nu)))
        assert result.converged
        radius = np.linalg.norm(mesh.vertices, axis=1)
        radial = np.einsum("ij,ij->i", result.displacements[-1], mesh.vertices / radius[:, None])
        errors.append([abs(radial[np.abs(radius - r) < 1e-9].mean() / exact(r) - 1) for r in (1.0, 2.0)])
    return np.array(errors)


def test_pressurised_sphere_converges_to_lame_at_second_order_with_linear_tetrahedra():
    errors = lame_errors([shell_octant(n, n // 2) for n in (4, 8, 16)])
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all(orders[-1] > 1.7) and errors[-1].max() < 0.02  # observed 1.85 (inner), 1.88 (outer); 1.6 %


def test_pressurised_sphere_converges_faster_with_curved_quadratic_tetrahedra():
    """Isoparametric quadratic tetrahedra fitted to the spheres (straight-sided ones stay at second order, limited
    by the faceted surfaces: observed 1.87 and 2.04)."""
    errors = lame_errors([shell_octant(n, n // 2, order=2, curved=True) for n in (2, 4, 8)])
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all(orders[-1] > 3.0) and errors[-1].max() < 1e-3  # observed 3.6 and 3.3; 4.4e-4, 5.7e-4
