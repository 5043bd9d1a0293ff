"""TOML text: a small writer for scene data (dumps: top-level lists of tables as [[key]], dicts as [dotted.key]
tables, everything deeper inline; floats in their shortest exact form), and the reader of text from outside (a
scene file, a --set KEY=VALUE) within limits (read_toml, parse_toml).

Text from outside is read within limits, so that no input makes the readers recurse past Python's stack or take
time quadratic in its length: a dotted key has at most MAX_KEY_PARTS parts (tomllib's cost grows with the square
of a key's parts: one key of 16,000 parts takes 8 s), data nest at most MAX_DEPTH tables and arrays deep, a --set
value has at most MAX_VALUE_CHARS characters and is valid UTF-8 (a byte the terminal could not decode is refused,
not written to a file). The scene format's deepest key has 5 parts (chambers[0].keyframes[1][0]) and 5 levels.
"""

from __future__ import annotations

import json
import re
import tomllib

import numpy as np

from ..errors import PneumaInputError, require

MAX_KEY_PARTS = 16
MAX_DEPTH = 16
MAX_VALUE_CHARS = 100_000
# TOML strings and comments (whose dots are no key's), then a run of MAX_KEY_PARTS dots between key
# parts (bare words or strings): a float or a date has one dot, so such a run is a dotted key
TOML_STRING_OR_COMMENT = re.compile(
    r'"""(?:[^\\]|\\.)*?"""|\'\'\'.*?\'\'\'|"(?:[^"\\\n]|\\.)*"|\'[^\'\n]*\'|#[^\n]*', re.DOTALL
)
TOML_KEY_RUN = re.compile(rf'(?<![\w"-])(?:(?:[\w-]++|"")[ \t]*+\.[ \t]*+){{{MAX_KEY_PARTS}}}')


def dumps(data: dict) -> str:
    """TOML text of nested dicts/lists/str/int/float/bool: top-level lists of tables as [[key]],
    dicts as [dotted.key] tables, everything deeper inline."""
    lines = [f"{_key(k)} = {_value(v)}" for k, v in data.items() if not _is_table(v) and not _is_table_list(v)]
    for k, v in data.items():
        if _is_table(v):
            _table(lines, [k], v)
        elif _is_table_list(v):
            for item in v:
                lines += ["", f"[[{_key(k)}]]"] + [f"{_key(a)} = {_value(b)}" for a, b in item.items()]
    return "\n".join(lines).lstrip("\n") + "\n"


def _table(lines: list, path: list, table: dict) -> None:
    scalars = {k: v for k, v in table.items() if not _is_table(v)}
    if scalars or not table:
        lines += ["", f"[{'.'.join(map(_key, path))}]"] + [f"{_key(k)} = {_value(v)}" for k, v in scalars.items()]
    for k, v in table.items():
        if _is_table(v):
            _table(lines, path + [k], v)


def _is_table(v) -> bool:
    return isinstance(v, dict)


def _is_table_list(v) -> bool:
    return isinstance(v, list) and len(v) > 0 and all(isinstance(x, dict) for x in v)


def _key(k: str) -> str:
    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else _string(k)


def _string(s: str) -> str:
    return json.dumps(s, ensure_ascii=False).replace("\x7f", "\\u007f")


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        require(np.isfinite(v), f"{v!r} cannot be written to a scene file")
        if v != 0 and not 1e-3 <= abs(v) < 1e5:  # 1e+09 rather than 1000000000.0: the shortest exact form
            # (none for a subnormal once Taichi has set flush-to-zero: repr then)
            return next((s for s in (f"{v:.{p}e}" for p in range(17)) if float(s) == v), repr(v))
        return repr(v)
    if isinstance(v, str):
        return _string(v)
    if isinstance(v, list):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"no TOML form for {v!r}")


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
