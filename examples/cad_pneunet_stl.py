"""The PneuNet of the shipped pneunet_3d scene as an STL file, the way a CAD tool exports a part for 3D printing:
its surface only (outside and chamber walls), as triangles, with no unit and no names: taichi_pneuma/scenes/
pneunet.stl, which pneunet_stl.toml reads (with scale = 1 and a point inside each chamber).

The surface is gmsh's triangulation of the generator's solid (fem/pneunet.py) at edges of EDGE: the rounded chamber
corners (radius 0.08) become facets, as in any STL export. The bottom layer, a region of the parametric body, is not
a surface: the scene gives it by a box.

    python examples/cad_pneunet_stl.py [OUT.stl]
"""

import sys
from pathlib import Path

import meshio

from taichi_pneuma.fem.gmsh_mesher import MeshSizes
from taichi_pneuma.fem.meshfile import MeshSurface
from taichi_pneuma.fem.pneunet import PneuNet
from taichi_pneuma.fem.solid_geometry import SolidGeometry

EDGE = 0.08

if __name__ == "__main__":
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "taichi_pneuma/scenes/pneunet.stl"
    body = PneuNet()
    chambers = tuple((f"c{k}", MeshSurface(f"c{k}")) for k in range(1, body.chambers + 1))
    mesh = SolidGeometry(body, chambers, MeshSizes(EDGE)).mesh()
    meshio.write(out, meshio.Mesh(mesh.vertices, [("triangle", mesh.surface[:, :3])]), file_format="stl", binary=True)
    print(f"wrote {out}: {len(mesh.surface)} triangles")
