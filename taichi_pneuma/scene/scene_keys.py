"""The scene file's keys, declared once as module-level tables of fileformat.py's entries: SCENE, the root table,
whose make() gives the keyword arguments of a Scene (build.py SCENE_FILE makes the Scene of them, so that this
module does not import the Scene); the shapes' tables are in shape_keys.py, the material's in material_keys.py,
the obstacles' in obstacle_keys.py, the fibres' and layers' in reinforcement_keys.py.
"""

from __future__ import annotations

import dataclasses

from ..errors import require
from ..fem.body import Body
from ..fem.cad import StepPart
from ..fem.elements import ORDERS
from ..fem.gmsh_mesher import MeshSizes
from ..fem.meshfile import MeshBody, MeshGeometry
from ..fem.planar import Geometry
from ..fem.solid_geometry import SolidGeometry, is_solid_shape
from ..fem.supports import SIDES, PointSet, Roller
from ..fem.surface_import import SurfaceBody, SurfaceGeometry
from ..io.units import LENGTH, NODAL_STIFFNESS, PLANE_AREA, UNITLESS, UNITS, default_in
from ..terms import VOLUMETRIC
from ..terms.chambers import KINDS
from ..terms.effects import EFFECTS
from .fileformat import Key, Named, System, Table, Tables, Variant, build, record
from .material_keys import MATERIAL
from .obstacle_keys import OBSTACLE
from .reinforcement_keys import FIBER, LAYER
from .schedule import MAX_STRETCH, ChamberControl, ChamberSchedule
from .shape_keys import BODY_SHAPES, BOX, CHAMBER_SHAPES, PLANAR_BODIES
from .targets import MAX_TARGETS, Target

CLAMP_STIFFNESS = 1e9  # the [clamp] stiffness key's default, in SI (Pa, 2D; Pa m, 3D)
MESH_SIZES = ("size", "near_chambers", "distance", "through_wall")  # the [mesh] keys of gmsh_mesher.MeshSizes, in order
# keys that exclude a sibling (two ways to give one thing; the pattern's [] any index): setting one (--set, --vary,
# with_values) drops the other where it is not set too
EXCLUSIVE = (
    ("mesh", "near_chambers", "through_wall"),  # the edge length near the chambers
    ("fibers[].path", "pitch", "angle"),  # a helix's pitch or its angle
    ("fibers[].path", "turns", "extent"),  # a helix's length in turns or along its axis
    ("material.regions[]", "box", "group"),  # a region's elements
    ("layers[]", "E", "preset"),  # a sheet's modulus, or a preset's
)
REPLACED = {f"{table}.{a}": b for table, one, other in EXCLUSIVE for a, b in ((one, other), (other, one))}
TARGET = record(
    Target,
    "a pose the tip should reach (inverse control)",
    tip=Key(tuple, doc="[x, y], or [x, y, z] on a 3D body (z free when not given)", unit=LENGTH),
    angle=Key(float, None, "tip rotation in degrees (none: free)"),
    weights=Key(tuple, (1.0, 1.0, 1.0), "[w_x, w_y, w_angle]"),
    weight_z=Key(float, 1.0, "w_z, the weight of a 3D tip's z error"),
)

ROLLER = record(
    Roller,
    "a roller support: the nodes' displacement along normal held, tangential motion free",
    normal=Key(tuple, doc="[nx, ny] ([nx, ny, nz] in 3D)"),
    point=Key(
        tuple,
        None,
        "[x, y]: the nodes within tolerance of the line through it, normal to normal (3D: [x, y, z], a plane)",
        unit=LENGTH,
    ),
    box=Key(tuple, None, f"{BOX}: the nodes in it (instead of point)", unit=LENGTH),
    tolerance=Key(float, 1e-6, unit=LENGTH),
)


def point_set(neither: str, **more) -> dict:
    """The keys of a [clamp] or [tip] node set: side, or box (then no side); neither: what neither means."""
    return {
        "side": Key(str, None, f"a side of the body's bounding box (neither side nor box: {neither})", SIDES),
        "box": Key(tuple, None, f"{BOX}: the nodes in it", unit=LENGTH),
        **more,
    }


def make_point_set(v: dict, default_side: str | None) -> PointSet | None:
    """The node set of the keys side and box; neither: the default side's, or None without one."""
    if v["side"] is None and v["box"] is None:
        return None if default_side is None else PointSet(side=default_side)
    return PointSet(side=v["side"], box=v["box"])


CHAMBER = Table(
    {
        "name": Key(str, doc="distinct among the chambers, not starting with = + - @ (it heads CSV columns)"),
        "shape": CHAMBER_SHAPES,
        "control": Variant(KINDS, lambda kind: kind.name, "area", "the chamber kind (its keys its parameters)"),
        "keyframes": Key(tuple, doc="[[step, command], ...], steps whole and increasing"),
        "bounds": Key(tuple, None, "[min, max] of the command under inverse control"),
    },
    make=lambda v: (
        v["name"],
        v["shape"],
        ChamberControl(schedule=ChamberSchedule(kind=v["control"], keyframes=v["keyframes"]), bounds=v["bounds"]),
    ),
    parts=lambda c: {
        "name": c[0],
        "shape": c[1],
        "control": c[2].kind,
        "keyframes": c[2].schedule.keyframes,
        "bounds": c[2].bounds,
    },
)


def scene_arguments(v: dict) -> dict:
    """The keyword arguments of the Scene of a scene file's values (its geometry made of the body, the chambers'
    shapes and the [mesh], [clamp], [tip] and [[rollers]] keys)."""
    require(v["chambers"], "scene names no chamber: add at least one [[chambers]] table")
    require(
        len(v["targets"]) <= MAX_TARGETS,
        f"{len(v['targets'])} [[targets]]: at most {MAX_TARGETS} are allowed (each is a reach)",
    )
    (material, regions), (clamp, clamp_stiffness) = v["material"], v["clamp"]
    units = UNITLESS if v["units"] is None else UNITS[v["units"]]
    body = in_units(v["body"], units)
    chambers, mesh = tuple((name, in_units(shape, units)) for name, shape, _ in v["chambers"]), v["mesh"]
    sized = [k for k in MESH_SIZES if mesh[k] is not None]
    planar = ["max_area"] if mesh["max_area"] is not None else []
    require(
        mesh["curved"] or is_solid_shape(v["body"]),
        "mesh.curved: only a 3D body from shapes takes it (a 2D body's quadratic triangles follow its curves "
        "always, a mesh file's elements are the file's)",
    )
    geometry: Body
    supports = dict(clamp=clamp, tip=v["tip"], rollers=v["rollers"])
    if is_solid_shape(body):
        sizes = tetrahedra_sizes(mesh, "a 3D body from shapes")
        geometry = SolidGeometry(
            body=body, chambers=chambers, sizes=sizes, order=mesh["order"], curved=mesh["curved"], **supports
        )
    elif isinstance(body, SurfaceBody):
        sizes = tetrahedra_sizes(mesh, "a surface body", walls_measured=False)
        geometry = SurfaceGeometry(body=body, chambers=chambers, sizes=sizes, order=mesh["order"], **supports)
    elif isinstance(body, MeshBody):
        require(
            not planar + sized,
            f"mesh.{(planar + sized + [''])[0]}: a mesh file's body keeps the file's elements (mesh.order only)",
        )
        geometry = MeshGeometry(body=body, chambers=chambers, order=mesh["order"], **supports)
    else:
        require(not sized, f"mesh.{sized[0] if sized else ''}: a 2D body takes mesh.max_area")
        geometry = Geometry(body=body, chambers=chambers, max_area=mesh["max_area"], order=mesh["order"], **supports)
    return dict(
        geometry=geometry,
        controls=tuple(control for *_, control in v["chambers"]),
        increments=v["schedule"]["increments"],
        material=material,
        regions=regions,
        clamp_stiffness=clamp_stiffness,
        effects=v["effects"],
        name=v["name"],
        targets=v["targets"],
        units=units,
        max_stretch=v["schedule"]["max_stretch"],
        volumetric=mesh["volumetric"],
        fibers=v["fibers"],
        layers=v["layers"],
        obstacles=v["obstacles"],
        ends_at_limit_point=v["schedule"]["ends_at_limit_point"],
    )


def tetrahedra_sizes(mesh: dict, what: str, walls_measured: bool = True) -> MeshSizes:
    """The [mesh] sizes of a body gmsh fills with tetrahedra (`what` names it in errors): mesh.size required, no
    max_area, and no through_wall where the body's walls are not measured."""
    require(
        mesh["max_area"] is None, f"mesh.max_area: {what} takes mesh.size (the tetrahedra's edge length), not max_area"
    )
    require(
        walls_measured or mesh["through_wall"] is None,
        f"mesh.through_wall: {what}'s walls are not measured; give mesh.near_chambers",
    )
    require(mesh["size"] is not None, f"missing key 'mesh.size': {what} needs the tetrahedra's edge length")
    return build("mesh", lambda: MeshSizes(**{k: mesh[k] for k in MESH_SIZES}))


def in_units(shape, units):
    """A CAD file's solid (fem/cad.py StepPart) read into the scene's length unit (None: a scene without units, which
    is refused when the part is built); any other shape as it is."""
    if isinstance(shape, StepPart):
        return dataclasses.replace(shape, metre=None if units.name is None else units.metre)
    return shape


def clamp_parts(scene) -> dict:
    """The [clamp] keys; without a clamp, its stiffness only if not the default (so no [clamp] is written)."""
    clamp, stiffness = scene.geometry.clamp, scene.clamp_stiffness
    default = default_in(CLAMP_STIFFNESS, NODAL_STIFFNESS, True, scene.units, scene.dim, "clamp.stiffness")
    return {
        "side": getattr(clamp, "side", None),
        "box": getattr(clamp, "box", None),
        "stiffness": None if clamp is None and stiffness == default else stiffness,
    }


def mesh_parts(scene) -> dict:
    """The [mesh] keys of a scene's geometry (and its volumetric key)."""
    return {
        "max_area": None,
        **dict.fromkeys(MESH_SIZES),
        "curved": True,
        **scene.geometry.mesh_values(),  # the keys this kind of geometry has (Body.mesh_values)
        "volumetric": None if scene.volumetric == "element" else scene.volumetric,
    }  # default: not written


def scene_system(data: dict) -> System:
    """The units and the dimension of the scene of the data of a scene file: its units key (unitless when it has
    none) and 3 for a 3D body shape, 2 otherwise (a bad value of either is refused when it is read)."""
    body = data.get("body")
    shape = body.get("shape") if isinstance(body, dict) else None
    units = data.get("units")
    return (
        UNITS[units] if isinstance(units, str) and units in UNITS else UNITLESS,
        3 if isinstance(shape, str) and shape in BODY_SHAPES.options and shape not in PLANAR_BODIES else 2,
    )


SCENE = Table(
    system=scene_system,
    keys={
        "name": Key(str, None, "names the result files (a plain file name); none: the scene file's own name"),
        "description": Key(str, "", "free text, not kept"),
        "units": Key(
            str, None, "the system of the scene's lengths and pressures (io/units.py; none: unitless)", tuple(UNITS)
        ),
        "body": Table({"shape": BODY_SHAPES}, make=lambda v: v["shape"], parts=lambda body: {"shape": body}),
        "mesh": Table(
            {
                "max_area": Key(float, None, "largest triangle area (2D)", unit=PLANE_AREA, scaled=False, si=0.0012),
                "size": Key(
                    float,
                    None,
                    "tetrahedron edge length in the bulk (3D body from shapes; required there)",
                    unit=LENGTH,
                ),
                "near_chambers": Key(
                    float,
                    None,
                    "edge length within that distance of the chamber walls (3D shapes; none: size; at most size)",
                    unit=LENGTH,
                ),
                "distance": Key(
                    float,
                    None,
                    "over which the edge length grows from near_chambers back to size (3D shapes; none: 2 size)",
                    unit=LENGTH,
                ),
                "through_wall": Key(
                    float,
                    None,
                    "edges through the thinnest rubber around the chambers, instead of near_chambers: "
                    "near_chambers = that wall's thickness / through_wall (3D shapes; the thickness measured on "
                    "the geometry)",
                ),
                "order": Key(
                    int,
                    1,
                    "1: linear triangles (tetrahedra), 2: quadratic (2D: boundary nodes on "
                    "the exact ellipses and rounded corners; 3D: midside nodes added, see curved), 3: cubic (2D)",
                    ORDERS,
                ),
                "curved": Key(
                    bool,
                    True,
                    "3D shapes, order 2: the midside nodes of the edges on the shapes' curved surfaces put on "
                    "those surfaces, where that folds no element (false: every one at its edge's middle, a "
                    "round wall a polyhedron)",
                ),
                "volumetric": Key(
                    str,
                    "element",
                    "where the law's volumetric part U(J) is evaluated: element "
                    "(each quadrature point), nodal (on each node's patch volume "
                    "ratio; order 1: linear elements that do not lock as nu -> 1/2) "
                    "or mixed (on each element's volume ratio, one pressure per "
                    "element; order 2: the P2/P0 'hybrid' element, nearer the "
                    "incompressible answer than element as nu -> 1/2; on linear "
                    "elements it is element); nodal and "
                    "mixed take law = neo_hookean, mooney_rivlin, yeoh or a preset",
                    tuple(VOLUMETRIC),
                ),
            },
            parts=mesh_parts,
            optional=True,
        ),
        "material": MATERIAL,
        "clamp": Table(
            point_set(
                "no clamp",
                stiffness=Key(
                    float,
                    None,
                    "penalty stiffness of the clamp and the rollers (E = 1/2 K |u|^2 per node)",
                    unit=NODAL_STIFFNESS,
                    si=CLAMP_STIFFNESS,
                ),
            ),
            make=lambda v: (make_point_set(v, None), v["stiffness"]),
            parts=clamp_parts,
            optional=True,
            doc="the clamped nodes; no [clamp] table (or one without side and box): no clamp, the body held "
            "by its rollers",
        ),
        "tip": Table(
            point_set("right"),
            make=lambda v: make_point_set(v, "right"),
            parts=lambda g: {"side": g.tip.side, "box": g.tip.box},
            optional=True,
            doc="the nodes whose mean displacement and rotation the history, sensitivities and reach use",
        ),
        "rollers": Tables(ROLLER, "roller supports; one along a body edge is a symmetry line that may cut chambers"),
        "chambers": Tables(CHAMBER, "the chambers, at least one"),
        "schedule": Table(
            {
                "increments": Key(int, doc="solves after the rest state"),
                "max_stretch": Key(
                    float,
                    MAX_STRETCH,
                    "a run whose largest principal stretch passes it warns (once, at the first step past it)",
                ),
                "ends_at_limit_point": Key(
                    bool,
                    False,
                    "the ramp is meant to end at a limit point (a pressure peak under pressure control): a run "
                    "that finds no equilibrium past some step stops there as planned (exit 0), its results up "
                    "to the last equilibrium written",
                ),
            },
            parts=lambda s: {
                "increments": s.increments,
                "max_stretch": s.max_stretch,
                "ends_at_limit_point": s.ends_at_limit_point,
            },
        ),
        "effects": Named(EFFECTS, "the effects the scene adds, by name"),
        "targets": Tables(TARGET, "poses for inverse control, in order"),
        "fibers": Tables(FIBER, "embedded fibres (tension-only cords), each a term of the energy"),
        "layers": Tables(LAYER, "strain-limiting sheets, each bonded to a face of the body"),
        "obstacles": Tables(
            OBSTACLE, "rigid obstacles the body's outer boundary cannot cross (with friction optional)"
        ),
    },
    make=scene_arguments,
    parts=lambda s: {
        "name": s.name,
        "description": None,
        "units": s.units.name,
        "body": s.geometry.body,
        "mesh": s,
        "material": s,
        "clamp": s,
        "tip": s.geometry,
        "rollers": s.geometry.rollers,
        "chambers": [(name, shape, control) for (name, shape), control in zip(s.geometry.chambers, s.controls)],
        "schedule": s,
        "effects": s.effects,
        "targets": s.targets,
        "fibers": s.fibers,
        "layers": s.layers,
        "obstacles": s.obstacles,
    },
)
