"""The scene file's format, declared once (schema.py's entries): read, written, edited by dotted keys and
listed in the key reference from this one declaration.

The classes the scene module defines (the scene, its regions and chamber controls) are taken
from the annotations of the Scene class passed in, so that scene.py imports this module without a cycle.
"""

from __future__ import annotations

import dataclasses
import functools
import typing

from ..errors import require
from ..fem.elements import ORDERS
from ..fem.gmsh_mesher import MeshSizes
from ..fem.meshfile import MeshBody, MeshGeometry, MeshSurface
from ..fem.planar import Geometry
from ..fem.pneunet import PneuNet
from ..fem.shapes import Ellipse, Polygon, Rectangle, RectangleUnion, RoundedRectangle
from ..fem.solid_geometry import SolidGeometry, is_solid_shape
from ..fem.solids import AXES, Box, Cylinder, Ellipsoid, Extrusion, HalfCylinder, RoundedBox
from ..fem.supports import SIDES, PointSet, Roller
from ..io.tomltext import dumps
from ..io.units import LENGTH, NODAL_STIFFNESS, PLANE_AREA, UNITLESS, UNITS, default_in
from ..materials.registry import SELECTORS, all_keys, form_of, forms, region_values
from ..terms import VOLUMETRIC
from ..terms.chambers import KINDS
from ..terms.effects import EFFECTS
from .obstacleformat import OBSTACLE
from .reinforcementformat import FIBER, LAYER
from .schedule import MAX_STRETCH, ChamberSchedule
from .schema import REQUIRED, Key, KeyInfo, Named, Table, Tables, Variant, build, edited, key_rows, record
from .targets import MAX_TARGETS, Target

PAIR, BOX, TRIPLE = "[x, y]", "[x0, y0, x1, y1]", "[x, y, z]"
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
    },
    doc="the body's outline (2D), or a 3D body (a mesh file, a 3D shape meshed by gmsh, or the PneuNet generator)",
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
    },
    doc="the chamber's wall",
)
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
        return None if default_side is None else PointSet(default_side)
    return PointSet(v["side"], v["box"])


MATERIAL_TAGS = tuple(SELECTORS)  # the keys choosing a material's form (material_kind)


def material_entries() -> dict[str, Key]:
    """The [material] table's keys: those of every registered material form (materials/registry.py), each
    optional."""
    return {name: Key(key.type, None, key.doc, key.allowed, key.unit, si=key.si) for name, key in all_keys().items()}


def material_kind(keys: dict) -> dict:
    """The keys of the material form that a [material] table's (or a region's) keys choose, each with the
    value a scene file writes for it when not given (REQUIRED: none): the form's form_keys, or the selector
    alone when it names no form."""
    form = form_of(keys)
    chosen = form.form_keys(keys) if form else dict.fromkeys(s for s in SELECTORS if keys.get(s) is not None)
    return {name: REQUIRED if default is None else default for name, default in chosen.items()}


def material_of(keys: dict):
    """The material of a [material] table's (or a region's) keys: that of the form they name."""
    form = form_of(keys)
    assert form is not None, "the schema checked the selector's value against the forms' names"
    return form.from_keys(keys)


def material_keys(material) -> dict:
    """The [material] (or region) keys of a material, None where absent: material_of's inverse."""
    return {**dict.fromkeys(all_keys()), **material.scene_values()}


def item_type(hint):
    """tuple[X, ...] -> X; X -> X."""
    return typing.get_args(hint)[0] if typing.get_origin(hint) is tuple else hint


@functools.cache
def scene_table(scene_class) -> Table:
    """The declaration of a scene file of scene_class (scene.Scene)."""
    hints = typing.get_type_hints(scene_class)
    region_class, control_class = (item_type(hints[k]) for k in ("regions", "controls"))
    entries = material_entries()  # the [material] keys of the forms registered now

    def make_material(v):  # the base first, then each region (its omitted keys the base's, unless it names a form)
        base_keys = {k: v[k] for k in entries}

        def region(r):
            return region_class(r["box"], material_of(region_values(base_keys, {k: r[k] for k in entries})), r["group"])

        return material_of(base_keys), tuple(
            build(f"material.regions[{i}]", functools.partial(region, r)) for i, r in enumerate(v["regions"])
        )

    region = Table(
        {
            "box": Key(
                tuple,
                None,
                f"{BOX} ([x0, y0, z0, x1, y1, z1] in 3D): the elements whose centroid lies in it",
                unit=LENGTH,
            ),
            "group": Key(
                str,
                None,
                "instead of box (3D): the tetrahedra of the mesh's named volume group "
                "(a mesh file's physical group, a pneunet's \"layer\")",
            ),
            **{k: dataclasses.replace(key, si=None) for k, key in entries.items()},
        },  # none: the base's
        parts=lambda r: {"box": r.box, "group": r.group, **material_keys(r.material)},
        kind=material_kind,
        tags=MATERIAL_TAGS,
    )
    regions = Tables(
        region,
        "materials for the elements of a box or a volume group (later regions win); keys as "
        "material's, and unless a region names a preset or law, each key it omits is material's",
    )
    material = Table(
        {**entries, "regions": regions},
        make=make_material,
        parts=lambda s: {**material_keys(s.material), "regions": s.regions},
        optional=True,
        kind=material_kind,
        tags=MATERIAL_TAGS,
        doc=f"the body's material: {', '.join(f.summary for f in forms()[:-1])}, or {forms()[-1].summary}",
    )
    chamber = Table(
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
            control_class(ChamberSchedule(v["control"], v["keyframes"]), v["bounds"]),
        ),
        parts=lambda c: {
            "name": c[0],
            "shape": c[1],
            "control": c[2].kind,
            "keyframes": c[2].schedule.keyframes,
            "bounds": c[2].bounds,
        },
    )

    def make_scene(v):
        require(v["chambers"], "scene names no chamber: add at least one [[chambers]] table")
        require(
            len(v["targets"]) <= MAX_TARGETS,
            f"{len(v['targets'])} [[targets]]: at most {MAX_TARGETS} are allowed (each is a reach)",
        )
        (material, regions), (clamp, clamp_stiffness) = v["material"], v["clamp"]
        chambers, mesh = tuple((name, shape) for name, shape, _ in v["chambers"]), v["mesh"]
        sized = [k for k in MESH_SIZES if mesh[k] is not None]
        planar = ["max_area"] if mesh["max_area"] is not None else []
        require(
            mesh["curved"] or is_solid_shape(v["body"]),
            "mesh.curved: only a 3D body from shapes takes it (a 2D body's quadratic triangles follow its curves "
            "always, a mesh file's elements are the file's)",
        )
        if is_solid_shape(v["body"]):
            require(
                mesh["max_area"] is None,
                "mesh.max_area: a 3D body from shapes takes mesh.size (the tetrahedra's edge length), not max_area",
            )
            require(
                mesh["size"] is not None,
                "missing key 'mesh.size': a 3D body from shapes needs the tetrahedra's edge length",
            )
            sizes = build("mesh", lambda: MeshSizes(*(mesh[k] for k in MESH_SIZES)))
            geometry = SolidGeometry(
                v["body"], chambers, sizes, mesh["order"], clamp, v["tip"], v["rollers"], mesh["curved"]
            )
        elif isinstance(v["body"], MeshBody):
            require(
                not planar + sized,
                f"mesh.{(planar + sized + [''])[0]}: a mesh file's body keeps the file's elements (mesh.order only)",
            )
            geometry = MeshGeometry(v["body"], chambers, mesh["order"], clamp, v["tip"], v["rollers"])
        else:
            require(not sized, f"mesh.{sized[0] if sized else ''}: a 2D body takes mesh.max_area")
            geometry = Geometry(
                v["body"],
                chambers,
                mesh["max_area"],
                clamp=clamp,
                order=mesh["order"],
                tip=v["tip"],
                rollers=v["rollers"],
            )
        return scene_class(
            geometry,
            tuple(control for *_, control in v["chambers"]),
            v["schedule"]["increments"],
            material,
            regions,
            clamp_stiffness,
            v["effects"],
            v["name"],
            v["targets"],
            UNITLESS if v["units"] is None else UNITS[v["units"]],
            v["schedule"]["max_stretch"],
            mesh["volumetric"],
            fibers=v["fibers"],
            layers=v["layers"],
            obstacles=v["obstacles"],
            ends_at_limit_point=v["schedule"]["ends_at_limit_point"],
        )

    def clamp_parts(scene):
        """The [clamp] keys; without a clamp, its stiffness only if not the default (so no [clamp] is written)."""
        clamp, stiffness = scene.geometry.clamp, scene.clamp_stiffness
        default = default_in(CLAMP_STIFFNESS, NODAL_STIFFNESS, True, scene.units, scene.dim, "clamp.stiffness")
        return {
            "side": getattr(clamp, "side", None),
            "box": getattr(clamp, "box", None),
            "stiffness": None if clamp is None and stiffness == default else stiffness,
        }

    def mesh_parts(scene):
        geometry = scene.geometry
        refinements = getattr(geometry, "refinements", 0)
        require(
            refinements == 0,
            f"a geometry refined {refinements} times has no scene-file form (scene files have no refinements key)",
        )
        sizes = getattr(geometry, "sizes", None)
        return {
            "max_area": getattr(geometry, "max_area", None),
            "order": geometry.order,
            **{k: getattr(sizes, k, None) for k in MESH_SIZES},
            "curved": getattr(geometry, "curved", True),
            "volumetric": None if scene.volumetric == "element" else scene.volumetric,
        }  # default: not written

    return Table(
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
                    "max_area": Key(
                        float, None, "largest triangle area (2D)", unit=PLANE_AREA, scaled=False, si=0.0012
                    ),
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
            "material": material,
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
            "rollers": Tables(
                ROLLER, "roller supports; one along a body edge is a symmetry line that may cut chambers"
            ),
            "chambers": Tables(chamber, "the chambers, at least one"),
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
        make=make_scene,
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


def scene_system(data: dict) -> tuple:
    """The units and the dimension of the scene of the data of a scene file: its units key (unitless when it has
    none) and 3 for a 3D body shape, 2 otherwise (a bad value of either is refused when it is read)."""
    body = data.get("body")
    shape = body.get("shape") if isinstance(body, dict) else None
    units = data.get("units")
    return (
        UNITS[units] if isinstance(units, str) and units in UNITS else UNITLESS,
        3 if isinstance(shape, str) and shape in BODY_SHAPES.options and shape not in PLANAR_BODIES else 2,
    )


def read_scene(data: dict, name: str, scene_class):
    """A scene_class from the data of a scene file, named `name` unless it has a name key."""
    return scene_table(scene_class).read_table({"name": name, **data} if isinstance(data, dict) else data, "")


def scene_data(scene) -> dict:
    """The scene as the data of a scene file: every key explicit, defaults included, but absent optional ones."""
    return scene_table(type(scene)).write_table(scene)  # type: ignore[arg-type]  # a class is hashable


def to_toml(scene) -> str:
    """The scene as a scene file (TOML text) that reads back to an equal scene."""
    return dumps(scene_data(scene))


def with_values(scene, values: dict):
    """A copy of scene with the dotted keys of `values` set, validated like a scene file."""
    return edited(scene_table(type(scene)), scene, values, REPLACED)  # type: ignore[arg-type]  # a class is hashable


def key_reference(scene_class) -> list[KeyInfo]:
    """Every key of the scene file: its type, default, allowed values, when it applies and what it means."""
    return key_rows(scene_table(scene_class).keys, "")
