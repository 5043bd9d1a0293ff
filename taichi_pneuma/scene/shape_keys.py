"""The shapes of a scene file's body and chambers ([body] shape = ..., [[chambers]] shape = ...), read off their
classes (io/registry.py: each shape's fields are its keys, its name the shape's): the 2D outlines (fem/shapes.py
PLANAR_BODIES, PLANAR_CHAMBERS), the 3D shapes bodies and chambers share (fem/solids.py SOLIDS), a 2D shape swept
along z, a mesh file's body and chamber walls (fem/meshfile.py), the PneuNet generator, a CAD file's solid
(fem/cad.py) and a triangle surface's body and cavities (fem/surface_import.py).
"""

from ..fem.cad import StepPart
from ..fem.meshfile import MeshBody, MeshSurface
from ..fem.pneunet import PneuNet
from ..fem.shapes import PLANAR_BODIES, PLANAR_CHAMBERS
from ..fem.solids import SOLIDS, Extrusion
from ..fem.surface_import import Cavity, SurfaceBody, SurfaceChamber
from .fileformat import Table, Variant, fields_table

BOX = "[x0, y0, x1, y1]"


def by_name(*shapes) -> dict:
    """The shapes by their names (each class's name)."""
    return {shape.name: shape for shape in shapes}


def extrusion(profiles: dict, what: str) -> Table:
    """The 3D shape of a 2D shape (one of profiles, in the table `profile`) swept along z over depth."""
    profile = Table(
        {"shape": Variant(profiles, doc=f"the 2D {what} shape swept")},
        make=lambda v: v["shape"],
        parts=lambda shape: {"shape": shape},
        doc="the 2D shape (in the x-y plane), its keys as in 2D",
    )
    return fields_table(Extrusion, profile=profile)


BODY_SHAPES = Variant(
    {
        **PLANAR_BODIES,
        **by_name(MeshBody),
        **SOLIDS,
        Extrusion.name: extrusion(PLANAR_BODIES, "body"),
        **by_name(PneuNet, StepPart, SurfaceBody),
    },
    doc="the body's outline (2D), or a 3D body (a mesh file, a 3D shape meshed by gmsh, the PneuNet generator, a CAD "
    "file's solid or a triangle surface)",
)
CHAMBER_SHAPES = Variant(
    {
        **PLANAR_CHAMBERS,
        **by_name(MeshSurface),
        **SOLIDS,
        Extrusion.name: extrusion(PLANAR_CHAMBERS, "chamber"),
        **by_name(StepPart, Cavity, SurfaceChamber),
    },
    doc="the chamber's wall",
)
