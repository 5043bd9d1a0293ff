"""Numbered axes: round tick values (matplotlib's choice), their figures, and a colour bar's ticks."""

from __future__ import annotations

from typing import cast

import numpy as np


def nice_ticks(lo: float, hi: float, integer: bool = False, bins: int = 5) -> np.ndarray:
    """Round tick values (1-2-5 steps, matplotlib's MaxNLocator) whose first and last enclose [lo, hi], at
    most bins intervals (fewer where a small frame has no room for more labels)."""
    from matplotlib.ticker import MaxNLocator

    if hi <= lo:
        pad = 0.1 * abs(lo) if lo != 0 else 1.0
        lo, hi = lo - pad, hi + pad
    bins = max(int(bins), 1)
    ticks = MaxNLocator(nbins=bins, integer=integer, min_n_ticks=min(3, bins + 1)).tick_values(lo, hi)
    return cast(np.ndarray, ticks)  # an array (the stubs say Sequence[float])


def tick_label(value: float) -> str:
    """A tick figure: 4 significant digits, round-off below 1e-9 shown as 0."""
    return f"{value if abs(value) > 1e-9 else 0.0:.4g}"


def colorbar_ticks(lo: float, hi: float, top: float, bottom: float) -> list[tuple[float, str]]:
    """A vertical colour bar's ticks over the colour range lo..hi, drawn from pixel row bottom (lo) up to
    top (hi): (row, figure) of each round tick within the range."""
    span = hi - lo if hi > lo else 1.0
    return [
        (bottom + (top - bottom) * (t - lo) / span, tick_label(t))
        for t in nice_ticks(lo, hi)
        if lo - 1e-12 <= t <= hi + 1e-12
    ]
