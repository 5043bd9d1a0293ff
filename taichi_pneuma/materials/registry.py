"""What a material form is (a way a scene names a material), and the registries of forms by the key that selects them.

A scene file's [material] table (and each region) names its form by a selector key, SELECTORS: `preset = "..."`
(a published material, presets.py), `law = "..."` (a law by name with its coefficients: the isochoric law's
forms, isochoric.py), or neither (the default form: the stable neo-Hookean Material of E and nu,
neo_hookean.py). A form is a frozen dataclass, the material itself, declared as every named part is
(io/registry.py): its fields are its scene-file keys, each field's key(...) its doc, unit and SI default and, where
the key is not the field's name, the key's (`youngs_modulus: float | None = key(..., name="E")`), and it is
registered under the values its selector takes for it, its class attributes name and aliases:

    @LAW_FORMS.register        law = "<name>"     (IsochoricMaterial: neo_hookean, mooney_rivlin, yeoh)
    @PRESET_FORMS.register     preset = "<name>"  (PresetMaterial: one name a preset)
    @DEFAULT_FORM.register     neither            (Material; the one default form, named after its law)

Its other class attributes: selector (the key naming it, and the field holding that name if it has one; None: the
default form) and summary (the form in a few words, for the [material] table's doc); its methods turn keys into the
material and back (from_keys, scene_values), check it (its __post_init__) and give its law and parameter vector in
the scene's units (law_parameters). A key several forms take is declared once: nu and K are the fields of
Compressible, the base of the forms that take either (keyword-only: its fields come first in the key order, last
in the constructor's), and poisson_ratio_key the default form's nu; keys of one name must agree (their doc, type
and unit: scene/material_keys.py checks).

The scene format (scene/material_keys.py) reads, writes and documents the union of every form's keys: the
selectors, then each form's keys in the order of forms() and of its fields, which is the order a scene file writes
them (preset, law, E, nu, K, C10, C01, C20, C30).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..errors import PneumaInputError, require
from ..io.registry import Registry, key, key_name
from ..io.units import PRESSURE
from .law import Law

# The keys that name a material's form, by priority (a table naming a preset and a law is read as the preset,
# which refuses law), and what each means
SELECTORS = {
    "preset": "a published material (its law and coefficients, converted into the scene's units)",
    "law": "a law by name with its coefficients (the isochoric law's forms: C10, ... and K or nu); none: "
    "stable neo-Hookean (E, nu)",
}
NU, K = "nu", "K"
ALTERNATIVES = (K, NU)  # keys a material gives one of: a region giving either replaces both of its base's


def poisson_ratio_key(default=None):
    """The field of a form's Poisson's ratio, key nu (default: the form's, None where it has none)."""
    return key(default, "Poisson's ratio, in (-1, 0.5); none: 0.45 (E), 0.49 (law), the preset's own", name=NU)


class MaterialForm:
    """The base of the forms: the class attributes and methods of the module docstring."""

    __dataclass_fields__: ClassVar[dict]  # every form is a dataclass
    name: ClassVar[str]
    aliases: ClassVar[tuple[str, ...]] = ()
    selector: ClassVar[str | None] = None
    summary: ClassVar[str] = ""

    @classmethod
    def key_fields(cls) -> dict[str, dataclasses.Field]:
        """Its scene-file keys but the selector, by name (key(name=...), else the field's), each its field, in the
        fields' order."""
        keys = {key_name(f): f for f in dataclasses.fields(cls)}
        if cls.selector:
            keys.pop(cls.selector, None)
        return keys

    @classmethod
    def form_keys(cls, values: dict) -> dict:
        """The keys of this form that a table's values choose (its selector first), each with the value a scene
        file writes for it when it is not given (None: none): editing the selector to another form drops the old
        form's keys that the new one lacks or that hold that value (scene/dotted_edits.py's switched)."""
        return dict.fromkeys(([cls.selector] if cls.selector else []) + list(cls.key_fields()))

    @classmethod
    def from_keys(cls, values: dict) -> MaterialForm:
        """The material of a table's values (key -> value, None where not given): refuses (PneumaInputError) a
        key of another form (refusal()) and one of its own keys left out whose field has no default; the
        material's __post_init__ checks the values."""
        keys = cls.key_fields()
        extra = [name for name in sorted(values) if values[name] is not None and name not in {cls.selector, *keys}]
        if extra:
            raise PneumaInputError(cls.refusal(extra, values))
        for name, f in keys.items():
            required = f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
            require(
                not (required and values.get(name) is None),
                f"{cls.selector} = {values.get(cls.selector)!r} needs {name}",
            )
        chosen = {f.name: values[name] for name, f in keys.items() if values.get(name) is not None}
        if cls.selector and cls.selector in cls.__dataclass_fields__:
            chosen[cls.selector] = values[cls.selector]
        return cls(**chosen)

    @classmethod
    def refusal(cls, extra: list[str], values: dict) -> str:
        """The message refusing the given keys `extra` that this form does not take."""
        return (
            f"{cls.selector} = {values.get(cls.selector)!r} takes {', '.join(cls.key_fields())}, not {', '.join(extra)}"
        )

    def scene_values(self) -> dict:
        """Its scene-file keys (its selector first) and their values, None where not given: from_keys' inverse."""
        selector = {self.selector: getattr(self, self.selector, self.name)} if self.selector else {}
        return {**selector, **{name: getattr(self, f.name) for name, f in self.key_fields().items()}}

    def law_parameters(self, units) -> tuple[type[Law], np.ndarray]:
        """The law and its parameter vector in the scene's units (io/units.py; a unitless scene's name is None)."""
        raise NotImplementedError


@dataclass(frozen=True, kw_only=True)
class Compressible(MaterialForm):
    """The base of the forms taking a bulk modulus K (in the scene's pressure unit) or else a Poisson's ratio nu,
    each None where not given (the form's own then: its __post_init__ checks them)."""

    poisson_ratio: float | None = poisson_ratio_key()
    bulk_modulus: float | None = key(None, "bulk modulus, instead of nu (law or preset)", unit=PRESSURE, name=K)


DEFAULT_FORM: Registry[type[MaterialForm]] = Registry("default material form")  # neither selector: one form
PRESET_FORMS: Registry[type[MaterialForm]] = Registry("preset")  # preset = "<name>" -> its form
LAW_FORMS: Registry[type[MaterialForm]] = Registry("law")  # law = "<name>" -> its form
SELECTED = {"preset": PRESET_FORMS, "law": LAW_FORMS}  # each selector's registry


def selector_names(selector: str) -> tuple[str, ...]:
    """The values the selector takes: the names its forms are registered by, in registration order."""
    return tuple(SELECTED[selector])


def default_form() -> type[MaterialForm]:
    """The form of a table naming no selector: the one form registered in DEFAULT_FORM."""
    registered = set(DEFAULT_FORM.values())
    if len(registered) != 1:
        raise ValueError(f"{len(registered)} default material forms are registered, not one: {sorted(DEFAULT_FORM)}")
    return registered.pop()


def form_of(values: dict) -> type[MaterialForm] | None:
    """The form a table's values name: that of the first selector (SELECTORS) given, by its value (None when no
    form has that name); the default form when they give none."""
    for selector in SELECTORS:
        name = values.get(selector)
        if name is not None:
            return SELECTED[selector].get(name) if isinstance(name, str) else None
    return default_form()


def forms() -> list[type[MaterialForm]]:
    """Every form once: the default one, the laws' and the presets', each in registration order."""
    return list(dict.fromkeys([default_form(), *LAW_FORMS.values(), *PRESET_FORMS.values()]))


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
