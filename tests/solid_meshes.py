"""Small 3D bodies for the tests, made without a mesh generator (fem/layered.py), and a scene geometry that
hands over a ready mesh.

    extruded_beam   the reference beam's triangles extruded through DEPTH along z, its chamber a prism through
                    the depth, rollers on both faces normal to z, clamped at its left face: the plane-strain
                    body in 3D
    shell_octant    an octant of the thick spherical shell inner <= r <= outer, its cavity closed by the three
                    coordinate planes (rollers), nothing clamped
    box_with_cavity the 3.5 x 0.8 x 0.8 box of a structured grid with a box-shaped closed cavity (its grid cells
                    left out), clamped at its left face; box_with_cavities: several named cavities
    lzma_vtu        a small VTU whose compressed points array expands to gigabytes
    moved_up        a gmsh 2.2 file's text with its node numbers moved up (numbered sparsely, from a large one)
"""

import base64
import lzma
import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from taichi_pneuma.fem.body import Body, SizeEstimate
from taichi_pneuma.fem.elements import TET_EDGES
from taichi_pneuma.fem.layered import extrude, layered_tets, spherical_shell_octant
from taichi_pneuma.fem.mesh import Mesh
from taichi_pneuma.fem.planar import BeamGeometry
from taichi_pneuma.fem.supports import PointSet, Roller
from taichi_pneuma.fem.tetmesh import tet_mesh
from taichi_pneuma.limits import Budget
from taichi_pneuma.scene.build import ChamberControl, Material, Scene

DEPTH = 0.8
Z_ROLLERS = (Roller((0.0, 0.0, 1.0), (0.0, 0.0, 0.0)), Roller((0.0, 0.0, 1.0), (0.0, 0.0, DEPTH)))
PLANES = tuple(Roller(tuple(n), (0.0, 0.0, 0.0)) for n in np.eye(3))


@dataclass(frozen=True)
class MeshOf(Body):
    """A scene geometry whose mesh is ready (triangles or tetrahedra): its chambers are the mesh's, named in order;
    its supports are the mesh's node sets already."""

    ready: Mesh
    names: tuple = ("main",)

    clamp = None
    tip = PointSet("right")
    rollers = ()

    @property
    def dim(self) -> int:  # a test double of either dimension
        return self.ready.vertices.shape[1]

    @property
    def order(self) -> int:
        return self.ready.order

    @property
    def chambers(self):
        return tuple((name, None) for name in self.names)

    def mesh(self, budget: Budget = Budget()) -> Mesh:
        return self.ready  # made already, in no budget

    def size_estimate(self) -> SizeEstimate:
        return SizeEstimate(self.ready.n_elements, self.ready.n_vertices)

    def mesh_values(self) -> dict:
        return {"order": self.order}


def extruded_beam(max_area: float, order: int = 1, layers: int = 1, chamber_points: int = 32, cy: float = 0.15):
    """(the 3D mesh, the 2D linear mesh it extrudes)."""
    planar = BeamGeometry(cy=cy, max_area=max_area, chamber_points=chamber_points).mesh()
    vertices, tets, walls = extrude(planar, DEPTH, layers)
    return tet_mesh(vertices, tets, {"main": walls[0]}, order=order, clamp=PointSet("left"), rollers=Z_ROLLERS), planar


def shell_octant(
    divisions: int, layers: int, order: int = 1, inner: float = 1.0, outer: float = 2.0, curved: bool = False
) -> Mesh:
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


def scene_of(mesh: Mesh, schedules, increments: int, material: Material = Material(), **more) -> Scene:
    """A scene of the mesh's chambers (named as the schedules' order) driven by the schedules."""
    names = tuple(f"c{i}" for i in range(len(schedules))) if len(schedules) > 1 else ("main",)
    return Scene(MeshOf(mesh, names), tuple(ChamberControl(s) for s in schedules), increments, material, **more)


def box_with_cavity(order: int = 1) -> Mesh:
    """A 7 x 4 x 4 grid of 0.5 x 0.2 x 0.2 cells over [-1.75, 1.75] x [-0.4, 0.4] x [-0.4, 0.4], each cell six
    tetrahedra, without the cells of the cavity [-0.75, 0.75] x [0, 0.2] x [-0.2, 0.2]: its wall is every
    boundary facet off the box's faces."""
    return box_with_cavities({"chamber": ((-0.75, 0.0, -0.2), (0.75, 0.2, 0.2))}, 4, order)


def box_with_cavities(cavities: dict, layers: int, order: int = 1) -> Mesh:
    """The box [-1.75, 1.75] x [-0.4, 0.4] x [-0.4, 0.4] of a 7 x 4 x `layers` grid of cells, each six
    tetrahedra, clamped at its left face, without the cells inside each cavity box (name: (low corner, high
    corner), on grid lines, apart from each other and from the box's faces); a cavity's wall is the boundary
    facets on its box."""
    x, y = np.meshgrid(np.linspace(-1.75, 1.75, 8), np.linspace(-0.4, 0.4, 5), indexing="ij")
    corner = np.arange(40).reshape(8, 5)[:-1, :-1].ravel()
    triangles = np.vstack(
        [np.column_stack([corner, corner + 5, corner + 6]), np.column_stack([corner, corner + 6, corner + 1])]
    )
    vertices = np.vstack(
        [np.column_stack([x.ravel(), y.ravel(), np.full(40, z)]) for z in np.linspace(-0.4, 0.4, layers + 1)]
    )
    tets = layered_tets(40, triangles, layers)
    inside = lambda points, box, slack: np.all(
        (points > np.subtract(box[0], slack)) & (points < np.add(box[1], slack)), axis=1
    )
    for box in cavities.values():
        tets = tets[~inside(vertices[tets].mean(axis=1), box, 0.0)]
    faces = np.vstack([tets[:, list(f)] for f in ((1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1))])
    keys, counts = np.unique(np.sort(faces, axis=1), axis=0, return_counts=True)
    boundary = keys[counts == 1]
    middle = vertices[boundary].mean(axis=1)
    walls = {name: boundary[inside(middle, box, 1e-9)] for name, box in cavities.items()}
    return tet_mesh(vertices, tets, walls, order=order, clamp=PointSet("left"))


# hostile mesh files (issue 28): small files that would claim gigabytes


def lzma_vtu(path: Path, blocks: int = 40, block: int = 64 * 2**20) -> Path:
    """A VTU of one tetrahedron whose points array is LZMA-compressed: blocks of `block` zero bytes each, one
    compressed block repeated (about 0.5 MB of file for 2.7 GB of points)."""
    one = lzma.compress(bytes(block), preset=0)
    header = struct.pack(f"<{3 + blocks}I", blocks, block, block, *([len(one)] * blocks))
    points = base64.b64encode(header).decode() + base64.b64encode(one * blocks).decode()
    path.write_text(f"""<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian" header_type="UInt32"
 compressor="vtkLZMADataCompressor"><UnstructuredGrid><Piece NumberOfPoints="4" NumberOfCells="1">
<Points><DataArray type="Float64" NumberOfComponents="3" format="binary">{points}</DataArray></Points>
<Cells><DataArray type="Int64" Name="connectivity" format="ascii">0 1 2 3</DataArray>
<DataArray type="Int64" Name="offsets" format="ascii">4</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">10</DataArray></Cells>
</Piece></UnstructuredGrid></VTKFile>
""")
    return path


def moved_up(text: str, by: int) -> str:
    """A gmsh 2.2 ASCII file's text with every node number (in $Nodes and in the elements) increased by `by`."""
    head, rest = text.split("$Nodes\n", 1)
    nodes, rest = rest.split("\n$EndNodes\n", 1)
    between, rest = rest.split("$Elements\n", 1)
    elements, tail = rest.split("\n$EndElements", 1)
    count, *lines = nodes.split("\n")
    lines = [f"{int(number) + by} {xyz}" for number, xyz in (line.split(None, 1) for line in lines)]
    cells, *rows = elements.split("\n")
    rows = [" ".join(f[: 3 + int(f[2])] + [str(int(n) + by) for n in f[3 + int(f[2]) :]]) for f in map(str.split, rows)]
    return (
        "\n".join([head + "$Nodes", count, *lines, "$EndNodes", between + "$Elements", cells, *rows])
        + "\n$EndElements"
        + tail
    )
