"""The files shipped inside the package (taichi_pneuma/scenes/: scene files and a targets CSV), found by name.

A path that exists is used as it is (or with the suffix added: `x` for `x.toml`); otherwise a bare name
(`pneunet_finger` or `pneunet_finger.toml`, no directory part) is looked up among the shipped files, so
`tp.load_scene("pneunet_finger")` and `--scene pneunet_finger` work from any directory, in a clone or an installed
wheel.
"""

from __future__ import annotations

import os
import re
import tomllib
from pathlib import Path

from ..errors import PneumaInputError, quoted

SHIPPED = Path(__file__).resolve().parent.parent / "scenes"


def shipped(suffix: str = ".toml") -> list[str]:
    """The names of the shipped files with this suffix, without it."""
    return sorted(p.stem for p in SHIPPED.glob(f"*{suffix}"))


def listing(width: int = 100) -> str:
    """Every shipped scene, a line each: its name and the first sentence of its description, cut at a word to at
    most `width` characters ('...' where cut)."""
    rows = []
    for name in shipped():
        text = " ".join(str(tomllib.loads((SHIPPED / f"{name}.toml").read_text()).get("description", "")).split())
        first = re.split(r"(?<! al)\. ", text)[0].rstrip(".")
        if len(first) > width:
            first = first[: width - 3].rsplit(" ", 1)[0].rstrip(",;:") + "..."
        rows.append(f"{name:<20} {first}")
    return "\n".join(rows)


def find(name: str | os.PathLike, suffix: str = ".toml", what: str = "scene file") -> Path:
    """The file `name` names: itself if it exists (or with the suffix added), else the shipped file of that
    bare name (the suffix optional); PneumaInputError naming it and the shipped names otherwise."""
    path = Path(name)
    try:
        if path.exists():
            return path
        if path.suffix != suffix and path.with_name(f"{path.name}{suffix}").is_file():
            return path.with_name(f"{path.name}{suffix}")
    except OSError as exc:  # a name too long for the file system, ...
        raise PneumaInputError(f"{what} {quoted(name)} cannot be read ({exc.strerror})") from None
    if path.parent == Path("."):
        for candidate in (SHIPPED / path.name, SHIPPED / f"{path.name}{suffix}"):
            if candidate.suffix == suffix and candidate.is_file():
                return candidate
    raise PneumaInputError(
        f"{what} {quoted(name)} cannot be read (no such file, and none of that name ships with "
        f"the package: {', '.join(shipped(suffix))})"
    )
