"""A study's figure: the tip deflection at the last step against the varied keys (a curve for one key, a heatmap
or a coloured scatter for two, a panel per key for more), failed runs marked, never drawn as data.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from .table import cell, is_number, shown

if TYPE_CHECKING:
    from matplotlib.collections import Collection

MAX_DRAWN = 1e100  # numbers the plot draws as such (matplotlib's axis arithmetic overflows near 1e308)


def _positions(values: list) -> tuple[np.ndarray, list | None]:
    """Numbers as they are, if a plot can draw them (MAX_DRAWN); anything else as category indices
    (returned with their labels: each distinct value, by its CSV cell, as shown() writes it)."""
    if all(is_number(v) and abs(v) <= MAX_DRAWN for v in values):
        return np.array(values, dtype=float), None
    first = {cell(v): v for v in reversed(values)}  # each cell's first value, in order of first appearance
    cells = list(dict.fromkeys(cell(v) for v in values))
    return np.array([cells.index(cell(v)) for v in values], dtype=float), [shown(first[c]) for c in cells]


GRID_TICKS = 12  # a heat map's numeric axis with at most this many grid values is ticked at them


def _edges(centres: np.ndarray) -> np.ndarray:
    """Cell edges around sorted cell centres (midpoints; one centre gets a cell of its own size)."""
    if len(centres) == 1:
        half = 0.5 * (abs(centres[0]) or 1.0)
        return np.array([centres[0] - half, centres[0] + half])
    mid = 0.5 * (centres[1:] + centres[:-1])
    return np.concatenate([[2 * centres[0] - mid[0]], mid, [2 * centres[-1] - mid[-1]]])


def study_figure(rows: list[dict], keys: list[str], sampled: bool = False, labels: list[str] | None = None):
    """Tip deflection against the varied keys (a matplotlib Figure, no pyplot), each axis labelled as the
    user named its key (labels: short names, default the keys). One key: curves of tip dy and dx. Two: a
    heatmap of tip dy over the grid (red up, blue down; a scatter coloured by it for a sampled study).
    More: tip dy against each key. A failed run has no figures: one key marks it by a shaded line at its
    value (never a point at y = 0, which would read as data); two keys by an x in its cell; more leave
    it out (the title counts it)."""
    from matplotlib.figure import Figure

    labels = labels or keys
    ok = [r for r in rows if r.get("error") is None and r.get("tip_dy") is not None]
    failed = [r for r in rows if r.get("error") is not None]
    n = len(ok)
    tip = np.clip([r["tip_dy"] for r in ok], -MAX_DRAWN, MAX_DRAWN)  # drawn; the CSV has them exact
    title = "tip deflection at the last step"
    if len(keys) > 2:
        figure = Figure(figsize=(4 * len(keys), 3.6), layout="constrained")
        axes = figure.subplots(1, len(keys), sharey=True)
        for ax, key, label in zip(axes, keys, labels):
            x, ticks = _positions([r[key] for r in ok])
            ax.plot(x, tip, "o", ms=4)
            if ticks:
                ax.set_xticks(range(len(ticks)), ticks)
            ax.set(xlabel=label)
        axes[0].set_ylabel("tip dy")
        figure.suptitle(title + (f" ({len(failed)} failed runs not shown)" if failed else ""))
        return figure
    figure = Figure(figsize=(6.5, 4.5), layout="constrained")
    ax = figure.add_subplot()
    positions = [_positions([r[k] for r in ok + failed]) for k in keys]
    x, xl = positions[0]
    if len(keys) == 1:
        order = np.argsort(x[:n], kind="stable")
        ax.plot(x[:n][order], tip[order], "o-", label="tip dy")
        ax.plot(x[:n][order], np.clip([r["tip_dx"] for r in ok], -MAX_DRAWN, MAX_DRAWN)[order], "s--", label="tip dx")
        ax.axhline(0, color="0.7", lw=0.8)
        for k, value in enumerate(x[n:]):
            ax.axvline(value, color="tab:red", alpha=0.25, lw=6, label="failed run (no figures)" if k == 0 else None)
        ax.set(ylabel="tip displacement")
    else:
        y, yl = positions[1]
        limit = float(np.abs(tip).max()) or 1.0
        colours: dict[str, Any] = dict(cmap="coolwarm", vmin=-limit, vmax=limit)
        image: Collection
        if sampled:
            image = ax.scatter(x[:n], y[:n], c=tip, s=40, edgecolors="k", linewidths=0.3, **colours)
        else:
            xs, ys = np.unique(x), np.unique(y)
            grid = np.full((len(ys), len(xs)), np.nan)
            grid[np.searchsorted(ys, y[:n]), np.searchsorted(xs, x[:n])] = tip
            image = ax.pcolormesh(_edges(xs), _edges(ys), np.ma.masked_invalid(grid), **colours)
            for values, labelled, set_ticks in ((xs, xl, ax.set_xticks), (ys, yl, ax.set_yticks)):
                if not labelled and len(values) <= GRID_TICKS:  # a numeric axis: its ticks on the grid's values
                    set_ticks(values, [f"{v:g}" for v in values])
            if grid.size <= 64:
                for (i, j), value in np.ndenumerate(grid):
                    if np.isfinite(value):
                        ax.text(
                            float(xs[j]),
                            float(ys[i]),
                            f"{value:+.3f}",
                            ha="center",
                            va="center",
                            fontsize=8,
                            color="w" if abs(value) > 0.6 * limit else "k",
                        )
        figure.colorbar(image, ax=ax, label="tip dy")
        if yl:
            ax.set_yticks(range(len(yl)), yl)
        ax.set(ylabel=labels[1])
        if failed:
            ax.plot(x[n:], y[n:], "x", color="k", ms=9, mew=2, label="failed run")
    if xl:
        ax.set_xticks(range(len(xl)), xl)
    ax.set(xlabel=labels[0], title=title)
    if len(keys) == 1 or failed:
        ax.legend()
    return figure
