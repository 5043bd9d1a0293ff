"""Scene files (TOML) read and written: TOML -> Scene, with one clear PneumaInputError naming the file, the key and
the value, and Scene -> its data (scene_data; Scene.to_toml writes the text), read(write(x)) == x.

    name = "bidirectional"
    [body]       shape = "rectangle" (center, size) | "polygon" (points) | "union" (rectangles = [{center, size}, ...])
                 | "mesh" (file: a 3D mesh file with tetrahedra, relative to the scene file)
    [mesh]       max_area (2D), order = 1 (linear triangles, tetrahedra) | 2 (quadratic)
    [material]   E, nu, regions = [{box = [x0, y0, x1, y1], E, nu}, ...]   (E, nu of a region default to the base)
    [clamp]      side = "left" | "right" | "bottom" | "top" ("back" | "front": z, in 3D)  or  box = [x0, y0, x1, y1]
                 ([x0, y0, z0, x1, y1, z1] in 3D);  stiffness (also the rollers')
    [tip]        side = "right" (default) | "left" | "bottom" | "top"  or  box = [x0, y0, x1, y1]: the nodes whose
                 mean displacement and rotation the history (tip_dx, tip_dy, tip_rotation), sensitivities and reach use
    [[rollers]]  normal = [nx, ny]; point = [x, y] (the nodes within tolerance of the line through it, normal to
                 normal) or box = [x0, y0, x1, y1]; tolerance = 1e-6. A roller line along the body's edge is a
                 symmetry line: a chamber crossing it is cut there, its area closed by the flat cap on the line.
                 In 3D: normal = [nx, ny, nz], point = [x, y, z] (a plane); a plane holding an open chamber
                 wall's rim closes that chamber
    [[chambers]] name, shape = "ellipse" (center, semi_axes, points) | "rounded_rectangle" (center, size,
                 radius, corner_points) | "polygon" (points) | "mesh_surface" (group: the mesh file's triangles
                 of the chamber's wall, for a mesh body); control = a chamber kind's name, "area"
                 (stiffness) | "pressure" (allow_vacuum) | "closed_gas" (atmosphere, gamma) | "syringe"
                 (syringe_volume, dead_volume, atmosphere, gamma) | ..., with that kind's parameters;
                 keyframes = [[step, value], ...]; bounds = [min, max] (inverse control)
    [schedule]   increments
    [effects.gravity] density, g      [effects.ground] height, dhat, stiffness, friction, friction_slip
    [effects.self_contact] dhat, stiffness (2D chamber walls)
    [effects.surface_contact] dhat, stiffness, friction, friction_slip (the whole surface, 2D and 3D)
    [effects.dynamics] density, dt
    [[targets]]  tip = [x, y], angle (degrees, optional), weights = [w_x, w_y, w_angle]  (inverse control, in order)

Every key is checked: an unknown key, a missing required one, or a value out of range is refused with its dotted
path (e.g. ``chambers[1].semi_axes``). The format is declared once, in scene_keys.py (the tables; build.py SCENE_FILE
makes the Scene of their values) with fileformat.py's entries; key_reference() lists every key with its type, default
and allowed values. A file over MAX_SCENE_BYTES, or one that is not a regular file (a FIFO, a device), is refused
unread; ``name`` must be a plain file name (output.check_stem); without it the file's own name, reduced to one, is
used.
"""

from __future__ import annotations

import os

from ..errors import PneumaInputError
from ..io.inputs import read_input
from ..io.output import reduce_to_stem
from ..io.tomltext import parse_toml
from .build import SCENE_FILE, Scene
from .fileformat import KeyInfo, key_rows

MAX_SCENE_BYTES = 1_000_000


def read_scene(data: dict, name: str) -> Scene:
    """A Scene from parsed TOML (named `name` unless it has a name key); every error names its dotted key."""
    return SCENE_FILE.read_table({"name": name, **data} if isinstance(data, dict) else data, "")


def key_reference() -> list[KeyInfo]:
    """Every key a scene file may have: its type, default, allowed values, when it applies and what it means."""
    return key_rows(SCENE_FILE.entries(), "")


def scene_data(scene: Scene) -> dict:
    """The scene as the data of a scene file: every key explicit, defaults included, but absent optional ones."""
    return SCENE_FILE.write_table(scene)


def load_scene(path: str | os.PathLike) -> Scene:
    """Read and validate a scene file (a regular file of at most MAX_SCENE_BYTES: a FIFO or a device is
    refused without waiting for it; TOML within tomltext.parse_toml's limits); errors are PneumaInputError
    prefixed with the file name."""
    raw = read_input(path, MAX_SCENE_BYTES, "scene file")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise PneumaInputError(f"{path}: not valid TOML (not UTF-8: {exc.reason} at byte {exc.start})") from None
    data = parse_toml(text, str(path))
    chambers = data.get("chambers")
    for table in [data.get("body")] + (chambers if isinstance(chambers, list) else []):
        if isinstance(table, dict) and isinstance(table.get("file"), str):  # a mesh or CAD file, relative to it
            table["file"] = os.path.join(os.path.dirname(os.path.abspath(path)), table["file"])
    try:
        return read_scene(data, reduce_to_stem(os.path.splitext(os.path.basename(path))[0]))
    except PneumaInputError as exc:
        raise PneumaInputError(f"{path}: {exc}") from None
