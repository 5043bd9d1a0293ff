"""The scene file's [[fibers]] and [[layers]] tables (terms/fibers.py Fiber, terms/sheets.py Layer): what
reinforces the body, declared with fileformat.py's entries:

[[fibers]]
name = "thread"
E = 31e6                       # the cord's Young's modulus
diameter = 0.2                 # or area (2D: a cross-section per unit depth)
path = { layout = "crossed", center = [1.0, 2.0, 0.0], axis = "x", radius = 7.0, pitch = 4.0, extent = 98.0 }

[[layers]]
name = "sheet"
side = "bottom"                # or box = [...]: the face the sheet is bonded to
E = 6.5e6
nu = 0.2
thickness = 0.1
wrinkles = true                # false: the sheet carries compression (and buckles)

(or preset = "paper" instead of E and nu: the preset's small-strain E and nu, in the scene's units)
"""

from ..fem.fiber_paths import LAYOUTS, PLANAR
from ..fem.supports import SIDES
from ..io.units import LENGTH, PRESSURE, SECTION
from ..materials.presets import PRESETS
from ..terms.fibers import Fiber
from ..terms.sheets import Layer
from .fileformat import Key, Table, Variant, record

BOX = "[x0, y0, x1, y1]"

FIBER = record(
    Fiber,
    "an embedded fibre: a tension-only elastic cord that follows the body",
    name=Key(str, None, "names it in messages; not starting with = + - @, a tab or a carriage return (as a chamber's)"),
    path=Table(
        {
            "layout": Variant(
                LAYOUTS,
                doc=f"the fibre's curve (fem/fiber_paths.py); 2D: {', '.join(PLANAR)}; 3D: also rings, helix (one "
                "helix), crossed (a right- and a left-handed helix)",
            )
        },
        make=lambda v: v["layout"],
        parts=lambda path: {"layout": path},
        doc="its curve: layout and the layout's keys",
    ),
    E=Key(float, doc="Young's modulus of the cord", unit=PRESSURE),
    area=Key(float, None, "cross-section (2D: per unit depth); give area or diameter", unit=SECTION),
    diameter=Key(float, None, "diameter of a round cord (3D), instead of area", unit=LENGTH),
    spacing=Key(float, None, "sample spacing along the curve (none: half the mean element edge)", unit=LENGTH),
)

LAYER = record(
    Layer,
    "a strain-limiting sheet bonded to a face of the body (a membrane on its boundary facets there)",
    name=Key(str, doc="names the layer in messages"),
    side=Key(str, None, "the face: a side of the body's bounding box (or box)", SIDES),
    box=Key(
        tuple, None, f"{BOX} ([x0, y0, z0, x1, y1, z1] in 3D): the boundary facets in it (instead of side)", unit=LENGTH
    ),
    E=Key(float, None, "the sheet's Young's modulus (give E and nu, or a preset)", unit=PRESSURE),
    nu=Key(float, None, "the sheet's Poisson's ratio, in [0, 0.5) (with a preset: replaces the preset's)"),
    preset=Key(
        str,
        None,
        "a material preset instead of E and nu (docs/materials.md): its small-strain E = 2 mu0 (1 + nu) and nu, in "
        "the scene's units, as a region's preset is converted",
        tuple(PRESETS),
    ),
    thickness=Key(float, doc="the sheet's thickness", unit=LENGTH),
    wrinkles=Key(
        bool,
        True,
        "true: the sheet wrinkles (2D: goes slack) instead of carrying compression (tension-field theory's relaxed "
        "membrane); false: the Saint Venant-Kirchhoff membrane, which buckles",
        (True, False),
    ),
)
