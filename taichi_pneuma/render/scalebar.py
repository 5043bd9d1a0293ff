"""A scale bar: the round length (1, 2 or 5 times a power of ten) that fills about a fifth of a view, and its label
with the scene's length unit, so that a frame says how big the body is; and the place for it that the body
leaves free."""

from __future__ import annotations

import math

import numpy as np


def scale_bar(view_width: float, unit: str = "", fraction: float = 0.2) -> tuple[float, str]:
    """(length, label) of the largest round length 10^k x {1, 2, 5} not above fraction x view_width (world units);
    the label is the length's figure followed by the unit suffix ('' in a unitless scene, ' mm' in mm-kPa)."""
    if not (math.isfinite(view_width) and view_width > 0):
        raise ValueError(f"view_width = {view_width!r} must be a finite length > 0")
    target = fraction * view_width
    power = 10.0 ** math.floor(math.log10(target))
    length = max(m * power for m in (1.0, 2.0, 5.0) if m * power <= target * (1 + 1e-12))
    return length, f"{length:g}{unit}"


def emptiest(boxes: np.ndarray, points: np.ndarray) -> int:
    """The index of the first of the boxes (k, 4: left, top, right, bottom) that holds fewest of the points (n, 2):
    where a scale bar covers no part of the body, if there is such a place."""
    inside = np.all((points[:, None] >= boxes[None, :, :2]) & (points[:, None] <= boxes[None, :, 2:]), axis=2)
    return int(np.argmin(inside.sum(axis=0)))
