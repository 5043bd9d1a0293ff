"""What a chamber kind is (a way of driving a chamber), and the registry of kinds by name.

A kind is a frozen dataclass whose fields are its parameters: the keys a scene file's chamber table
takes besides its name, shape, control, keyframes and bounds, with their types, defaults and units (the
named parts' one idiom, io/registry.py). Its class attributes describe its command q:

    name       the scene file's `control = "..."`; aliases: other names it is read by
    quantity   what q is, in words, for labels and messages ("area ratio", "pressure")
    rest       q of the unloaded chamber, where every schedule starts (1.0, 0.0)
    dimension  q's dimension (io/units.py: "" none, "pressure", "area"), the unit outputs give it in a scene
               with units

and its methods do the rest: check() refuses values q cannot take, default_bounds() gives the range
inverse control keeps to when the scene names none, term() builds the chamber's energy term (a
wall.Chamber subclass: energy, pressure, and -d(residual)/dq for sensitivities). Decorate the class
with @KINDS.register to make scenes and scene files find it by name.
"""

from __future__ import annotations

import dataclasses
from typing import ClassVar

from ...errors import require
from ...io.registry import Registry


class ChamberKind:
    """The base of the kinds: the class attributes and methods described in the module docstring."""

    __dataclass_fields__: ClassVar[dict]  # every kind is a dataclass
    name: ClassVar[str]
    aliases: ClassVar[tuple[str, ...]] = ()
    quantity: ClassVar[str]
    rest: ClassVar[float]
    dimension: ClassVar[str] = ""

    def check(self, what: str, values: list[float]) -> None:
        """Refuse (PneumaInputError naming `what` and the value) a command this kind cannot take;
        what: where the values come from ("keyframes", "bounds = [...]:"). Every finite value by default."""

    def default_bounds(self, values: list[float]) -> tuple[float, float]:
        """(min, max) command for inverse control when the scene gives no bounds, from the keyframe
        values: by default the range the schedule drives (the rest command and every keyframe value)."""
        values = [self.rest, *values]
        return min(values), max(values)

    def term(self, config, loop, name: str, order: int, origin=None):
        """The chamber's energy term (a wall.Chamber) on the wall loop `loop` of the model's config (an open
        wall closed along symmetry lines through `origin`, if given)."""
        raise NotImplementedError


KINDS: Registry[type[ChamberKind]] = Registry(
    "chamber kind"
)  # name -> the kind (a ChamberKind dataclass), filled by @KINDS.register


def chamber_kind(name: str) -> type[ChamberKind]:
    """The kind registered under `name` (PneumaInputError naming it and the known ones otherwise)."""
    require(isinstance(name, str) and name in KINDS, f"control = {name!r} is not one of {', '.join(KINDS)}")
    return KINDS[name]


def default_kind(name: str) -> ChamberKind:
    """The kind registered under `name` with its default parameters (PneumaInputError naming the parameters
    it has no default for: such a kind is given with them, e.g. Syringe(syringe_volume=1.0))."""
    kind = chamber_kind(name)
    required = [f.name for f in dataclasses.fields(kind) if f.default is dataclasses.MISSING]
    require(
        not required,
        f"control = {name!r} has no default for {', '.join(required)}: "
        f"give {kind.__name__}({', '.join(f'{key}=...' for key in required)})",
    )
    return kind()
