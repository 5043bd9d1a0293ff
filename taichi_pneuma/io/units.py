"""A scene's units: a consistent system of a length unit and a pressure (stress) unit, and the labels its outputs
carry.

    units = "mm-kPa"    lengths in millimetres, pressures and moduli in kilopascals
    units = "mm-MPa"    millimetres and megapascals (N and mm: Abaqus' usual system)
    units = "m-Pa"      SI
    (no units key)      unitless, as the reference scene: numbers are what the scene says they are

Every other quantity follows from these two: an area is length^2, a force per unit depth (the 2D contact
force) pressure x length, an energy per unit depth pressure x length^2, a mass pressure x length x s^2 (so
that force = mass x acceleration: kg in mm-kPa, tonnes in mm-MPa). Angles are in degrees and times in seconds
whatever the system.

Defaults are stored in SI and converted into a scene's units: a key declares its dimension (scene/fileformat.Key's
unit; a chamber kind's or an effect's field through unit()), and a default of dimension L^a P^b in 2D (or
3D) is divided by factor() = metre^a pascal^b when read (material presets likewise: a modulus in Pa divided
by the pressure unit in Pa). A unitless scene takes every number as it is, as SI. Some defaults are numerical
parameters calibrated for the unitless scenes (bodies of size about 1, moduli about 1e4): a penalty stiffness
or a barrier's distance, whose SI value would be far off at a real actuator's scale (an area penalty of 1e5
Pa/m^2 holds nothing on a chamber of a few mm^2); unit(dimension, scaled=False) declares one, and a scene
with units must give it.

Outputs of a scene with units say their unit: a column or array named `x` is written `x [unit]` (history CSV
headers, VTU arrays and field data), printed values carry the unit, plots label their axes with it and the
summary JSON has a "units" entry. A unitless scene's outputs are named as they always were.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import TypeVar

from ..errors import require

T = TypeVar("T")

LENGTH, AREA, PRESSURE, FORCE, ANGLE, TIME = "length", "area", "pressure", "force", "angle", "time"
VOLUME = "volume"  # a 3D chamber's measure
MOMENT = "moment"  # force x length (per unit depth in 2D, as FORCE)
FORCE_3D, MOMENT_3D = "force (3D)", "moment (3D)"  # FORCE and MOMENT in a 3D body (in_dimension): not per depth
MEASURES = {2: AREA, 3: VOLUME}  # what a chamber encloses, by dimension
ACCELERATION, DENSITY = "acceleration", "density"
PLANE_AREA = "plane area"  # an area in 2D and 3D alike (a triangle's), where AREA is a chamber's measure
SECTION = "cross-section"  # a fibre's cross-section: an area in 3D, an area per unit depth (a length) in 2D
NODAL_STIFFNESS = "nodal penalty stiffness"  # energy per length^2 at a node: K of E = 1/2 K |u|^2 (per depth in 2D)
MEASURE_STIFFNESS = "measure penalty stiffness"  # pressure per chamber measure: k of E = 1/2 k (A - A*)^2
# (length, pressure, time) exponents of each dimension in 2D and in 3D (a chamber's measure is an area, a volume
# per unit depth, in 2D; an energy is per unit depth in 2D); times are in seconds in every system
EXPONENTS = {
    LENGTH: ((1, 0, 0),) * 2,
    AREA: ((2, 0, 0), (3, 0, 0)),
    VOLUME: ((3, 0, 0),) * 2,
    PLANE_AREA: ((2, 0, 0),) * 2,
    SECTION: ((1, 0, 0), (2, 0, 0)),
    PRESSURE: ((0, 1, 0),) * 2,
    ANGLE: ((0, 0, 0),) * 2,
    FORCE: ((1, 1, 0),) * 2,
    FORCE_3D: ((2, 1, 0),) * 2,
    MOMENT: ((2, 1, 0),) * 2,
    MOMENT_3D: ((3, 1, 0),) * 2,
    TIME: ((0, 0, 1),) * 2,
    ACCELERATION: ((1, 0, -2),) * 2,
    DENSITY: ((-2, 1, 2),) * 2,
    NODAL_STIFFNESS: ((0, 1, 0), (1, 1, 0)),
    MEASURE_STIFFNESS: ((-2, 1, 0), (-3, 1, 0)),
}


def unit(dimension: str, scaled: bool = True) -> dict:
    """A dataclass field's metadata declaring its dimension (field(metadata=unit(DENSITY))): a value in the
    scene's units (scaled=False: see si_default)."""
    return {"unit": dimension, "scaled": scaled}


def si_default(si, dimension: str, scaled: bool = True):
    """A dataclass field of dimension `dimension` whose default, None, stands for `si` (in SI) converted into the
    scene's units (default_in) when the Scene resolves it (resolved); scaled=False: a numerical default for
    unitless scenes, which a scene with units must give."""
    return field(default=None, metadata={**unit(dimension, scaled), "si": si})


def given(value: T | None, name: str) -> T:
    """The value of a si_default field (None until the Scene sets it: resolved) once it is set: a term is built from
    a resolved scene only, so None here is a bug in the program, not an input to refuse."""
    if value is None:
        raise ValueError(f"{name} is None: the Scene sets it (units.resolved) before any term is built")
    return value


def default_in(si, dimension: str, scaled: bool, units: Units, dim: int, key: str):
    """The default `si` (a number or an array of numbers, in SI) of key `key` in `units` in a body of dimension
    dim: si / units.factor(dimension, dim); a numerical default (scaled=False) is taken as it is in a unitless
    scene and refused, naming the key, in a scene with units. Scene files and the Python API both come here."""
    if units.name is None:
        return si
    require(
        scaled,
        f"missing key '{key}': a scene with units gives it (in {units.name}); its default {si!r} is a "
        f"numerical parameter for unitless scenes",
    )
    factor = units.factor(dimension, dim)
    return tuple(v / factor for v in si) if isinstance(si, tuple) else si / factor


def defaults(obj, units: Units, dim: int, path: str) -> dict:
    """The value in `units` (default_in) of every si_default field of obj (a dataclass) left None, by name; path:
    the scene-file table of obj, naming a key a scene with units must give."""
    if not dataclasses.is_dataclass(obj):
        return {}
    return {
        f.name: default_in(f.metadata["si"], f.metadata["unit"], f.metadata["scaled"], units, dim, f"{path}.{f.name}")
        for f in dataclasses.fields(obj)
        if "si" in f.metadata and getattr(obj, f.name) is None
    }


def resolved(obj, units: Units, dim: int, path: str):
    """obj with its defaults (defaults()) set; obj itself when it has none left None."""
    given = defaults(obj, units, dim, path)
    return dataclasses.replace(obj, **given) if given else obj


def si_text(dimension: str) -> str:
    """The SI unit of a dimension ("Pa", "m^2 (2D), m^3 (3D)", "deg" for angles): the key reference's unit."""
    if dimension == ANGLE:
        return "deg"

    def text(exponents) -> str:
        length, pressure, time = exponents
        parts = [
            f"{symbol}^{e}" if e != 1 else symbol for symbol, e in (("Pa", pressure), ("m", length), ("s", time)) if e
        ]
        return " ".join(parts) or "1"

    plane, solid = (text(e) for e in EXPONENTS[dimension])
    return plane if plane == solid else f"{plane} (2D), {solid} (3D)"


@dataclass(frozen=True)
class Units:
    """A system of units: its name (None: unitless), the length and pressure units' symbols and sizes in SI, and
    the name of the force unit they make in 3D (pressure x length^2: kPa mm^2 = mN)."""

    name: str | None = None
    length: str = ""
    pressure: str = ""
    metre: float = 1.0  # the length unit, in m
    pascal: float = 1.0  # the pressure unit, in Pa
    force: str = ""  # pressure x length^2, by its name

    def symbol(self, dimension: str) -> str:
        """The unit of a dimension (LENGTH, AREA, PRESSURE, FORCE per unit depth, ANGLE, TIME) in this system;
        "" when unitless or dimensionless ("")."""
        if self.name is None or not dimension:
            return ""
        return {
            LENGTH: self.length,
            AREA: f"{self.length}^2",
            PRESSURE: self.pressure,
            FORCE: f"{self.pressure} {self.length}",
            ANGLE: "deg",
            TIME: "s",
            VOLUME: f"{self.length}^3",
            MOMENT: f"{self.pressure} {self.length}^2",
            FORCE_3D: self.force,
            MOMENT_3D: f"{self.force} {self.length}",
        }[dimension]

    def label(self, name: str, dimension: str) -> str:
        """name with its unit in brackets ("main.pressure [kPa]"); name itself when there is none."""
        unit = self.symbol(dimension)
        return f"{name} [{unit}]" if unit else name

    def suffix(self, dimension: str) -> str:
        """ " kPa" after a printed value; "" when there is no unit."""
        unit = self.symbol(dimension)
        return f" {unit}" if unit else ""

    def factor(self, dimension: str, dim: int) -> float:
        """The size in SI of this system's unit of `dimension` in a body of dimension dim (a value in SI divided
        by it is the value in this system): metre^a pascal^b for L^a P^b."""
        length, pressure, _ = EXPONENTS[dimension][dim - 2]
        return self.metre**length * self.pascal**pressure

    def summary(self, dim: int = 2) -> dict | None:
        """The summary JSON's "units" entry for a body of dimension dim: the system and each dimension's unit
        (a force is per unit depth in 2D, a force in 3D); None when unitless."""
        if self.name is None:
            return None
        symbols = {d: self.symbol(d) for d in (LENGTH, AREA, PRESSURE, FORCE, ANGLE, TIME)}
        return {"system": self.name, **symbols, FORCE: self.symbol(in_dimension(FORCE, dim))}


UNITLESS = Units()
UNITS = {
    u.name: u
    for u in (
        Units("mm-kPa", "mm", "kPa", 1e-3, 1e3, "mN"),
        Units("mm-MPa", "mm", "MPa", 1e-3, 1e6, "N"),
        Units("m-Pa", "m", "Pa", 1.0, 1.0, "N"),
    )
}


def in_dimension(dimension: str, dim: int) -> str:
    """A quantity's dimension in a body of dimension dim: AREA (a chamber's measure, or a volume of air per unit
    depth) is VOLUME in 3D, FORCE and MOMENT (per unit depth in 2D) FORCE_3D and MOMENT_3D; others are
    themselves."""
    if dim == 3:
        return {AREA: VOLUME, FORCE: FORCE_3D, MOMENT: MOMENT_3D}.get(dimension, dimension)
    return dimension
