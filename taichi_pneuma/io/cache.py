"""A cache of computed arrays on disk, for results that take seconds to make and are a pure function of their
inputs (gmsh meshes: fem/gmsh_mesher.py).

Where: the folder PNEUMA_CACHE_DIR names; set empty or to `off`, no cache is read or written. Unset: the user's
cache folder, as platformdirs finds it: $XDG_CACHE_HOME/taichi-pneuma (default ~/.cache/taichi-pneuma) on
Linux and the BSDs, ~/Library/Caches/taichi-pneuma on macOS, %LOCALAPPDATA%\\taichi-pneuma\\Cache on Windows.

An entry is one .npz file named by its key: the SHA-256 of a canonical text of everything the result depends
on (key()), which names dataclasses by their module and class and writes floats exactly (repr), arrays by dtype,
shape and a hash of their bytes; a value of any other type makes the result uncacheable (key() is None), never
a key that two different inputs could share. The file also holds its key, and is written whole or not at all
(output.write_atomic), uncompressed. Reading never trusts a file: one that does not load (corrupt, truncated,
compressed beyond its size bound, pickled objects), that holds another key, or whose arrays the caller's check
refuses (shapes, dtypes, indices in range) counts as a miss, and the fresh result is written over it. A cache
that cannot be written (read-only, disk full) is skipped silently: it only ever saves time.
"""

from __future__ import annotations

import dataclasses
import enum
import hashlib
import os
import sys
import zipfile
from pathlib import Path

import numpy as np

from ..errors import PneumaInputError
from .output import write_atomic

VARIABLE = "PNEUMA_CACHE_DIR"
OFF = ("", "off")
APP = "taichi-pneuma"
KEY = "__key__"  # the array holding the entry's key


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


def key(*parts) -> str | None:
    """The SHA-256 (hex) of the parts' canonical text; None if a part has none (the result is then not cached)."""
    try:
        text = canonical(parts)
    except Uncacheable:
        return None
    return hashlib.sha256(text.encode()).hexdigest()


def path_of(kind: str, entry: str) -> Path | None:
    folder = directory()
    return None if folder is None else folder / f"{kind}-{entry}.npz"


def load(kind: str, entry: str | None, check, max_bytes: int) -> dict[str, np.ndarray] | None:
    """The arrays of the entry if the cache holds it, loads cleanly within max_bytes (uncompressed, no pickles),
    holds this key and check(arrays) is true; else None (a miss)."""
    path = None if entry is None else path_of(kind, entry)
    if path is None:
        return None
    try:
        with zipfile.ZipFile(path) as archive:
            if sum(info.file_size for info in archive.infolist()) > max_bytes:
                return None
        with np.load(path, allow_pickle=False) as stored:
            arrays = {name: stored[name] for name in stored.files}
    except Exception:  # missing, unreadable, not an npz, a pickled object, a truncated member: a miss
        return None
    stored_key = arrays.pop(KEY, None)
    if stored_key is None or stored_key.shape != () or str(stored_key) != entry:
        return None
    try:
        return arrays if check(arrays) else None
    except (KeyError, IndexError, ValueError, TypeError):  # a check reading a missing or ill-shaped array
        return None


def store(kind: str, entry: str | None, arrays: dict[str, np.ndarray]) -> None:
    """Write the entry (atomically); do nothing if the cache is off or cannot be written."""
    path = None if entry is None else path_of(kind, entry)
    if path is None:
        return

    def write(tmp: Path) -> None:
        with open(tmp, "wb") as f:
            # NumPy's stubs take any keyword for savez's allow_pickle
            np.savez(f, **arrays, **{KEY: np.array(entry)})  # type: ignore[arg-type]

    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_atomic(path, write)
    except (OSError, PneumaInputError):
        pass
