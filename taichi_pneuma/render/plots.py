"""A run's history as a matplotlib figure with axes: only the panels that say something about this run.

Candidate panels, in this order:

    pressure against area ratio              each chamber's curve p(A / A_rest)
    chamber area ratio against the command   left out where it is the command (y = x) or the first panel again
    chamber pressure against the command     (the command is the other of area ratio and pressure)
    tip deflection, bending angle (and twist in 3D), axial extension, the forces on the obstacles (with
        obstacles: the net force, blocked_force, and each obstacle's contact force, the sum of the nodes' |f|,
        a gripper's grip): the actuator's responses (RESPONSES, each drawing the history columns that name it
        as their panel in the registry solve/columns.py COLUMNS; a panel of several columns names the others in
        its title), against the pressure p of the chamber that drives the run, else the step

"The command" is the chambers' commanded value (area ratio, pressure, displaced volume, ...) when every
chamber gets the same command at every step (command_axis); otherwise the step. A chamber's curve of its own
commanded quantity is not drawn (it is the schedule, not a response); a curve constant over the run (a twist of
zero, a chamber at rest) is not drawn, and a panel left without curves is left out. Chambers whose curves are
identical (a PneuNet's chambers on one supply) are one curve, "all 6 chambers"; otherwise each chamber has its own
colour (the same in every panel) and a legend entry with its name; a response panel has a legend when it draws
more than one curve. The run is "driven by one chamber" when the
chambers whose command varies all have the same pressure history (one chamber, or chambers on one supply); the
responses are then drawn against that pressure. The grid has as many axes as panels. In a scene with units every
axis with a dimension says its unit ("pressure p [kPa]").
"""

from __future__ import annotations

import io
import math
import warnings
from dataclasses import dataclass, field

import numpy as np
from matplotlib.figure import Figure

from ..io.units import ANGLE, FORCE, LENGTH, PRESSURE, in_dimension
from ..solve import columns


def command_axis(command: np.ndarray, quantities: list[str]) -> tuple[np.ndarray, str]:
    """The x values and label of the 'against the command' panels: command (steps, chambers) and what each
    chamber's command is (its kind's quantity: 'area ratio', 'pressure'); see the module docstring."""
    if len(set(quantities)) == 1 and np.all(command == command[:, :1]):
        return command[:, 0], f"commanded {quantities[0]}"
    return np.arange(len(command), dtype=float), "step"


class NotebookFigure(Figure):
    """A matplotlib Figure made without pyplot (no global state, nothing left open) that a notebook shows:
    IPython displays an object's _repr_png_."""

    def _repr_png_(self) -> bytes:
        buffer = io.BytesIO()
        self.savefig(buffer, format="png", dpi=100)
        return buffer.getvalue()


# the ratio a chamber's axis shows, and what it measures, by the body's dimension
RATIO = {2: ("area ratio A / A_rest", "area"), 3: ("volume ratio V / V_rest", "volume")}
# one panel's size and the figure's margins in inches, fixed: matplotlib's constrained layout would find them
# itself, at twice the time of the whole plot (0.75 against 1.7 s measured)
PANEL_IN, MARGIN_IN = (5.0, 3.4), dict(left=0.7, right=0.3, bottom=0.55, top=0.75)


@dataclass
class Panel:
    """One axes: its title and axis labels, and its curves as (label, x, y, colour) (label '' for no legend)."""

    title: str
    x_label: str
    y_label: str
    curves: list = field(default_factory=list)


def constant(values: np.ndarray) -> bool:
    """True when values do not change over the run (to rounding: a spread within 1e-9 of their size)."""
    values = np.asarray(values, float)
    return bool(np.ptp(values) <= 1e-9 * (1.0 + np.abs(values).max()))


def chamber_colour(k: int) -> str:
    """Chamber k's colour in every panel (matplotlib's tab10 cycle)."""
    return f"C{k % 10}"


def chamber_curves(names: list[str], xs: np.ndarray, ys: np.ndarray, keep: list[bool]) -> list:
    """Curves (label, x, y, colour) of the chambers kept (xs, ys: (steps, chambers); x may be one column for
    all), those whose y is constant left out. Chambers with identical curves are one curve, labelled by their
    names ('all n chambers' when they are all of them), in the first one's colour (black for all)."""
    xs = np.broadcast_to(np.asarray(xs, float).reshape(len(ys), -1), ys.shape)
    groups: list[list[int]] = []
    for k in (k for k in range(ys.shape[1]) if keep[k] and not constant(ys[:, k])):
        like = [g for g in groups if all(np.allclose(a[:, k], a[:, g[0]], rtol=1e-9, atol=0) for a in (xs, ys))]
        if like:
            like[0].append(k)
        else:
            groups.append([k])
    if len(names) == 1 or (len(groups) == 1 and len(groups[0]) == len(names)):
        label = f"all {len(names)} chambers" if len(names) > 1 else ""
        return [(label, xs[:, 0], ys[:, 0], "k")] if groups else []
    return [(", ".join(short(names[k]) for k in g), xs[:, g[0]], ys[:, g[0]], chamber_colour(g[0])) for g in groups]


def response_axis(result) -> tuple[np.ndarray, str]:
    """The x of the response panels: the pressure of the chamber(s) driving the run (module docstring) and its
    label, else the step."""
    names, pressure, command = result.chamber_names, result.pressure, result.command
    driving = [k for k in range(len(names)) if not constant(command[:, k])] or list(range(len(names)))
    p = pressure[:, driving[0]]
    if constant(p) or not all(np.allclose(pressure[:, k], p, rtol=1e-9, atol=0) for k in driving):
        return np.arange(len(p), dtype=float), "step"
    which = "" if len(names) == 1 else f" of all {len(names)} chambers" if len(driving) == len(names) else ""
    if len(names) > 1 and not which:
        which = " of " + ", ".join(short(names[k]) for k in driving)
    return p, result.scene.units.label("pressure p" + which, PRESSURE)


OBSTACLE_COLOURS = ("tab:blue", "tab:green", "tab:red", "tab:purple", "tab:brown")  # each obstacle's force curve
RESPONSE_COLOURS = ("k", "tab:orange", "tab:cyan", "tab:olive")  # a response panel's columns, in COLUMNS' order
# the response panels (module docstring) by the key of columns.Column.panel: title, y label and its dimension
RESPONSES = (
    ("deflection", "tip deflection (mean y displacement of the tip)", "tip deflection dy", LENGTH),
    ("bending", "bending angle (tip rotation)", "angle", ANGLE),
    ("extension", "axial extension (mean x displacement of the tip)", "extension dx", LENGTH),
    ("obstacles", "force on the obstacles", "force", FORCE),
)


def history_panels(result) -> list[Panel]:
    """The panels of the module docstring that have something to draw for this run."""
    units, kinds, history, names = (
        result.scene.units,
        [c.kind for c in result.scene.controls],
        result.history,
        result.chamber_names,
    )
    quantities = [kind.quantity for kind in kinds]
    ratio, measure = RATIO[result.mesh.dim]
    pressure_label = units.label("pressure p", PRESSURE)
    x, x_label = command_axis(result.command, quantities)
    commanded = x_label != "step"
    x_label = x_label if not commanded else units.label(x_label, in_dimension(kinds[0].dimension, result.mesh.dim))
    panels = [
        Panel(
            f"pressure against {measure} ratio",
            ratio,
            pressure_label,
            chamber_curves(names, result.area_ratio, result.pressure, [True] * len(names)),
        )
    ]
    for quantity, other, values, title, y_label in (
        ("area ratio", "pressure", result.area_ratio, f"chamber {measure}", ratio),
        ("pressure", "area ratio", result.pressure, "chamber pressure", pressure_label),
    ):
        if not (commanded and quantities[0] == other):  # else: the first panel with its axes swapped
            keep = [q != quantity for q in quantities]  # a chamber's own command is the schedule, not a response
            panels.append(Panel(title, x_label, y_label, chamber_curves(names, x, values, keep)))
    xr, xr_label = response_axis(result)
    for key, title, y_label, dimension in RESPONSES:
        drawn = [
            (c.label, xr, history[c.name], RESPONSE_COLOURS[k % len(RESPONSE_COLOURS)])
            for k, c in enumerate(c for c in columns.COLUMNS if c.panel == key)
            if c.name in history and not constant(history[c.name])
        ]
        if drawn[1:]:  # the columns after the panel's first, named in its title
            title += " and " + ", ".join(label for label, *_ in drawn[1:])
        if key == "obstacles":  # each obstacle's contact force (a gripper's grip)
            for k, obstacle in enumerate(result.scene.obstacles):
                name = f"{obstacle.name}.magnitude"
                if not constant(history[name]):
                    colour = OBSTACLE_COLOURS[k % len(OBSTACLE_COLOURS)]
                    drawn.append((f"{obstacle.name}: sum of |f|", xr, history[name], colour))
        curves = [(label if drawn[1:] else "", *curve) for label, *curve in drawn]  # a legend for several curves
        panels.append(Panel(title, xr_label, units.label(y_label, in_dimension(dimension, result.mesh.dim)), curves))
    return [p for p in panels if p.curves]


def history_figure(result, figure=None, title: str | None = None):
    """Draw the history of an api.Result on `figure` (by default a new NotebookFigure sized to the panels): one
    axes per panel of history_panels, in a grid of up to three columns (two for four panels), under `title` (by
    default the scene's name; a saved figure's, its files' stem, which names what the run changed)."""
    panels = history_panels(result)
    n = max(len(panels), 1)
    cols = 2 if n == 4 else min(n, 3)
    rows = math.ceil(n / cols)
    size = (PANEL_IN[0] * cols, PANEL_IN[1] * rows + 0.4)
    fig = figure if figure is not None else NotebookFigure(figsize=size)
    if figure is None:
        m = MARGIN_IN
        fig.subplots_adjust(
            left=m["left"] / size[0],
            right=1 - m["right"] / size[0],
            bottom=m["bottom"] / size[1],
            top=1 - m["top"] / size[1],
            wspace=0.3,
            hspace=0.55,
        )
    for k, panel in enumerate(panels):
        ax = fig.add_subplot(rows, cols, k + 1)
        for label, x, y, colour in panel.curves:
            ax.plot(x, y, ".-", color=colour, label=label or None)
        ax.set(xlabel=panel.x_label, ylabel=panel.y_label, title=panel.title)
        ax.grid(True, alpha=0.3)
        if any(label for label, *_ in panel.curves):
            ax.legend(fontsize="small")
    fig.suptitle(short(title or result.scene.name, 80))
    return fig


def short(text: str, most: int = 24) -> str:
    """A name for a legend or title: cut to `most` characters, unprintable characters (tabs, ...) as '?'."""
    text = "".join(c if c.isprintable() else "?" for c in text)
    return text if len(text) <= most else text[: most - 3] + "..."


def save_history_png(result, path, title: str | None = None) -> None:
    """Write the history figure (under title: history_figure) to path (PNG). A name's character without a glyph in
    the font is drawn as a box; matplotlib says so each time, but the figure is still whole, so it is not passed on
    as a warning."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Glyph .* missing from font")
        history_figure(result, title=title).savefig(path, dpi=100, format="png")
