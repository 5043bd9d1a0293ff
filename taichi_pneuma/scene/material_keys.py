"""The scene file's [material] table and its regions (material.regions = [{...}, ...]), declared with
fileformat.py's entries: the union of the keys of every registered material form (materials/registry.py), read off
their fields (fileformat.field_entry, as every registered part's keys are) when the table is used, so that a form
registered after this module is imported is read, written, edited and documented like the others.
"""

from __future__ import annotations

import dataclasses
import functools
import typing

from ..io.units import LENGTH
from ..materials.registry import SELECTORS, form_of, forms, region_values, selector_names
from .fileformat import REQUIRED, Key, Table, Tables, build, field_entry
from .region import Region
from .shape_keys import BOX

MATERIAL_TAGS = tuple(SELECTORS)  # the keys choosing a material's form (material_kind)


def material_entries() -> dict[str, Key]:
    """The [material] table's keys, each optional: the selectors (their allowed values the names registered
    under them), then the keys of every material form registered now (materials/registry.py), in the order of
    forms() and of each form's fields; a key several forms take must be the same but for its default (a
    ValueError names the form that differs)."""
    keys = {s: Key(str, None, doc, selector_names(s)) for s, doc in SELECTORS.items()}
    for form in forms():
        hints = typing.get_type_hints(form)
        for name, f in form.key_fields().items():
            entry = dataclasses.replace(field_entry(f, hints[f.name], form.__name__), default=None)
            known = keys.setdefault(name, entry)
            if dataclasses.replace(known, si=None) != dataclasses.replace(entry, si=None):
                raise ValueError(f"{form.__name__}: key {name!r} is {entry}, the other forms' {known}")
    return keys


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
    return {**dict.fromkeys(material_entries()), **material.scene_values()}


def region_entries() -> dict:
    """A region's keys: box or group, and the [material] keys (none: the base's)."""
    return {
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
        **{k: dataclasses.replace(key, si=None) for k, key in material_entries().items()},
    }


def make_material(v: dict) -> tuple:
    """(the material, its regions) of the [material] table's values: the base first, then each region (its
    omitted keys the base's, unless it names a form)."""
    entries = material_entries()
    base_keys = {k: v[k] for k in entries}

    def region(r):
        return Region(
            box=r["box"], material=material_of(region_values(base_keys, {k: r[k] for k in entries})), group=r["group"]
        )

    return material_of(base_keys), tuple(
        build(f"material.regions[{i}]", functools.partial(region, r)) for i, r in enumerate(v["regions"])
    )


def material_doc() -> str:
    """The [material] table's doc: the registered forms in a few words."""
    return f"the body's material: {', '.join(f.summary for f in forms()[:-1])}, or {forms()[-1].summary}"


REGION = Table(
    region_entries,
    parts=lambda r: {"box": r.box, "group": r.group, **material_keys(r.material)},
    kind=material_kind,
    tags=MATERIAL_TAGS,
)
REGIONS = Tables(
    REGION,
    "materials for the elements of a box or a volume group (later regions win); keys as "
    "material's, and unless a region names a preset or law, each key it omits is material's",
)
MATERIAL = Table(
    lambda: {**material_entries(), "regions": REGIONS},
    make=make_material,
    parts=lambda s: {**material_keys(s.material), "regions": s.regions},
    optional=True,
    kind=material_kind,
    tags=MATERIAL_TAGS,
    doc=material_doc,
)
