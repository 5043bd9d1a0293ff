"""Scene files (TOML) -> Scene, with one clear PneumaInputError naming the file, the key and the value.

    name = "bidirectional"
    [body]       shape = "rectangle" (center, size) | "polygon" (points) | "union" (rectangles = [{center, size}, ...])
    [mesh]       max_area, order = 1 (linear triangles) | 2 (quadratic)
    [material]   E, nu, regions = [{box = [x0, y0, x1, y1], E, nu}, ...]   (E, nu of a region default to the base)
    [clamp]      side = "left" | "right" | "bottom" | "top"  or  box = [x0, y0, x1, y1];  stiffness (also the rollers')
    [tip]        side = "right" (default) | "left" | "bottom" | "top"  or  box = [x0, y0, x1, y1]: the nodes whose
                 mean displacement and rotation the history (tip_dx, tip_dy, tip_rotation), sensitivities and reach use
    [[rollers]]  normal = [nx, ny]; point = [x, y] (the nodes within tolerance of the line through it, normal to
                 normal) or box = [x0, y0, x1, y1]; tolerance = 1e-6. A roller line along the body's edge is a
                 symmetry line: a chamber crossing it is cut there, its area closed by the flat cap on the line
    [[chambers]] name, shape = "ellipse" (center, semi_axes, points) | "rounded_rectangle" (center, size,
                 radius, corner_points) | "polygon" (points); control = a chamber kind's name, "area"
                 (stiffness) | "pressure" (allow_vacuum) | ..., with that kind's parameters;
                 keyframes = [[step, value], ...]; bounds = [min, max] (inverse control)
    [schedule]   increments
    [effects.gravity] density, g      [effects.ground] height, dhat, stiffness      [effects.self_contact] dhat, stiffness
    [effects.dynamics] density, dt
    [[targets]]  tip = [x, y], angle (degrees, optional), weights = [w_x, w_y, w_angle]  (inverse control, in order)

Every key is checked: an unknown key, a missing required one, or a value out of range is refused
with its dotted path (e.g. ``chambers[1].semi_axes``). A file over MAX_SCENE_BYTES is refused unread;
``name`` must be a plain file name (output.check_stem); without it the file's own name, reduced to one, is used.
"""

from __future__ import annotations

import dataclasses
import os

import tomllib

from ..control.targets import Target
from ..errors import PneumaInputError, require
from ..fem.geometry import Ellipse, Geometry, PointSet, Polygon, Rectangle, RectangleUnion, Roller, RoundedRectangle
from ..scene import ChamberControl, Material, Region, Scene
from ..solve.schedule import ChamberSchedule
from ..terms.chambers import chamber_kind
from ..terms.effects import EFFECTS
from .output import reduce_to_stem

REQUIRED = object()
MAX_SCENE_BYTES = 1_000_000


class Table:
    """One TOML table under a dotted path; take() reads keys, close() refuses any key never read."""

    def __init__(self, data, path: str):
        require(isinstance(data, dict), f"{path or 'scene'} must be a table, not {data!r}")
        self.data, self.path, self.known = data, path, set()

    def key(self, key: str) -> str:
        return f"{self.path}.{key}" if self.path else key

    def take(self, key: str, default=REQUIRED, kind=None):
        self.known.add(key)
        if key not in self.data:
            require(default is not REQUIRED, f"missing key '{self.key(key)}'")
            return default
        value = self.data[key]
        if kind is float:
            require(isinstance(value, (int, float)) and not isinstance(value, bool),
                    f"{self.key(key)} = {value!r} must be a number")
        elif kind is not None:
            require(isinstance(value, kind) and not (kind is int and isinstance(value, bool)),
                    f"{self.key(key)} = {value!r} must be of type {kind.__name__}")
        return value

    def table(self, key: str, default=REQUIRED) -> "Table | None":
        value = self.take(key, default)
        return None if value is None else Table(value, self.key(key))

    def tables(self, key: str) -> list["Table"]:
        items = self.take(key, [], list)
        return [Table(item, f"{self.key(key)}[{i}]") for i, item in enumerate(items)]

    def close(self) -> None:
        unknown = sorted(set(self.data) - self.known)
        require(not unknown, f"unknown key '{self.key(unknown[0]) if unknown else ''}' "
                             f"(allowed here: {', '.join(sorted(self.known))})")


def build(table: Table, make):
    """Call make() and prefix any PneumaInputError it raises with the table's path (unless it names a key in it)."""
    try:
        return make()
    except PneumaInputError as exc:
        if not table.path or f"{table.path}." in str(exc):
            raise
        raise PneumaInputError(f"{table.path}: {exc}") from None


def read_body(t: Table):
    shape = t.take("shape", kind=str)
    if shape == "rectangle":
        body = build(t, lambda: Rectangle(tuple(t.take("center", [0.0, 0.0], list)), tuple(t.take("size", kind=list))))
    elif shape == "polygon":
        body = build(t, lambda: Polygon(tuple(map(tuple, t.take("points", kind=list)))))
    elif shape == "union":
        rects = []
        for r in t.tables("rectangles"):
            rects.append(build(r, lambda r=r: Rectangle(tuple(r.take("center", kind=list)),
                                                        tuple(r.take("size", kind=list)))))
            r.close()
        body = build(t, lambda: RectangleUnion(tuple(rects)))
    else:
        raise PneumaInputError(f"{t.key('shape')} = {shape!r} is not one of rectangle, polygon, union")
    t.close()
    return body


def read_chamber_shape(t: Table):
    shape = t.take("shape", kind=str)
    if shape == "ellipse":
        return build(t, lambda: Ellipse(tuple(t.take("center", kind=list)), tuple(t.take("semi_axes", kind=list)),
                                        t.take("points", 64, int)))
    if shape == "rounded_rectangle":
        return build(t, lambda: RoundedRectangle(tuple(t.take("center", kind=list)), tuple(t.take("size", kind=list)),
                                                 t.take("radius", kind=float), t.take("corner_points", 6, int)))
    if shape == "polygon":
        return build(t, lambda: Polygon(tuple(map(tuple, t.take("points", kind=list)))))
    raise PneumaInputError(f"{t.key('shape')} = {shape!r} is not one of ellipse, rounded_rectangle, polygon")


def read_chamber(t: Table) -> tuple[str, object, ChamberControl]:
    name = t.take("name", kind=str)
    shape = read_chamber_shape(t)
    control = t.take("control", "area", str)
    kind = build(t, lambda: chamber_kind(control))
    parameters = {key: t.take(key, REQUIRED if default is dataclasses.MISSING else default, type_)
                  for key, (type_, default) in kind.parameters().items()}
    keyframes = tuple(tuple(k) if isinstance(k, list) else k for k in t.take("keyframes", kind=list))
    schedule = build(t, lambda: ChamberSchedule(kind(**parameters), keyframes))
    bounds = t.take("bounds", None, list)
    t.close()
    return name, shape, build(t, lambda: ChamberControl(schedule, None if bounds is None else tuple(bounds)))


def read_target(t: Table) -> Target:
    target = build(t, lambda: Target(tuple(t.take("tip", kind=list)), t.take("angle", None, float),
                                     tuple(t.take("weights", [1.0, 1.0, 1.0], list))))
    t.close()
    return target


def read_material(t: Table | None) -> tuple[Material, tuple[Region, ...]]:
    if t is None:
        return Material(), ()
    base = build(t, lambda: Material(t.take("E", 1e4, float), t.take("nu", 0.45, float)))
    regions = []
    for r in t.tables("regions"):
        regions.append(build(r, lambda r=r: Region(tuple(r.take("box", kind=list)),
                                                   Material(r.take("E", base.youngs_modulus, float),
                                                            r.take("nu", base.poisson_ratio, float)))))
        r.close()
    t.close()
    return base, tuple(regions)


def read_effect(name: str, t: Table):
    require(name in EFFECTS, f"unknown key 'effects.{name}' (allowed here: {', '.join(EFFECTS)})")
    cls = EFFECTS[name]
    kwargs = {f.name: t.take(f.name, f.default if f.default is not dataclasses.MISSING else REQUIRED, float)
              for f in dataclasses.fields(cls)}
    t.close()
    return build(t, lambda: cls(**kwargs))


def read_point_set(t: Table, default_side: str) -> PointSet:
    """A [clamp] or [tip] table's node set: side, or box (then no side); the caller reads its other keys."""
    box = t.take("box", None, list)
    return build(t, lambda: PointSet(t.take("side", None if box is not None else default_side, str),
                                     None if box is None else tuple(box)))


def read_roller(t: Table) -> Roller:
    """One [[rollers]] table: normal, point (a line) or box, tolerance."""
    point, box = t.take("point", None, list), t.take("box", None, list)
    roller = build(t, lambda: Roller(tuple(t.take("normal", kind=list)), None if point is None else tuple(point),
                                     None if box is None else tuple(box), t.take("tolerance", 1e-6, float)))
    t.close()
    return roller


def read_scene(data: dict, name: str) -> Scene:
    """Build a Scene from parsed TOML; every error names its dotted key."""
    top = Table(data, "")
    scene_name = top.take("name", name, str)
    top.take("description", "", str)
    body = read_body(top.table("body"))
    mesh = top.table("mesh", {})
    max_area = mesh.take("max_area", 0.0012, float)
    order = mesh.take("order", 1, int)
    mesh.close()
    material, regions = read_material(top.table("material", None))
    clamp_t = top.table("clamp", {})
    clamp = read_point_set(clamp_t, "left")
    clamp_stiffness = clamp_t.take("stiffness", 1e9, float)
    clamp_t.close()
    tip_t = top.table("tip", {})
    tip = read_point_set(tip_t, "right")
    tip_t.close()
    rollers = tuple(read_roller(t) for t in top.tables("rollers"))
    chamber_tables = top.tables("chambers")
    require(chamber_tables, "scene names no chamber: add at least one [[chambers]] table")
    chambers = [read_chamber(t) for t in chamber_tables]
    schedule = top.table("schedule")
    increments = schedule.take("increments", kind=int)
    schedule.close()
    effects_t = top.table("effects", {})
    effects = tuple(read_effect(key, effects_t.table(key)) for key in list(effects_t.data))
    effects_t.known |= set(effects_t.data)
    targets = tuple(read_target(t) for t in top.tables("targets"))
    top.close()
    geometry = build(top, lambda: Geometry(body, tuple((n, s) for n, s, _ in chambers), max_area, clamp, order,
                                           tip=tip, rollers=rollers))
    return build(top, lambda: Scene(geometry, tuple(c for _, _, c in chambers), increments, material, regions,
                                    clamp_stiffness, effects, scene_name, targets))


def load_scene(path: str | os.PathLike) -> Scene:
    """Read and validate a scene file; errors are PneumaInputError prefixed with the file name."""
    try:
        with open(path, "rb") as f:
            raw = f.read(MAX_SCENE_BYTES + 1)
    except OSError as exc:
        raise PneumaInputError(f"scene file {str(path)!r} cannot be read ({exc.strerror})") from None
    require(len(raw) <= MAX_SCENE_BYTES, f"{path}: larger than {MAX_SCENE_BYTES} bytes, the most a scene file may be")
    try:
        data = tomllib.loads(raw.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise PneumaInputError(f"{path}: not valid TOML (not UTF-8: {exc.reason} at byte {exc.start})") from None
    except tomllib.TOMLDecodeError as exc:
        raise PneumaInputError(f"{path}: not valid TOML ({exc})") from None
    except RecursionError:
        raise PneumaInputError(f"{path}: not valid TOML (arrays or tables nested too deeply)") from None
    try:
        return read_scene(data, reduce_to_stem(os.path.splitext(os.path.basename(path))[0]))
    except PneumaInputError as exc:
        raise PneumaInputError(f"{path}: {exc}") from None
