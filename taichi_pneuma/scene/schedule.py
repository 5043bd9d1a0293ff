"""Scripted actuation: per chamber, piecewise-linear keyframes of its kind's command (area ratio, pressure, ...)
over increments.

A schedule has `increments` solves after the rest state (step 0 .. increments). A chamber's
command at step s interpolates linearly between its keyframes (s_k, v_k); before the first
keyframe it holds its kind's rest value (area ratio 1, pressure 0) at s = 0, after the last it
holds the last value. Inflate, hold and deflate are keyframes rising, constant and falling:

    keyframes = [[0, 1.0], [10, 3.0], [15, 3.0], [25, 1.0]]     # area ratio: inflate, hold, deflate
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import require, require_finite, shape_of
from ..terms.chambers import AreaControl, Chamber, ChamberKind, default_kind

# A run past this largest principal stretch warns (a scene's schedule.max_stretch replaces it). The presets are
# fitted to uniaxial data up to 200 % strain (a stretch of 3; docs/materials.md): past that their stresses are
# extrapolated, and at 5 (400 % strain) a silicone is past Dragon Skin 30's elongation at break (364 %) and half
# way to the others' (700-1000 %); the stable neo-Hookean law has no such data at all.
MAX_STRETCH = 5.0


@dataclass(frozen=True, init=False)
class ChamberSchedule:
    """Keyframes ((step, value), ...) of one chamber driven by `kind`, whose check() the values pass.

    kind: a ChamberKind with its parameters (e.g. AreaControl(stiffness=1e5)), or the name of a
    registered kind for its default parameters ("area", "pressure"), which the constructor turns into that kind:
    the field is a ChamberKind."""

    kind: ChamberKind
    keyframes: tuple[tuple[float, float], ...]

    def __init__(self, kind: ChamberKind | str, keyframes: tuple[tuple[float, float], ...]):
        object.__setattr__(self, "kind", kind if isinstance(kind, ChamberKind) else default_kind(kind))
        object.__setattr__(self, "keyframes", keyframes)
        require(
            len(self.keyframes) >= 1 and all(shape_of(k) == (2,) for k in self.keyframes),
            f"keyframes = {self.keyframes!r} must be a non-empty list of [step, value] pairs",
        )
        steps = [require_finite("keyframes step", s) for s, _ in self.keyframes]
        values = [require_finite("keyframes value", v) for _, v in self.keyframes]
        require(
            all(float(s).is_integer() and s >= 0 for s in steps),
            f"keyframes steps {steps!r} must be whole numbers >= 0",
        )
        require(all(b > a for a, b in zip(steps, steps[1:])), f"keyframes steps {steps!r} must increase")
        self.kind.check("keyframes", values)

    @property
    def last_step(self) -> int:
        return int(self.keyframes[-1][0])

    def command(self, step: float) -> float:
        steps = [0.0] + [float(s) for s, _ in self.keyframes]
        values = [self.kind.rest] + [float(v) for _, v in self.keyframes]
        if steps[1] == 0.0:
            steps, values = steps[1:], values[1:]
        return float(np.interp(step, steps, values))


@dataclass(frozen=True)
class Schedule:
    """The increments of a run and one ChamberSchedule per chamber, in the scene's chamber order; obstacles: the
    scene's obstacles (terms/obstacles.py Obstacle), whose moving ones' translations (3 each, in order) follow the
    chambers' commands in the commands vector, so that a cut-back increment moves them by the same fraction."""

    increments: int
    chambers: tuple[ChamberSchedule, ...]
    obstacles: tuple = ()

    def __post_init__(self):
        require(
            isinstance(self.increments, (int, np.integer)) and self.increments >= 1,
            f"increments = {self.increments!r} must be an integer >= 1",
        )
        for c in (*self.chambers, *self.obstacles):
            require(
                c.last_step <= self.increments,
                f"keyframe step {c.last_step} lies past the last increment ({self.increments})",
            )

    @property
    def moving(self) -> tuple:
        """The obstacles that move (have keyframes), whose translations the commands carry."""
        return tuple(o for o in self.obstacles if o.moving)

    def commands(self, step: float) -> np.ndarray:
        """Every chamber's command at (possibly fractional) step, then each moving obstacle's translation (3)."""
        return np.array([c.command(step) for c in self.chambers] + [x for o in self.moving for x in o.offset(step)])

    @property
    def rest_commands(self) -> np.ndarray:
        rests = [float(c.kind.rest) for c in self.chambers]
        return np.array(rests + [0.0] * (3 * len(self.moving)))


def area_ramp(growth: float, steps: int, stiffness: float = 1e5) -> ChamberSchedule:
    """The reference ramp for one area-controlled chamber (stiffness k): area ratio 1 -> growth over steps - 1
    increments."""
    require(require_finite("growth", growth) > 0, f"growth = {growth!r} must be > 0")
    require(
        isinstance(steps, (int, np.integer)) and steps >= 2,
        f"steps = {steps!r} must be an integer >= 2 (the rest state and at least one increment)",
    )
    return ChamberSchedule(AreaControl(stiffness), ((0, 1.0), (steps - 1, float(growth))))


@dataclass(frozen=True)
class ChamberControl:
    """How a chamber is driven: its schedule (whose kind carries the kind's parameters, e.g. the area
    penalty's stiffness) and the (min, max) command bounds inverse control keeps to (None: the kind's
    default_bounds of the schedule)."""

    schedule: ChamberSchedule
    bounds: tuple[float, float] | None = None

    def __post_init__(self):
        if self.bounds is not None:
            require(len(self.bounds) == 2, f"bounds = {list(self.bounds)!r} must be [min, max]")
            low, high = (require_finite("bounds", b) for b in self.bounds)
            require(low < high, f"bounds = {list(self.bounds)!r}: min {low:g} must be < max {high:g}")
            self.kind.check(f"bounds = {list(self.bounds)!r}:", [low, high])

    @property
    def kind(self) -> ChamberKind:
        return self.schedule.kind

    def term(self, config, loop: np.ndarray, name: str, order: int, origin: np.ndarray | None = None) -> Chamber:
        return self.kind.term(config, loop, name, order, origin)
