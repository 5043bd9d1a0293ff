"""The keys a study varies: `--vary KEY=start:stop:count` or `KEY=v1,v2,...` parsed to an Axis, checked against the
base scene, and the runs planned over the axes: every combination (a full grid) or the points of a seeded Latin
hypercube, without repeats.

    axes = check_axes(scene, [parse_vary("chambers[0].center[1]=-0.15:0.15:3"), parse_vary("E=1e4,2e4")])
    runs = plan(axes)            # [{"chambers[0].center[1]": -0.15, "material.E": 10000.0}, ...]
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.stats import qmc

from .. import limits
from ..errors import PneumaInputError, require, require_finite
from ..io.keys import dotted
from ..scene.build import Scene
from ..scene.dotted_edits import parse_key, parse_value
from ..scene.scenefile import scene_data
from .table import MAX_CELL, cell, is_number, run_key

MAX_RUNS = limits.MAX_RUNS


@dataclass(frozen=True)
class Axis:
    """One varied key: a range (low, high, count: count evenly spaced values, ends included; integers
    if both ends are) or a list of values; name: the short name the user gave it (io/keys.py), if any."""

    key: str
    spec: str
    low: float | None = None
    high: float | None = None
    count: int | None = None
    items: tuple = ()
    name: str = ""

    @property
    def label(self) -> str:
        """The key as the user wrote it: its short name, else the dotted key."""
        return self.name or self.key

    @property
    def is_range(self) -> bool:
        return self.low is not None

    @property
    def integer(self) -> bool:
        return self.is_range and isinstance(self.low, int) and isinstance(self.high, int)

    @property
    def ends(self) -> tuple[float, float]:
        """A range's (low, high)."""
        assert self.low is not None and self.high is not None, f"{self.key}: a list of values, not a range"
        return self.low, self.high

    def grid(self) -> list:
        """The values of a full grid."""
        if not self.is_range:
            return list(self.items)
        if self.count is None:
            raise PneumaInputError(
                f"--vary {self.key}={self.spec}: a range needs a count (start:stop:count) unless --samples is given"
            )
        values = np.linspace(*self.ends, self.count)
        if self.integer:
            values = np.round(values).astype(int)
            require(
                len(set(values)) == len(values),
                f"--vary {self.key}={self.spec}: {self.count} integers do not fit between {self.low} and {self.high}",
            )
        return [v.item() for v in values]

    def sample(self, u: np.ndarray) -> list:
        """Values at the unit-interval coordinates u: uniform over a range (integers: each equally
        likely), over the items of a list."""
        if not self.is_range:
            return [self.items[i] for i in np.minimum((u * len(self.items)).astype(int), len(self.items) - 1)]
        low, high = self.ends
        if self.integer:
            span = high - low + 1
            return [int(v) for v in np.minimum(low + np.floor(u * span), high)]
        return [float(v) for v in low + u * (high - low)]


def parse_vary(text: str) -> Axis:
    """'KEY=start:stop:count' (or start:stop with --samples) or 'KEY=v1,v2,...' -> Axis. KEY is a dotted
    scene key (material.E, chambers[0].center[1]) or a short name of io/keys.py (cy, cx, E, nu, k, max_area)."""
    typed, sep, spec = text.partition("=")
    key, spec = dotted(typed.strip()), spec.strip()
    name = typed.strip() if key != typed.strip() else ""
    require(bool(sep) and key and spec, f"--vary {text[:100]!r} must look like KEY=start:stop:count or KEY=v1,v2,...")
    parse_key(key)  # the dotted-key syntax
    where = f"--vary {key}={spec}"
    if ":" in spec:
        parts = spec.split(":")
        require(len(parts) in (2, 3), f"{where}: a range is start:stop:count (or start:stop with --samples)")
        ends = [parse_value(p, where) for p in parts[:2]]
        for end in ends:
            require(is_number(end), f"{where}: {end!r} is not a number")
            require_finite(where, end)
        count = None
        if len(parts) == 3:
            count = parse_value(parts[2], where)
            require(
                isinstance(count, int) and not isinstance(count, bool) and 1 <= count <= MAX_RUNS,
                f"{where}: count {parts[2]!r} must be an integer from 1 to {MAX_RUNS}",
            )
        return Axis(key, spec, ends[0], ends[1], count, name=name)
    items = [p.strip() for p in spec.split(",")]
    require(all(items), f"{where}: an empty value in the list")
    values = tuple(parse_value(p, where) for p in items)
    require(
        all(len(cell(v)) <= MAX_CELL for v in values),
        f"--vary {key}: a value of more than {MAX_CELL} characters (as a CSV cell)",
    )
    require(len({cell(v) for v in values}) == len(values), f"{where}: a value is listed twice")
    return Axis(key, spec, items=values, name=name)


def plan(axes: list[Axis], samples: int | None = None, seed: int = 0, max_runs: int = MAX_RUNS) -> list[dict]:
    """The runs: every combination of the axes' values, or `samples` points of a Latin hypercube over
    them (scipy.stats.qmc, seeded: the same command plans the same runs), without repeats."""
    if samples is None:
        values = [axis.grid() for axis in axes]
        total = math.prod(len(v) for v in values)  # Python integers: no int64 wrap-around
        require(total <= max_runs, f"the grid has {total} runs; the limit is {max_runs} (--max-runs raises it)")
        runs = [dict(zip([a.key for a in axes], combination)) for combination in itertools.product(*values)]
    else:
        require(1 <= samples <= max_runs, f"--samples {samples} must lie in 1 .. {max_runs} (--max-runs raises it)")
        u = qmc.LatinHypercube(len(axes), seed=seed).random(samples)
        columns = [axis.sample(u[:, j]) for j, axis in enumerate(axes)]
        runs = [dict(zip([a.key for a in axes], values)) for values in zip(*columns)]
    unique = {run_key(run): run for run in runs}  # discrete axes can draw a combination twice
    return list(unique.values())


def lookup(data: dict, key: str):
    """The value of a dotted key in scene data, or KeyError."""
    node = data
    for part in parse_key(key):
        try:
            node = node[part]
        except (IndexError, TypeError):
            raise KeyError(key) from None
    return node


def require_distinct_keys(axes: list[Axis]) -> None:
    require(len({a.key for a in axes}) == len(axes), "a key is varied twice")


def check_axes(base: Scene, axes: list[Axis]) -> list[Axis]:
    """The axes checked against the scene, numbers made floats where the scene holds a float (so
    cy=0:1:3 is 0.0, 0.5, 1.0, not integers). Refuses a key the scene does not have and a value of the
    wrong kind (a word for a number).

    A key present in the base scene's data takes values of its kind; a key that is not (a new effect's
    table, say) must be accepted by the scene reader for at least one of its values. Values that make
    an invalid scene (a chamber outside the body) are not refused here: those runs record the error."""
    require_distinct_keys(axes)
    data, checked = scene_data(base), []
    for axis in axes:
        values = [axis.low, axis.high] if axis.is_range else list(axis.items)
        try:
            current = lookup(data, axis.key)
        except KeyError:
            errors = []
            for value in values:
                try:
                    base.with_value(axis.key, value)
                    break
                except PneumaInputError as exc:
                    errors.append(str(exc))
            else:
                raise PneumaInputError(f"--vary {axis.key}: {errors[0]}") from None
            checked.append(axis)
            continue
        for value in values:
            same = is_number(value) if is_number(current) else isinstance(value, type(current))
            kind = "number" if is_number(current) else type(current).__name__
            require(same, f"--vary {axis.key}: {value!r} is not a {kind} like the scene's {axis.key} = {current!r}")
        if isinstance(current, float):
            axis = (
                replace(axis, items=tuple(float(v) for v in axis.items))
                if not axis.is_range
                else replace(axis, low=float(axis.ends[0]), high=float(axis.ends[1]))
            )
        checked.append(axis)
    return checked
