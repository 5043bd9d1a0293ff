"""A small TOML writer for scene data: top-level lists of tables as [[key]], dicts as [dotted.key] tables,
everything deeper inline; floats in their shortest exact form."""

from __future__ import annotations

import json
import re

import numpy as np

from ..errors import require


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
