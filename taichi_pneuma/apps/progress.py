"""The line an app prints after each step of a ramp (pneuma-inflate, pneuma-reach --output)."""

from __future__ import annotations

from ..io.units import LENGTH, PRESSURE
from ..render.text import number


def step_line(step, increments: int, units) -> str:
    """The line printed after each step of a ramp: its chambers, the tip, the Newton iterations, cuts, residual."""
    chambers = "  ".join(
        f"{name}: x{c.area_ratio:5.3f} p = {number(c.pressure, '8.2f')}{units.suffix(PRESSURE)}"
        for name, c in step.chambers.items()
    )
    tip = f"{step.tip_dy:+.4f}{units.suffix(LENGTH)}"
    return (
        f"  step {step.step:3d}/{increments}  {chambers}  tip dy = {tip} "
        f"rot = {step.tip_rotation:+6.1f} deg  {step.iterations:2d} Newton it  {step.cuts} cuts  "
        f"residual {step.residual:.1e}"
    )
