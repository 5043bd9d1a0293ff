"""Targets of inverse control: a tip point (optionally a tip rotation) to reach, each with a weight.

The tip point is the mean of the tip vertices (as in inflate's tip deflection), in scene
coordinates: (x, y), or (x, y, z) on a 3D body (an (x, y) target there leaves z free); the rotation
is their least-squares rigid rotation in the x-y plane (in 3D about the bending axis z), in degrees,
counter-clockwise. A list of targets comes from a scene file's [[targets]] tables or from a CSV file
with a header naming the columns x, y and, optionally, z, angle, wx, wy, wz, wangle (weights; an
empty z or angle cell leaves that free). A list has at most MAX_TARGETS targets (each is a reach:
seconds of solves), and a targets file is read only if it is a regular file, and at most
MAX_TARGETS_BYTES of it.
"""

from __future__ import annotations

import csv
import io
import itertools
import os
from dataclasses import dataclass

from ..errors import PneumaInputError, parse_number, require, require_finite
from ..io.inputs import read_input

COLUMNS = ("x", "y", "z", "angle", "wx", "wy", "wz", "wangle")
MAX_TARGETS = 1000
MAX_TARGETS_BYTES = 1_000_000


@dataclass(frozen=True)
class Target:
    """tip: (x, y) or, on a 3D body, (x, y, z) to reach; angle: tip rotation in degrees, or None to leave it
    free; weights: (w_x, w_y, w_angle) >= 0 of the errors in the least-squares objective; weight_z: w_z >= 0,
    that of the z error of an (x, y, z) tip."""

    tip: tuple[float, ...]
    angle: float | None = None
    weights: tuple[float, float, float] = (1.0, 1.0, 1.0)
    weight_z: float = 1.0

    def __post_init__(self):
        require(len(self.tip) in (2, 3), f"target tip = {list(self.tip)!r} must be [x, y] or [x, y, z]")
        object.__setattr__(self, "tip", tuple(require_finite("target tip", v) for v in self.tip))
        if self.angle is not None:
            object.__setattr__(self, "angle", require_finite("target angle", self.angle))
        require(len(self.weights) == 3, f"target weights = {list(self.weights)!r} must be [w_x, w_y, w_angle]")
        weights = tuple(require_finite("target weight", w) for w in self.weights)
        require(
            all(w >= 0 for w in weights) and (weights[0] > 0 or weights[1] > 0),
            f"target weights = {list(self.weights)!r} must be >= 0, w_x or w_y > 0",
        )
        object.__setattr__(self, "weights", weights)
        require(
            require_finite("target weight", self.weight_z) >= 0, f"target weight_z = {self.weight_z!r} must be >= 0"
        )


def read_targets_csv(path: str | os.PathLike) -> list[Target]:
    """Targets, one per row of a CSV file with a header (x, y required; z, angle, wx, wy, wz, wangle optional)."""
    try:
        lines = io.StringIO(read_input(path, MAX_TARGETS_BYTES, "targets file").decode("utf-8"), newline="")
        rows = list(itertools.islice(csv.DictReader(lines), MAX_TARGETS + 1))
        header = rows[0].keys() if rows else []
    except (csv.Error, UnicodeDecodeError) as exc:
        raise PneumaInputError(f"{path}: not a CSV file ({exc})") from None
    require(rows, f"{path}: no targets (a header line x,y[,angle,...] and one row per target)")
    require(
        len(rows) <= MAX_TARGETS,
        f"{path}: more than {MAX_TARGETS} targets; at most {MAX_TARGETS} are allowed (each is a reach)",
    )
    unknown = sorted(set(header) - set(COLUMNS), key=str)
    require(
        not unknown and {"x", "y"} <= set(header),
        f"{path}: columns {list(header)!r} must include x and y and be among {', '.join(COLUMNS)}",
    )
    targets = []
    for i, row in enumerate(rows, start=2):
        try:

            def cell(key, default=None, row=row):
                """The row's number in column key; default where the cell is empty."""
                return default if not (row.get(key) or "").strip() else parse_number(key, row[key])

            z = cell("z")
            targets.append(
                Target(
                    (cell("x"), cell("y")) + (() if z is None else (z,)),
                    cell("angle"),
                    (cell("wx", 1.0), cell("wy", 1.0), cell("wangle", 1.0)),
                    cell("wz", 1.0),
                )
            )
        except PneumaInputError as exc:
            raise PneumaInputError(f"{path}, line {i}: {exc}") from None
    return targets
