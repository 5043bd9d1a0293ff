"""A cache of computed arrays on disk, for results that take seconds to make and are a pure function of their
inputs (gmsh meshes: fem/gmsh_mesher.py).

Where: the folder PNEUMA_CACHE_DIR names; set empty or to `off`, no cache is read or written. Unset: the user's
cache folder, as platformdirs finds it: $XDG_CACHE_HOME/taichi-pneuma (default ~/.cache/taichi-pneuma) on
Linux and the BSDs, ~/Library/Caches/taichi-pneuma on macOS, %LOCALAPPDATA%\\taichi-pneuma\\Cache on Windows.

An entry is one .npz file named by its key: the SHA-256 of a canonical text of everything the result depends
on (key()), which names dataclasses by their module and class and writes floats exactly (repr), arrays by dtype,
shape and a hash of their bytes; a value of any other type makes the result uncacheable (key() is None), never
a key that two different inputs could share. The file also holds its key, that canonical text (the key's inputs)
and a content hash: the SHA-256 of the text and of every array's name, dtype, shape and bytes (content_hash). It is
written whole or not at all (output.write_atomic), uncompressed.

Reading never trusts a file. It is opened only if it is a regular file (not blocking: a FIFO, a device or a
folder at an entry's name is a miss, never a hang) of at most its size bound, and read whole into memory before
it is parsed. One that does not load (corrupt, truncated, compressed beyond its size bound, pickled objects),
that holds another key, inputs other than this call's (re-checked as text, not only by their hash), a content
hash that its arrays do not reproduce, or arrays the caller's check refuses (shapes, dtypes, indices in range)
counts as a miss, and the fresh result is written over it. So an entry copied under another entry's name, its
arrays swapped for another valid result's or altered is meshed afresh. The hash is not a signature: whoever can
write the cache folder can write a consistent wrong entry, as they could replace the program; a folder others can
write is not a cache to use (PNEUMA_CACHE_DIR=off). A cache that cannot be written (read-only, disk full) is
skipped silently: it only ever saves time.
"""

from __future__ import annotations

import dataclasses
import enum
import hashlib
import io
import os
import sys
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import PneumaInputError
from .inputs import read_input
from .output import write_atomic

VARIABLE = "PNEUMA_CACHE_DIR"
OFF = ("", "off")
APP = "taichi-pneuma"
KEY = "__key__"  # the array holding the entry's key
INPUTS = "__inputs__"  # ... the canonical text of its inputs
HASH = "__sha256__"  # ... and its content hash
OVERHEAD = 2**16  # bytes of an entry beyond its arrays and its inputs' text: the zip's and the arrays' headers


def directory() -> Path | None:
    """The cache folder (module docstring), or None when PNEUMA_CACHE_DIR turns the cache off."""
    chosen = os.environ.get(VARIABLE)
    if chosen is not None:
        return None if chosen.strip().lower() in OFF else Path(chosen).expanduser()
    if sys.platform == "win32":
        return Path(os.environ.get("LOCALAPPDATA") or Path.home() / "AppData" / "Local") / APP / "Cache"
    if sys.platform == "darwin":
        return Path.home() / "Library" / "Caches" / APP
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / APP


class Uncacheable(TypeError):
    """A value canonical() has no exact text for."""


def canonical(value) -> str:
    """An exact text of a value built of dataclasses, enums, tuples, lists, dicts, str, bool, int, float, None
    and NumPy arrays and scalars; Uncacheable for anything else."""
    kind = type(value)
    if value is None or kind in (bool, int, str):
        return repr(value)
    if kind is float:
        return repr(value)  # the shortest text that reads back to the same double
    if isinstance(value, np.generic):
        return canonical(value.item())
    if isinstance(value, np.ndarray):
        data = np.ascontiguousarray(value)
        if data.dtype.hasobject:
            return canonical(data.tolist())
        return f"array({data.dtype.str},{data.shape},{hashlib.sha256(data.tobytes()).hexdigest()})"
    if isinstance(value, enum.Enum):
        return f"{kind.__module__}.{kind.__qualname__}.{value.name}"
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = ",".join(f"{f.name}={canonical(getattr(value, f.name))}" for f in dataclasses.fields(value))
        return f"{kind.__module__}.{kind.__qualname__}({fields})"
    if kind in (tuple, list):
        return "(" + ",".join(canonical(v) for v in value) + ")"
    if kind is dict:
        return "{" + ",".join(f"{canonical(k)}:{canonical(v)}" for k, v in sorted(value.items(), key=repr)) + "}"
    raise Uncacheable(f"no exact text for a {kind.__qualname__}")


class Key(str):
    """An entry's name, the SHA-256 (hex) of `text`, the canonical text of its inputs, which it carries."""

    text: str

    def __new__(cls, text: str) -> Key:
        name = super().__new__(cls, hashlib.sha256(text.encode()).hexdigest())
        name.text = text
        return name


def key(*parts) -> Key | None:
    """The Key of the parts' canonical text; None if a part has none (the result is then not cached)."""
    try:
        return Key(canonical(parts))
    except Uncacheable:
        return None


def content_hash(text: str, arrays: dict[str, np.ndarray]) -> str:
    """The SHA-256 (hex) of the inputs' text, then of each array in the order of their names: its name, dtype,
    shape and bytes (C order)."""
    digest = hashlib.sha256(text.encode())
    for name in sorted(arrays):
        data = np.ascontiguousarray(arrays[name])
        digest.update(f"\0{name}\0{data.dtype.str}\0{data.shape}\0".encode())
        digest.update(data.tobytes())
    return digest.hexdigest()


def path_of(kind: str, entry: str) -> Path | None:
    folder = directory()
    return None if folder is None else folder / f"{kind}-{entry}.npz"


def load(kind: str, entry: Key | None, check, max_bytes: int) -> dict[str, np.ndarray] | None:
    """The arrays of the entry if the cache holds it as a regular file, it loads cleanly within max_bytes of arrays
    (uncompressed, no pickles), holds this key and these inputs, its content hash is that of its arrays and
    check(arrays) is true; else None (a miss)."""
    path = None if entry is None else path_of(kind, entry)
    if path is None or entry is None:
        return None
    bound = max_bytes + 4 * len(entry.text) + OVERHEAD  # NumPy stores text as UTF-32
    try:
        data = read_input(path, bound, "cache entry")  # a regular file, opened without blocking, read within bound
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            if sum(info.file_size for info in archive.infolist()) > bound:
                return None
        with np.load(io.BytesIO(data), allow_pickle=False) as stored:
            arrays = {name: stored[name] for name in stored.files}
    except Exception:  # not a regular file, too large, unreadable, not an npz, pickled, truncated: a miss
        return None
    told = [arrays.pop(name, None) for name in (KEY, INPUTS, HASH)]
    if any(t is None or t.shape != () or t.dtype.kind != "U" for t in told):
        return None
    stored_key, inputs, stored_hash = (str(t) for t in told)
    if stored_key != entry or inputs != entry.text or stored_hash != content_hash(inputs, arrays):
        return None
    try:
        return arrays if check(arrays) else None
    except (KeyError, IndexError, ValueError, TypeError):  # a check reading a missing or ill-shaped array
        return None


def store(kind: str, entry: Key | None, arrays: dict[str, np.ndarray]) -> None:
    """Write the entry (atomically), with its key, its inputs' text and its content hash; do nothing if the cache
    is off or cannot be written."""
    path = None if entry is None else path_of(kind, entry)
    if path is None or entry is None:
        return
    told = {KEY: np.array(str(entry)), INPUTS: np.array(entry.text), HASH: np.array(content_hash(entry.text, arrays))}

    def write(tmp: Path) -> None:
        with open(tmp, "wb") as f:
            named: dict[str, Any] = {**arrays, **told}  # (NumPy's stubs read any keyword as savez's allow_pickle)
            np.savez(f, **named)

    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_atomic(path, write)
    except (OSError, PneumaInputError):
        pass
