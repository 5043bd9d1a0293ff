"""Editing a file format's data by dotted keys (chambers[0].center[1] = 0.1): a copy of an object with some keys
set, read back through its declaration (scene/fileformat.py), so that an edit is validated as a file is; switching
a kind's tag drops the old kind's keys. The values come from --set KEY=VALUE text, read as TOML values within
io/tomltext.py's limits (a key has at most MAX_KEY_PARTS parts; the scene format's deepest has 5).
"""

from __future__ import annotations

import re
import tomllib

from ..errors import PneumaInputError, require
from ..io.tomltext import MAX_KEY_PARTS, MAX_VALUE_CHARS, read_toml
from .fileformat import REQUIRED, Key, Table, Tables, Variant, plain

KEY_PART = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)")


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
    entry = table_entries(table.entries(), node).get(name)
    if isinstance(entry, Variant) and not rest:
        old = node.get(name, entry.default)
        if old != value and old in entry.options and isinstance(value, str) and value in entry.options:
            keys = table_entries(entry.table(old).entries(), node)
            drop_kind(
                node,
                {k: e.default if isinstance(e, Key) else REQUIRED for k, e in keys.items()},
                table_entries(entry.table(value).entries(), {}),
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
            entries.update(table_entries(entry.table(option).entries(), data))
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
