"""Scene -> the plain data of a scene file (scenefile.py's format) and TOML text; changing dotted keys.

scene_data() is the inverse of scenefile.read_scene: read_scene(scene_data(s)) == s. Every key
is written explicitly, defaults included, so a dotted key of the format (``material.E``,
``chambers[0].center[1]``, ``schedule.increments``, ``effects.gravity.density``) names a value of
the data. with_values() changes keys there and re-reads the data with read_scene: a changed scene
is validated by the same code as a scene file, and an error names the key.
"""

from __future__ import annotations

import dataclasses
import json
import re

import numpy as np
import tomllib

from ..errors import PneumaInputError, require
from ..fem.geometry import Ellipse, Polygon, Rectangle, RectangleUnion, RoundedRectangle

KEY_PART = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)")


def plain(value):
    """Tuples to lists and NumPy scalars/arrays to Python numbers, recursively."""
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def shape_data(shape) -> dict:
    """The keys of one body or chamber shape."""
    if isinstance(shape, Rectangle):
        return {"shape": "rectangle", "center": shape.center, "size": shape.size}
    if isinstance(shape, RectangleUnion):
        return {"shape": "union", "rectangles": [{"center": r.center, "size": r.size} for r in shape.rectangles]}
    if isinstance(shape, Polygon):
        return {"shape": "polygon", "points": shape.points}
    if isinstance(shape, Ellipse):
        return {"shape": "ellipse", "center": shape.center, "semi_axes": shape.semi_axes, "points": shape.points}
    if isinstance(shape, RoundedRectangle):
        return {"shape": "rounded_rectangle", "center": shape.center, "size": shape.size, "radius": shape.radius,
                "corner_points": shape.corner_points}
    raise TypeError(f"no scene-file form for the shape {shape!r}")


def scene_data(scene) -> dict:
    """The scene as the data of a scene file (every key explicit), ready for TOML."""
    geometry = scene.geometry
    require(geometry.refinements == 0, f"a geometry refined {geometry.refinements} times has no scene-file form "
                                       f"(scene files have no refinements key)")
    chambers = []
    for (name, shape), control in zip(geometry.chambers, scene.controls):
        kind = control.kind
        chamber = {"name": name, **shape_data(shape), "control": kind.name,
                   **{key: getattr(kind, key) for key in kind.parameters()}, "keyframes": control.schedule.keyframes}
        if control.bounds is not None:
            chamber["bounds"] = control.bounds
        chambers.append(chamber)
    material = {"E": scene.material.youngs_modulus, "nu": scene.material.poisson_ratio}
    if scene.regions:
        material["regions"] = [{"box": r.box, "E": r.material.youngs_modulus, "nu": r.material.poisson_ratio}
                               for r in scene.regions]
    clamp = geometry.clamp
    data = {
        "name": scene.name,
        "body": shape_data(geometry.body),
        "mesh": {"max_area": geometry.max_area, "order": geometry.order},
        "material": material,
        "clamp": {**({"side": clamp.side} if clamp.side is not None else {"box": clamp.box}),
                  "stiffness": scene.clamp_stiffness},
        "chambers": chambers,
        "schedule": {"increments": scene.increments},
    }
    if scene.effects:
        data["effects"] = {e.name: {f.name: getattr(e, f.name) for f in dataclasses.fields(e)} for e in scene.effects}
    if scene.targets:
        data["targets"] = [{"tip": t.tip, **({} if t.angle is None else {"angle": t.angle}), "weights": t.weights}
                           for t in scene.targets]
    return plain(data)


def to_toml(scene) -> str:
    """The scene as a scene file (TOML text) that scenefile.load_scene reads back to an equal scene."""
    return dumps(scene_data(scene))


def with_values(scene, values: dict):
    """A copy of scene with the dotted keys of `values` set, validated like a scene file.

    A bad key or value raises one PneumaInputError naming the key."""
    from .scenefile import read_scene  # scenefile imports scene, which imports this module lazily

    data = scene_data(scene)
    for key, value in values.items():
        set_key(data, key, plain(value))
    try:
        return read_scene(data, scene.name)
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


# --- a small TOML writer for this data: tables, [[arrays of tables]] at the top level, inline values ---

def dumps(data: dict) -> str:
    """TOML text of nested dicts/lists/str/int/float/bool: top-level lists of tables as [[key]],
    dicts as [dotted.key] tables, everything deeper inline."""
    lines = [f"{_key(k)} = {_value(v)}" for k, v in data.items() if not _is_table(v) and not _is_table_list(v)]
    for k, v in data.items():
        if _is_table(v):
            _table(lines, [k], v)
        elif _is_table_list(v):
            for item in v:
                lines += ["", f"[[{_key(k)}]]"] + [f"{_key(a)} = {_value(b)}" for a, b in item.items()]
    return "\n".join(lines).lstrip("\n") + "\n"


def _table(lines: list, path: list, table: dict) -> None:
    scalars = {k: v for k, v in table.items() if not _is_table(v)}
    if scalars or not table:
        lines += ["", f"[{'.'.join(map(_key, path))}]"] + [f"{_key(k)} = {_value(v)}" for k, v in scalars.items()]
    for k, v in table.items():
        if _is_table(v):
            _table(lines, path + [k], v)


def _is_table(v) -> bool:
    return isinstance(v, dict)


def _is_table_list(v) -> bool:
    return isinstance(v, list) and len(v) > 0 and all(isinstance(x, dict) for x in v)


def _key(k: str) -> str:
    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else _string(k)


def _string(s: str) -> str:
    return json.dumps(s, ensure_ascii=False).replace("\x7f", "\\u007f")


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        require(np.isfinite(v), f"{v!r} cannot be written to a scene file")
        if v != 0 and not 1e-3 <= abs(v) < 1e5:  # 1e+09 rather than 1000000000.0: the shortest exact form
            return next(s for s in (f"{v:.{p}e}" for p in range(17)) if float(s) == v)
        return repr(v)
    if isinstance(v, str):
        return _string(v)
    if isinstance(v, list):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"no TOML form for {v!r}")
