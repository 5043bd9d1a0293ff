"""Small 3D bodies for the tests, made without a mesh generator (fem/layered.py), and a scene geometry that
hands over a ready mesh.

    extruded_beam   the reference beam's triangles extruded through DEPTH along z, its chamber a prism through
                    the depth, rollers on both faces normal to z: the plane-strain body in 3D
    shell_octant    an octant of the thick spherical shell inner <= r <= outer, its cavity closed by the three
                    coordinate planes (rollers), nothing clamped
"""

from dataclasses import dataclass

import numpy as np

from taichi_pneuma.fem.elements import TET_EDGES
from taichi_pneuma.fem.geometry import BeamGeometry, Roller
from taichi_pneuma.fem.layered import extrude, spherical_shell_octant
from taichi_pneuma.fem.tetmesh import TetMesh, tet_mesh
from taichi_pneuma.scene import ChamberControl, Material, Scene

DEPTH = 0.8
Z_ROLLERS = (Roller((0.0, 0.0, 1.0), (0.0, 0.0, 0.0)), Roller((0.0, 0.0, 1.0), (0.0, 0.0, DEPTH)))
PLANES = tuple(Roller(tuple(n), (0.0, 0.0, 0.0)) for n in np.eye(3))


@dataclass(frozen=True)
class MeshOf:
    """A scene geometry whose mesh is ready: its chambers are the mesh's, named in order."""

    ready: TetMesh
    names: tuple = ("main",)

    @property
    def chambers(self):
        return tuple((name, None) for name in self.names)

    def mesh(self) -> TetMesh:
        return self.ready


def extruded_beam(max_area: float, order: int = 1, layers: int = 1, chamber_points: int = 32, cy: float = 0.15):
    """(the 3D mesh, the 2D linear mesh it extrudes)."""
    planar = BeamGeometry(cy=cy, max_area=max_area, chamber_points=chamber_points).mesh()
    vertices, tets, walls = extrude(planar, DEPTH, layers)
    return tet_mesh(vertices, tets, {"main": walls[0]}, order=order, rollers=Z_ROLLERS), planar


def shell_octant(divisions: int, layers: int, order: int = 1, inner: float = 1.0, outer: float = 2.0,
                 curved: bool = False) -> TetMesh:
    """The octant mesh; curved (order 2): every midside node moved radially to the mean radius of its edge's ends,
    so that the quadratic (isoparametric) tetrahedra fit the spheres."""
    vertices, tets, wall = spherical_shell_octant(inner, outer, divisions, layers)
    mesh = tet_mesh(vertices, tets, {"cavity": wall}, order=order, clamp=None, rollers=PLANES)
    if not curved:
        return mesh
    x = mesh.vertices.copy()
    radius = np.linalg.norm(x, axis=1)
    for k, (i, j) in enumerate(TET_EDGES):
        middle = mesh.elements[:, 4 + k]
        target = 0.5 * (radius[mesh.elements[:, i]] + radius[mesh.elements[:, j]])
        x[middle] = mesh.vertices[middle] * (target / radius[middle])[:, None]
    return tet_mesh(x, mesh.elements, {"cavity": mesh.chambers[0]}, order=2, clamp=None, rollers=PLANES)


def scene_of(mesh: TetMesh, schedules, increments: int, material: Material = Material(), **more) -> Scene:
    """A scene of the mesh's chambers (named as the schedules' order) driven by the schedules."""
    names = tuple(f"c{i}" for i in range(len(schedules))) if len(schedules) > 1 else ("main",)
    return Scene(MeshOf(mesh, names), tuple(ChamberControl(s) for s in schedules), increments, material, **more)
