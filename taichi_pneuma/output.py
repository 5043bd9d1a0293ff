"""Result files written whole or not at all: write to a temporary name beside the target, then rename."""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

import numpy as np

from .errors import PneumaInputError


def prepare_directory(path: str | os.PathLike) -> Path:
    """Create the output directory if needed and check it is writable; raise naming it otherwise."""
    directory = Path(path)
    try:
        directory.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=directory):
            pass
    except OSError as exc:
        raise PneumaInputError(f"output directory {str(directory)!r} is not writable ({exc.strerror})") from None
    return directory


def write_atomic(path: Path, write) -> Path:
    """Call write(tmp_path) and rename tmp_path to path only if it returns without error."""
    tmp = path.with_name(f".{path.name}.partial{path.suffix}")
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


def save_text(path: Path, text: str) -> Path:
    return write_atomic(path, lambda tmp: tmp.write_text(text))


def save_json(path: Path, data: dict) -> Path:
    return save_text(path, json.dumps(data, indent=2) + "\n")


def save_npz(path: Path, **arrays) -> Path:
    def write(tmp: Path) -> None:
        with open(tmp, "wb") as f:
            np.savez_compressed(f, **arrays)

    return write_atomic(path, write)
