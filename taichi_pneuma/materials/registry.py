"""What a material form is (a way a scene names a material), and the registry of forms by the key that selects them.

A scene file's [material] table (and each region) names its form by a selector key, SELECTORS: `preset = "..."`
(a published material, presets.py), `law = "..."` (a law by name with its coefficients: the isochoric law's
forms, isochoric.py), or neither (the default form: the stable neo-Hookean Material of E and nu,
neo_hookean.py). A form is a frozen dataclass, the material itself, whose class attributes declare

    selector   the key naming it (None: the default form, a table naming none), and names: its values
    keys       its other scene-file keys (MaterialKey: name, the field holding it, type, doc, unit, SI default),
               in the order a scene file writes them; a key several forms take is one MaterialKey they share
    summary    the form in a few words, for the [material] table's doc

and whose methods turn keys into the material and back (from_keys, scene_values), check it (its __post_init__)
and give its law and parameter vector in the scene's units (law_parameters). Decorate the class with
@register_form to make scene files find it; the scene format (scene/material_keys.py) reads, writes and
documents the union of every form's keys, all_keys().
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import ClassVar, TypeVar

import numpy as np

from ..errors import PneumaInputError, require
from ..io.units import PRESSURE
from .law import Law

# The keys that name a material's form, by priority (a table naming a preset and a law is read as the preset,
# which refuses law), and what each means
SELECTORS = {
    "preset": "a published material (its law and coefficients, converted into the scene's units)",
    "law": "a law by name with its coefficients (the isochoric law's forms: C10, ... and K or nu); none: "
    "stable neo-Hookean (E, nu)",
}


@dataclass(frozen=True)
class MaterialKey:
    """A scene-file key of a material form: its name, the form's field that holds it, its value's type (float or
    str), what it means, the values it may take, its dimension (io/units.py; "" none) and the SI default that a
    value left out stands for (units.si_default: the Scene converts it into its units; None: none)."""

    name: str
    field: str
    type: type = float
    doc: str = ""
    allowed: tuple = ()
    unit: str = ""
    si: float | None = None


POISSON_RATIO = MaterialKey(
    "nu", "poisson_ratio", doc="Poisson's ratio, in (-1, 0.5); none: 0.45 (E), 0.49 (law), the preset's own"
)
BULK_MODULUS = MaterialKey("K", "bulk_modulus", doc="bulk modulus, instead of nu (law or preset)", unit=PRESSURE)
ALTERNATIVES = (
    BULK_MODULUS.name,
    POISSON_RATIO.name,
)  # keys a material gives one of: a region giving either replaces both of its base's


class MaterialForm:
    """The base of the forms: the class attributes and methods of the module docstring."""

    __dataclass_fields__: ClassVar[dict]  # every form is a dataclass
    selector: ClassVar[str | None] = None
    names: ClassVar[tuple[str, ...]] = ()
    keys: ClassVar[tuple[MaterialKey, ...]] = ()
    summary: ClassVar[str] = ""

    @classmethod
    def form_keys(cls, values: dict) -> dict:
        """The keys of this form that a table's values choose (its selector first), each with the value a scene
        file writes for it when it is not given (None: none): editing the selector to another form drops the old
        form's keys that the new one lacks or that hold that value (scene/dotted_edits.py's switched)."""
        return dict.fromkeys(([cls.selector] if cls.selector else []) + [key.name for key in cls.keys])

    @classmethod
    def from_keys(cls, values: dict) -> MaterialForm:
        """The material of a table's values (key -> value, None where not given): refuses (PneumaInputError) a
        key of another form (refusal()) and one of its own keys left out whose field has no default; the
        material's __post_init__ checks the values."""
        given = sorted(name for name, value in values.items() if value is not None)
        own = {cls.selector, *(key.name for key in cls.keys)}
        extra = [name for name in given if name not in own]
        if extra:
            raise PneumaInputError(cls.refusal(extra, values))
        fields = {f.name: f for f in dataclasses.fields(cls)}
        for key in cls.keys:
            missing = fields[key.field].default is dataclasses.MISSING and values.get(key.name) is None
            require(not missing, f"{cls.selector} = {values.get(cls.selector)!r} needs {key.name}")
        chosen = {key.field: values[key.name] for key in cls.keys if values.get(key.name) is not None}
        if cls.selector in fields:
            chosen[cls.selector] = values[cls.selector]
        return cls(**chosen)

    @classmethod
    def refusal(cls, extra: list[str], values: dict) -> str:
        """The message refusing the given keys `extra` that this form does not take."""
        return (
            f"{cls.selector} = {values.get(cls.selector)!r} takes {', '.join(k.name for k in cls.keys)}, not "
            f"{', '.join(extra)}"
        )

    def scene_values(self) -> dict:
        """Its scene-file keys (its selector first) and their values, None where not given: from_keys' inverse."""
        selector = {self.selector: getattr(self, self.selector, self.names[0])} if self.selector else {}
        return {**selector, **{key.name: getattr(self, key.field) for key in self.keys}}

    def law_parameters(self, units) -> tuple[type[Law], np.ndarray]:
        """The law and its parameter vector in the scene's units (io/units.py; a unitless scene's name is None)."""
        raise NotImplementedError


DEFAULT: list[type[MaterialForm]] = []  # the default form (no selector), once registered
NAMED: dict[tuple[str, str], type[MaterialForm]] = {}  # (selector, name) -> the form
REGISTERED: list[type[MaterialForm]] = []  # every form, in registration order


Form = TypeVar("Form", bound=type[MaterialForm])


def register_form(form: Form) -> Form:
    """Class decorator: make a form known to scene files by its selector's names (the default form: by none); a
    key it shares with another form by name must be the same MaterialKey."""
    if form.selector is None:
        if DEFAULT:
            raise ValueError(f"{form.__name__}: {DEFAULT[0].__name__} is the default form already")
        DEFAULT.append(form)
    else:
        if form.selector not in SELECTORS:
            raise ValueError(f"{form.__name__}: selector {form.selector!r} is not one of {', '.join(SELECTORS)}")
        for name in form.names:
            if NAMED.get((form.selector, name), form) is not form:
                raise ValueError(f"{form.selector} = {name!r} is taken by {NAMED[form.selector, name].__name__}")
            NAMED[form.selector, name] = form
    for key in form.keys:
        other = next((k for f in REGISTERED for k in f.keys if k.name == key.name), key)
        if other != key:
            raise ValueError(f"{form.__name__}: key {key.name!r} differs from the other forms' {other!r}")
    REGISTERED.append(form)
    return form


def selector_names(selector: str) -> tuple[str, ...]:
    """The values the selector takes: the names of the forms registered under it, in registration order."""
    return tuple(name for (s, name) in NAMED if s == selector)


def form_of(values: dict) -> type[MaterialForm] | None:
    """The form a table's values name: that of the first selector (SELECTORS) given, by its value (None when no
    form has that name); the default form when they give none."""
    for selector in SELECTORS:
        name = values.get(selector)
        if name is not None:
            return NAMED.get((selector, name)) if isinstance(name, str) else None
    return DEFAULT[0]


def forms() -> list[type[MaterialForm]]:
    """Every form: the default one, then the others in registration order."""
    return DEFAULT + [form for form in REGISTERED if form.selector is not None]


def all_keys() -> dict[str, MaterialKey]:
    """Every form's keys by name: the selectors (str, their allowed values the registered names), then each
    form's other keys, in the order of forms() (the order a scene file writes them)."""
    keys = {s: MaterialKey(s, s, str, doc, selector_names(s)) for s, doc in SELECTORS.items()}
    for form in forms():
        keys.update({key.name: key for key in form.keys if key.name not in keys})
    return keys


def region_values(base: dict, region: dict) -> dict:
    """The values a region's material is read from: its own if it names a form (a selector), else each key it
    omits is the base's, except that its K or nu (ALTERNATIVES) replaces both."""
    if any(region.get(selector) is not None for selector in SELECTORS):
        return region
    alternative = any(region.get(name) is not None for name in ALTERNATIVES)
    return {
        name: base.get(name) if value is None and not (alternative and name in ALTERNATIVES) else value
        for name, value in region.items()
    }
