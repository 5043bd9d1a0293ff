"""A file format declared once: from one tree of entries come reading (data -> objects, every error naming
its dotted key), writing (objects -> data) and the key reference (scene/dotted_edits.py edits the data by dotted
keys; io/tomltext.py reads and writes the TOML text, within limits).

    Key(type, default, doc, allowed,  a value: float (any number), int, str, bool; tuple (an array, read as
        unit, scaled, si)             nested tuples) or list (an array, read as is). default: REQUIRED, a
                                      value, or None (optional: absent reads as None, None is not written).
                                      unit: its dimension (io/units.py); si: the SI default that a default
                                      None stands for, which the Scene converts into its units (a key of
                                      the geometry has its SI default as default, converted when read);
                                      both through units.default_in (scaled=False: a scene with units
                                      must give the key)
    Table(keys, make, parts)          a table: make(values by key) builds its object, parts(object) gives the
                                      values back; read(write(x)) == x is the contract (a property test checks it).
                                      keys (and doc) may be a function giving them when used: the keys of the
                                      parts registered then. system(data): the units and dimension (a System)
                                      the defaults are converted into while the table is read (the root's: the
                                      scene's); every read passes it down as an argument
    Tables(table)                     an array of tables ([[chambers]], regions = [{...}, ...]), read as a tuple
    Variant(options, choose)          a tag key (shape = "ellipse") choosing the Table (or the registered
                                      dataclass) of further keys its table has; choose(object) names the
                                      option an object is written as
    Named(registry)                   optional tables named by a registry of dataclasses, in the file's order;
                                      a dataclass's fields are its keys, typed by their annotations (fields_table)

Reading checks every key's type, refuses unknown keys, and prefixes an error a constructor raises with
the table's dotted path (``chambers[1]: ...``).
"""

from __future__ import annotations

import dataclasses
import functools
import types
import typing
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import PneumaInputError, require
from ..io.registry import key_name
from ..io.tomltext import dumps
from ..io.units import UNITLESS, Units, default_in

REQUIRED = object()
TYPE_NAMES = {float: "number", int: "integer", str: "string", bool: "boolean", tuple: "array", list: "array"}
System = tuple[Units, int]  # the units and the dimension a table's defaults are converted into
UNITLESS_2D: System = (UNITLESS, 2)


@dataclass(frozen=True)
class KeyInfo:
    """One row of the key reference. key: dotted, [] for any item of an array of tables (chambers[].center)."""

    key: str
    type: str
    default: str
    allowed: str = ""
    when: str = ""  # the tag choosing the key, e.g. chambers[].shape = "ellipse"
    doc: str = ""
    unit: str = ""  # its dimension (io/units.py), "" none; the default is in SI
    scaled: bool = True  # False: a numerical default, which a scene with units must give


@dataclass(frozen=True)
class Key:
    type: type
    default: object = REQUIRED
    doc: str = ""
    allowed: tuple = ()
    unit: str = ""
    scaled: bool = True
    si: object = None  # the SI default that a default None stands for (units.si_default: the Scene converts it)

    def read(self, data: dict, name: str, path: str, known: set, system: System):
        full = join(path, name)
        if name not in data:
            require(self.default is not REQUIRED, f"missing key '{full}'")
            return self.converted(full, system)
        value = data[name]
        if self.type is float:
            require(
                isinstance(value, (int, float)) and not isinstance(value, bool), f"{full} = {value!r} must be a number"
            )
        else:
            kind = list if self.type is tuple else self.type
            require(
                isinstance(value, kind) and not (kind is int and isinstance(value, bool)),
                f"{full} = {value!r} must be of type {kind.__name__}" + (" (true or false)" if kind is bool else ""),
            )
        require(
            not self.allowed or value in self.allowed,
            f"{full} = {value!r} is not one of {', '.join(map(str, self.allowed))}",
        )
        return freeze(value) if self.type is tuple else value

    def converted(self, full: str, system: System):
        """The default in the units of the table being read (its system; units.default_in), for a key of the
        geometry (which the Scene does not resolve)."""
        if not self.unit or self.default is None:
            return self.default
        return default_in(self.default, self.unit, self.scaled, *system, full)

    def write(self, value, name: str, data: dict) -> None:
        if value is not None:
            data[name] = plain(value)

    def rows(self, path: str, name: str, when: str) -> list[KeyInfo]:
        shown = self.default if self.si is None else self.si
        return [
            KeyInfo(
                join(path, name),
                TYPE_NAMES[self.type],
                default_text(shown),
                ", ".join(map(str, self.allowed)),
                when,
                self.doc,
                self.unit,
                self.scaled,
            )
        ]


@dataclass(frozen=True)
class Table:
    keys: dict | Callable[[], dict]  # name -> entry, or a function giving them when used (the registered parts')
    make: Callable = dict
    parts: Callable = dict
    optional: bool = False  # absent: read as an empty table (every key at its default); empty: not written
    cls: type | None = None  # the class make() builds, by which a Variant knows an object's option
    doc: str | Callable[[], str] = ""
    # A table of kinds that are not a Variant's (the [material]: a preset, a law, or E and nu): kind(data), the
    # keys of the kind its data choose, name -> default (REQUIRED: none); tags, the keys that choose it (one
    # at a time). Editing a tag to another kind drops the old kind's keys (switched).
    kind: Callable | None = None
    tags: tuple = ()
    system: Callable[[dict], System] | None = None

    def entries(self) -> dict:
        """Its keys: name -> entry."""
        return self.keys() if callable(self.keys) else self.keys

    def read(self, data: dict, name: str, path: str, known: set, system: System):
        return self.read_table(data.get(name, {} if self.optional else None), join(path, name), system)

    def read_table(self, data, path: str, system: System = UNITLESS_2D):
        """The object of the table data at path, its defaults in system's units and dimension (this table's own
        system of the data, if it has one)."""
        require(data is not None, f"missing key '{path}'")
        require(isinstance(data, dict), f"{path or 'scene'} must be a table, not {data!r}")
        known: set[str] = set()
        values = read_keys(self.entries(), data, path, known, system if self.system is None else self.system(data))
        unknown = sorted(set(data) - known)
        require(
            not unknown,
            f"unknown key '{join(path, unknown[0]) if unknown else ''}' (allowed here: {', '.join(sorted(known))})",
        )
        return build(path, lambda: self.make(values))

    def write(self, value, name: str, data: dict) -> None:
        table = self.write_table(value)
        if table or not self.optional:  # an optional table with no key is not written: absent reads the same
            data[name] = table

    def write_table(self, obj) -> dict:
        data: dict = {}
        write_keys(self.entries(), self.parts(obj), data)
        return data

    def text(self) -> str:
        """What it is, in words (doc)."""
        return self.doc() if callable(self.doc) else self.doc

    def rows(self, path: str, name: str, when: str) -> list[KeyInfo]:
        key = join(path, name)
        return [KeyInfo(key, "table", "{}" if self.optional else "required", "", when, self.text())] + key_rows(
            self.entries(), key
        )


@dataclass(frozen=True)
class Tables:
    table: Table
    doc: str = ""

    def read(self, data: dict, name: str, path: str, known: set, system: System) -> tuple:
        items = Key(list, []).read(data, name, path, known, system)
        return tuple(self.table.read_table(item, f"{join(path, name)}[{i}]", system) for i, item in enumerate(items))

    def write(self, value, name: str, data: dict) -> None:
        if value:
            data[name] = [self.table.write_table(item) for item in value]

    def rows(self, path: str, name: str, when: str) -> list[KeyInfo]:
        key = join(path, name)
        return [KeyInfo(key, "array of tables", "[]", "", when, self.doc)] + key_rows(self.table.entries(), f"{key}[]")


@dataclass(frozen=True)
class Variant:
    options: dict  # name -> Table, or a registry: name -> dataclass (its fields are the option's keys)
    choose: Callable | None = None  # object -> its option's name; None: the option whose class it is
    default: object = REQUIRED
    doc: str = ""

    def table(self, option: str) -> Table:
        entry = self.options[option]
        return entry if isinstance(entry, Table) else dataclass_table(entry)

    def read(self, data: dict, name: str, path: str, known: set, system: System):
        option = self.table(Key(str, self.default, allowed=tuple(self.options)).read(data, name, path, known, system))
        values = read_keys(option.entries(), data, path, known, system)
        return build(path, lambda: option.make(values))

    def write(self, value, name: str, data: dict) -> None:
        tag = (
            self.choose(value)
            if self.choose
            else next(k for k in self.options if isinstance(value, self.table(k).cls or ()))
        )
        data[name] = tag
        write_keys(self.table(tag).entries(), self.table(tag).parts(value), data)

    def rows(self, path: str, name: str, when: str) -> list[KeyInfo]:
        key = join(path, name)
        rows = [KeyInfo(key, "string", default_text(self.default), ", ".join(self.options), when, self.doc)]
        for option in self.options:
            rows += key_rows(self.table(option).entries(), path, f'{key} = "{option}"')
        return rows


@dataclass(frozen=True)
class Named:
    registry: dict  # name -> dataclass
    doc: str = ""

    def read(self, data: dict, name: str, path: str, known: set, system: System) -> tuple:
        key, tables = join(path, name), data.get(name, {})
        require(isinstance(tables, dict), f"{key} must be a table, not {tables!r}")
        for option in tables:
            require(
                option in self.registry, f"unknown key '{join(key, option)}' (allowed here: {', '.join(self.registry)})"
            )
        return tuple(
            dataclass_table(self.registry[option]).read_table(table, join(key, option), system)
            for option, table in tables.items()
        )

    def write(self, value, name: str, data: dict) -> None:
        names = {cls: option for option, cls in self.registry.items()}
        if value:
            options = [names[type(item)] for item in value]
            data[name] = {o: dataclass_table(self.registry[o]).write_table(item) for o, item in zip(options, value)}

    def rows(self, path: str, name: str, when: str) -> list[KeyInfo]:
        key = join(path, name)
        rows = [KeyInfo(key, "table", "{}", ", ".join(self.registry), when, self.doc)]
        for option, cls in self.registry.items():
            table = dataclass_table(cls)
            rows += [KeyInfo(join(key, option), "table", "none", "", when, table.text())] + key_rows(
                table.entries(), join(key, option)
            )
        return rows


def record(cls, doc: str = "", **keys) -> Table:
    """A table whose keys are fields of the dataclass cls."""
    return Table(
        keys, make=lambda values: cls(**values), parts=lambda obj: {k: getattr(obj, k) for k in keys}, cls=cls, doc=doc
    )


@functools.cache  # a function of the class alone (a memo: nothing to invalidate when parts register)
def dataclass_table(cls) -> Table:
    """The table of the dataclass cls: fields_table(cls)."""
    return fields_table(cls)


def fields_table(cls, **entries) -> Table:
    """A table whose keys are the fields of the dataclass cls (those the constructor takes, but internal() ones,
    io/registry.py), each its field_entry, or the entry given for it in entries (a field whose table depends on
    where it is used: an extrusion's profile); its doc the first paragraph of the class's docstring."""
    hints = typing.get_type_hints(cls)
    fields = [f for f in dataclasses.fields(cls) if f.init and f.metadata.get("key", True)]
    names = {f.name: key_name(f) for f in fields}
    keys = {
        names[f.name]: entries[f.name] if f.name in entries else field_entry(f, hints[f.name], cls.__name__)
        for f in fields
    }
    return Table(
        keys,
        make=lambda values: cls(**{field: values[name] for field, name in names.items()}),
        parts=lambda obj: {name: getattr(obj, field) for field, name in names.items()},
        cls=cls,
        doc=" ".join((cls.__doc__ or "").split("\n\n")[0].split()),
    )


def field_entry(f: dataclasses.Field, hint, owner: str):
    """The entry of the dataclass field f of annotation hint (of the class named owner): an array of tables for a
    tuple of dataclasses (tuple[Rectangle, ...]), else a Key typed by the annotation (float, int, str, bool, tuple,
    list; X | None, a units.si_default field's, as X), its default the field's (key(omitted=...): the value a file
    leaving it out reads), its doc, allowed values, unit and SI default the field's metadata (io/registry.py key)."""
    if isinstance(hint, types.UnionType):
        (hint,) = (arg for arg in typing.get_args(hint) if arg is not type(None))
    kind, args = typing.get_origin(hint) or hint, typing.get_args(hint)
    item = args[0] if kind is tuple and args[1:] == (Ellipsis,) else None
    if isinstance(item, type) and dataclasses.is_dataclass(item):
        return Tables(dataclass_table(item), f.metadata.get("doc", ""))
    if kind not in TYPE_NAMES:
        raise TypeError(f"{owner}.{f.name}: {hint} has no scene-file form")
    default = (
        f.metadata["omitted"]
        if "omitted" in f.metadata
        else f.default
        if f.default is not dataclasses.MISSING
        else f.default_factory()
        if f.default_factory is not dataclasses.MISSING
        else REQUIRED
    )
    return Key(
        kind,
        default,
        f.metadata.get("doc", ""),
        f.metadata.get("allowed", ()),
        unit=f.metadata.get("unit", ""),
        scaled=f.metadata.get("scaled", True),
        si=f.metadata.get("si"),
    )


def read_keys(keys: dict, data: dict, path: str, known: set, system: System) -> dict:
    """The values of keys (and of the keys their variants choose) in the table data at path, their defaults in
    system's units and dimension."""
    known |= set(keys)
    return {name: entry.read(data, name, path, known, system) for name, entry in keys.items()}


def write_keys(keys: dict, values: dict, data: dict) -> None:
    if set(values) != set(keys):
        raise TypeError(f"parts() gave the keys {sorted(values)}; the declaration has {sorted(keys)}")
    for name, entry in keys.items():
        entry.write(values[name], name, data)


def key_rows(keys: dict, path: str, when: str = "") -> list[KeyInfo]:
    return [row for name, entry in keys.items() for row in entry.rows(path, name, when)]


def join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def freeze(value: list) -> tuple:
    """An array as a tuple; an array of arrays as a tuple of tuples, recursively (a mixed one keeps its
    inner lists, which the constructors refuse showing them as written)."""
    return tuple(freeze(v) for v in value) if all(isinstance(v, list) for v in value) else tuple(value)


def plain(value):
    """Tuples to lists and NumPy scalars/arrays to Python numbers, recursively."""
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def build(path: str, make):
    """make(), with a PneumaInputError it raises prefixed with the table's path (unless it names a key in it)."""
    try:
        return make()
    except PneumaInputError as exc:
        if not path or f"{path}." in str(exc):
            raise
        raise PneumaInputError(f"{path}: {exc}") from None


def default_text(default) -> str:
    if default is REQUIRED:
        return "required"
    return "none" if default is None else dumps({"v": plain(default)})[4:].strip()
