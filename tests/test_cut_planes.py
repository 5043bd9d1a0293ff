"""A roller on a symmetry plane through a full section of a body from shapes: gmsh's mesh is split by the plane
(gmsh_mesher.Solid's cuts), so the plane carries nodes for the roller to hold.

Before, the roller held the nodes gmsh happened to put on the plane: the tube below (radii 0.15 and 0.3, length 1,
along x) at size 0.09 had none on z = 0 (gmsh 4.15.2: 0, 1, 1 and 8 vertices at sizes 0.09, 0.10, 0.11, 0.12) and
the scene was refused."""

import numpy as np
import pytest
from solid_meshes import scene_of

import taichi_pneuma as tp
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.gmsh_mesher import MeshSizes, Solid
from taichi_pneuma.fem.solid_geometry import SolidGeometry
from taichi_pneuma.fem.solids import Cylinder
from taichi_pneuma.fem.supports import PointSet, Roller
from taichi_pneuma.scene.build import Material
from taichi_pneuma.scene.schedule import ChamberSchedule

TUBE = Cylinder((0, 0, 0), 0.3, 1.0, "x")
BORE = Cylinder((0, 0, 0), 0.15, 0.6, "x")
# two symmetry planes of the tube through its axis: z = 0 and the oblique y + z = 0
PLANES = (Roller((0.0, 0.0, 1.0), (0.0, 0.0, 0.0)), Roller((0.0, 1.0, 1.0), (0.2, 0.1, -0.1)))


def test_roller_planes_through_the_body_carry_nodes_and_a_conforming_mesh_and_hold_the_run():
    pytest.importorskip("gmsh", reason="gmsh is not installed (pip install 'taichi-pneuma[3d]')")
    geometry = SolidGeometry(TUBE, (("main", BORE),), MeshSizes(0.09), 2, PointSet("left"), rollers=PLANES)
    mesh = geometry.mesh()
    x = mesh.vertices
    assert mesh.surface is not None
    for (held, normal), roller in zip(mesh.rollers, PLANES):
        on = np.flatnonzero(np.abs((x - roller.point) @ normal) < 1e-9)
        assert len(held) > 100 and set(held.tolist()) == set(on.tolist())
        # conforming: no facet of the body's surface lies in the plane, inside the body
        inner = np.all(np.abs((x[mesh.surface[:, :3]] - roller.point) @ normal) < 1e-9, axis=1)
        assert not inner.any()
    p = 200.0
    result = tp.simulate(scene_of(mesh, [ChamberSchedule("pressure", ((2, p),))], 2, Material(1e4, 0.3)))
    assert result.converged
    u = result.displacements[-1]
    for held, normal in mesh.rollers:  # the symmetry planes stay put along their normals
        assert np.abs(u[held] @ normal).max() < 1e-6 * np.abs(u).max()
    assert np.abs(u).max() > 1e-3  # the tube did swell


def test_a_cut_plane_is_three_numbers_and_a_nonzero_normal():
    for normal, point in (((0, 0, 0), (0, 0, 0)), ((0, 0, 1), (0, 0)), ((0, float("nan"), 1), (0, 0, 0))):
        with pytest.raises(PneumaInputError, match="cut plane"):
            Solid(TUBE, (("main", BORE),), cuts=((normal, point),))
