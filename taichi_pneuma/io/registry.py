"""Named parts, declared one way: a chamber kind, an effect, an obstacle shape, a fibre layout is a frozen dataclass
whose fields are its scene-file keys and whose class attribute `name` (and `aliases`, other names it is read by) is
the name a scene file gives it; a Registry's decorator makes it known by that name.

    @OBSTACLE_SHAPES.register
    @dataclass(frozen=True)
    class Sphere(Shape):
        name = "sphere"
        center: tuple = key(doc="[x, y] (2D) or [x, y, z]", unit=LENGTH)
        radius: float = key(unit=LENGTH)

A field's type is its annotation (float, int, str, bool, tuple or list; X | None as X; a tuple of dataclasses,
tuple[Rectangle, ...], an array of their tables) and key() declares the rest as the field's metadata: what it
means (doc), the values it may take (allowed), its dimension (unit, io/units.py: a value in the scene's units), the
SI default that a default None stands for (si; scaled=False: a numerical default for unitless scenes, which a scene
with units must give; units.si_default is key(si=..., unit=...) with no doc), the key's name where it is not the
field's (name: a material's "E" for youngs_modulus) and the value a scene file that leaves the key out reads where
the constructor has none or another (omitted: a body rectangle's center). A field that is not a key (set by the
program, as a CAD part's length unit from the scene's) is declared internal(). The scene format's reader and writer
(scene/fileformat.py dataclass_table), the Scene's unit conversion (units.defaults) and the key reference
(docs/_generate.py) all read this one declaration.

A Registry is filled once, when the module defining its parts is imported (the registries are the package's only
module-level tables that grow, and only by these decorators).
"""

from __future__ import annotations

import dataclasses
from typing import ClassVar, Protocol, TypeVar

from .units import unit as unit_metadata


class Named(Protocol):
    name: ClassVar[str]


#: the class of a registered part (a dataclass with a class attribute `name`)
Part = TypeVar("Part", bound=type[Named])


def key(
    default=dataclasses.MISSING,
    doc: str = "",
    *,
    unit: str = "",
    scaled: bool = True,
    si=None,
    allowed=(),
    name: str = "",
    omitted=dataclasses.MISSING,
):
    """A dataclass field declaring its scene-file key (the module docstring): default (none: the key is
    required; with si, None), doc, unit, scaled, si, allowed, name and omitted as its metadata."""
    metadata: dict = {"doc": doc, "allowed": tuple(allowed)}
    if unit:
        metadata.update(unit_metadata(unit, scaled))
    if si is not None:
        metadata["si"] = si
        default = None
    if name:
        metadata["name"] = name
    if omitted is not dataclasses.MISSING:
        metadata["omitted"] = omitted
    return dataclasses.field(default=default, metadata=metadata)


def key_name(f: dataclasses.Field) -> str:
    """The scene-file key of a dataclass field: its key(name=...), else the field's name."""
    return f.metadata.get("name", f.name)


def internal(default=None):
    """A dataclass field that is no scene-file key: the program sets it (default: its value until then)."""
    return dataclasses.field(default=default, metadata={"key": False})


class Registry(dict[str, Part]):
    """The parts of one kind by name (and alias), in the order they were registered; `what` names the kind in
    errors ("chamber kind", "effect")."""

    def __init__(self, what: str):
        super().__init__()
        self.what = what

    def register(self, part: Part) -> Part:
        """Class decorator: make part known by its name and aliases (ValueError if another part has one)."""
        for name in (part.name, *getattr(part, "aliases", ())):
            if self.get(name, part) is not part:
                raise ValueError(f"{self.what} name {name!r} is taken by {self[name].__name__}")
            self[name] = part
        return part
