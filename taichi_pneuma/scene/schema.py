"""A file format declared once: from one tree of entries come reading (data -> objects, every error naming
its dotted key), writing (objects -> data), editing by dotted keys and the key reference.

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
                                      system(data): the units and dimension the defaults are converted into
                                      while the table is read (the root's: the scene's)
    Tables(table)                     an array of tables ([[chambers]], regions = [{...}, ...]), read as a tuple
    Variant(options, choose)          a tag key (shape = "ellipse") choosing the Table (or the registered
                                      dataclass) of further keys its table has; choose(object) names the
                                      option an object is written as
    Named(registry)                   optional tables named by a registry of dataclasses, in the file's order;
                                      a dataclass's fields are its keys, typed by their annotations

Reading checks every key's type, refuses unknown keys, and prefixes an error a constructor raises with
the table's dotted path (``chambers[1]: ...``).

Text from outside (a scene file, a --set KEY=VALUE) is read within limits, so that no input makes the
readers recurse past Python's stack or take time quadratic in its length: a dotted key has at most
MAX_KEY_PARTS parts (tomllib's cost grows with the square of a key's parts: one key of 16,000 parts takes
8 s), data nest at most MAX_DEPTH tables and arrays deep, a --set value has at most MAX_VALUE_CHARS
characters and is valid UTF-8 (a byte the terminal could not decode is refused, not written to a file).
The scene format's deepest key has 5 parts (chambers[0].keyframes[1][0]) and 5 levels.
"""

from __future__ import annotations

import contextvars
import dataclasses
import functools
import re
import tomllib
import types
import typing
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import PneumaInputError, require
from ..io.tomltext import dumps
from ..io.units import UNITLESS, Units, default_in

REQUIRED = object()
KEY_PART = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)")
MAX_KEY_PARTS = 16
MAX_DEPTH = 16
MAX_VALUE_CHARS = 100_000
# TOML strings and comments (whose dots are no key's), then a run of MAX_KEY_PARTS dots between key
# parts (bare words or strings): a float or a date has one dot, so such a run is a dotted key
TOML_STRING_OR_COMMENT = re.compile(
    r'"""(?:[^\\]|\\.)*?"""|\'\'\'.*?\'\'\'|"(?:[^"\\\n]|\\.)*"|\'[^\'\n]*\'|#[^\n]*', re.DOTALL
)
TOML_KEY_RUN = re.compile(rf'(?<![\w"-])(?:(?:[\w-]++|"")[ \t]*+\.[ \t]*+){{{MAX_KEY_PARTS}}}')
TYPE_NAMES = {float: "number", int: "integer", str: "string", bool: "boolean", tuple: "array", list: "array"}
SYSTEM = contextvars.ContextVar("SYSTEM", default=(UNITLESS, 2))  # (units, dim) the defaults read are in


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

    def read(self, data: dict, name: str, path: str, known: set):
        full = join(path, name)
        if name not in data:
            require(self.default is not REQUIRED, f"missing key '{full}'")
            return self.converted(full)
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

    def converted(self, full: str):
        """The default in the units of the table being read (SYSTEM; units.default_in), for a key of the geometry
        (which the Scene does not resolve)."""
        if not self.unit or self.default is None:
            return self.default
        return default_in(self.default, self.unit, self.scaled, *SYSTEM.get(), full)

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
    keys: dict
    make: Callable = dict
    parts: Callable = dict
    optional: bool = False  # absent: read as an empty table (every key at its default); empty: not written
    cls: type | None = None  # the class make() builds, by which a Variant knows an object's option
    doc: str = ""
    # A table of kinds that are not a Variant's (the [material]: a preset, a law, or E and nu): kind(data), the
    # keys of the kind its data choose, name -> default (REQUIRED: none); tags, the keys that choose it (one
    # at a time). Editing a tag to another kind drops the old kind's keys (switched).
    kind: Callable | None = None
    tags: tuple = ()
    system: Callable[[dict], tuple[Units, int]] | None = None

    def read(self, data: dict, name: str, path: str, known: set):
        return self.read_table(data.get(name, {} if self.optional else None), join(path, name))

    def read_table(self, data, path: str):
        require(data is not None, f"missing key '{path}'")
        require(isinstance(data, dict), f"{path or 'scene'} must be a table, not {data!r}")
        if self.system is None:
            return self.read_values(data, path)
        token = SYSTEM.set(self.system(data))
        try:
            return self.read_values(data, path)
        finally:
            SYSTEM.reset(token)

    def read_values(self, data: dict, path: str):
        known: set[str] = set()
        values = read_keys(self.keys, data, path, known)
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
        write_keys(self.keys, self.parts(obj), data)
        return data

    def rows(self, path: str, name: str, when: str) -> list[KeyInfo]:
        key = join(path, name)
        return [KeyInfo(key, "table", "{}" if self.optional else "required", "", when, self.doc)] + key_rows(
            self.keys, key
        )


@dataclass(frozen=True)
class Tables:
    table: Table
    doc: str = ""

    def read(self, data: dict, name: str, path: str, known: set) -> tuple:
        items = Key(list, []).read(data, name, path, known)
        return tuple(self.table.read_table(item, f"{join(path, name)}[{i}]") for i, item in enumerate(items))

    def write(self, value, name: str, data: dict) -> None:
        if value:
            data[name] = [self.table.write_table(item) for item in value]

    def rows(self, path: str, name: str, when: str) -> list[KeyInfo]:
        key = join(path, name)
        return [KeyInfo(key, "array of tables", "[]", "", when, self.doc)] + key_rows(self.table.keys, f"{key}[]")


@dataclass(frozen=True)
class Variant:
    options: dict  # name -> Table, or a registry: name -> dataclass (its fields are the option's keys)
    choose: Callable | None = None  # object -> its option's name; None: the option whose class it is
    default: object = REQUIRED
    doc: str = ""

    def table(self, option: str) -> Table:
        entry = self.options[option]
        return entry if isinstance(entry, Table) else dataclass_table(entry)

    def read(self, data: dict, name: str, path: str, known: set):
        option = self.table(Key(str, self.default, allowed=tuple(self.options)).read(data, name, path, known))
        values = read_keys(option.keys, data, path, known)
        return build(path, lambda: option.make(values))

    def write(self, value, name: str, data: dict) -> None:
        tag = (
            self.choose(value) if self.choose else next(k for k in self.options if isinstance(value, self.table(k).cls))  # type: ignore[arg-type]
        )
        data[name] = tag
        write_keys(self.table(tag).keys, self.table(tag).parts(value), data)

    def rows(self, path: str, name: str, when: str) -> list[KeyInfo]:
        key = join(path, name)
        rows = [KeyInfo(key, "string", default_text(self.default), ", ".join(self.options), when, self.doc)]
        for option in self.options:
            rows += key_rows(self.table(option).keys, path, f'{key} = "{option}"')
        return rows


@dataclass(frozen=True)
class Named:
    registry: dict  # name -> dataclass
    doc: str = ""

    def read(self, data: dict, name: str, path: str, known: set) -> tuple:
        key, tables = join(path, name), data.get(name, {})
        require(isinstance(tables, dict), f"{key} must be a table, not {tables!r}")
        for option in tables:
            require(
                option in self.registry, f"unknown key '{join(key, option)}' (allowed here: {', '.join(self.registry)})"
            )
        return tuple(
            dataclass_table(self.registry[option]).read_table(table, join(key, option))
            for option, table in tables.items()
        )

    def write(self, value, name: str, data: dict) -> None:
        names = {cls: option for option, cls in self.registry.items()}
        if value:
            data[name] = {
                names[type(item)]: dataclass_table(type(item)).write_table(item)  # type: ignore[arg-type]
                for item in value
            }

    def rows(self, path: str, name: str, when: str) -> list[KeyInfo]:
        key = join(path, name)
        rows = [KeyInfo(key, "table", "{}", ", ".join(self.registry), when, self.doc)]
        for option, cls in self.registry.items():
            table = dataclass_table(cls)
            rows += [KeyInfo(join(key, option), "table", "none", "", when, table.doc)] + key_rows(
                table.keys, join(key, option)
            )
        return rows


def record(cls, doc: str = "", **keys) -> Table:
    """A table whose keys are fields of the dataclass cls."""
    return Table(
        keys, make=lambda values: cls(**values), parts=lambda obj: {k: getattr(obj, k) for k in keys}, cls=cls, doc=doc
    )


@functools.cache
def dataclass_table(cls) -> Table:
    """A table of every field of the dataclass cls, typed by its annotation (float, int, str, bool, tuple, list;
    X | None, a units.si_default field's, as X)."""
    hints = typing.get_type_hints(cls)
    keys = {}
    for f in dataclasses.fields(cls):
        hint = hints[f.name]
        if isinstance(hint, types.UnionType):
            (hint,) = (arg for arg in typing.get_args(hint) if arg is not type(None))
        kind = typing.get_origin(hint) or hint
        if kind not in TYPE_NAMES:
            raise TypeError(f"{cls.__name__}.{f.name}: {hints[f.name]} has no scene-file form")
        default = (
            f.default
            if f.default is not dataclasses.MISSING
            else f.default_factory()
            if f.default_factory is not dataclasses.MISSING
            else REQUIRED
        )
        keys[f.name] = Key(
            kind,
            default,
            unit=f.metadata.get("unit", ""),
            scaled=f.metadata.get("scaled", True),
            si=f.metadata.get("si"),
        )
    return record(cls, " ".join((cls.__doc__ or "").split("\n\n")[0].split()), **keys)


def read_keys(keys: dict, data: dict, path: str, known: set) -> dict:
    """The values of keys (and of the keys their variants choose) in the table data at path."""
    known |= set(keys)
    return {name: entry.read(data, name, path, known) for name, entry in keys.items()}


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


# --- editing by dotted keys ---


def edited(root: Table, obj, values: dict, replaced: dict | None = None):
    """A copy of obj with the dotted keys of `values` set in its data, read back (validated) through root;
    a bad key or value raises one PneumaInputError naming the key. A value that switches a Variant's tag
    (chambers[0].control = "pressure"), or one of a table's tags (material.law, material.preset), first drops the
    old kind's keys (switched), then every value is set: a key of the old kind set in the same edit is kept,
    and refused if the new kind lacks it. A value None unsets its key (its default, or nothing). replaced: a key's
    pattern (indices as []) -> the name of its sibling that it replaces (two ways to give one thing), dropped where
    the key is set and the sibling is not."""
    data = root.write_table(obj)
    for key in values:
        other = (replaced or {}).get(re.sub(r"\[\d+\]", "[]", key))
        sibling = f"{key.rpartition('.')[0]}.{other}" if other else None
        if sibling is not None and sibling not in values:
            set_key(data, sibling, None)
    for key, value in values.items():
        switched(root, data, parse_key(key), plain(value))
    for key, value in values.items():
        set_key(data, key, plain(value))
    try:
        return root.read_table(data, "")
    except PneumaInputError as exc:
        message = str(exc)
        if not any(key in message for key in values):
            message = f"{', '.join(f'{k} = {v!r}' for k, v in values.items())}: {message}"
        raise PneumaInputError(message) from None


def switched(table: Table, node, parts: list, value) -> None:
    """If parts (a parsed dotted key) names, through tables and arrays of tables, a key that switches the kind
    of its table node to another (a Variant's tag, or one of its table's tags, the others then unset): drop
    from node the keys of the old kind that the new one lacks or that hold the old kind's default (keys the
    user did not choose for the new kind, written out only because every key is)."""
    if not isinstance(node, dict) or not parts or not isinstance(parts[0], str):
        return
    name, rest = parts[0], parts[1:]
    entry = table_entries(table.keys, node).get(name)
    if isinstance(entry, Variant) and not rest:
        old = node.get(name, entry.default)
        if old != value and old in entry.options and isinstance(value, str) and value in entry.options:
            keys = table_entries(entry.table(old).keys, node)
            drop_kind(
                node,
                {k: e.default if isinstance(e, Key) else REQUIRED for k, e in keys.items()},
                table_entries(entry.table(value).keys, {}),
            )
    elif name in table.tags and not rest:
        assert table.kind is not None  # a table with tags has a kind
        old = table.kind(node)
        new = table.kind({**{k: v for k, v in node.items() if k not in table.tags}, name: value})
        if set(old) != set(new):
            drop_kind(node, old, new)
    elif isinstance(entry, Table):
        switched(entry, node.get(name), rest, value)
    elif isinstance(entry, Tables) and rest and isinstance(rest[0], int) and rest[0] < len(node.get(name) or ()):
        switched(entry.table, node[name][rest[0]], rest[1:], value)


def drop_kind(node: dict, old: dict, new) -> None:
    """Drop from node each key of the old kind (name -> its default, REQUIRED: none) that the new kind (its key
    names) lacks or that holds its old default."""
    for key, default in old.items():
        if key not in new or (default is not REQUIRED and key in node and node[key] == plain(default)):
            node.pop(key, None)


def table_entries(keys: dict, data: dict) -> dict:
    """The entries of a table's data: keys, and the keys of the option each Variant among them chooses there."""
    entries = dict(keys)
    for name, entry in keys.items():
        option = data.get(name, entry.default) if isinstance(entry, Variant) else None
        if isinstance(option, str) and option in entry.options:
            entries.update(table_entries(entry.table(option).keys, data))
    return entries


def parse_key(key: str) -> list:
    """'chambers[0].center[1]' -> ['chambers', 0, 'center', 1]; at most MAX_KEY_PARTS parts."""
    require(
        key.count(".") + key.count("[") < MAX_KEY_PARTS,
        f"the key {key[:40]!r}... has more than {MAX_KEY_PARTS} parts: no scene key is that deep",
    )
    parts = []
    for segment in key.split("."):
        match = KEY_PART.fullmatch(segment)
        if match is None:
            raise PneumaInputError(f"{key!r} is not a dotted scene key (like material.E or chambers[0].center[1])")
        parts.append(match.group(1))
        parts += [int(i) for i in re.findall(r"\[(\d+)\]", match.group(2))]
    return parts


def set_key(data: dict, key: str, value) -> None:
    """Set a dotted key in nested data; missing tables on the way are created (e.g. a new effect); None unsets it
    (a key of a table: removed, if there)."""
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
        if last and value is None and isinstance(node, dict):
            node.pop(part, None)
        elif last:
            node[part] = value
        else:
            node = node[part]


def parse_assignment(text: str) -> tuple[str, object]:
    """'KEY=VALUE' -> (key, parse_value(VALUE))."""
    key, sep, raw = text.partition("=")
    require(bool(sep) and key.strip(), f"--set {text[:100]!r} must look like KEY=VALUE (e.g. material.E=2e4)")
    return key.strip(), parse_value(raw, f"--set {key.strip()[:40]}")


def parse_value(raw: str, what: str):
    """A value as TOML reads it (1e4, true, [0, 0.1], "x"), else the text (stripped) as a string; refused
    (naming `what`) past MAX_VALUE_CHARS characters, past the limits of read_toml, or not valid UTF-8."""
    require(
        len(raw) <= MAX_VALUE_CHARS,
        f"{what}: the value has {len(raw)} characters; at most {MAX_VALUE_CHARS} are allowed",
    )
    try:
        raw.encode("utf-8")
    except UnicodeEncodeError:
        raise PneumaInputError(
            f"{what}: {raw[:60]!r} is not valid UTF-8 (bytes the terminal could not decode)"
        ) from None
    try:
        return read_toml(f"v = {raw.strip()}", what)["v"]
    except tomllib.TOMLDecodeError:
        return raw.strip()


def nested_past(data, depth: int) -> bool:
    """Whether tables and arrays nest in data deeper than depth (iteratively: no recursion)."""
    stack = [(data, 0)]
    while stack:
        node, level = stack.pop()
        children = node.values() if isinstance(node, dict) else node if isinstance(node, (list, tuple)) else None
        if children is not None:
            if level >= depth:
                return True
            stack.extend((child, level + 1) for child in children)
    return False


def read_toml(text: str, what: str) -> dict:
    """tomllib.loads(text) within the limits of the module docstring (PneumaInputError naming `what` past
    them); text that is not TOML raises tomllib.TOMLDecodeError."""
    stripped = TOML_STRING_OR_COMMENT.sub(lambda m: "" if m.group().startswith("#") else '""', text)
    require(
        TOML_KEY_RUN.search(stripped) is None,
        f"{what}: a dotted key of more than {MAX_KEY_PARTS} parts (the scene format has none deeper than 5)",
    )
    try:
        data = tomllib.loads(text)
    except RecursionError:
        data = None
    if data is None or nested_past(data, MAX_DEPTH):
        raise PneumaInputError(f"{what}: arrays or tables nested too deeply (at most {MAX_DEPTH} levels)")
    return data


def parse_toml(text: str, what: str) -> dict:
    """read_toml(text, what), text that is not TOML a PneumaInputError too (naming `what` and tomllib's reason)."""
    try:
        return read_toml(text, what)
    except tomllib.TOMLDecodeError as exc:
        raise PneumaInputError(f"{what}: not valid TOML ({exc})") from None
