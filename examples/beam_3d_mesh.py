"""Write taichi_pneuma/scenes/beam_3d.msh, the mesh file of taichi_pneuma/scenes/beam_3d.toml, with gmsh
(pip install gmsh).

The reference beam in 3D: a 3.5 x 0.8 x 0.8 box centred at the origin with an ellipsoidal cavity of semi-axes
(0.85, 0.22, 0.25) centred at (0, 0.15, 0); physical groups "body" (the tetrahedra) and "chamber" (the
cavity's surface triangles), mesh size SIZE.

    python examples/beam_3d_mesh.py [out.msh]
"""

import sys
from pathlib import Path

import gmsh

SIZE = 0.13
OUT = Path(__file__).resolve().parents[1] / "taichi_pneuma" / "scenes" / "beam_3d.msh"


def main(path: Path = OUT) -> None:
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("beam_3d")
    occ = gmsh.model.occ
    box = occ.addBox(-1.75, -0.4, -0.4, 3.5, 0.8, 0.8)
    cavity = occ.addSphere(0.0, 0.0, 0.0, 1.0)
    occ.dilate([(3, cavity)], 0.0, 0.0, 0.0, 0.85, 0.22, 0.25)
    occ.translate([(3, cavity)], 0.0, 0.15, 0.0)
    body, _ = occ.cut([(3, box)], [(3, cavity)])
    occ.synchronize()
    walls = [
        tag
        for dim, tag in gmsh.model.getBoundary(body, oriented=False)  # not on the box's faces
        if max(abs(c) - h for c, h in zip(occ.getCenterOfMass(dim, tag), (1.75, 0.4, 0.4))) < -1e-6
    ]
    gmsh.model.addPhysicalGroup(3, [tag for _, tag in body], name="body")
    gmsh.model.addPhysicalGroup(2, walls, name="chamber")
    gmsh.option.setNumber("Mesh.MeshSizeMax", SIZE)
    gmsh.option.setNumber("Mesh.Algorithm", 5)  # Delaunay (Frontal-Delaunay leaves this elongated cavity unmeshed)
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.model.mesh.generate(3)
    gmsh.write(str(path))
    gmsh.finalize()


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else OUT)
