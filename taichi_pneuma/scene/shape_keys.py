"""The shapes of a scene file's body and chambers ([body] shape = ..., [[chambers]] shape = ...), declared with
fileformat.py's entries: the 2D outlines (fem/shapes.py), the 3D shapes bodies and chambers share (fem/solids.py),
a 2D shape swept along z, a mesh file's body and chamber walls (fem/meshfile.py) and the PneuNet generator.
"""

from ..fem.cad import StepPart
from ..fem.meshfile import MeshBody, MeshSurface
from ..fem.pneunet import PneuNet
from ..fem.shapes import Ellipse, Polygon, Rectangle, RectangleUnion, RoundedRectangle
from ..fem.solids import AXES, Box, Cylinder, Ellipsoid, Extrusion, HalfCylinder, RoundedBox
from ..fem.surface_import import Cavity, SurfaceBody, SurfaceChamber
from ..io.units import LENGTH
from .fileformat import Key, Table, Tables, Variant, record

PAIR, BOX, TRIPLE = "[x, y]", "[x0, y0, x1, y1]", "[x, y, z]"
POLYGON = record(Polygon, "a simple polygon", points=Key(tuple, doc="[[x, y], ...], at least 3", unit=LENGTH))
PLANAR_BODIES = {
    "rectangle": record(
        Rectangle,
        "an axis-aligned rectangle",
        center=Key(tuple, (0.0, 0.0), PAIR, unit=LENGTH),
        size=Key(tuple, doc="[width, height]", unit=LENGTH),
    ),
    "polygon": POLYGON,
    "union": record(
        RectangleUnion,
        "a union of axis-aligned rectangles (one region, no holes)",
        rectangles=Tables(
            record(Rectangle, center=Key(tuple, doc=PAIR, unit=LENGTH), size=Key(tuple, doc="[w, h]", unit=LENGTH))
        ),
    ),
}
PLANAR_CHAMBERS = {
    "ellipse": record(
        Ellipse,
        "an ellipse",
        center=Key(tuple, doc=PAIR, unit=LENGTH),
        semi_axes=Key(tuple, doc="[a, b]", unit=LENGTH),
        points=Key(int, 64, "wall points, 8 or more (2D)"),
    ),
    "rounded_rectangle": record(
        RoundedRectangle,
        "a rectangle with quarter-circle corners",
        center=Key(tuple, doc=PAIR, unit=LENGTH),
        size=Key(tuple, doc="[w, h]", unit=LENGTH),
        radius=Key(float, doc="corner radius, below half the shorter side", unit=LENGTH),
        corner_points=Key(int, 6, "points per corner (2D)"),
    ),
    "polygon": POLYGON,
}


def extrusion(profiles: dict, what: str) -> Table:
    """The 3D shape of a 2D shape (one of profiles, in the table `profile`) swept along z over depth."""
    profile = Table(
        {"shape": Variant(profiles, doc=f"the 2D {what} shape swept")},
        make=lambda v: v["shape"],
        parts=lambda shape: {"shape": shape},
        doc="the 2D shape (in the x-y plane), its keys as in 2D",
    )
    return record(
        Extrusion,
        f"a 2D {what} shape swept along z (3D)",
        profile=profile,
        depth=Key(float, doc="its extent along z", unit=LENGTH),
        z=Key(float, 0.0, "the z of its middle", unit=LENGTH),
    )


SOLIDS = {  # the 3D shapes bodies and chambers share (fem/solids.py); with extrusion and pneunet, the 3D bodies
    "box": record(
        Box,
        "an axis-aligned box (3D)",
        center=Key(tuple, doc=TRIPLE, unit=LENGTH),
        size=Key(tuple, doc=TRIPLE, unit=LENGTH),
    ),
    "rounded_box": record(
        RoundedBox,
        "a box with every edge and corner rounded (3D)",
        center=Key(tuple, doc=TRIPLE, unit=LENGTH),
        size=Key(tuple, doc=TRIPLE, unit=LENGTH),
        radius=Key(float, doc="below half the shortest side", unit=LENGTH),
    ),
    "cylinder": record(
        Cylinder,
        "a circular cylinder (3D)",
        center=Key(tuple, doc=TRIPLE, unit=LENGTH),
        radius=Key(float, unit=LENGTH),
        length=Key(float, unit=LENGTH),
        axis=Key(str, "z", "its axis", AXES),
    ),
    "half_cylinder": record(
        HalfCylinder,
        "the half of a circular cylinder above the plane y = center y, on a box of height base: a flat bottom face, a "
        "round top (3D)",
        center=Key(tuple, doc=f"{TRIPLE}: the middle of the flat face", unit=LENGTH),
        radius=Key(float, unit=LENGTH),
        length=Key(float, unit=LENGTH),
        axis=Key(str, "x", "its axis", ("x", "z")),
        base=Key(float, 0.0, "the height of a box under the flat face, as wide as the diameter", unit=LENGTH),
        fillet=Key(float, 0.0, "the radius its edges are rounded to (0: sharp; with no base)", unit=LENGTH),
    ),
    "ellipsoid": record(
        Ellipsoid,
        "an axis-aligned ellipsoid (3D)",
        center=Key(tuple, doc=TRIPLE, unit=LENGTH),
        semi_axes=Key(tuple, doc="[a, b, c]", unit=LENGTH),
    ),
}
STEP = record(
    StepPart,
    "a solid of a STEP or IGES file, in the file's unit converted into the scene's (3D; fem/cad.py)",
    file=Key(str, doc="the CAD file, relative to the scene file"),
    solid=Key(str, None, "the solid's name (its label in the file); none: the file's only solid"),
)
BODY_SHAPES = Variant(
    {
        **PLANAR_BODIES,
        "mesh": record(
            MeshBody,
            "a 3D body read from a mesh file (any meshio format with tetrahedra)",
            file=Key(str, doc="the mesh file, relative to the scene file"),
        ),
        **SOLIDS,
        "extrusion": extrusion(PLANAR_BODIES, "body"),
        "pneunet": PneuNet,
        "step": STEP,
        "surface": record(
            SurfaceBody,
            "a 3D body bounded by a triangle surface (STL, OBJ, PLY, OFF), repaired and filled with tetrahedra "
            "(fem/surface_import.py)",
            file=Key(str, doc="the surface file, relative to the scene file"),
            scale=Key(float, doc="the length of one file unit in the scene's units (required: the file has none)"),
        ),
    },
    doc="the body's outline (2D), or a 3D body (a mesh file, a 3D shape meshed by gmsh, the PneuNet generator, a CAD "
    "file's solid or a triangle surface)",
)
CHAMBER_SHAPES = Variant(
    {
        **PLANAR_CHAMBERS,
        "mesh_surface": record(
            MeshSurface,
            "the wall of a mesh body's chamber: a group of the mesh file's triangles "
            "(of a pneunet body: its chambers c1 .. cn)",
            group=Key(str, doc="the group (gmsh physical group) of the wall's triangles"),
        ),
        **SOLIDS,
        "extrusion": extrusion(PLANAR_CHAMBERS, "chamber"),
        "step": STEP,
        "cavity": record(
            Cavity,
            "a cavity of a surface body: the one enclosing the point inside",
            inside=Key(tuple, doc=f"{TRIPLE}, a point in the cavity", unit=LENGTH),
        ),
        "surface": record(
            SurfaceChamber,
            "a surface body's chamber drawn as a closed triangle surface of its own: the cavity it encloses",
            file=Key(str, doc="the chamber's surface file, relative to the scene file"),
            scale=Key(float, None, "the length of one file unit in the scene's units (none: the body's scale)"),
        ),
    },
    doc="the chamber's wall",
)
