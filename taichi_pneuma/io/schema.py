"""The scene file's one declaration: reading (TOML data -> Scene), writing (Scene -> data), editing by dotted
keys and the key reference all come from it, so the writer cannot drift from the reader.

A declaration is a tree of five kinds of entry:

    Key(type, default, doc)           a value: float (any number), int, str, bool; tuple (an array, read as
                                      nested tuples) or list (an array, read as is). default: REQUIRED, a
                                      value, None (optional: absent reads as None, None is not written) or
                                      Same("material.E") (the value of a key read before)
    Table(keys, make, parts)          a table: make(values by key) builds its object, parts(object) gives the
                                      values back (read(write(x)) == x is the contract a property test checks)
    Tables(table)                     an array of tables ([[chambers]], regions = [{...}, ...]), read as a tuple
    Variant(options, choose)          a tag key (shape = "ellipse") choosing the Table of further keys its table
                                      has; choose(object) names the option an object is written as
    Named(registry, table)            optional named tables in the file's order (the effects)

Reading checks every key's type, refuses unknown keys, and prefixes any error a constructor raises with the
table's dotted path (``chambers[1]: ...``). The Scene's own classes (Material, Region, ChamberControl) come
from the annotations of the Scene class passed in, so scene.py can import this module without a cycle.
"""

from __future__ import annotations

import dataclasses
import functools
import re
import typing
from dataclasses import dataclass
from typing import Callable

import numpy as np
import tomllib

from ..control.targets import Target
from ..errors import PneumaInputError, require
from ..fem.geometry import (ORDERS, SIDES, ClampSelection, Ellipse, Geometry, Polygon, Rectangle, RectangleUnion,
                            RoundedRectangle)
from ..solve.schedule import ChamberSchedule
from ..terms.effects import EFFECTS
from .tomltext import dumps

REQUIRED = object()
KEY_PART = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)")
TYPE_NAMES = {float: "number", int: "integer", str: "string", bool: "boolean", tuple: "array", list: "array"}


@dataclass(frozen=True)
class Same:
    """A default: the value of another key read before (``Same("material.E")``)."""

    key: str


@dataclass(frozen=True)
class Key:
    type: type
    default: object = REQUIRED
    doc: str = ""
    allowed: tuple = ()


@dataclass(frozen=True)
class Table:
    keys: dict
    make: Callable = dict
    parts: Callable = dict
    optional: bool = False  # absent: read as an empty table (every key at its default)
    cls: type | None = None  # the class make() builds, where a Variant chooses by it
    doc: str = ""


@dataclass(frozen=True)
class Tables:
    table: Table
    doc: str = ""


@dataclass(frozen=True)
class Variant:
    options: dict
    choose: Callable | None = None  # object -> option name; None: the option whose cls the object is
    default: object = REQUIRED
    doc: str = ""

    def name_of(self, obj) -> str:
        if self.choose is not None:
            return self.choose(obj)
        return next(name for name, table in self.options.items() if isinstance(obj, table.cls))


@dataclass(frozen=True)
class Named:
    registry: dict
    table: Callable  # registered class -> its Table
    doc: str = ""


def record(cls, doc: str = "", **keys) -> Table:
    """A table whose keys are fields of the dataclass cls."""
    return Table(keys, make=lambda values: cls(**values), parts=lambda obj: {k: getattr(obj, k) for k in keys},
                 cls=cls, doc=doc)


def effect_table(cls) -> Table:
    """An effect's table: its dataclass fields, typed by their annotations (float, int, str, bool, tuple, list)."""
    hints = typing.get_type_hints(cls)
    keys = {}
    for f in dataclasses.fields(cls):
        kind = typing.get_origin(hints[f.name]) or hints[f.name]
        if kind not in TYPE_NAMES:
            raise TypeError(f"{cls.__name__}.{f.name}: {hints[f.name]} has no scene-file form")
        default = (f.default if f.default is not dataclasses.MISSING else
                   f.default_factory() if f.default_factory is not dataclasses.MISSING else REQUIRED)
        keys[f.name] = Key(kind, default)
    return record(cls, " ".join((cls.__doc__ or "").split("\n\n")[0].split()), **keys)


# --- reading ---

def join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def freeze(value: list) -> tuple:
    """An array as a tuple; an array of arrays as a tuple of tuples, recursively (a mixed one keeps its
    inner lists, which the constructors refuse showing them as written)."""
    return tuple(freeze(v) for v in value) if all(isinstance(v, list) for v in value) else tuple(value)


def build(path: str, make):
    """make(), with any PneumaInputError it raises prefixed with the table's path (unless it names a key in it)."""
    try:
        return make()
    except PneumaInputError as exc:
        if not path or f"{path}." in str(exc):
            raise
        raise PneumaInputError(f"{path}: {exc}") from None


def read_key(key: Key, data: dict, name: str, path: str, scope: dict):
    full = join(path, name)
    if name not in data:
        require(key.default is not REQUIRED, f"missing key '{full}'")
        return scope[key.default.key] if isinstance(key.default, Same) else key.default
    value = data[name]
    if key.type is float:
        require(isinstance(value, (int, float)) and not isinstance(value, bool), f"{full} = {value!r} must be a number")
    else:
        kind = list if key.type is tuple else key.type
        require(isinstance(value, kind) and not (kind is int and isinstance(value, bool)),
                f"{full} = {value!r} must be of type {kind.__name__}")
    require(not key.allowed or value in key.allowed,
            f"{full} = {value!r} is not one of {', '.join(map(str, key.allowed))}")
    return freeze(value) if key.type is tuple else value


def read_keys(keys: dict, data: dict, path: str, scope: dict, known: set) -> dict:
    """The values of keys (and of the keys of the options their variants choose) in data."""
    values = {}
    for name, entry in keys.items():
        known.add(name)
        if isinstance(entry, Key):
            values[name] = scope[re.sub(r"\[\d+\]", "[]", join(path, name))] = read_key(entry, data, name, path, scope)
        elif isinstance(entry, Variant):
            tag = read_key(Key(str, entry.default, allowed=tuple(entry.options)), data, name, path, scope)
            option = entry.options[tag]
            option_values = read_keys(option.keys, data, path, scope, known)
            values[name] = build(path, lambda: option.make(option_values))
        elif isinstance(entry, Table):
            values[name] = read_table(entry, data.get(name, {} if entry.optional else None), join(path, name), scope)
        elif isinstance(entry, Tables):
            items = read_key(Key(list, []), data, name, path, scope)
            values[name] = tuple(read_table(entry.table, item, f"{join(path, name)}[{i}]", scope)
                                 for i, item in enumerate(items))
        else:  # Named
            named = data.get(name, {})
            require(isinstance(named, dict), f"{join(path, name)} must be a table, not {named!r}")
            for key in named:
                require(key in entry.registry, f"unknown key '{join(join(path, name), key)}' "
                                               f"(allowed here: {', '.join(entry.registry)})")
            values[name] = tuple(read_table(entry.table(entry.registry[key]), item, join(join(path, name), key), scope)
                                 for key, item in named.items())
    return values


def read_table(table: Table, data, path: str, scope: dict):
    if data is None:
        raise PneumaInputError(f"missing key '{path}'")
    require(isinstance(data, dict), f"{path or 'scene'} must be a table, not {data!r}")
    known = set()
    values = read_keys(table.keys, data, path, scope, known)
    unknown = sorted(set(data) - known)
    require(not unknown, f"unknown key '{join(path, unknown[0]) if unknown else ''}' "
                         f"(allowed here: {', '.join(sorted(known))})")
    return build(path, lambda: table.make(values))


# --- writing ---

def plain(value):
    """Tuples to lists and NumPy scalars/arrays to Python numbers, recursively."""
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def write_keys(keys: dict, values: dict, data: dict) -> None:
    """Write the values of keys into data; None, no tables and no named tables are not written."""
    if set(values) != set(keys):
        raise TypeError(f"parts() gave the keys {sorted(values)}, the declaration has {sorted(keys)}")
    for name, entry in keys.items():
        value = values[name]
        if isinstance(entry, Key):
            written = plain(value)
        elif isinstance(entry, Variant):
            written = entry.name_of(value)
        elif isinstance(entry, Table):
            written = write_table(entry, value)
        elif isinstance(entry, Tables):
            written = [write_table(entry.table, item) for item in value] or None
        else:  # Named
            written = {item.name: write_table(entry.table(type(item)), item) for item in value} or None
        if written is not None:
            data[name] = written
        if isinstance(entry, Variant):
            option = entry.options[written]
            write_keys(option.keys, option.parts(value), data)


def write_table(table: Table, obj) -> dict:
    data = {}
    write_keys(table.keys, table.parts(obj), data)
    return data


# --- the key reference ---

@dataclass(frozen=True)
class KeyInfo:
    """One row of the key reference. key: dotted, [] for any item of an array of tables (chambers[].center)."""

    key: str
    type: str
    default: str
    allowed: str = ""
    when: str = ""  # the variant choosing the key, e.g. chambers[].shape = "ellipse"
    doc: str = ""


def default_text(default) -> str:
    if default is REQUIRED:
        return "required"
    if default is None:
        return "none"
    if isinstance(default, Same):
        return f"same as {default.key}"
    return dumps({"v": plain(default)})[4:].strip()


def key_rows(keys: dict, path: str, when: str = "") -> list[KeyInfo]:
    rows = []
    for name, entry in keys.items():
        key = join(path, name)
        if isinstance(entry, Key):
            rows.append(KeyInfo(key, TYPE_NAMES[entry.type], default_text(entry.default),
                                ", ".join(map(str, entry.allowed)), when, entry.doc))
        elif isinstance(entry, Variant):
            rows.append(KeyInfo(key, "string", default_text(entry.default), ", ".join(entry.options), when, entry.doc))
            for option, table in entry.options.items():
                rows += key_rows(table.keys, path, f'{key} = "{option}"')
        elif isinstance(entry, Table):
            rows.append(KeyInfo(key, "table", "{}" if entry.optional else "required", "", when, entry.doc))
            rows += key_rows(entry.keys, key, when)
        elif isinstance(entry, Tables):
            rows.append(KeyInfo(key, "array of tables", "[]", "", when, entry.doc))
            rows += key_rows(entry.table.keys, f"{key}[]", when)
        else:  # Named
            rows.append(KeyInfo(key, "table", "{}", ", ".join(entry.registry), when, entry.doc))
            for option, cls in entry.registry.items():
                table = entry.table(cls)
                rows.append(KeyInfo(join(key, option), "table", "none", "", when, table.doc))
                rows += key_rows(table.keys, join(key, option))
    return rows


# --- the scene file ---

PAIR, BOX = "[x, y]", "[x0, y0, x1, y1]"
POLYGON = record(Polygon, "a simple polygon", points=Key(tuple, doc="[[x, y], ...], at least 3"))
BODY_SHAPES = Variant({
    "rectangle": record(Rectangle, "an axis-aligned rectangle", center=Key(tuple, (0.0, 0.0), PAIR),
                        size=Key(tuple, doc="[width, height]")),
    "polygon": POLYGON,
    "union": record(RectangleUnion, "a union of axis-aligned rectangles (one region, no holes)",
                    rectangles=Tables(record(Rectangle, center=Key(tuple, doc=PAIR), size=Key(tuple, doc="[w, h]")))),
}, doc="the body's outline")
CHAMBER_SHAPES = Variant({
    "ellipse": record(Ellipse, "an ellipse", center=Key(tuple, doc=PAIR), semi_axes=Key(tuple, doc="[a, b]"),
                      points=Key(int, 64, "wall points, 8 or more")),
    "rounded_rectangle": record(RoundedRectangle, "a rectangle with quarter-circle corners",
                                center=Key(tuple, doc=PAIR), size=Key(tuple, doc="[w, h]"),
                                radius=Key(float, doc="corner radius, below half the shorter side"),
                                corner_points=Key(int, 6, "points per corner")),
    "polygon": POLYGON,
}, doc="the chamber's wall")
TARGET = record(Target, "a pose the tip should reach (inverse control)", tip=Key(tuple, doc=PAIR),
                angle=Key(float, None, "tip rotation in degrees (none: free)"),
                weights=Key(tuple, (1.0, 1.0, 1.0), "[w_x, w_y, w_angle]"))


def chamber_controls(control_class) -> tuple[Variant, Callable]:
    """The chamber control kinds in ONE place: the keys each adds to a [[chambers]] table, and
    make(kind, params, keyframes, bounds) -> control_class, the inverse of the Variant's parts."""
    area = Table({"stiffness": Key(float, 1e5, "penalty stiffness k of the area constraint")},
                 make=lambda v: ("area", v), parts=lambda c: {"stiffness": c.stiffness})
    pressure = Table({"allow_vacuum": Key(bool, False, "allow a negative pressure (suction)")},
                     make=lambda v: ("pressure", v), parts=lambda c: {"allow_vacuum": c.schedule.allow_vacuum})

    def make(kind: str, params: dict, keyframes, bounds):
        if kind == "area":
            return control_class(ChamberSchedule(kind, keyframes), params["stiffness"], bounds)
        return control_class(ChamberSchedule(kind, keyframes, params["allow_vacuum"]), bounds=bounds)

    variant = Variant({"area": area, "pressure": pressure}, lambda c: c.schedule.control, "area",
                      "what the keyframes' values are: area ratios or pressures")
    return variant, make


def item_type(hint):
    """tuple[X, ...] -> X; X -> X."""
    return typing.get_args(hint)[0] if typing.get_origin(hint) is tuple else hint


@functools.cache
def scene_table(scene_class) -> Table:
    """The declaration of a scene file for scene_class (scene.Scene), whose annotations name the classes
    of its material, regions and controls."""
    hints = typing.get_type_hints(scene_class)
    material_class, region_class, control_class = (item_type(hints[k]) for k in ("material", "regions", "controls"))
    controls, make_control = chamber_controls(control_class)
    region = Table({"box": Key(tuple, doc=BOX), "E": Key(float, Same("material.E")), "nu": Key(float, Same("material.nu"))},
                   make=lambda v: region_class(v["box"], material_class(v["E"], v["nu"])),
                   parts=lambda r: {"box": r.box, "E": r.material.youngs_modulus, "nu": r.material.poisson_ratio},
                   doc="a material for the triangles whose centroid lies in box; later regions win")
    material = Table({"E": Key(float, 1e4, "Young's modulus, > 0"), "nu": Key(float, 0.45, "Poisson's ratio, in (-1, 0.5)"),
                      "regions": Tables(region)},
                     make=lambda v: (material_class(v["E"], v["nu"]), v["regions"]),
                     parts=lambda s: {"E": s.material.youngs_modulus, "nu": s.material.poisson_ratio,
                                      "regions": s.regions},
                     optional=True, doc="the stable neo-Hookean material")
    chamber = Table({"name": Key(str, doc="distinct among the chambers"), "shape": CHAMBER_SHAPES, "control": controls,
                     "keyframes": Key(tuple, doc="[[step, value], ...], steps whole and increasing"),
                     "bounds": Key(tuple, None, "[min, max] of the command under inverse control")},
                    make=lambda v: (v["name"], v["shape"], make_control(*v["control"], v["keyframes"], v["bounds"])),
                    parts=lambda c: {"name": c[0], "shape": c[1], "control": c[2],
                                     "keyframes": c[2].schedule.keyframes, "bounds": c[2].bounds})

    def make_scene(v):
        require(v["chambers"], "scene names no chamber: add at least one [[chambers]] table")
        (material, regions), (clamp, clamp_stiffness) = v["material"], v["clamp"]
        geometry = Geometry(v["body"], tuple((name, shape) for name, shape, _ in v["chambers"]),
                            v["mesh"]["max_area"], clamp, v["mesh"]["order"])
        return scene_class(geometry, tuple(control for *_, control in v["chambers"]), v["schedule"]["increments"],
                           material, regions, clamp_stiffness, v["effects"], v["name"], v["targets"])

    def mesh_parts(geometry):
        require(geometry.refinements == 0, f"a geometry refined {geometry.refinements} times has no scene-file form "
                                           f"(scene files have no refinements key)")
        return {"max_area": geometry.max_area, "order": geometry.order}

    return Table({
        "name": Key(str, None, "names the result files (a plain file name); none: the scene file's own name"),
        "description": Key(str, "", "free text, not kept"),
        "body": Table({"shape": BODY_SHAPES}, make=lambda v: v["shape"], parts=lambda body: {"shape": body}),
        "mesh": Table({"max_area": Key(float, 0.0012, "largest triangle area"),
                       "order": Key(int, 1, "1: linear triangles, 2: quadratic", ORDERS)},
                      parts=mesh_parts, optional=True),
        "material": material,
        "clamp": Table({"side": Key(str, None, "the clamped side (without box: left)", SIDES),
                        "box": Key(tuple, None, f"{BOX}: the vertices in it are clamped"),
                        "stiffness": Key(float, 1e9, "penalty stiffness of the clamp")},
                       make=lambda v: (ClampSelection("left" if v["side"] is None and v["box"] is None else v["side"],
                                                      v["box"]), v["stiffness"]),
                       parts=lambda s: {"side": s.geometry.clamp.side, "box": s.geometry.clamp.box,
                                        "stiffness": s.clamp_stiffness}, optional=True),
        "chambers": Tables(chamber, "the chambers, at least one"),
        "schedule": Table({"increments": Key(int, doc="solves after the rest state")},
                          parts=lambda s: {"increments": s.increments}),
        "effects": Named(EFFECTS, effect_table, "the effects the scene adds, by name"),
        "targets": Tables(TARGET, "poses for inverse control, in order"),
    }, make=make_scene, parts=lambda s: {
        "name": s.name, "description": None, "body": s.geometry.body, "mesh": s.geometry, "material": s, "clamp": s,
        "chambers": [(name, shape, control) for (name, shape), control in zip(s.geometry.chambers, s.controls)],
        "schedule": s, "effects": s.effects, "targets": s.targets})


def read_scene(data: dict, name: str, scene_class):
    """A scene_class from the data of a scene file; name when it has no name key. Errors name their dotted key."""
    if isinstance(data, dict):
        data = {"name": name, **data}
    return read_table(scene_table(scene_class), data, "", {})


def scene_data(scene) -> dict:
    """The scene as the data of a scene file, every key explicit (defaults included) but for absent optional ones."""
    return write_table(scene_table(type(scene)), scene)


def to_toml(scene) -> str:
    """The scene as a scene file (TOML text) that reads back to an equal scene."""
    return dumps(scene_data(scene))


def key_reference(scene_class) -> list[KeyInfo]:
    """Every key of the scene file: its type, default, allowed values, when it applies and what it means."""
    return key_rows(scene_table(scene_class).keys, "")


# --- editing by dotted keys ---

def with_values(scene, values: dict):
    """A copy of scene with the dotted keys of `values` set, validated like a scene file.

    A bad key or value raises one PneumaInputError naming the key."""
    data = scene_data(scene)
    for key, value in values.items():
        set_key(data, key, plain(value))
    try:
        return read_scene(data, scene.name, type(scene))
    except PneumaInputError as exc:
        message = str(exc)
        if not any(key in message for key in values):
            message = f"{', '.join(f'{k} = {v!r}' for k, v in values.items())}: {message}"
        raise PneumaInputError(message) from None


def parse_key(key: str) -> list:
    """'chambers[0].center[1]' -> ['chambers', 0, 'center', 1]."""
    parts = []
    for segment in key.split("."):
        match = KEY_PART.fullmatch(segment)
        require(match is not None, f"{key!r} is not a dotted scene key (like material.E or chambers[0].center[1])")
        parts.append(match.group(1))
        parts += [int(i) for i in re.findall(r"\[(\d+)\]", match.group(2))]
    return parts


def set_key(data: dict, key: str, value) -> None:
    """Set a dotted key in nested scene data; missing tables on the way are created (e.g. a new effect)."""
    parts = parse_key(key)
    node, path = data, ""
    for i, part in enumerate(parts):
        last = i == len(parts) - 1
        if isinstance(part, int):
            require(isinstance(node, list), f"{key}: {path} is not a list")
            require(part < len(node), f"{key}: {path} has {len(node)} items, there is no [{part}]")
            path += f"[{part}]"
        else:
            require(isinstance(node, dict), f"{key}: {path} is not a table")
            if not last and part not in node:
                node[part] = {}
            path += f".{part}" if path else part
        if last:
            node[part] = value
        else:
            node = node[part]


def parse_assignment(text: str) -> tuple[str, object]:
    """'KEY=VALUE' -> (key, value); VALUE is read as a TOML value (1e4, true, [0, 0.1], "x"), else as a string."""
    key, sep, raw = text.partition("=")
    require(bool(sep) and key.strip(), f"--set {text!r} must look like KEY=VALUE (e.g. material.E=2e4)")
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()
    return key.strip(), value
